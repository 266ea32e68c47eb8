// Per-object state at run time, kept by global object index (the package's object table):
// hidden, selected and a colour override, for the design-review tools (layers, search,
// picking). The GPU reads it from one buffer indexed by object (GlRenderer::setObjectStates), in
// every pass that colours or outputs an object id, so it holds at every level of detail and
// survives the eviction and reload of pages: nothing of it lives in the pages.
//
// Why one buffer by object and not flags in the geometry: a coarse cluster merges many objects,
// and their triangles keep their object ids (the id buffer); a state per object then applies to
// exactly its triangles at any level, and changing a million objects is one upload.
// The CPU side also answers "is every object of [first, last] hidden?" in O(1) (a prefix count),
// so the frame loop drops clusters with nothing left to show before drawing them.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

namespace tw {

// Bits of GpuObjectState::flags; the shaders use the same values (gl_shaders.h).
inline constexpr uint32_t kObjectHidden = 1u;     // drawn nowhere, occludes nothing
inline constexpr uint32_t kObjectSelected = 2u;   // tinted
inline constexpr uint32_t kObjectRecolored = 8u;  // color_rgba replaces the object's colour

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

  // Sets or clears `bits` of one object, or of all. Objects past the table are ignored.
  void set(uint32_t object, uint32_t bits, bool on);
  void setAll(uint32_t bits, bool on);
  void setColor(uint32_t object, uint32_t rgba);  // and kObjectRecolored
  void clearColor(uint32_t object);

  // Whether every object of [first, last] (inclusive, clamped to the table) is hidden, and
  // whether any is. O(1) after a change of hidden bits has been counted (O(objects) once).
  bool allHidden(uint32_t first, uint32_t last) const;
  bool anyHidden(uint32_t first, uint32_t last) const;
  bool noneHidden() const { return hiddenCount() == 0; }

  // What the GPU buffer should hold, and whether it changed since markUploaded().
  std::span<const GpuObjectState> gpuStates() const { return states_; }
  bool changed() const { return changed_; }
  void markUploaded() { changed_ = false; }

 private:
  void countHidden() const;
  uint32_t hiddenCount() const;

  std::vector<GpuObjectState> states_;
  bool changed_ = true;
  // visible_before_[i]: objects below i that are not hidden; rebuilt lazily.
  mutable std::vector<uint32_t> visible_before_;
  mutable bool counted_ = false;
};

}  // namespace tw
