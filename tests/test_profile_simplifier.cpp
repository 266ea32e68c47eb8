// ProfileSimplifier (runtime/parametrics/profile_simplifier.h): open and closed profiles lose only the points
// within the tolerance of what they keep, the kept points are a subset in order, and nothing is
// lost at a tolerance below the profile's detail.
#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

#include <glm/geometric.hpp>

#include "parametrics/profile_simplifier.h"

namespace tw {
namespace {

// An I-profile as the plant generator makes them: 0.7 m deep, 0.3 m wide, 42 mm flanges, 24.5 mm
// web, counter-clockwise.
std::vector<glm::vec2> iProfile() {
  const float h = 0.35f, b = 0.15f, tf = 0.042f, tw = 0.01225f;
  return {{-b, -h}, {b, -h}, {b, -h + tf}, {tw, -h + tf}, {tw, h - tf}, {b, h - tf},
          {b, h},   {-b, h}, {-b, h - tf}, {-tw, h - tf}, {-tw, -h + tf}, {-b, -h + tf}};
}

float distanceToSegment(glm::vec2 p, glm::vec2 a, glm::vec2 b) {
  const glm::vec2 ab = b - a;
  const float length2 = glm::dot(ab, ab);
  const float t = length2 > 0.0f ? std::clamp(glm::dot(p - a, ab) / length2, 0.0f, 1.0f) : 0.0f;
  return glm::length(p - (a + t * ab));
}

// The largest distance from a point of `original` to the closed outline `kept`.
float worstDistance(const std::vector<glm::vec2>& original, const std::vector<glm::vec2>& kept) {
  float worst = 0.0f;
  for (glm::vec2 p : original) {
    float nearest = 1e30f;
    for (size_t k = 0; k < kept.size(); ++k)
      nearest = std::min(nearest, distanceToSegment(p, kept[k], kept[(k + 1) % kept.size()]));
    worst = std::max(worst, nearest);
  }
  return worst;
}

bool subsetInOrder(const std::vector<glm::vec2>& original, const std::vector<glm::vec2>& kept) {
  size_t at = 0;
  for (glm::vec2 p : kept) {
    while (at < original.size() && original[at] != p) ++at;
    if (at == original.size()) return false;
    ++at;
  }
  return true;
}

TEST(ProfileSimplifier, ClosedProfileLosesOnlyDetailWithinTheTolerance) {
  ProfileSimplifier simplifier;
  std::vector<glm::vec2> kept;
  const std::vector<glm::vec2> profile = iProfile();
  simplifier.simplifyClosed(profile, 0.001f, kept);
  EXPECT_EQ(kept, profile);  // finer than every step of the profile: all kept

  // Coarser than the flanges' thickness, finer than the recesses' depth (0.138 m): the flange
  // tips lose a corner each, the recess corners stay.
  simplifier.simplifyClosed(profile, 0.064f, kept);
  EXPECT_LT(kept.size(), profile.size());
  EXPECT_GE(kept.size(), 8u);
  EXPECT_TRUE(subsetInOrder(profile, kept));
  EXPECT_LE(worstDistance(profile, kept), 0.064f);

  // Coarser than the recesses: little more than the box's corners.
  simplifier.simplifyClosed(profile, 0.2f, kept);
  EXPECT_GE(kept.size(), 3u);
  EXPECT_LE(kept.size(), 6u);
  EXPECT_LE(worstDistance(profile, kept), 0.2f);
}

TEST(ProfileSimplifier, ClosedSquareKeepsItsCornersOnly) {
  const std::vector<glm::vec2> square = {{0, 0}, {0.5f, 0}, {1, 0}, {1, 0.5f}, {1, 1},
                                         {0.5f, 1}, {0, 1}, {0, 0.5f}};
  ProfileSimplifier simplifier;
  std::vector<glm::vec2> kept;
  simplifier.simplifyClosed(square, 1e-4f, kept);
  EXPECT_EQ(kept, (std::vector<glm::vec2>{{0, 0}, {1, 0}, {1, 1}, {0, 1}}));
  // Too short to simplify: copied.
  simplifier.simplifyClosed(std::vector<glm::vec2>{{0, 0}, {1, 0}}, 10.0f, kept);
  EXPECT_EQ(kept.size(), 2u);
}

TEST(ProfileSimplifier, OpenProfileKeepsItsEnds) {
  // A vessel's half profile: a straight wall with a bump of 5 cm, and a collinear point.
  const std::vector<glm::vec2> profile = {{0, 0},    {1, 0}, {1, 1}, {1.05f, 1.5f},
                                          {1, 2},    {1, 2.5f}, {1, 3}, {0, 3}};
  ProfileSimplifier simplifier;
  std::vector<glm::vec2> kept;
  simplifier.simplify(profile, 0.01f, kept);
  EXPECT_EQ(kept.size(), 7u);  // the collinear (1, 2.5) goes, the bump stays
  EXPECT_TRUE(subsetInOrder(profile, kept));
  simplifier.simplify(profile, 0.1f, kept);
  EXPECT_LT(kept.size(), 7u);
  EXPECT_TRUE(subsetInOrder(profile, kept));
  EXPECT_EQ(kept.front(), profile.front());
  EXPECT_EQ(kept.back(), profile.back());
  float worst = 0.0f;  // every point within the tolerance of the kept polyline
  for (glm::vec2 p : profile) {
    float nearest = 1e30f;
    for (size_t k = 0; k + 1 < kept.size(); ++k)
      nearest = std::min(nearest, distanceToSegment(p, kept[k], kept[k + 1]));
    worst = std::max(worst, nearest);
  }
  EXPECT_LE(worst, 0.1f);
}

}  // namespace
}  // namespace tw
