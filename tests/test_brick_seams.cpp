// Brick seams: exact open-edge keys, and the edges open in two bricks at once (the only ones a
// brick's DAG must lock).
#include <gtest/gtest.h>

#include "brick_seams.h"

namespace tw {
namespace {

std::vector<glm::vec3> quadPositions(float x0) {
  return {{x0, 0, 0}, {x0 + 1, 0, 0}, {x0 + 1, 1, 0}, {x0, 1, 0}};
}

TEST(BrickSeams, OpenEdgesOfAClosedTetrahedronAreNone) {
  const std::vector<glm::vec3> p = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  const std::vector<uint32_t> tris = {0, 2, 1, 0, 1, 3, 1, 2, 3, 0, 3, 2};
  EXPECT_TRUE(openEdgeKeys(p, tris).empty());
}

TEST(BrickSeams, OpenEdgesOfAQuadAreItsFourSidesWeldedByPosition) {
  // Two triangles with their own copies of the shared vertices: welding is by position.
  std::vector<glm::vec3> p = quadPositions(0);
  p.push_back(p[0]);
  p.push_back(p[2]);
  const std::vector<uint32_t> tris = {0, 1, 2, 4, 5, 3};
  const auto open = openEdgeKeys(p, tris);
  EXPECT_EQ(open.size(), 4u);
  EXPECT_FALSE(std::binary_search(open.begin(), open.end(), seamEdgeKey(p[0], p[2])));
  EXPECT_TRUE(std::binary_search(open.begin(), open.end(), seamEdgeKey(p[1], p[0])));
}

TEST(BrickSeams, DegenerateAndNonFiniteTrianglesAreSkipped) {
  std::vector<glm::vec3> p = quadPositions(0);
  p.push_back({NAN, 0, 0});
  const std::vector<uint32_t> tris = {0, 1, 1, 0, 1, 4, 0, 1, 9};
  EXPECT_TRUE(openEdgeKeys(p, tris).empty());
  // -0 and +0 weld.
  EXPECT_EQ(seamEdgeKey({-0.0f, 0, 0}, {1, 0, 0}), seamEdgeKey({1, 0, 0}, {0.0f, 0, 0}));
}

TEST(BrickSeams, OnlyEdgesOpenInTwoBricksAreSeams) {
  // Brick A: the quad [0,1]; brick B: the quad [1,2]. They share the edge x = 1. Each also has
  // its own open edges (the model's), which must not count.
  const auto a = quadPositions(0), b = quadPositions(1);
  const std::vector<uint32_t> tris = {0, 1, 2, 0, 2, 3};
  BrickSeams seams = BrickSeams::fromOpenEdges({openEdgeKeys(a, tris), openEdgeKeys(b, tris)});
  EXPECT_EQ(seams.size(), 1u);
  EXPECT_TRUE(seams.contains({1, 0, 0}, {1, 1, 0}));
  EXPECT_TRUE(seams.contains({1, 1, 0}, {1, 0, 0}));
  EXPECT_FALSE(seams.contains({0, 0, 0}, {0, 1, 0}));
  EXPECT_FALSE(seams.contains({2, 0, 0}, {2, 1, 0}));
  EXPECT_EQ(BrickSeams::fromOpenEdges({openEdgeKeys(a, tris)}).size(), 0u);
}

// Non-manifold input: an edge used by two triangles in one brick and one in another is open in
// the second brick only; it must still count as a seam there.
TEST(BrickSeams, AnEdgeUsedTwiceInOneBrickAndOnceInAnotherIsASeam) {
  const std::vector<glm::vec3> p = {{0, 0, 0}, {1, 0, 0}, {0.5f, 1, 0}, {0.5f, -1, 0},
                                    {0.5f, 0, 1}};
  const std::vector<uint32_t> two = {0, 1, 2, 1, 0, 3};  // edge 0-1 used twice
  const std::vector<uint32_t> one = {0, 1, 4};
  const auto open_in_two = openEdgeKeys(p, two);
  EXPECT_FALSE(std::binary_search(open_in_two.begin(), open_in_two.end(), seamEdgeKey(p[0], p[1])));
  BrickSeams seams = BrickSeams::fromOpenEdges({edgeKeys(p, two), edgeKeys(p, one)});
  EXPECT_TRUE(seams.contains(p[0], p[1]));
  EXPECT_FALSE(seams.contains(p[0], p[2]));
}

}  // namespace
}  // namespace tw
