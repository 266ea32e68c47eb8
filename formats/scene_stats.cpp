// Counting sink behind `terawalk info`.
#include "scene_stats.h"

#include "nurbs_conforming.h"
#include "tessellate.h"

namespace tw {

SceneStats::SceneStats(float tolerance) : tolerance_(tolerance) {}

void SceneStats::onLayer(uint32_t index, const Layer& layer) {
  if (layers.size() <= index) layers.resize(index + 1);
  layers[index].name = layer.name;
}

void SceneStats::onObject(const SceneObject& object) {
  ++parts;
  const ObjectInfo& info = object.info;
  // Parts of one object arrive consecutively; the set catches ids that come back later.
  bool is_new = !(any_ && info.id == last_id_) && seen_ids_.insert(info.id).second;
  any_ = true;
  last_id_ = info.id;
  if (layers.size() <= info.layer) layers.resize(info.layer + 1);
  LayerStats& layer = layers[info.layer];
  GeometryKind kind = kindOf(object.geometry);
  if (is_new) {
    ++objects;
    ++layer.objects;
    ++objects_by_kind[static_cast<size_t>(kind)];
    if (!info.db_key.empty()) ++objects_with_db_key;
  }
  uint64_t triangles = 0;
  if (const auto* mesh = std::get_if<TriangleMesh>(&object.geometry)) {
    triangles = mesh->triangleCount();
    mesh_triangles += triangles;
    mesh_vertices += mesh->positions.size();
  } else if (const auto* primitive = std::get_if<Primitive>(&object.geometry)) {
    triangles = primitiveTriangleCount(*primitive, tolerance_);
    primitive_triangles += triangles;
    ++primitives_by_type[primitive->index()];
  } else if (const auto* nurbs = std::get_if<NurbsPatchSet>(&object.geometry)) {
    triangles = nurbsConformingTriangleCount(*nurbs, tolerance_);  // as the preprocessor
    nurbs_triangles += triangles;
    nurbs_patches += nurbs->patches.size();
  }
  layer.triangles += triangles;
  bounds.add(worldBounds(object));
}

const char* SceneStats::primitiveTypeName(size_t index) {
  static const char* const kNames[] = {"cylinder", "cone",      "sphere",    "torus",
                                       "box",      "extrusion", "revolution"};
  static_assert(std::size(kNames) == kPrimitiveTypes);
  return index < kPrimitiveTypes ? kNames[index] : "?";
}

const char* SceneStats::geometryKindName(size_t index) {
  static const char* const kNames[] = {"mesh", "primitive", "nurbs"};
  return index < kGeometryKinds ? kNames[index] : "?";
}

}  // namespace tw
