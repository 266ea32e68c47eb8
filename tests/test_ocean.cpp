// The ocean: Gerstner waves against their formula, the quadtree mesh without T-vertices, and
// geomorphing that keeps the surface continuous as the eye crosses level boundaries.
#include <algorithm>
#include <cmath>
#include <map>
#include <utility>

#include <glm/gtc/constants.hpp>
#include <gtest/gtest.h>

#include "environment/gerstner_waves.h"
#include "environment/ocean_mesh.h"

namespace tw {
namespace {

TEST(Gerstner, OneWaveRisesAndFallsAsACosineAndMovesAlongItsDirection) {
  OceanWaves sea;
  sea.steepness = 0.8;
  sea.waves = {{1.25, 30.0, 60.0, 0.4}};
  const std::vector<WaveTerm> terms = waveTerms(sea);
  const double k = 2.0 * glm::pi<double>() / 30.0, omega = std::sqrt(kGravity * k);
  const glm::dvec2 d(std::cos(glm::radians(60.0)), std::sin(glm::radians(60.0)));
  const double q = std::min(1.0, 0.8 / (k * 1.25));  // steepness / (k A n), n = 1, at most 1
  for (const auto& [x0, t] : {std::pair{glm::dvec2(0.0, 0.0), 0.0}, {glm::dvec2(13.7, -4.2), 2.5},
                              {glm::dvec2(-250.0, 1000.0), 17.0}}) {
    const double theta = k * glm::dot(d, x0) - omega * t + 0.4;
    const glm::dvec3 got = gerstnerDisplacement(terms, x0, t);
    EXPECT_NEAR(got.z, 1.25 * std::cos(theta), 1e-12);
    EXPECT_NEAR(got.x, -q * 1.25 * d.x * std::sin(theta), 1e-12);
    EXPECT_NEAR(got.y, -q * 1.25 * d.y * std::sin(theta), 1e-12);
  }
}

TEST(Gerstner, CrestsNeverLoopAtFullSteepness) {
  // The displaced surface folds where the map x0 -> x stops being one-to-one: its Jacobian's
  // determinant would reach 0. At steepness 1 it may touch 0 at a crest, never go below.
  OceanWaves sea = wavesForWind(15.0, 10.0, 12);
  sea.steepness = 1.0;
  const std::vector<WaveTerm> terms = waveTerms(sea);
  double sum = 0.0;
  for (const WaveTerm& w : terms) sum += w.q * w.k * w.amplitude;
  EXPECT_LE(sum, 1.0 + 1e-12);
  double smallest = 1e9;
  const double h = 1e-4;
  for (int i = 0; i < 200; ++i)
    for (int j = 0; j < 200; ++j) {
      const glm::dvec2 x0(i * 1.37, j * 0.91);
      auto x = [&](glm::dvec2 p) { return p + glm::dvec2(gerstnerDisplacement(terms, p, 3.0)); };
      const glm::dvec2 dx = (x(x0 + glm::dvec2(h, 0)) - x(x0 - glm::dvec2(h, 0))) / (2 * h);
      const glm::dvec2 dy = (x(x0 + glm::dvec2(0, h)) - x(x0 - glm::dvec2(0, h))) / (2 * h);
      smallest = std::min(smallest, dx.x * dy.y - dx.y * dy.x);
    }
  EXPECT_GT(smallest, -1e-6);
}

TEST(Gerstner, TheNormalIsPerpendicularToTheDisplacedSurface) {
  const std::vector<WaveTerm> terms = waveTerms(wavesForWind(10.0, 45.0, 6));
  const glm::dvec2 x0(12.0, -7.0);
  const double h = 1e-4;
  auto p = [&](glm::dvec2 q) { return glm::dvec3(q, 0.0) + gerstnerDisplacement(terms, q, 1.0); };
  const glm::dvec3 tx = p(x0 + glm::dvec2(h, 0)) - p(x0 - glm::dvec2(h, 0));
  const glm::dvec3 ty = p(x0 + glm::dvec2(0, h)) - p(x0 - glm::dvec2(0, h));
  const glm::dvec3 n = gerstnerNormal(terms, x0, 1.0);
  EXPECT_NEAR(glm::dot(n, glm::normalize(tx)), 0.0, 1e-6);
  EXPECT_NEAR(glm::dot(n, glm::normalize(ty)), 0.0, 1e-6);
  EXPECT_GT(n.z, 0.0);
}

TEST(Gerstner, BadWavesAreRefusedWithTheirNumber) {
  OceanWaves sea = wavesForWind(8.0, 0.0, 3);
  sea.waves[1].wavelength_m = std::nan("");
  try {
    validateWaves(sea);
    FAIL() << "a NaN wavelength was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("wave 2"), std::string::npos) << e.what();
  }
  EXPECT_THROW(wavesForWind(8.0, 0.0, 17), std::invalid_argument);
  EXPECT_THROW(wavesForWind(0.0, 0.0, 4), std::invalid_argument);
}

// Edges of the mesh, its vertices welded by position, with how many triangles hold each.
// `positions` receives each welded vertex's position.
std::map<std::pair<uint32_t, uint32_t>, int> edgeUses(const OceanMesh& mesh, std::vector<glm::dvec2>& positions) {
  std::map<std::pair<double, double>, uint32_t> welded;
  std::vector<uint32_t> weld(mesh.positions.size());
  positions.clear();
  for (size_t v = 0; v < mesh.positions.size(); ++v) {
    const auto [it, added] = welded.try_emplace({mesh.positions[v].x, mesh.positions[v].y}, uint32_t(welded.size()));
    if (added) positions.push_back(mesh.positions[v]);
    weld[v] = it->second;
  }
  std::map<std::pair<uint32_t, uint32_t>, int> uses;
  for (size_t t = 0; t < mesh.indices.size(); t += 3)
    for (int e = 0; e < 3; ++e) {
      const uint32_t a = weld[mesh.indices[t + e]], b = weld[mesh.indices[t + (e + 1) % 3]];
      ++uses[{std::min(a, b), std::max(a, b)}];
    }
  return uses;
}

TEST(OceanMesh, EveryEdgeIsSharedByTwoTrianglesOrLiesOnTheOuterBorder) {
  OceanGridOptions grid;
  grid.center = {1000.0, -500.0};
  grid.size_m = 8192.0;
  grid.waterline_m = -10.0;
  // Still water, geomorphing off: every vertex on its lattice point, so the border test is exact.
  grid.geomorph = false;
  const double half = 0.5 * grid.size_m;
  int meshes_with_stitches = 0;
  for (const glm::dvec3& eye : {glm::dvec3(1000.0, -500.0, 20.0), glm::dvec3(1003.3, -497.1, 2.0),
                                glm::dvec3(-3000.0, 3500.0, 30.0), glm::dvec3(5200.0, -500.0, 50.0),
                                glm::dvec3(1200.0, -800.0, 900.0)}) {
    const OceanMesh mesh = buildOceanMesh(grid, eye);
    ASSERT_GT(mesh.leaves, 1u);
    std::vector<glm::dvec2> positions;
    const auto uses = edgeUses(mesh, positions);
    int border = 0;
    for (const auto& [edge, count] : uses) {
      ASSERT_LE(count, 2) << "an edge of three triangles";
      if (count == 2) continue;
      const glm::dvec2 a = positions[edge.first] - grid.center, b = positions[edge.second] - grid.center;
      const bool on_border = (std::abs(a.x) == half && a.x == b.x) || (std::abs(a.y) == half && a.y == b.y);
      ASSERT_TRUE(on_border) << "an open edge inside the square: a T-vertex, from eye (" << eye.x << ", "
                             << eye.y << ", " << eye.z << ")";
      ++border;
    }
    EXPECT_GT(border, 0);
    // Leaves of different sizes met: the stitching was needed (triangles of a leaf number 2 n^2
    // unless some collapsed).
    meshes_with_stitches += mesh.indices.size() / 3 < size_t(mesh.leaves) * 2 * 64;
  }
  EXPECT_EQ(meshes_with_stitches, 5);
}

// Heights of the still-water mesh with waves added (vertical only), sampled at fixed points by
// interpolating the triangle that holds each point: what the viewer sees at that place.
class SurfaceSampler {
 public:
  // Only the triangles that reach into [lo, hi] are kept.
  SurfaceSampler(const OceanGridOptions& grid, const std::vector<WaveTerm>& terms, const glm::dvec3& eye,
                 const glm::dvec2& lo, const glm::dvec2& hi)
      : mesh_(buildOceanMesh(grid, eye)) {
    std::vector<uint32_t> kept;
    for (size_t t = 0; t < mesh_.indices.size(); t += 3) {
      glm::dvec2 a = mesh_.positions[mesh_.indices[t]], b = a;
      for (int v = 1; v < 3; ++v) {
        a = glm::min(a, mesh_.positions[mesh_.indices[t + v]]);
        b = glm::max(b, mesh_.positions[mesh_.indices[t + v]]);
      }
      if (a.x <= hi.x && a.y <= hi.y && b.x >= lo.x && b.y >= lo.y)
        kept.insert(kept.end(), mesh_.indices.begin() + t, mesh_.indices.begin() + t + 3);
    }
    mesh_.indices = std::move(kept);
    heights_.assign(mesh_.positions.size(), 0.0);
    for (uint32_t v : mesh_.indices) {
      const glm::dvec2 p = mesh_.positions[v];
      const double distance = glm::length(glm::dvec3(p - glm::dvec2(eye), grid.waterline_m - eye.z));
      heights_[v] = gerstnerDisplacement(terms, p, 0.0, oceanCellSizeAt(grid, distance)).z;
    }
  }
  // NaN when no triangle holds the point.
  double heightAt(const glm::dvec2& q) const {
    for (size_t t = 0; t < mesh_.indices.size(); t += 3) {
      const glm::dvec2 a = mesh_.positions[mesh_.indices[t]], b = mesh_.positions[mesh_.indices[t + 1]],
                       c = mesh_.positions[mesh_.indices[t + 2]];
      const double area = cross(b - a, c - a);
      if (area <= 1e-12) continue;
      const double wa = cross(b - q, c - q) / area, wb = cross(c - q, a - q) / area, wc = 1.0 - wa - wb;
      if (wa < -1e-9 || wb < -1e-9 || wc < -1e-9) continue;
      return wa * heights_[mesh_.indices[t]] + wb * heights_[mesh_.indices[t + 1]] +
             wc * heights_[mesh_.indices[t + 2]];
    }
    return std::nan("");
  }
  uint32_t leaves() const { return mesh_.leaves; }

 private:
  static double cross(const glm::dvec2& u, const glm::dvec2& v) { return u.x * v.y - u.y * v.x; }
  OceanMesh mesh_;
  std::vector<double> heights_;
};

// The largest change of the sampled heights between consecutive eye positions, the eye moving
// 5 cm a step away from the samples (frozen waves), and how often the leaves changed.
struct EyeWalk {
  double largest_jump_m = 0.0;
  int leaf_changes = 0;
};
EyeWalk walkAway(const OceanGridOptions& grid) {
  OceanWaves sea = wavesForWind(8.0, 20.0, 8);
  sea.steepness = 0.0;  // vertical only: the surface over a point is the mesh's height there
  const std::vector<WaveTerm> terms = waveTerms(sea);
  std::vector<glm::dvec2> samples;
  for (int i = 0; i < 12; ++i) samples.push_back({37.0 + 1.71 * i, 3.0 + 0.53 * i});
  EyeWalk walk;
  std::vector<double> before;
  uint32_t leaves_before = 0;
  for (int step = 0; step <= 400; ++step) {
    const glm::dvec3 eye(30.0 - 0.05 * step, 0.0, 6.0);  // from 7 m to 27 m from the samples
    const SurfaceSampler sampler(grid, terms, eye, samples.front(), samples.back());
    std::vector<double> now;
    for (const glm::dvec2& s : samples) now.push_back(sampler.heightAt(s));
    if (!before.empty()) {
      for (size_t i = 0; i < now.size(); ++i) walk.largest_jump_m = std::max(walk.largest_jump_m, std::abs(now[i] - before[i]));
      walk.leaf_changes += sampler.leaves() != leaves_before;
    }
    before = now;
    leaves_before = sampler.leaves();
  }
  return walk;
}

TEST(OceanMesh, GeomorphingKeepsHeightsContinuousAcrossLevelBoundaries) {
  OceanGridOptions grid;
  grid.size_m = 4096.0;
  grid.finest_node_m = 2.0;
  const EyeWalk morphed = walkAway(grid);
  grid.geomorph = false;
  const EyeWalk popping = walkAway(grid);
  // The walk crosses level boundaries (the leaves change) ...
  EXPECT_GE(morphed.leaf_changes, 4);
  // ... and the surface moves a few millimetres a 5 cm step with geomorphing, where without it a
  // vertex appears or vanishes at once.
  EXPECT_LT(morphed.largest_jump_m, 0.02) << "popping: " << popping.largest_jump_m;
  std::printf("largest height change a 5 cm step: %.4f m geomorphed, %.4f m without; %d leaf changes\n",
              morphed.largest_jump_m, popping.largest_jump_m, morphed.leaf_changes);
  EXPECT_GT(popping.largest_jump_m, 5.0 * morphed.largest_jump_m);
}

TEST(OceanMesh, CellsGrowWithDistanceAndBadOptionsAreRefused) {
  OceanGridOptions grid;
  EXPECT_DOUBLE_EQ(oceanCellSizeAt(grid, 0.0), grid.size_m / double(8 << 13));
  EXPECT_GT(oceanCellSizeAt(grid, 5000.0), 100.0 * oceanCellSizeAt(grid, 0.0));
  grid.cells_per_node = 7;
  EXPECT_THROW(validateOceanGrid(grid), std::invalid_argument);
  grid = {};
  grid.size_m = std::numeric_limits<double>::infinity();
  EXPECT_THROW(validateOceanGrid(grid), std::invalid_argument);
}

}  // namespace
}  // namespace tw
