// The near-vertex index marks exactly what a brute-force pairwise test marks: vertices of one
// group within the tolerance (on every axis) of a vertex of another group or of a shared one.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "near_group_vertices.h"

namespace tw {
namespace {

constexpr uint32_t kMulti = 0xFFFFFFFEu;

std::vector<uint8_t> bruteForce(const std::vector<glm::vec3>& positions,
                                const std::vector<uint32_t>& owner, float tolerance) {
  std::vector<uint8_t> near(positions.size(), 0);
  for (uint32_t v = 0; v < positions.size(); ++v) {
    if (owner[v] == kMulti) continue;
    for (uint32_t w = 0; w < positions.size(); ++w) {
      if (w == v || owner[w] == owner[v]) continue;
      const glm::vec3 d = glm::abs(positions[w] - positions[v]);
      if (std::max({d.x, d.y, d.z}) <= tolerance) near[v] = 1;
    }
  }
  return near;
}

// Points in small clumps (a clump's points lie within about the tolerance of each other), spread
// over a box, owned by random groups, a few of them shared.
struct Cloud {
  std::vector<glm::vec3> positions;
  std::vector<uint32_t> owner;
  std::vector<uint32_t> vertices;
};

Cloud clumps(uint32_t seed, int clump_count, int per_clump, float spread, float tolerance) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> where(-5.0f, 5.0f);
  std::uniform_real_distribution<float> jitter(-spread * tolerance, spread * tolerance);
  std::uniform_int_distribution<uint32_t> group(0, 6);
  Cloud cloud;
  for (int c = 0; c < clump_count; ++c) {
    const glm::vec3 centre(where(rng), where(rng), where(rng));
    for (int k = 0; k < per_clump; ++k) {
      cloud.positions.push_back(centre + glm::vec3(jitter(rng), jitter(rng), jitter(rng)));
      const uint32_t g = group(rng);
      cloud.owner.push_back(g == 6 ? kMulti : g);
    }
  }
  for (uint32_t v = 0; v < cloud.positions.size(); ++v) cloud.vertices.push_back(v);
  return cloud;
}

TEST(NearGroupVertices, MarksWhatAPairwiseTestMarks) {
  const float tolerance = 4.2e-4f;
  for (uint32_t seed = 1; seed <= 5; ++seed) {
    const Cloud cloud = clumps(seed, 300, 3, 1.5f, tolerance);
    std::vector<uint8_t> near(cloud.positions.size(), 0);
    NearVertexIndex index(cloud.positions, cloud.vertices, tolerance);
    index.markNearOtherGroups(cloud.positions, cloud.owner, kMulti, near);
    const std::vector<uint8_t> expected = bruteForce(cloud.positions, cloud.owner, tolerance);
    EXPECT_EQ(near, expected) << "seed " << seed;
    const auto marked = std::count(expected.begin(), expected.end(), 1);
    EXPECT_GT(marked, 50) << "the clumps should put many vertices near another group";
    EXPECT_LT(marked, int(expected.size())) << "and leave some unmarked";
  }
}

TEST(NearGroupVertices, OneIndexServesAttemptsWithOtherGroups) {
  const float tolerance = 1e-3f;
  Cloud cloud = clumps(7, 200, 4, 1.2f, tolerance);
  NearVertexIndex index(cloud.positions, cloud.vertices, tolerance);
  for (int attempt = 0; attempt < 3; ++attempt) {
    for (uint32_t v = 0; v < cloud.owner.size(); ++v)
      if (cloud.owner[v] != kMulti) cloud.owner[v] = (cloud.owner[v] + 1 + attempt) % 4;
    std::vector<uint8_t> near(cloud.positions.size(), 0);
    index.markNearOtherGroups(cloud.positions, cloud.owner, kMulti, near);
    EXPECT_EQ(near, bruteForce(cloud.positions, cloud.owner, tolerance)) << attempt;
  }
}

TEST(NearGroupVertices, ThousandsOfVerticesOnOneSpotStillMarkCorrectly) {
  // Far more pairs than the index lists: it searches its cells at each marking instead.
  const float tolerance = 1e-3f;
  Cloud cloud = clumps(11, 2, 600, 0.3f, tolerance);
  Cloud sparse = clumps(12, 100, 2, 1.5f, tolerance);
  for (uint32_t v = 0; v < sparse.positions.size(); ++v) {
    cloud.vertices.push_back(uint32_t(cloud.positions.size()));
    cloud.positions.push_back(sparse.positions[v]);
    cloud.owner.push_back(sparse.owner[v]);
  }
  std::vector<uint8_t> near(cloud.positions.size(), 0);
  NearVertexIndex(cloud.positions, cloud.vertices, tolerance)
      .markNearOtherGroups(cloud.positions, cloud.owner, kMulti, near);
  EXPECT_EQ(near, bruteForce(cloud.positions, cloud.owner, tolerance));
}

TEST(NearGroupVertices, NonFiniteAndZeroToleranceMarkNothing) {
  std::vector<glm::vec3> positions = {{0, 0, 0}, {0, 0, 0}, {NAN, 0, 0}};
  std::vector<uint32_t> owner = {0, 1, 2};
  std::vector<uint32_t> vertices = {0, 1, 2};
  std::vector<uint8_t> near(3, 0);
  markVerticesNearOtherGroups(positions, vertices, owner, kMulti, 0.0f, near);
  EXPECT_EQ(near, std::vector<uint8_t>({0, 0, 0}));
  markVerticesNearOtherGroups(positions, vertices, owner, kMulti, 1e-3f, near);
  EXPECT_EQ(near, std::vector<uint8_t>({1, 1, 0}));
}

}  // namespace
}  // namespace tw
