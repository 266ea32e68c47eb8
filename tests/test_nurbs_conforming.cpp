// Tests of the conforming NURBS tessellation (formats/nurbs_conforming.h) and of its OpenMesh
// verification (preprocess/patch_mesh_check.h): layouts with adjacent patches parameterised
// differently (reversed, other degree, other knots), corners of 3 and 4 patches, a closed
// cylinder and the generator's hull. Each must verify with zero T-vertices and zero inner
// boundary edges and stay within the chordal tolerance; today's per-patch tessellateNurbs is run
// on the same layouts to show that the check does fail on cracked meshes.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <utility>

#include "nurbs.h"
#include "nurbs_conforming.h"
#include "patch_mesh_check.h"
#include "scene_io.h"
#include "tessellate.h"
#include "test_support.h"
#include "nurbs_test_support.h"

namespace tw {
namespace {

// ---------------------------------------------------------------------------------------------
// Patch construction helpers.

using test::clampedKnots;
using test::makePatch;

glm::dvec4 homogeneous(const glm::vec4& c) { return {double(c.x) * c.w, double(c.y) * c.w, double(c.z) * c.w, c.w}; }
glm::vec4 cartesian(const glm::dvec4& h) { return glm::vec4(glm::dvec3(h) / h.w, h.w); }

NurbsPatch transposed(const NurbsPatch& p) {
  NurbsPatch t;
  t.degree_u = p.degree_v, t.degree_v = p.degree_u, t.count_u = p.count_v, t.count_v = p.count_u;
  t.knots_u = p.knots_v, t.knots_v = p.knots_u;
  for (uint32_t i = 0; i < p.count_u; ++i)
    for (uint32_t j = 0; j < p.count_v; ++j) t.control_points.push_back(p.control_points[j * p.count_u + i]);
  return t;
}

// The same surface with u running the other way (knots mirrored).
NurbsPatch reversedU(const NurbsPatch& p) {
  NurbsPatch r = p;
  const float a = p.knots_u.front(), b = p.knots_u.back();
  for (size_t i = 0; i < p.knots_u.size(); ++i) r.knots_u[i] = a + b - p.knots_u[p.knots_u.size() - 1 - i];
  for (uint32_t j = 0; j < p.count_v; ++j)
    for (uint32_t i = 0; i < p.count_u; ++i)
      r.control_points[j * p.count_u + i] = p.control_points[j * p.count_u + (p.count_u - 1 - i)];
  return r;
}
NurbsPatch reversedV(const NurbsPatch& p) { return transposed(reversedU(transposed(p))); }

// The same surface with knot `tau` inserted along u (Boehm), in homogeneous coordinates.
NurbsPatch insertKnotU(const NurbsPatch& p, float tau) {
  const uint32_t deg = p.degree_u, n = p.count_u;
  uint32_t k = deg;
  while (k + 1 < n && p.knots_u[k + 1] <= tau) ++k;
  NurbsPatch r = p;
  r.count_u = n + 1;
  r.knots_u.insert(r.knots_u.begin() + k + 1, tau);
  r.control_points.clear();
  for (uint32_t j = 0; j < p.count_v; ++j)
    for (uint32_t i = 0; i <= n; ++i) {
      auto P = [&](uint32_t x) { return homogeneous(p.control_points[j * n + x]); };
      glm::dvec4 q;
      if (i + deg <= k)
        q = P(i);
      else if (i > k)
        q = P(i - 1);
      else {
        const double alpha = (tau - p.knots_u[i]) / (double(p.knots_u[i + deg]) - p.knots_u[i]);
        q = alpha * P(i) + (1.0 - alpha) * P(i - 1);
      }
      r.control_points.push_back(cartesian(q));
    }
  return r;
}
NurbsPatch insertKnotV(const NurbsPatch& p, float tau) { return transposed(insertKnotU(transposed(p), tau)); }

// The same Bezier surface one degree higher along u.
NurbsPatch elevatedU(const NurbsPatch& p) {
  const uint32_t deg = p.degree_u, n = p.count_u;
  NurbsPatch r = p;
  r.degree_u = deg + 1;
  r.count_u = n + 1;
  r.knots_u = clampedKnots(deg + 1, n + 1);
  r.control_points.clear();
  for (uint32_t j = 0; j < p.count_v; ++j)
    for (uint32_t i = 0; i <= n; ++i) {
      auto P = [&](uint32_t x) { return homogeneous(p.control_points[j * n + x]); };
      const double a = static_cast<double>(i) / (deg + 1);
      const glm::dvec4 q = i == 0 ? P(0) : i == n ? P(n - 1) : a * P(i - 1) + (1.0 - a) * P(i);
      r.control_points.push_back(cartesian(q));
    }
  return r;
}
NurbsPatch elevatedV(const NurbsPatch& p) { return transposed(elevatedU(transposed(p))); }

// A bicubic Bezier patch on the square [x0, x0+1] x [y0, y0+1] whose height at control point
// (i, j) is height(x, y) of its plan position, so that neighbours built from one function share
// their border control points bit for bit.
template <typename F>
NurbsPatch heightPatch(float x0, float y0, F height) {
  std::vector<glm::vec4> pts;
  for (int j = 0; j < 4; ++j)
    for (int i = 0; i < 4; ++i) {
      const float x = x0 + static_cast<float>(i) / 3.0f, y = y0 + static_cast<float>(j) / 3.0f;
      pts.push_back({x, y, height(x, y), 1.0f});
    }
  return makePatch(3, 3, 4, 4, std::move(pts));
}

float wavy(float x, float y) { return 0.25f * std::sin(2.1f * x + 0.3f) * std::cos(1.7f * y - 0.2f) + 0.1f * x * y; }

constexpr float kW = 0.70710678f;

// Quarter k of the circle of radius r at height z: rational quadratic, counter-clockwise.
std::array<glm::vec4, 3> quarter(int k, float r, float z) {
  static constexpr int kAxis[5][2] = {{1, 0}, {0, 1}, {-1, 0}, {0, -1}, {1, 0}};
  const float ax = kAxis[k][0] * r, ay = kAxis[k][1] * r, bx = kAxis[k + 1][0] * r, by = kAxis[k + 1][1] * r;
  return {glm::vec4(ax, ay, z, 1.0f), glm::vec4(ax + bx, ay + by, z, kW), glm::vec4(bx, by, z, 1.0f)};
}

// ---------------------------------------------------------------------------------------------
// Measurement: distance from points of the triangles to the exact surface.

// Closest-point distance to a patch set: from the nearest point of a 17 x 17 sample grid of each
// nearby patch, Gauss-Newton on the parameters (finite-difference Jacobian), clamped to the domain.
class SurfaceDistance {
 public:
  explicit SurfaceDistance(const NurbsPatchSet& set) : set_(set) {
    for (const NurbsPatch& p : set.patches) {
      Grid g;
      g.dom = nurbsDomain(p);
      for (int j = 0; j <= kN; ++j)
        for (int i = 0; i <= kN; ++i) {
          const glm::dvec3 q(evaluateNurbs(p, u(g, i / double(kN)), v(g, j / double(kN))));
          g.pts.push_back(q);
          g.lo = glm::min(g.lo, q);
          g.hi = glm::max(g.hi, q);
        }
      double cell = 0.0;
      for (int j = 0; j < kN; ++j)
        for (int i = 0; i < kN; ++i) cell = std::max(cell, glm::length(g.pts[j * (kN + 1) + i] - g.pts[(j + 1) * (kN + 1) + i + 1]));
      g.margin = cell;
      grids_.push_back(std::move(g));
    }
  }

  // `good_enough`: a distance below which the search may stop. Patches are tried in the order
  // of their nearest sample.
  double operator()(const glm::dvec3& q, double good_enough) const {
    std::vector<std::pair<double, size_t>> candidates;
    for (size_t k = 0; k < grids_.size(); ++k) {
      const Grid& g = grids_[k];
      if (glm::any(glm::lessThan(q, g.lo - g.margin)) || glm::any(glm::greaterThan(q, g.hi + g.margin))) continue;
      double nearest = INFINITY;
      for (const glm::dvec3& p : g.pts) nearest = std::min(nearest, glm::length(p - q));
      candidates.push_back({nearest, k});
    }
    std::sort(candidates.begin(), candidates.end());
    double best = INFINITY;
    for (const auto& [nearest, k] : candidates) {
      if (best <= good_enough) break;
      best = std::min(best, project(set_.patches[k], grids_[k], q, good_enough));
    }
    return best;
  }

 private:
  static constexpr int kN = 16;
  struct Grid {
    NurbsDomain dom;
    std::vector<glm::dvec3> pts;
    glm::dvec3 lo{INFINITY}, hi{-INFINITY};
    double margin = 0.0;
  };
  static float u(const Grid& g, double x) { return static_cast<float>(g.dom.u0 + (double(g.dom.u1) - g.dom.u0) * x); }
  static float v(const Grid& g, double y) { return static_cast<float>(g.dom.v0 + (double(g.dom.v1) - g.dom.v0) * y); }

  // From the nearest grid sample; where that lands far (a seam: the nearest sample may sit on the
  // wrong side of the parameter domain), again from the next nearest ones.
  static double project(const NurbsPatch& p, const Grid& g, const glm::dvec3& q, double good_enough) {
    size_t nearest = 0;
    for (size_t i = 1; i < g.pts.size(); ++i)
      if (glm::length(g.pts[i] - q) < glm::length(g.pts[nearest] - q)) nearest = i;
    double best = descend(p, g, q, nearest);
    if (best <= good_enough) return best;
    std::vector<std::pair<double, size_t>> order(g.pts.size());
    for (size_t i = 0; i < g.pts.size(); ++i) order[i] = {glm::length(g.pts[i] - q), i};
    std::partial_sort(order.begin(), order.begin() + 4, order.end());
    for (int start = 1; start < 4 && !(best <= good_enough); ++start) best = std::min(best, descend(p, g, q, order[start].second));
    return best;
  }
  static double descend(const NurbsPatch& p, const Grid& g, const glm::dvec3& q, size_t nearest) {
    double x = double(nearest % (kN + 1)) / kN, y = double(nearest / (kN + 1)) / kN;
    auto S = [&](double a, double b) { return glm::dvec3(evaluateNurbs(p, u(g, std::clamp(a, 0.0, 1.0)), v(g, std::clamp(b, 0.0, 1.0)))); };
    double best = glm::length(g.pts[nearest] - q);
    for (int it = 0; it < 12; ++it) {
      const double h = 1e-4;
      const glm::dvec3 s = S(x, y);
      best = std::min(best, glm::length(s - q));
      const glm::dvec3 su = (S(x + h, y) - S(x - h, y)) / (2 * h), sv = (S(x, y + h) - S(x, y - h)) / (2 * h);
      const glm::dvec3 r = s - q;
      const double a = glm::dot(su, su), b = glm::dot(su, sv), c = glm::dot(sv, sv);
      const double ru = glm::dot(su, r), rv = glm::dot(sv, r), det = a * c - b * b;
      if (!(std::abs(det) > 1e-30)) break;
      const double nx = std::clamp(x - (c * ru - b * rv) / det, 0.0, 1.0);
      const double ny = std::clamp(y - (a * rv - b * ru) / det, 0.0, 1.0);
      const bool converged = std::abs(nx - x) < 1e-9 && std::abs(ny - y) < 1e-9;
      x = nx, y = ny;
      if (converged) break;
    }
    return std::min(best, glm::length(S(x, y) - q));
  }

  const NurbsPatchSet& set_;
  std::vector<Grid> grids_;
};

// The largest distance from a triangle's centroid or an edge midpoint to the surface.
double maxChordalError(const TriangleMesh& mesh, const NurbsPatchSet& set, double good_enough) {
  SurfaceDistance distance(set);
  double worst = 0.0;
  for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
    const glm::dvec3 a(mesh.positions[mesh.indices[t]]), b(mesh.positions[mesh.indices[t + 1]]),
        c(mesh.positions[mesh.indices[t + 2]]);
    for (const glm::dvec3& q : {(a + b + c) / 3.0, 0.5 * (a + b), 0.5 * (b + c), 0.5 * (c + a)})
      worst = std::max(worst, distance(q, good_enough));
  }
  return worst;
}

std::string describe(const PatchMeshReport& r) {
  return "faces " + std::to_string(r.faces) + " refused " + std::to_string(r.refused_faces) + " boundary " +
         std::to_string(r.boundary_edges) + " inner " + std::to_string(r.inner_boundary_edges) + " T " +
         std::to_string(r.t_vertices) + " orientation " + std::to_string(r.inconsistent_orientation) +
         " degenerate " + std::to_string(r.degenerate_faces) + ": " + r.first_problem;
}

// The checks every layout goes through. Returns the conforming mesh.
TriangleMesh expectConforming(const NurbsPatchSet& set, float tolerance, uint64_t expected_boundary_edges_min = 0,
                              bool closed = false) {
  TriangleMesh mesh;
  ConformingTessellationStats stats;
  tessellateNurbsConforming(set, tolerance, mesh, &stats);
  EXPECT_EQ(stats.patches, set.patches.size());
  EXPECT_EQ(stats.triangles, mesh.triangleCount());
  EXPECT_GT(mesh.triangleCount(), 0u);
  EXPECT_EQ(mesh.normals.size(), mesh.positions.size());
  for (const glm::vec3& n : mesh.normals) EXPECT_NEAR(glm::length(n), 1.0f, 1e-4f);
  const PatchMeshReport report = checkPatchMesh(mesh, set);
  EXPECT_TRUE(report.ok()) << describe(report);
  EXPECT_EQ(report.t_vertices, 0u);
  EXPECT_EQ(report.inner_boundary_edges, 0u);
  EXPECT_EQ(report.inconsistent_orientation, 0u);
  EXPECT_EQ(report.refused_faces, 0u);
  EXPECT_EQ(report.degenerate_faces, 0u);
  EXPECT_GE(report.boundary_edges, expected_boundary_edges_min);
  if (closed) {
    EXPECT_EQ(report.boundary_edges, 0u);
  }
  const double error = maxChordalError(mesh, set, 0.25 * tolerance);
  EXPECT_LT(error, tolerance) << "measured chordal error " << error;
  std::printf("[ measured ] %zu patches: %llu triangles, %u shared borders, max chordal error %.3g (tolerance %.3g)\n",
              set.patches.size(), static_cast<unsigned long long>(mesh.triangleCount()), stats.shared_borders, error,
              static_cast<double>(tolerance));
  return mesh;
}

// Today's per-patch tessellation of the same layout must fail the check (it cracks where the
// parameterisations differ), which shows the check can fail.
void expectPerPatchFails(const NurbsPatchSet& set, float tolerance) {
  TriangleMesh mesh;
  tessellateNurbs(set, tolerance, mesh);
  const PatchMeshReport report = checkPatchMesh(mesh, set);
  EXPECT_FALSE(report.ok()) << describe(report);
  EXPECT_GT(report.inner_boundary_edges + report.t_vertices, 0u);
}

constexpr float kTol = 0.002f;

// ---------------------------------------------------------------------------------------------
// The check itself on hand-made meshes.

TEST(PatchMeshCheck, FindsATVertexAndTheCrackAroundIt) {
  // Two unit squares sharing x = 1; the right one has an extra vertex at (1, 0.5).
  NurbsPatchSet set;
  set.patches.push_back(makePatch(1, 1, 2, 2, {{0, 0, 0, 1}, {1, 0, 0, 1}, {0, 1, 0, 1}, {1, 1, 0, 1}}));
  set.patches.push_back(makePatch(1, 1, 2, 2, {{1, 0, 0, 1}, {2, 0, 0, 1}, {1, 1, 0, 1}, {2, 1, 0, 1}}));
  TriangleMesh mesh;
  mesh.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {2, 0, 0}, {2, 1, 0}, {1, 0.5f, 0}};
  mesh.indices = {0, 1, 2, 0, 2, 3, 1, 4, 6, 4, 5, 6, 6, 5, 2};
  PatchMeshReport r = checkPatchMesh(mesh, set);
  EXPECT_FALSE(r.ok());
  EXPECT_EQ(r.t_vertices, 1u);
  EXPECT_EQ(r.inner_boundary_edges, 3u);  // 1-2 on the left, 1-6 and 6-2 on the right
  EXPECT_NE(r.first_problem.find("T-vertices"), std::string::npos) << r.first_problem;

  // The same without the extra vertex is fine: 6 outer boundary edges.
  mesh.indices = {0, 1, 2, 0, 2, 3, 1, 4, 5, 1, 5, 2};
  r = checkPatchMesh(mesh, set);
  EXPECT_TRUE(r.ok()) << describe(r);
  EXPECT_EQ(r.boundary_edges, 6u);
  EXPECT_TRUE(r.first_problem.empty());

  // One face flipped: orientation disagrees across the shared edge.
  mesh.indices = {0, 1, 2, 0, 2, 3, 1, 5, 4, 1, 2, 5};
  r = checkPatchMesh(mesh, set);
  EXPECT_FALSE(r.ok());
  EXPECT_GT(r.inconsistent_orientation, 0u);

  // A one-ulp crack: positions that differ by one float step do not weld.
  mesh.positions.push_back({std::nextafter(1.0f, 2.0f), 1.0f, 0.0f});
  mesh.indices = {0, 1, 2, 0, 2, 3, 1, 4, 5, 1, 5, 7};
  r = checkPatchMesh(mesh, set);
  EXPECT_FALSE(r.ok());
  EXPECT_GT(r.inner_boundary_edges, 0u);
}

// ---------------------------------------------------------------------------------------------
// Layouts.

TEST(NurbsConforming, TwoPatchesWithReversedDirection) {
  const NurbsPatch a = heightPatch(0.0f, 0.0f, wavy), b = heightPatch(1.0f, 0.0f, wavy);
  // Reversed along the shared border, orientation kept (both directions reversed).
  NurbsPatchSet set{{a, reversedU(reversedV(b))}};
  ConformingTessellationStats stats;
  TriangleMesh mesh = expectConforming(set, kTol, 6);
  tessellateNurbsConforming(set, kTol, mesh, &stats);
  EXPECT_EQ(stats.shared_borders, 1u);
  // Today's tessellator walks identical border data the same way: it conforms here too.
  TriangleMesh old;
  tessellateNurbs(set, kTol, old);
  EXPECT_TRUE(checkPatchMesh(old, set).ok());

  // Reversed and refined: a knot inserted along the shared border on one side only.
  NurbsPatchSet refined{{a, insertKnotV(reversedU(reversedV(b)), 0.3f)}};
  expectConforming(refined, kTol, 6);
  expectPerPatchFails(refined, kTol);

  // Reversed along the border only: the second patch faces the other way and is flipped.
  NurbsPatchSet flipped{{a, reversedV(b)}};
  TriangleMesh f = expectConforming(flipped, kTol, 6);
  for (const glm::vec3& n : f.normals) EXPECT_GT(n.z, 0.0f);
}

TEST(NurbsConforming, DifferentDegreesAndKnotSpacing) {
  // A: bicubic with a knot inserted at v = 0.25 (uneven spacing); B: biquadratic whose left
  // border, degree-elevated, is A's right border; C: bilinear next to B along a straight border
  // that B parameterises unevenly.
  auto profile = [](int j) { return glm::vec2(static_cast<float>(j) / 2.0f, j == 1 ? 0.35f : 0.0f); };  // (y, z)
  std::vector<glm::vec4> bq;
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i) {
      const glm::vec2 yz = profile(j);
      const float x = 1.0f + static_cast<float>(i) / 2.0f;
      float y = yz.x, z = i == 0 ? yz.y : i == 1 ? 0.2f * static_cast<float>(j == 1) - 0.1f : 0.0f;
      if (i == 2) y = j == 0 ? 0.0f : j == 1 ? 0.8f : 1.0f;  // straight, uneven
      bq.push_back({x, y, z, 1.0f});
    }
  NurbsPatch b = makePatch(2, 2, 3, 3, bq);
  // A's right border: B's left border (a quadratic) elevated to cubic; interior a bump.
  const NurbsPatch b_left = elevatedV(b);  // left column of b_left is the elevated border
  std::vector<glm::vec4> ap;
  for (int j = 0; j < 4; ++j)
    for (int i = 0; i < 4; ++i) {
      const glm::vec4 edge = b_left.control_points[j * 3 + 0];
      if (i == 3) {
        ap.push_back(edge);
        continue;
      }
      const float x = static_cast<float>(i) / 3.0f;
      ap.push_back({x, edge.y, edge.z * x + (i == 1 && (j == 1 || j == 2) ? 0.3f : 0.0f), 1.0f});
    }
  const NurbsPatch a = insertKnotV(makePatch(3, 3, 4, 4, ap), 0.25f);
  const NurbsPatch c = makePatch(1, 1, 2, 2, {{2, 0, 0, 1}, {3, 0, 0.2f, 1}, {2, 1, 0, 1}, {3, 1, -0.2f, 1}});
  NurbsPatchSet set{{a, b, c}};
  ConformingTessellationStats stats;
  TriangleMesh mesh = expectConforming(set, kTol, 8);
  tessellateNurbsConforming(set, kTol, mesh, &stats);
  EXPECT_EQ(stats.shared_borders, 2u);
  expectPerPatchFails(set, kTol);
}

// A 7 x 7 Bezier net over [0,2]^2 cut into 2 x 2 bicubic patches, each then parameterised its
// own way.
NurbsPatchSet gridOfFour(bool vary) {
  NurbsPatchSet set;
  for (int pj = 0; pj < 2; ++pj)
    for (int pi = 0; pi < 2; ++pi) set.patches.push_back(heightPatch(static_cast<float>(pi), static_cast<float>(pj), wavy));
  if (vary) {
    set.patches[1] = reversedU(reversedV(set.patches[1]));
    set.patches[2] = elevatedU(set.patches[2]);
    set.patches[3] = insertKnotV(insertKnotU(set.patches[3], 0.6f), 0.3f);
  }
  return set;
}

TEST(NurbsConforming, FourPatchesMeetingAtOneCorner) {
  const NurbsPatchSet same = gridOfFour(false), varied = gridOfFour(true);
  TriangleMesh mesh = expectConforming(varied, kTol, 8);
  ConformingTessellationStats stats;
  tessellateNurbsConforming(varied, kTol, mesh, &stats);
  EXPECT_EQ(stats.shared_borders, 4u);
  // The centre (1, 1) is one vertex used by all four patches.
  const glm::vec3 centre(1.0f, 1.0f, wavy(1.0f, 1.0f));
  TriangleMesh fresh;
  tessellateNurbsConforming(varied, kTol, fresh);
  size_t at_centre = 0;
  for (const glm::vec3& p : fresh.positions) at_centre += glm::length(p - centre) < 1e-5f;
  EXPECT_EQ(at_centre, 1u);
  expectPerPatchFails(varied, kTol);
  expectConforming(same, kTol, 8);
}

// Three faces of a cube around the corner (1,1,1), pushed outward as a pillow. Control points
// are a function of their position on the cube, so shared borders agree bit for bit.
NurbsPatch pillowFace(int axis, float sign, bool flip_uv) {
  std::vector<glm::vec4> pts;
  const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
  for (int j = 0; j < 4; ++j)
    for (int i = 0; i < 4; ++i) {
      glm::vec3 q(0.0f);
      q[axis] = sign;
      q[a1] = -1.0f + 2.0f * static_cast<float>(flip_uv ? j : i) / 3.0f;
      q[a2] = -1.0f + 2.0f * static_cast<float>(flip_uv ? i : j) / 3.0f;
      const float push = 1.0f + 0.15f * (3.0f - std::abs(q.x) - std::abs(q.y) - std::abs(q.z));
      pts.push_back(glm::vec4(q * push, 1.0f));
    }
  return makePatch(3, 3, 4, 4, std::move(pts));
}

TEST(NurbsConforming, ThreePatchesMeetingAtACorner) {
  NurbsPatchSet set{{pillowFace(0, 1.0f, false), pillowFace(1, 1.0f, true), elevatedU(pillowFace(2, 1.0f, false))}};
  set.patches[1] = insertKnotU(set.patches[1], 0.4f);
  ConformingTessellationStats stats;
  TriangleMesh mesh = expectConforming(set, kTol, 12);
  tessellateNurbsConforming(set, kTol, mesh, &stats);
  EXPECT_EQ(stats.shared_borders, 3u);
  expectPerPatchFails(set, kTol);

  // The whole pillow cube is closed: no boundary at all.
  NurbsPatchSet cube;
  for (int axis = 0; axis < 3; ++axis)
    for (float sign : {-1.0f, 1.0f}) cube.patches.push_back(pillowFace(axis, sign, axis == 1));
  cube.patches[4] = elevatedV(cube.patches[4]);
  expectConforming(cube, kTol, 0, true);
}

// A closed cylinder (radius 1, height 2) of four rational quarter walls, capped by quarter discs
// whose centre border collapses to a point (a pole).
NurbsPatchSet closedCylinder(bool vary) {
  NurbsPatchSet set;
  for (int k = 0; k < 4; ++k) {
    const auto lo = quarter(k, 1.0f, 0.0f), hi = quarter(k, 1.0f, 2.0f);
    NurbsPatch wall = makePatch(2, 1, 3, 2, {lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]});
    if (vary && k % 2 == 1) wall = insertKnotV(elevatedV(wall), 0.5f);
    set.patches.push_back(wall);
    // Top: u around, v from rim to centre (normal +Z); bottom: v from centre to rim (-Z).
    for (int end = 0; end < 2; ++end) {
      const float z = end == 0 ? 2.0f : 0.0f;
      const auto rim = quarter(k, 1.0f, z);
      std::array<glm::vec4, 3> centre;
      for (int i = 0; i < 3; ++i) centre[i] = glm::vec4(0.0f, 0.0f, z, rim[i].w);
      std::vector<glm::vec4> pts;
      if (end == 0)
        pts = {rim[0], rim[1], rim[2], centre[0], centre[1], centre[2]};
      else
        pts = {centre[0], centre[1], centre[2], rim[0], rim[1], rim[2]};
      NurbsPatch disc = makePatch(2, 1, 3, 2, pts);
      if (vary && end == 1) disc = reversedU(disc);  // flipped orientation: must be repaired
      set.patches.push_back(disc);
    }
  }
  return set;
}

TEST(NurbsConforming, ClosedCylinderWithSeamsAndPoles) {
  for (bool vary : {false, true}) {
    SCOPED_TRACE(vary ? "varied" : "plain");
    const NurbsPatchSet set = closedCylinder(vary);
    TriangleMesh mesh = expectConforming(set, kTol, 0, true);
    // Wall normals point outward.
    for (size_t v = 0; v < mesh.positions.size(); ++v) {
      const glm::vec3 p = mesh.positions[v], n = mesh.normals[v];
      if (p.z > 0.1f && p.z < 1.9f) {
        EXPECT_GT(glm::dot(glm::vec2(n), glm::vec2(p)), 0.5f);
      }
      if (p.z == 2.0f && glm::length(glm::vec2(p)) < 0.9f) {
        EXPECT_GT(n.z, 0.9f);
      }
    }
    if (vary) expectPerPatchFails(set, kTol);
  }
  // One patch closing on itself: a full circle of 9 rational control points, seam at u = 0 = 1.
  std::vector<glm::vec4> pts;
  for (float z : {0.0f, 1.0f}) {
    for (int k = 0; k < 4; ++k) {
      const auto q = quarter(k, 1.0f, z);
      pts.push_back(q[0]);
      pts.push_back(q[1]);
    }
    pts.push_back(quarter(0, 1.0f, z)[0]);
  }
  NurbsPatch tube = makePatch(2, 1, 9, 2, pts);
  tube.knots_u = {0, 0, 0, 0.25f, 0.25f, 0.5f, 0.5f, 0.75f, 0.75f, 1, 1, 1};
  ConformingTessellationStats stats;
  TriangleMesh mesh = expectConforming(NurbsPatchSet{{tube}}, kTol, 8);
  tessellateNurbsConforming(NurbsPatchSet{{tube}}, kTol, mesh, &stats);
  EXPECT_EQ(stats.shared_borders, 1u);  // the seam
}

// The generator's hull, read from a small generated plant.
std::vector<NurbsPatchSet> generatedHulls() {
  const auto dir = test::processScratchDir("nurbs-conforming");
  const auto path = dir / "plant.tws";
  if (!std::filesystem::exists(path)) {
    const test::CommandResult r = test::runTerawalk("gen plant --triangles 60K --no-db -o " + path.string());
    EXPECT_EQ(r.exit_code, 0) << r.output;
  }
  test::CollectingSink sink;
  readScene(path, sink);
  std::vector<NurbsPatchSet> hulls;
  for (const auto& o : sink.objects)
    if (const auto* n = std::get_if<NurbsPatchSet>(&o.geometry)) hulls.push_back(*n);
  return hulls;
}

TEST(NurbsConforming, GeneratedHull) {
  const std::vector<NurbsPatchSet> hulls = generatedHulls();
  ASSERT_FALSE(hulls.empty());
  const NurbsPatchSet& hull = hulls.front();
  ASSERT_GT(hull.patches.size(), 50u);
  TriangleMesh mesh = expectConforming(hull, kDefaultChordalTolerance, 0, true);
  ConformingTessellationStats stats;
  tessellateNurbsConforming(hull, kDefaultChordalTolerance, mesh, &stats);
  EXPECT_EQ(stats.shared_borders, 2 * hull.patches.size());  // closed: every border shared
  // Today's tessellator also closes this hull (its patches share control points bit for bit);
  // re-parameterise every third patch (same surface) and it no longer does, while this one does.
  NurbsPatchSet varied = hull;
  for (size_t i = 0; i < varied.patches.size(); i += 3)
    varied.patches[i] = i % 2 ? insertKnotU(varied.patches[i], 0.4f) : elevatedV(reversedU(reversedV(varied.patches[i])));
  expectConforming(varied, kDefaultChordalTolerance, 0, true);
  expectPerPatchFails(varied, kDefaultChordalTolerance);
}

// ---------------------------------------------------------------------------------------------
// Contract details.

TEST(NurbsConforming, BadPatchesThrowNamingTheirIndex) {
  NurbsPatchSet set = gridOfFour(false);
  set.patches[2].control_points[5].w = 0.0f;
  try {
    TriangleMesh mesh;
    tessellateNurbsConforming(set, kTol, mesh);
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("NURBS patch 2"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("weight"), std::string::npos) << e.what();
  }
  set = gridOfFour(false);
  set.patches[3].knots_u.pop_back();
  EXPECT_THROW(
      {
        TriangleMesh mesh;
        tessellateNurbsConforming(set, kTol, mesh);
      },
      std::invalid_argument);
}

TEST(NurbsConforming, DeterministicAndAppending) {
  const NurbsPatchSet set = gridOfFour(true);
  TriangleMesh a, b;
  tessellateNurbsConforming(set, kTol, a);
  tessellateNurbsConforming(set, kTol, b);
  ASSERT_EQ(a.positions.size(), b.positions.size());
  ASSERT_EQ(a.indices, b.indices);
  EXPECT_EQ(std::memcmp(a.positions.data(), b.positions.data(), a.positions.size() * sizeof(glm::vec3)), 0);
  EXPECT_EQ(std::memcmp(a.normals.data(), b.normals.data(), a.normals.size() * sizeof(glm::vec3)), 0);

  // Appending to a mesh offsets the indices; a mesh without normals stays without.
  TriangleMesh c;
  c.positions = {{9, 9, 9}};
  c.normals = {{0, 0, 1}};
  tessellateNurbsConforming(set, kTol, c);
  ASSERT_EQ(c.positions.size(), a.positions.size() + 1);
  for (size_t i = 0; i < a.indices.size(); ++i) ASSERT_EQ(c.indices[i], a.indices[i] + 1);
  TriangleMesh d;
  d.positions = {{9, 9, 9}};
  tessellateNurbsConforming(set, kTol, d);
  EXPECT_TRUE(d.normals.empty());

  // A finer tolerance gives more triangles.
  TriangleMesh fine;
  tessellateNurbsConforming(set, kTol / 8, fine);
  EXPECT_GT(fine.triangleCount(), 2 * a.triangleCount());
}

TEST(NurbsConforming, HostileInputIsBounded) {
  // A wildly oscillating control net at a vanishing tolerance: the grid and borders are capped.
  std::vector<glm::vec4> pts;
  for (int j = 0; j < 4; ++j)
    for (int i = 0; i < 4; ++i) pts.push_back({float(i), float(j), (i + j) % 2 ? 1e6f : -1e6f, 1.0f});
  NurbsPatchSet set{{makePatch(3, 3, 4, 4, pts), makePatch(3, 3, 4, 4, pts)}};
  TriangleMesh mesh;
  tessellateNurbsConforming(set, 1e-9f, mesh);
  EXPECT_GT(mesh.triangleCount(), 1000u);
  EXPECT_LE(mesh.triangleCount(), uint64_t{1} << 23);
  // Non-finite or zero tolerance: the coarsest tessellation, still valid.
  for (float tol : {0.0f, -1.0f, NAN, INFINITY}) {
    TriangleMesh coarse;
    tessellateNurbsConforming(gridOfFour(true), tol, coarse);
    EXPECT_GT(coarse.triangleCount(), 0u);
    EXPECT_LE(coarse.triangleCount(), 400u);
    EXPECT_TRUE(checkPatchMesh(coarse, gridOfFour(true)).ok());
  }
  // Twenty thousand copies of one patch: every corner and border coincides with thousands of
  // others. Candidate searches are capped, so this stays linear (about a second, not hours).
  NurbsPatchSet copies;
  copies.patches.assign(20000, makePatch(1, 1, 2, 2, {{0, 0, 0, 1}, {1, 0, 0, 1}, {0, 1, 0, 1}, {1, 1, 0, 1}}));
  TriangleMesh many;
  ConformingTessellationStats stats;
  tessellateNurbsConforming(copies, kTol, many, &stats);
  EXPECT_EQ(stats.patches, 20000u);
  EXPECT_GE(many.triangleCount(), 20000u * 4);
  EXPECT_LE(many.triangleCount(), 20000u * 16);
  // An empty set appends nothing.
  TriangleMesh empty;
  tessellateNurbsConforming(NurbsPatchSet{}, kTol, empty);
  EXPECT_TRUE(empty.positions.empty());
}

}  // namespace
}  // namespace tw
