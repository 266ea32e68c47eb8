// A sink that counts what a scene holds: what `terawalk info` prints and tests check.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <unordered_set>
#include <vector>

#include "bounds.h"
#include "scene_sink.h"

namespace tw {

class SceneStats : public SceneSink {
 public:
  static constexpr size_t kPrimitiveTypes = std::variant_size_v<Primitive>;
  static constexpr size_t kGeometryKinds = 3;

  // `tolerance` sets the chordal tolerance used to count tessellated-equivalent triangles.
  explicit SceneStats(float tolerance);

  void onLayer(uint32_t index, const Layer& layer) override;
  void onObject(const SceneObject& object) override;

  struct LayerStats {
    std::string name;
    uint64_t objects = 0;
    uint64_t triangles = 0;  // tessellated equivalent
  };

  uint64_t objects = 0;       // distinct object ids
  uint64_t parts = 0;         // onObject calls
  uint64_t objects_with_db_key = 0;
  std::array<uint64_t, kGeometryKinds> objects_by_kind{};  // indexed by GeometryKind
  std::array<uint64_t, kPrimitiveTypes> primitives_by_type{};  // indexed like Primitive
  uint64_t nurbs_patches = 0;
  uint64_t mesh_triangles = 0;       // triangles stored as meshes
  uint64_t primitive_triangles = 0;  // tessellated equivalent of primitives
  uint64_t nurbs_triangles = 0;      // NURBS as the preprocessor tessellates them (conforming)
  uint64_t mesh_vertices = 0;
  Aabb bounds;
  std::vector<LayerStats> layers;

  uint64_t totalTriangles() const { return mesh_triangles + primitive_triangles + nurbs_triangles; }
  static const char* primitiveTypeName(size_t index);
  static const char* geometryKindName(size_t index);

 private:
  float tolerance_;
  std::unordered_set<uint32_t> seen_ids_;
  uint32_t last_id_ = 0;
  bool any_ = false;
};

}  // namespace tw
