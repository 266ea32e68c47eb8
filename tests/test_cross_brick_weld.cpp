// The cross-brick weld: rim copies of different bricks within one step become one position, the
// same in every brick; copies in one brick alone, far copies and non-finite ones are left.
#include <gtest/gtest.h>

#include <cmath>

#include "brick_seams.h"
#include "cross_brick_weld.h"

namespace tw {
namespace {

constexpr float kStep = 1.0f / 65536.0f;

// A ring of `sides` vertices at x, radius 0.3, around a plant-sized offset (so one float ulp is a
// sizeable part of the step, as in the 10M plant).
std::vector<glm::vec3> ring(float x, int sides) {
  std::vector<glm::vec3> p;
  for (int s = 0; s < sides; ++s) {
    const float a = 6.2831853f * float(s) / float(sides);
    p.push_back({x, 55.0f + 0.3f * std::cos(a), 8.0f + 0.3f * std::sin(a)});
  }
  return p;
}

// One ulp away on z, as a CAD exporter's second copy of a shared ring.
std::vector<glm::vec3> noisy(std::vector<glm::vec3> p) {
  for (size_t i = 0; i < p.size(); i += 2) p[i].z = std::nextafter(p[i].z, 100.0f);
  return p;
}

// A tube between rings x0 and x1 (open at both ends), as one brick's triangle soup.
void tube(const std::vector<glm::vec3>& a, const std::vector<glm::vec3>& b,
          std::vector<glm::vec3>& positions, std::vector<uint32_t>& indices) {
  const uint32_t base = uint32_t(positions.size()), n = uint32_t(a.size());
  positions.insert(positions.end(), a.begin(), a.end());
  positions.insert(positions.end(), b.begin(), b.end());
  for (uint32_t s = 0; s < n; ++s) {
    const uint32_t i = base + s, j = base + (s + 1) % n;
    indices.insert(indices.end(), {i, j, j + n, i, j + n, i + n});
  }
}

std::vector<CrossBrickWeld::Candidate> candidates(const std::vector<glm::vec3>& p, uint32_t brick) {
  std::vector<CrossBrickWeld::Candidate> out;
  for (const glm::vec3& q : p) out.push_back({q, brick});
  return out;
}

TEST(CrossBrickWeld, NoisyCopiesOfARingInTwoBricksBecomeOneSeam) {
  // Brick 0 holds a pipe ending at x = 1, brick 1 the elbow starting there with its own copy of
  // the ring, every other vertex one ulp off.
  const std::vector<glm::vec3> joint = ring(1.0f, 16), copy = noisy(joint);
  std::vector<glm::vec3> p0, p1;
  std::vector<uint32_t> t0, t1;
  tube(ring(0.0f, 16), joint, p0, t0);
  tube(copy, ring(2.0f, 16), p1, t1);
  // Without the weld, only the ring edges between two exact vertices are seams: none here.
  EXPECT_EQ(BrickSeams::fromOpenEdges({openEdgeKeys(p0, t0), openEdgeKeys(p1, t1)}).size(), 0u);

  std::vector<CrossBrickWeld::Candidate> rims = candidates(joint, 0);
  for (const auto& c : candidates(copy, 1)) rims.push_back(c);
  const CrossBrickWeld weld = CrossBrickWeld::build(rims, kStep);
  EXPECT_EQ(weld.movedPositions(), 8u);  // the noisy half
  EXPECT_EQ(weld.bricksWithMoves().size(), 1u);
  const std::vector<glm::vec3> before0 = p0, before1 = p1;
  weld.apply(p0);
  weld.apply(p1);
  for (size_t i = 0; i < p0.size(); ++i) {
    EXPECT_LE(glm::length(p0[i] - before0[i]), kStep);
    EXPECT_LE(glm::length(p1[i] - before1[i]), kStep);
  }
  // The ring is now bit-identical in both bricks: all 16 of its edges are seams.
  const BrickSeams seams =
      BrickSeams::fromOpenEdges({openEdgeKeys(p0, t0), openEdgeKeys(p1, t1)});
  EXPECT_EQ(seams.size(), 16u);
  for (int s = 0; s < 16; ++s) EXPECT_TRUE(seams.contains(p1[s], p1[(s + 1) % 16]));
}

TEST(CrossBrickWeld, CopiesInOneBrickAloneAreLeftToTheGridWeld) {
  const std::vector<glm::vec3> joint = ring(1.0f, 8);
  std::vector<CrossBrickWeld::Candidate> rims = candidates(joint, 3);
  for (const auto& c : candidates(noisy(joint), 3)) rims.push_back(c);
  EXPECT_EQ(CrossBrickWeld::build(rims, kStep).movedPositions(), 0u);
}

TEST(CrossBrickWeld, MovesAreAtMostOneStepAndNeverChain) {
  // Three bricks, each 0.75 step further on x: the second joins the first; the third is 1.5 steps
  // from the first and may not join the second, which moved.
  const glm::vec3 a(10.0f, 0.0f, 0.0f);
  const glm::vec3 b = a + glm::vec3(0.75f * kStep, 0, 0), c = b + glm::vec3(0.75f * kStep, 0, 0);
  const CrossBrickWeld weld = CrossBrickWeld::build({{c, 2}, {b, 1}, {a, 0}}, kStep);
  std::vector<glm::vec3> p = {a, b, c};
  weld.apply(p);
  EXPECT_EQ(p[0], a);
  EXPECT_EQ(p[1], a);
  EXPECT_EQ(p[2], c);
  EXPECT_EQ(weld.bricksWithMoves(), std::vector<uint32_t>{1});
}

TEST(CrossBrickWeld, FarAndNonFinitePositionsStay) {
  const glm::vec3 a(1.0f, 2.0f, 3.0f), far = a + glm::vec3(0, 0, 1.5f * kStep);
  const CrossBrickWeld weld =
      CrossBrickWeld::build({{a, 0}, {far, 1}, {{NAN, 2.0f, 3.0f}, 1}, {-a, 1}, {-a, 0}}, kStep);
  EXPECT_EQ(weld.movedPositions(), 0u);
  EXPECT_TRUE(CrossBrickWeld::build({{a, 0}, {a, 1}}, 0.0f).bricksWithMoves().empty());
}

}  // namespace
}  // namespace tw
