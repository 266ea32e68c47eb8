// Per-object state at run time, kept by global object index (the package's object table):
// hidden, selected, X-ray and a colour override, for the design-review tools (layers, search,
// picking). The GPU reads it from one buffer indexed by object (GlRenderer::setObjectStates), in
// every pass that colours or outputs an object id, so it holds at every level of detail and
// survives the eviction and reload of pages: nothing of it lives in the pages.
//
// Why one buffer by object and not flags in the geometry: a coarse cluster merges many objects,
// and their triangles keep their object ids (the id buffer); a state per object then applies to
// exactly its triangles at any level, and changing a million objects is one upload.
//
// The flags decide how an object looks (ObjectLook): hidden wins over everything; a selected
// object is drawn opaque even when X-rayed (the reviewer sees what was picked); an X-rayed one is
// drawn ghosted in the frame's second surface pass (SurfacePass::Xray), translucent, writing no
// depth and no id, so it neither occludes nor is picked. The CPU side answers "does any object of
// [first, last] look so?" in O(1) (prefix counts), so the frame loop leaves a cluster out of the
// passes that would draw nothing of it.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

namespace tw {

// Bits of GpuObjectState::flags; the shaders use the same values (gl_shaders.h).
inline constexpr uint32_t kObjectHidden = 1u;     // drawn nowhere, occludes nothing
inline constexpr uint32_t kObjectSelected = 2u;   // tinted and outlined, opaque even if X-rayed
inline constexpr uint32_t kObjectXray = 4u;       // ghosted: translucent, no depth, no id
inline constexpr uint32_t kObjectRecolored = 8u;  // color_rgba replaces the object's colour
// Moved by a review edit: the package's clusters do not draw it (at any level, like hidden), the
// moved-objects pass draws it at its new placement (moved_objects_pass.h).
inline constexpr uint32_t kObjectMoved = 16u;

enum class ObjectLook : uint8_t { Hidden, Opaque, Ghosted };

// The frame's two surface passes: the opaque one (depth, ids) and the ghosted X-ray one after it.
enum class SurfacePass : uint8_t { Opaque, Xray };

inline ObjectLook objectLook(uint32_t flags) {
  if (flags & (kObjectHidden | kObjectMoved)) return ObjectLook::Hidden;
  if ((flags & kObjectXray) && !(flags & kObjectSelected)) return ObjectLook::Ghosted;
  return ObjectLook::Opaque;
}

// Whether an object of these flags is drawn by `pass`.
inline bool drawnIn(uint32_t flags, SurfacePass pass) {
  return objectLook(flags) == (pass == SurfacePass::Opaque ? ObjectLook::Opaque : ObjectLook::Ghosted);
}

// std430 layout of the GLSL struct (8 bytes, array stride 8).
struct GpuObjectState {
  uint32_t flags = 0;
  uint32_t color_rgba = 0;  // 0xAABBGGRR, with kObjectRecolored
};
static_assert(sizeof(GpuObjectState) == 8);

class ObjectStates {
 public:
  explicit ObjectStates(size_t object_count = 0);

  size_t size() const { return states_.size(); }
  uint32_t flags(uint32_t object) const { return states_[object].flags; }
  ObjectLook look(uint32_t object) const { return objectLook(states_[object].flags); }

  // Sets or clears `bits` of one object, or of all. Objects past the table are ignored.
  void set(uint32_t object, uint32_t bits, bool on);
  void setAll(uint32_t bits, bool on);
  void setColor(uint32_t object, uint32_t rgba);  // and kObjectRecolored
  void clearColor(uint32_t object);

  // Counts over [first, last] (inclusive, clamped to the table), O(1) once the looks have been
  // counted after a change (O(objects) once).
  bool anyOpaque(uint32_t first, uint32_t last) const;   // something for the opaque pass
  bool allOpaque(uint32_t first, uint32_t last) const;   // nothing hidden or ghosted
  bool anyGhosted(uint32_t first, uint32_t last) const;  // something for the X-ray pass
  bool everyObjectOpaque() const;
  bool anyGhosted() const;
  bool anySelected() const;  // among objects not hidden

  // What the GPU buffer should hold, and whether it changed since markUploaded().
  std::span<const GpuObjectState> gpuStates() const { return states_; }
  bool changed() const { return changed_; }
  void markUploaded() { changed_ = false; }

 private:
  void countLooks() const;
  // Of the counts below: objects in [first, last] (clamped; 0 for an empty range).
  uint32_t countIn(const std::vector<uint32_t>& before, uint32_t first, uint32_t last,
                   uint32_t* range_size = nullptr) const;

  std::vector<GpuObjectState> states_;
  bool changed_ = true;
  // opaque_before_[i], ghosted_before_[i]: objects below i that look so; rebuilt lazily.
  mutable std::vector<uint32_t> opaque_before_;
  mutable std::vector<uint32_t> ghosted_before_;
  mutable uint32_t selected_shown_ = 0;
  mutable bool counted_ = false;
};

}  // namespace tw
