// Per-vertex object tags (runtime/vertex_object_tags.h): every triangle's last vertex names a
// triangle of the same object unless all its corners are shared, rotation keeps the winding,
// and shared vertices are marked. The shaders' use of the tags is tested in test_gl_renderer.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <random>
#include <vector>

#include "vertex_object_tags.h"

namespace tw {
namespace {

// The triangle as its smallest rotation (same winding compares equal, repeated corners too).
std::array<uint16_t, 3> canonical(const uint16_t* t) {
  std::array<uint16_t, 3> best = {t[0], t[1], t[2]};
  for (int k = 1; k < 3; ++k)
    best = std::min(best, std::array<uint16_t, 3>{t[k], t[(k + 1) % 3], t[(k + 2) % 3]});
  return best;
}

TEST(VertexObjectTags, OneObjectTagsEveryVertexWithItsFirstTriangleAndRotatesNothing) {
  std::vector<pkg::EncodedVertex> vertices(4);
  std::vector<uint16_t> indices = {0, 1, 2, 0, 2, 3};
  const std::vector<uint16_t> before = indices;
  EXPECT_EQ(tagVertexObjects(vertices, indices, std::vector<uint32_t>{7, 7}), 0u);
  EXPECT_EQ(indices, before);
  EXPECT_EQ(vertexObjectTag(vertices[0]), 0u);
  EXPECT_EQ(vertexObjectTag(vertices[1]), 0u);
  EXPECT_EQ(vertexObjectTag(vertices[2]), 0u);
  EXPECT_EQ(vertexObjectTag(vertices[3]), 1u);
}

TEST(VertexObjectTags, SharedVerticesAreMarkedAndTrianglesRotateToAnOwnCorner) {
  // A quad split between two objects: vertices 0 and 2 are on both triangles.
  std::vector<pkg::EncodedVertex> vertices(4);
  std::vector<uint16_t> indices = {0, 1, 2, 2, 3, 0};
  EXPECT_EQ(tagVertexObjects(vertices, indices, std::vector<uint32_t>{1, 2}), 0u);
  EXPECT_EQ(vertexObjectTag(vertices[0]), kSharedVertexTag);
  EXPECT_EQ(vertexObjectTag(vertices[2]), kSharedVertexTag);
  EXPECT_EQ(vertexObjectTag(vertices[1]), 0u);
  EXPECT_EQ(vertexObjectTag(vertices[3]), 1u);
  EXPECT_EQ(indices[2], 1u);  // (0, 1, 2) -> (2, 0, 1)
  EXPECT_EQ(indices[5], 3u);  // (2, 3, 0) -> (0, 2, 3)
  EXPECT_EQ(canonical(&indices[0]), (std::array<uint16_t, 3>{0, 1, 2}));
  EXPECT_EQ(canonical(&indices[3]), (std::array<uint16_t, 3>{0, 2, 3}));
}

TEST(VertexObjectTags, RandomClustersKeepTheirTrianglesAndTagTheRightObjects) {
  std::mt19937 rng(17);
  for (int trial = 0; trial < 200; ++trial) {
    const uint32_t vertex_count = 3 + rng() % 40, triangle_count = 1 + rng() % 60;
    const uint32_t object_count = 1 + rng() % 4;
    std::vector<pkg::EncodedVertex> vertices(vertex_count);
    std::vector<uint16_t> indices;
    std::vector<uint32_t> objects;
    for (uint32_t t = 0; t < triangle_count; ++t) {
      for (int k = 0; k < 3; ++k) indices.push_back(static_cast<uint16_t>(rng() % vertex_count));
      objects.push_back(100 + rng() % object_count);
    }
    const std::vector<uint16_t> before = indices;
    const uint32_t unresolved = tagVertexObjects(vertices, indices, objects);
    uint32_t shared_last = 0;
    for (uint32_t t = 0; t < triangle_count; ++t) {
      ASSERT_EQ(canonical(&indices[3 * t]), canonical(&before[3 * t])) << "trial " << trial;
      const uint16_t tag = vertexObjectTag(vertices[indices[3 * t + 2]]);
      if (tag == kSharedVertexTag) {
        ++shared_last;
        // Only when no corner of the triangle is its own.
        for (int k = 0; k < 3; ++k)
          EXPECT_EQ(vertexObjectTag(vertices[indices[3 * t + k]]), kSharedVertexTag);
        continue;
      }
      ASSERT_LT(tag, triangle_count);
      EXPECT_EQ(objects[tag], objects[t]) << "trial " << trial << " triangle " << t;
    }
    EXPECT_EQ(unresolved, shared_last);
  }
}

TEST(VertexObjectTags, UnusedVerticesAndOutOfRangeIndicesAreHarmless) {
  std::vector<pkg::EncodedVertex> vertices(3);
  std::vector<uint16_t> indices = {0, 1, 9};  // 9: beyond the vertices (the decoder rejects it)
  EXPECT_EQ(tagVertexObjects(vertices, indices, std::vector<uint32_t>{3}), 0u);
  EXPECT_EQ(vertexObjectTag(vertices[2]), kSharedVertexTag);  // unused: no object to name
  EXPECT_NE(indices[2], 9u);                                    // an own corner is last
  EXPECT_EQ(canonical(indices.data()), (std::array<uint16_t, 3>{0, 1, 9}));
}

}  // namespace
}  // namespace tw
