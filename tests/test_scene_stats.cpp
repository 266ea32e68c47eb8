// SceneStats: the counts behind `terawalk info`.
#include <gtest/gtest.h>

#include "scene_stats.h"
#include "tessellate.h"

namespace tw {
namespace {

SceneObject meshObject(uint32_t id, uint32_t layer, glm::dvec3 origin) {
  SceneObject o;
  o.info.id = id;
  o.info.layer = layer;
  o.info.transform.origin = origin;
  TriangleMesh mesh;
  mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  mesh.indices = {0, 1, 2, 0, 2, 3};
  o.geometry = mesh;
  return o;
}

TEST(SceneStats, CountsObjectsPartsLayersAndBounds) {
  SceneStats stats(kDefaultChordalTolerance);
  stats.onLayer(0, {"piping", 0});
  stats.onLayer(1, {"structure", 0});
  stats.onObject(meshObject(7, 0, {1000.0, 0, 0}));
  stats.onObject(meshObject(7, 0, {1000.0, 0, 0}));  // second part of object 7
  SceneObject key = meshObject(8, 1, {0, -5.0, 0});
  key.info.db_key = "P-1203-A";
  stats.onObject(key);
  EXPECT_EQ(stats.objects, 2u);
  EXPECT_EQ(stats.parts, 3u);
  EXPECT_EQ(stats.objects_with_db_key, 1u);
  EXPECT_EQ(stats.mesh_triangles, 6u);
  EXPECT_EQ(stats.objects_by_kind[0], 2u);
  ASSERT_EQ(stats.layers.size(), 2u);
  EXPECT_EQ(stats.layers[0].name, "piping");
  EXPECT_EQ(stats.layers[0].objects, 1u);
  EXPECT_EQ(stats.layers[0].triangles, 4u);
  EXPECT_EQ(stats.layers[1].objects, 1u);
  EXPECT_DOUBLE_EQ(stats.bounds.min.x, 0.0);
  EXPECT_DOUBLE_EQ(stats.bounds.max.x, 1001.0);
  EXPECT_DOUBLE_EQ(stats.bounds.min.y, -5.0);
}

TEST(SceneStats, PrimitivesCountTheirTessellation) {
  SceneStats stats(0.01f);
  SceneObject pipe;
  pipe.info.id = 1;
  pipe.geometry = Primitive{Cylinder{0.1f, 3.0f, false}};
  stats.onObject(pipe);
  SceneObject elbow;
  elbow.info.id = 2;
  elbow.geometry = Primitive{TorusSegment{0.3f, 0.1f, 1.5707964f}};
  stats.onObject(elbow);
  EXPECT_EQ(stats.objects_by_kind[static_cast<size_t>(GeometryKind::Parametric)], 2u);
  EXPECT_EQ(stats.primitives_by_type[0], 1u);  // cylinder
  EXPECT_EQ(stats.primitives_by_type[3], 1u);  // torus
  uint64_t expected = primitiveTriangleCount(std::get<Primitive>(pipe.geometry), 0.01f) +
                      primitiveTriangleCount(std::get<Primitive>(elbow.geometry), 0.01f);
  EXPECT_GT(expected, 0u);
  EXPECT_EQ(stats.primitive_triangles, expected);
  EXPECT_EQ(stats.totalTriangles(), expected);
}

}  // namespace
}  // namespace tw
