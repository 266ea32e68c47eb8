// Tests for the package-grid weld of full-resolution vertices (preprocess/grid_weld.h).
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <vector>

#include "grid_weld.h"
#include "package_format.h"

namespace tw {
namespace {

constexpr double kStep = pkg::kDefaultPositionStepM;

TriangleClusters oneClusterPerTriangle(size_t triangles) {
  TriangleClusters clusters;
  for (uint32_t t = 0; t < triangles; ++t) {
    clusters.triangles.push_back(t);
    clusters.offsets.push_back(t);
  }
  clusters.offsets.push_back(uint32_t(triangles));
  return clusters;
}

bool onGrid(float value, double cell) {
  return double(value) == std::nearbyint(double(value) / cell) * cell;
}

TEST(GridWeld, ShiftIsTheSmallestThatHoldsTheExtentIn16Bits) {
  std::vector<glm::vec3> p = {{0, 0, 0}, {0.5f, 0, 0}};
  EXPECT_EQ(clusterPositionShift(p, kStep), 0u);
  p[1].x = 1.5f;  // 98,304 base steps: needs cells twice as large
  EXPECT_EQ(clusterPositionShift(p, kStep), 1u);
  p[1].y = 3.0f;
  EXPECT_EQ(clusterPositionShift(p, kStep), 2u);
  EXPECT_EQ(clusterPositionShift(p, kStep, 5), 5u);
}

// Two parts touching end to end, one float ulp apart: after the weld they share the vertices.
TEST(GridWeld, WeldsVerticesOneUlpApartAcrossParts) {
  const float x = 14.25f, x_noisy = std::nextafter(14.25f, 20.0f);
  std::vector<glm::vec3> positions = {
      {x, 0, 0}, {x, 1, 0}, {x - 1, 0, 0},             // part A ends at x
      {x_noisy, 0, 0}, {x_noisy, 1, 0}, {x + 1, 0, 0}  // part B starts a ulp later
  };
  std::vector<uint32_t> indices = {0, 1, 2, 3, 5, 4};
  GridWeld weld = weldOnPackageGrid(positions, indices, oneClusterPerTriangle(2), {}, kStep);
  EXPECT_EQ(weld.remap[0], weld.remap[3]);
  EXPECT_EQ(weld.remap[1], weld.remap[4]);
  EXPECT_NE(weld.remap[0], weld.remap[1]);
  EXPECT_EQ(weld.positions.size(), 4u);
  EXPECT_EQ(weld.merged_vertices, 2u);
}

// A pointwise grid can round two noisy copies apart (one just below a rounding boundary, one just
// above); the tolerance pass still joins them.
TEST(GridWeld, WeldsNoisyCopiesOnBothSidesOfAGridBoundary) {
  const float boundary = float(1000.5 * kStep);  // halfway between two base grid points
  const float below = std::nextafter(boundary, 0.0f), above = std::nextafter(boundary, 1.0f);
  std::vector<glm::vec3> positions = {{below, 0, 0}, {0, 0.1f, 0}, {0, 0, 0.1f},
                                      {above, 0, 0}, {0, 0.1f, 0}, {0, 0, 0.2f}};
  std::vector<uint32_t> indices = {0, 1, 2, 3, 4, 5};
  GridWeld weld = weldOnPackageGrid(positions, indices, oneClusterPerTriangle(2), {}, kStep);
  EXPECT_EQ(weld.remap[0], weld.remap[3]);
  EXPECT_EQ(weld.remap[1], weld.remap[4]);
  EXPECT_NE(weld.remap[2], weld.remap[5]);
}

// An exporter's noise is an ulp of the world coordinate it wrote: at 288.75 m that is two base
// steps, which one step of tolerance leaves apart (the 100M plant's pipe joints) and the noise
// tolerance joins.
TEST(GridWeld, NoiseToleranceJoinsCopiesTwoStepsApart) {
  const float x = float(5816322 * kStep), x_noisy = float(5816324 * kStep);
  std::vector<glm::vec3> positions = {{x, 0, 0}, {x, 1, 0}, {x - 1, 0, 0},
                                      {x_noisy, 0, 0}, {x_noisy, 1, 0}, {x + 1, 0, 0}};
  std::vector<uint32_t> indices = {0, 1, 2, 3, 5, 4};
  const GridWeld apart = weldOnPackageGrid(positions, indices, oneClusterPerTriangle(2), {}, kStep);
  EXPECT_NE(apart.remap[0], apart.remap[3]);
  const GridWeld joined =
      weldOnPackageGrid(positions, indices, oneClusterPerTriangle(2), {}, kStep, 3 * kStep);
  EXPECT_EQ(joined.remap[0], joined.remap[3]);
  EXPECT_EQ(joined.remap[1], joined.remap[4]);
  EXPECT_EQ(joined.merged_vertices, 2u);
}

TEST(GridWeld, KeepsVerticesFartherApartThanAStep) {
  std::vector<glm::vec3> positions = {{0, 0, 0}, {float(3 * kStep), 0, 0}, {0, 0.2f, 0}};
  std::vector<uint32_t> indices = {0, 1, 2};
  GridWeld weld = weldOnPackageGrid(positions, indices, oneClusterPerTriangle(1), {}, kStep);
  EXPECT_EQ(weld.positions.size(), 3u);
}

TEST(GridWeld, SnapsToTheCoarsestGridOfTheClustersUsingAVertex) {
  // Cluster 0 is small (shift 0); cluster 1 spans 3 m (shift 2) and shares vertex 0.
  std::vector<glm::vec3> positions = {
      {0.1234567f, 0.2345678f, 0.3456789f}, {0.2f, 0.25f, 0.3f}, {0.15f, 0.3f, 0.35f},
      {3.1f, 0.1f, 0.1f}, {0.1f, 3.0f, 0.2f}};
  std::vector<uint32_t> indices = {0, 1, 2, 0, 3, 4};
  GridWeld weld = weldOnPackageGrid(positions, indices, oneClusterPerTriangle(2), {}, kStep);
  const double coarse = std::ldexp(kStep, 2), fine = kStep;
  const glm::vec3 shared = weld.positions[weld.remap[0]];
  for (int a = 0; a < 3; ++a) {
    EXPECT_TRUE(onGrid(shared[a], coarse)) << a;
    EXPECT_LE(std::abs(shared[a] - positions[0][a]), 0.5 * coarse + 1e-7);
    EXPECT_TRUE(onGrid(weld.positions[weld.remap[1]][a], fine)) << a;
  }
  EXPECT_GT(weld.moved_vertices, 0u);
}

TEST(GridWeld, LeavesKeptVerticesWhereTheyAre) {
  const float x = 0.1234567f, x_noisy = std::nextafter(x, 1.0f);
  std::vector<glm::vec3> positions = {{x, 0, 0}, {0, 0.1f, 0}, {0, 0, 0.1f}, {x_noisy, 0, 0}};
  std::vector<uint32_t> indices = {0, 1, 2, 3, 2, 1};
  std::vector<uint8_t> keep = {1, 0, 0, 1};
  GridWeld weld = weldOnPackageGrid(positions, indices, oneClusterPerTriangle(2), keep, kStep);
  EXPECT_EQ(weld.positions[weld.remap[0]], positions[0]);
  EXPECT_EQ(weld.positions[weld.remap[3]], positions[3]);
  EXPECT_NE(weld.remap[0], weld.remap[3]);  // two seam vertices the other brick sees apart
}

TEST(GridWeld, RejectsBadArguments) {
  std::vector<glm::vec3> positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  std::vector<uint32_t> indices = {0, 1, 3};
  EXPECT_THROW(weldOnPackageGrid(positions, indices, oneClusterPerTriangle(1), {}, kStep),
               std::invalid_argument);
  indices = {0, 1, 2};
  std::vector<uint8_t> keep = {0, 1};
  EXPECT_THROW(weldOnPackageGrid(positions, indices, oneClusterPerTriangle(1), keep, kStep),
               std::invalid_argument);
  EXPECT_THROW(weldOnPackageGrid(positions, indices, oneClusterPerTriangle(2), {}, kStep),
               std::invalid_argument);
}

}  // namespace
}  // namespace tw
