// A SceneSink that turns a streamed scene into a ray-traceable EmbreeScene for CPU snapshots.
//
// Parametric primitives and NURBS are tessellated at a chordal tolerance; everything is moved to
// world space relative to a double-precision origin, and small objects are packed into shared
// Embree geometries (a plant has hundreds of thousands of objects; one Embree geometry each
// would cost more than the triangles). Each triangle keeps a "slot" naming its object and
// colour, so the renderer can colour by scene colours or by object.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "bounds.h"
#include "embree_scene.h"
#include "scene_sink.h"
#include "tessellate.h"

namespace tw {

struct SnapshotBuildOptions {
  float tolerance = kDefaultChordalTolerance;  // chordal tolerance for tessellation, scene units
  // The frame origin for single-precision vertices. Default: the centre of the first object's
  // world bounds, which keeps every vertex within the model's extent of the origin (float error
  // about 1e-7 of the model size: 0.1 mm over a kilometre).
  std::optional<glm::dvec3> origin;
  // Triangles packed into one Embree geometry before starting the next. 256K triangles keeps
  // the number of geometries small while each batch's buffers stay a few MB.
  uint32_t batch_triangles = 1u << 18;
};

// The finished, committed scene and what the renderer needs to colour it.
struct SnapshotScene {
  struct Slot {
    uint32_t object_id = 0;
    uint32_t color_rgba = 0;  // 0xAABBGGRR, resolved from object, vertex or layer colour
  };

  std::unique_ptr<EmbreeScene> rt;  // committed; never nullptr after SnapshotBuilder::finish
  // Per Embree geometry (== its user id), one slot index per triangle. 4 bytes per triangle.
  std::vector<std::vector<uint32_t>> triangle_slots;
  std::vector<Slot> slots;
  Aabb bounds;  // world bounds of every vertex added (double precision)

  uint64_t objects = 0;          // distinct object ids seen
  uint64_t parts = 0;            // onObject calls
  uint64_t triangles = 0;        // triangles added to the Embree scene
  uint64_t skipped_parts = 0;    // parts whose tessellation failed (bad parameters)
  uint32_t distinct_colors = 0;  // distinct slot colours, counted up to 64

  const Slot& slotOf(const EmbreeScene::Hit& hit) const {
    return slots[triangle_slots[hit.user_id][hit.primitive]];
  }
};

class SnapshotBuilder : public SceneSink {
 public:
  explicit SnapshotBuilder(const SnapshotBuildOptions& options = {});
  ~SnapshotBuilder() override;

  void onLayer(uint32_t index, const Layer& layer) override;
  void onObject(const SceneObject& object) override;

  // Flushes the last batch and builds the BVH (the slow part: about a second per few million
  // triangles on two cores). The builder is spent afterwards. Throws std::runtime_error on an
  // Embree failure (for example out of memory).
  SnapshotScene finish();

 private:
  void ensureScene(const SceneObject& first);
  void flushBatch();
  uint32_t slotFor(uint32_t object_id, uint32_t color_rgba);
  uint32_t layerColor(uint32_t layer) const;

  SnapshotBuildOptions options_;
  SnapshotScene out_;
  std::vector<uint32_t> layer_colors_;
  TriangleMesh scratch_;  // tessellation output, reused between objects

  // The batch being filled.
  std::vector<glm::vec3> batch_positions_;
  std::vector<uint32_t> batch_indices_;
  std::vector<uint32_t> batch_slots_;

  // Slots of the current object only (parts of one object arrive one after another).
  std::unordered_map<uint32_t, uint32_t> object_slots_;
  uint32_t current_object_ = 0;
  bool have_object_ = false;
  std::unordered_set<uint32_t> seen_colors_;
  std::unordered_set<uint32_t> seen_ids_;
  bool finished_ = false;
};

}  // namespace tw
