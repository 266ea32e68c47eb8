// Tests of NURBS evaluation, validation and crack-free tessellation of patch sets.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <map>
#include <numbers>
#include <random>
#include <set>

#include "nurbs.h"
#include "nurbs_conforming.h"
#include "tessellate.h"
#include "watertight_check.h"
#include "nurbs_test_support.h"

namespace tw {
namespace {

constexpr float kW = 0.70710678f;  // weight of the middle point of a rational quarter circle

using test::clampedKnots;
using test::makePatch;

// Quarter k (0..3) of the circle of radius r at height z, as rational quadratic control points
// running counter-clockwise. Exact floats: only 0 and +-r appear.
std::array<glm::vec4, 3> quarter(int k, float r, float z) {
  static constexpr int kAxis[5][2] = {{1, 0}, {0, 1}, {-1, 0}, {0, -1}, {1, 0}};
  const float ax = kAxis[k][0] * r, ay = kAxis[k][1] * r, bx = kAxis[k + 1][0] * r, by = kAxis[k + 1][1] * r;
  return {glm::vec4(ax, ay, z, 1.0f), glm::vec4(ax + bx, ay + by, z, kW), glm::vec4(bx, by, z, 1.0f)};
}

// A quarter of a cylinder wall: u around (counter-clockwise), v up. Normal points outward.
NurbsPatch cylinderQuarter(int k, float r, float h) {
  const auto lo = quarter(k, r, 0.0f), hi = quarter(k, r, h);
  return makePatch(2, 1, 3, 2, {lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]});
}

// A quarter disc at height z, degenerate at the centre: u around, v from centre to rim when
// `facing_down`, rim to centre otherwise, so the normal faces -Z or +Z.
NurbsPatch discQuarter(int k, float r, float z, bool facing_down) {
  const auto rim = quarter(k, r, z);
  std::array<glm::vec4, 3> centre;
  for (int i = 0; i < 3; ++i) centre[i] = glm::vec4(0.0f, 0.0f, z, rim[i].w);
  if (facing_down) return makePatch(2, 1, 3, 2, {centre[0], centre[1], centre[2], rim[0], rim[1], rim[2]});
  return makePatch(2, 1, 3, 2, {rim[0], rim[1], rim[2], centre[0], centre[1], centre[2]});
}

NurbsPatchSet closedCylinder(float r, float h) {
  NurbsPatchSet set;
  for (int k = 0; k < 4; ++k) {
    set.patches.push_back(cylinderQuarter(k, r, h));
    set.patches.push_back(discQuarter(k, r, 0.0f, true));
    set.patches.push_back(discQuarter(k, r, h, false));
  }
  return set;
}

TriangleMesh tessellateSet(const NurbsPatchSet& set, float tol) {
  TriangleMesh m;
  tessellateNurbs(set, tol, m);
  return m;
}

void expectWellFormed(const TriangleMesh& m) {
  ASSERT_EQ(m.indices.size() % 3, 0u);
  for (uint32_t i : m.indices) ASSERT_LT(i, m.positions.size());
  ASSERT_TRUE(m.normals.empty() || m.normals.size() == m.positions.size());
  for (const glm::vec3& n : m.normals) ASSERT_NEAR(glm::length(n), 1.0f, 1e-4f);
}

// Boundary edges (used by one triangle) by welded position, as pairs of positions.
std::vector<std::pair<glm::vec3, glm::vec3>> boundaryEdges(const TriangleMesh& m) {
  auto key = [](const glm::vec3& p) { return std::array<float, 3>{p.x + 0.0f, p.y + 0.0f, p.z + 0.0f}; };
  std::map<std::pair<std::array<float, 3>, std::array<float, 3>>, int> uses;
  for (size_t t = 0; t < m.indices.size(); t += 3)
    for (int e = 0; e < 3; ++e) {
      auto a = key(m.positions[m.indices[t + e]]), b = key(m.positions[m.indices[t + (e + 1) % 3]]);
      if (b < a) std::swap(a, b);
      ++uses[{a, b}];
    }
  std::vector<std::pair<glm::vec3, glm::vec3>> out;
  for (const auto& [edge, n] : uses)
    if (n == 1)
      out.push_back({{edge.first[0], edge.first[1], edge.first[2]}, {edge.second[0], edge.second[1], edge.second[2]}});
  return out;
}

TEST(NurbsEvaluation, BilinearPatchMatchesFormula) {
  const glm::vec3 p00(0, 0, 0), p10(2, 0, 1), p01(0, 3, -1), p11(2.5f, 3.5f, 2);
  const NurbsPatch patch = makePatch(1, 1, 2, 2, {{p00, 1}, {p10, 1}, {p01, 1}, {p11, 1}});
  EXPECT_TRUE(validateNurbsPatch(patch).empty());
  for (float u : {0.0f, 0.25f, 0.5f, 0.9f, 1.0f})
    for (float v : {0.0f, 0.3f, 0.75f, 1.0f}) {
      glm::vec3 n;
      const glm::vec3 p = evaluateNurbs(patch, u, v, &n);
      const glm::vec3 expect = (1 - u) * (1 - v) * p00 + u * (1 - v) * p10 + (1 - u) * v * p01 + u * v * p11;
      EXPECT_NEAR(glm::distance(p, expect), 0.0f, 1e-5f) << u << " " << v;
      const glm::vec3 su = (1 - v) * (p10 - p00) + v * (p11 - p01), sv = (1 - u) * (p01 - p00) + u * (p11 - p10);
      EXPECT_NEAR(glm::distance(n, glm::normalize(glm::cross(su, sv))), 0.0f, 1e-5f);
    }
}

TEST(NurbsEvaluation, RationalQuarterCylinderIsExact) {
  const float r = 2.5f, h = 4.0f;
  const NurbsPatch patch = cylinderQuarter(0, r, h);
  ASSERT_TRUE(validateNurbsPatch(patch).empty());
  for (int i = 0; i <= 20; ++i)
    for (float v : {0.0f, 0.5f, 1.0f}) {
      const float u = static_cast<float>(i) / 20.0f;
      glm::vec3 n;
      const glm::vec3 p = evaluateNurbs(patch, u, v, &n);
      EXPECT_NEAR(std::hypot(p.x, p.y), r, 1e-5f);
      EXPECT_NEAR(p.z, v * h, 1e-5f);
      EXPECT_GE(p.x, -1e-6f);
      EXPECT_GE(p.y, -1e-6f);
      EXPECT_NEAR(glm::distance(n, glm::vec3(p.x / r, p.y / r, 0.0f)), 0.0f, 1e-5f) << "outward radial normal";
    }
  // The parameter midpoint of a symmetric quarter is at 45 degrees.
  const glm::vec3 mid = evaluateNurbs(patch, 0.5f, 0.0f);
  EXPECT_NEAR(mid.x, r * 0.70710678f, 1e-5f);
  EXPECT_NEAR(mid.y, r * 0.70710678f, 1e-5f);
}

TEST(NurbsEvaluation, NonUniformKnotsReproduceLinearFunctions) {
  // Control points at the Greville abscissae reproduce x = u and y = v exactly (linear
  // precision), for any knot vector, degree and uniform weight: checks the basis functions.
  const uint32_t du = 3, dv = 2, cu = 7, cv = 5;
  NurbsPatch p;
  p.degree_u = du;
  p.degree_v = dv;
  p.count_u = cu;
  p.count_v = cv;
  p.knots_u = {1, 1, 1, 1, 1.5f, 2.5f, 2.5f, 4, 4, 4, 4};
  p.knots_v = {0, 0, 0.2f, 0.7f, 1, 1.3f, 2, 2};  // not clamped at either end
  for (uint32_t j = 0; j < cv; ++j)
    for (uint32_t i = 0; i < cu; ++i) {
      float gu = 0, gv = 0;
      for (uint32_t k = 1; k <= du; ++k) gu += p.knots_u[i + k] / du;
      for (uint32_t k = 1; k <= dv; ++k) gv += p.knots_v[j + k] / dv;
      p.control_points.push_back({gu, gv, 0.0f, 2.0f});
    }
  ASSERT_EQ(validateNurbsPatch(p), "");
  const NurbsDomain d = nurbsDomain(p);
  EXPECT_EQ(d.u0, 1.0f);
  EXPECT_EQ(d.u1, 4.0f);
  EXPECT_EQ(d.v0, 0.2f);
  EXPECT_EQ(d.v1, 1.3f);
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> uu(d.u0, d.u1), vv(d.v0, d.v1);
  for (int i = 0; i < 500; ++i) {
    const float u = uu(rng), v = vv(rng);
    glm::vec3 n;
    const glm::vec3 s = evaluateNurbs(p, u, v, &n);
    EXPECT_NEAR(s.x, u, 2e-5f);
    EXPECT_NEAR(s.y, v, 2e-5f);
    EXPECT_NEAR(n.z, 1.0f, 1e-5f);
  }
  EXPECT_NEAR(evaluateNurbs(p, d.u1, d.v1).x, 4.0f, 1e-5f);  // domain end uses the last span
}

TEST(NurbsEvaluation, NormalMatchesFiniteDifferences) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> c(-1.0f, 1.0f), w(0.5f, 2.0f);
  std::vector<glm::vec4> pts;
  for (int j = 0; j < 5; ++j)
    for (int i = 0; i < 4; ++i) pts.push_back({i + 0.3f * c(rng), j + 0.3f * c(rng), c(rng), w(rng)});
  const NurbsPatch p = makePatch(3, 2, 4, 5, pts);
  for (float u : {0.1f, 0.4f, 0.77f})
    for (float v : {0.2f, 0.5f, 0.9f}) {
      glm::vec3 n;
      evaluateNurbs(p, u, v, &n);
      const float e = 1e-3f;
      const glm::vec3 su = evaluateNurbs(p, u + e, v) - evaluateNurbs(p, u - e, v);
      const glm::vec3 sv = evaluateNurbs(p, u, v + e) - evaluateNurbs(p, u, v - e);
      EXPECT_NEAR(glm::distance(n, glm::normalize(glm::cross(su, sv))), 0.0f, 2e-3f);
    }
}

TEST(NurbsValidation, RejectsBadPatches) {
  const NurbsPatch good = cylinderQuarter(0, 1.0f, 1.0f);
  ASSERT_EQ(validateNurbsPatch(good), "");
  struct Case {
    const char* expect;
    std::function<void(NurbsPatch&)> damage;
  };
  const std::vector<Case> cases = {
      {"degree", [](NurbsPatch& p) { p.degree_v = 0; }},
      {"degree", [](NurbsPatch& p) { p.degree_u = 40; }},
      {"exceed the degree", [](NurbsPatch& p) { p.count_u = 2; }},
      {"control points", [](NurbsPatch& p) { p.control_points.pop_back(); }},
      {"control points", [](NurbsPatch& p) { p.count_v = 3; p.knots_v = clampedKnots(1, 3); }},
      {"entries", [](NurbsPatch& p) { p.knots_u.pop_back(); }},
      {"decreasing", [](NurbsPatch& p) { p.knots_u = {0, 0, 0, 1, 0.5f, 1}; }},
      {"empty domain", [](NurbsPatch& p) { p.knots_v = {0, 1, 1, 2}; }},
      {"non-finite", [](NurbsPatch& p) { p.knots_v[1] = NAN; }},
      {"multiplicity", [](NurbsPatch& p) { p.knots_v = {0, 0, 0, 1}; }},
      {"positive", [](NurbsPatch& p) { p.control_points[1].w = 0.0f; }},
      {"positive", [](NurbsPatch& p) { p.control_points[1].w = -1.0f; }},
      {"non-finite", [](NurbsPatch& p) { p.control_points[4].y = INFINITY; }},
      {"above", [](NurbsPatch& p) { p.count_u = 100000; }},
  };
  for (const Case& c : cases) {
    NurbsPatch p = good;
    c.damage(p);
    const std::string reason = validateNurbsPatch(p);
    EXPECT_NE(reason.find(c.expect), std::string::npos) << "got '" << reason << "', expected '" << c.expect << "'";
    // Invalid patches are skipped by tessellation, never crash it.
    NurbsPatchSet set{{p, good}};
    EXPECT_EQ(nurbsTriangleCount(set, 0.01f), nurbsTriangleCount(NurbsPatchSet{{good}}, 0.01f));
    EXPECT_EQ(tessellateSet(set, 0.01f).triangleCount(), nurbsTriangleCount(set, 0.01f));
  }
}

TEST(NurbsTessellation, QuarterCircleEdgesWithinTolerance) {
  for (float tol : {0.0005f, 0.002f, 0.01f}) {
    const float r = 1.0f;
    const TriangleMesh m = tessellateSet({{cylinderQuarter(0, r, 1.0f)}}, tol);
    expectWellFormed(m);
    double worst = 0.0;
    for (size_t t = 0; t < m.indices.size(); t += 3)
      for (int e = 0; e < 3; ++e) {
        const glm::dvec3 a = m.positions[m.indices[t + e]], b = m.positions[m.indices[t + (e + 1) % 3]];
        const glm::dvec3 mid = 0.5 * (a + b);
        worst = std::max(worst, r - std::hypot(mid.x, mid.y));
      }
    EXPECT_LE(worst, tol) << tol;
    EXPECT_GT(worst, tol / 4) << "much finer than needed at " << tol;
  }
}

TEST(NurbsTessellation, SinglePatchFullCylinderClosesItsSeam) {
  // The classic 9-point rational circle (double interior knots) swept up: one patch whose left and
  // right borders coincide. The seam must weld; only the two rims stay open.
  const float r = 0.8f, h = 2.0f, tol = 0.001f;
  NurbsPatch p = makePatch(2, 1, 9, 2, {});
  p.knots_u = {0, 0, 0, 1, 1, 2, 2, 3, 3, 4, 4, 4};
  for (float z : {0.0f, h}) {
    for (int k = 0; k < 4; ++k) {
      const auto q = quarter(k, r, z);
      p.control_points.push_back(q[0]);
      p.control_points.push_back(q[1]);
    }
    p.control_points.push_back(quarter(0, r, z)[0]);
  }
  ASSERT_EQ(validateNurbsPatch(p), "");
  const TriangleMesh m = tessellateSet({{p}}, tol);
  EXPECT_EQ(m.triangleCount(), nurbsTriangleCount({{p}}, tol));
  const MeshTopologyReport rep = checkWatertight(m);
  size_t rim_vertices = 0;
  for (const glm::vec3& q : m.positions) rim_vertices += q.z == 0.0f || q.z == h;
  EXPECT_EQ(rep.boundary_edges, rim_vertices);
  EXPECT_EQ(rep.non_manifold_edges, 0u);
  EXPECT_EQ(rep.rejected_faces, 0u);
  double worst = 0.0;
  for (size_t t = 0; t < m.indices.size(); t += 3)
    for (int e = 0; e < 3; ++e) {
      const glm::dvec3 a = m.positions[m.indices[t + e]], b = m.positions[m.indices[t + (e + 1) % 3]];
      const glm::dvec3 mid = 0.5 * (a + b);
      worst = std::max(worst, r - std::hypot(mid.x, mid.y));
    }
  EXPECT_LE(worst, tol);
  EXPECT_GE(rim_vertices, 2u * arcSegments(r, 6.2831855f, tol)) << "at least as fine as a primitive cylinder";
}

// A 2x2 set of bicubic patches over [0, 2]^2 sharing borders; patch (1, 1) has a tall bump
// inside, so its interior needs a much finer grid than its neighbours. Patches are stored with
// different parameter orientations and knot ranges (always counter-clockwise seen from +Z).
NurbsPatchSet twoByTwo(float bump) {
  // Global 7x7 control net; z varies smoothly so shared borders are curved.
  auto z = [](int i, int j) { return 0.15f * std::sin(0.9f * i) + 0.1f * std::cos(1.3f * j); };
  glm::vec4 net[7][7];
  for (int j = 0; j < 7; ++j)
    for (int i = 0; i < 7; ++i) net[j][i] = {i / 3.0f, j / 3.0f, z(i, j), 1.0f};
  net[4][4].z += bump;
  net[4][5].z += bump;
  net[5][4].z += bump;
  net[5][5].z -= bump;
  NurbsPatchSet set;
  for (int pj = 0; pj < 2; ++pj)
    for (int pi = 0; pi < 2; ++pi) {
      const int variant = pj * 2 + pi;
      NurbsPatch p = makePatch(3, 3, 4, 4, {});
      for (int b = 0; b < 4; ++b)
        for (int a = 0; a < 4; ++a) {
          // (a, b) are the patch's own (u, v) indices; (i, j) the net's.
          int i = a, j = b;
          if (variant == 1) i = 3 - a, j = 3 - b;  // rotated 180 degrees
          if (variant == 2) i = 3 - b, j = a;      // rotated 90 degrees
          if (variant == 3) i = b, j = 3 - a;      // rotated -90 degrees
          p.control_points.push_back(net[pj * 3 + j][pi * 3 + i]);
        }
      if (variant == 1) p.knots_u = clampedKnots(3, 4, 5.0f, 7.0f);
      if (variant == 2) p.knots_v = clampedKnots(3, 4, -1.0f, 3.0f);
      set.patches.push_back(p);
    }
  return set;
}

TEST(NurbsTessellation, SharedBordersAreCrackFreeWithDifferentInteriorResolutions) {
  const float tol = 0.002f;
  const NurbsPatchSet set = twoByTwo(1.5f);
  // The bumped patch needs far more triangles than a flat-ish neighbour.
  const uint64_t bumped = nurbsTriangleCount({{set.patches[3]}}, tol);
  const uint64_t plain = nurbsTriangleCount({{set.patches[0]}}, tol);
  EXPECT_GT(bumped, 4 * plain);

  const TriangleMesh m = tessellateSet(set, tol);
  expectWellFormed(m);
  EXPECT_EQ(m.triangleCount(), nurbsTriangleCount(set, tol));
  const MeshTopologyReport r = checkWatertight(m);
  EXPECT_EQ(r.non_manifold_edges, 0u);
  EXPECT_EQ(r.rejected_faces, 0u);
  EXPECT_EQ(r.degenerate_faces, 0u);
  // Every boundary edge lies on the outer square: no cracks, no T-junctions inside.
  const auto boundary = boundaryEdges(m);
  auto on_outer = [](const glm::vec3& p) {
    return p.x == 0.0f || p.y == 0.0f || std::abs(p.x - 2.0f) < 1e-6f || std::abs(p.y - 2.0f) < 1e-6f;
  };
  size_t outer_vertices = 0;
  std::vector<bool> seen(m.positions.size(), false);
  for (size_t i = 0; i < m.positions.size(); ++i) outer_vertices += on_outer(m.positions[i]);
  for (const auto& [a, b] : boundary) EXPECT_TRUE(on_outer(a) && on_outer(b)) << a.x << "," << a.y << " " << b.x << "," << b.y;
  EXPECT_EQ(r.boundary_edges, boundary.size());
  EXPECT_EQ(r.boundary_edges, outer_vertices) << "the outer boundary is one closed loop of welded vertices";
  EXPECT_GT(r.boundary_edges, 8u);
}

TEST(NurbsTessellation, ClosedCylinderOfTwelvePatchesIsWatertight) {
  for (float tol : {0.0005f, 0.002f, 0.05f, 10.0f}) {
    const NurbsPatchSet set = closedCylinder(0.5f, 1.5f);
    const TriangleMesh m = tessellateSet(set, tol);
    expectWellFormed(m);
    EXPECT_EQ(m.triangleCount(), nurbsTriangleCount(set, tol));
    const MeshTopologyReport r = checkWatertight(m);
    EXPECT_TRUE(r.watertight()) << tol << ": boundary " << r.boundary_edges << " non-manifold "
                                << r.non_manifold_edges << " rejected " << r.rejected_faces << " degenerate "
                                << r.degenerate_faces;
    // Outward: positive signed volume close to the cylinder's.
    double volume = 0.0;
    for (size_t t = 0; t < m.indices.size(); t += 3) {
      const glm::dvec3 a = m.positions[m.indices[t]], b = m.positions[m.indices[t + 1]], c = m.positions[m.indices[t + 2]];
      volume += glm::dot(a, glm::cross(b, c)) / 6.0;
    }
    const double exact = std::numbers::pi * 0.25 * 1.5;
    EXPECT_GT(volume, 0.0);
    EXPECT_LE(volume, exact * (1 + 1e-5));
    if (tol < 0.01f) {
      EXPECT_GT(volume, exact * 0.98);
    }
    // Side vertex normals are radial, cap normals vertical.
    for (size_t i = 0; i < m.positions.size(); ++i) {
      const glm::vec3 p = m.positions[i], n = m.normals[i];
      if (p.z > 1e-4f && p.z < 1.5f - 1e-4f) {
        EXPECT_NEAR(glm::distance(n, glm::normalize(glm::vec3(p.x, p.y, 0))), 0.0f, 1e-3f);
      } else if (std::hypot(p.x, p.y) < 0.5f - 1e-4f) {
        EXPECT_NEAR(std::abs(n.z), 1.0f, 1e-4f);
        EXPECT_GT(n.z * (p.z - 0.75f), 0.0f);
      }
    }
  }
}

// A "pillow" cube: six biquadratic patches whose borders bulge outwards; each face is
// parameterised differently and every shared border appears once reversed.
NurbsPatchSet pillowCube(float bulge) {
  auto point = [&](int x, int y, int z) {  // x, y, z in {-1, 0, 1}: corners, edge midpoints, centres
    const int zeros = (x == 0) + (y == 0) + (z == 0);
    const float push = zeros == 0 ? 1.0f : zeros == 1 ? 1.0f + bulge : 1.0f + 1.5f * bulge;
    return glm::vec4(x * push, y * push, z * push, 1.0f);
  };
  NurbsPatchSet set;
  // For each face: outward axis n and tangents s, t with s x t = n (so u along s, v along t).
  const int faces[6][3][3] = {
      {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}},   {{-1, 0, 0}, {0, 0, 1}, {0, 1, 0}},
      {{0, 1, 0}, {0, 0, 1}, {1, 0, 0}},   {{0, -1, 0}, {1, 0, 0}, {0, 0, 1}},
      {{0, 0, 1}, {1, 0, 0}, {0, 1, 0}},   {{0, 0, -1}, {0, 1, 0}, {1, 0, 0}},
  };
  for (const auto& f : faces) {
    std::vector<glm::vec4> pts;
    for (int b = -1; b <= 1; ++b)
      for (int a = -1; a <= 1; ++a)
        pts.push_back(point(f[0][0] + a * f[1][0] + b * f[2][0], f[0][1] + a * f[1][1] + b * f[2][1],
                            f[0][2] + a * f[1][2] + b * f[2][2]));
    set.patches.push_back(makePatch(2, 2, 3, 3, pts));
  }
  return set;
}

TEST(NurbsTessellation, ClosedPillowCubeIsWatertight) {
  for (float tol : {0.001f, 0.01f}) {
    const NurbsPatchSet set = pillowCube(0.3f);
    const TriangleMesh m = tessellateSet(set, tol);
    EXPECT_EQ(m.triangleCount(), nurbsTriangleCount(set, tol));
    const MeshTopologyReport r = checkWatertight(m);
    EXPECT_TRUE(r.watertight()) << tol << ": boundary " << r.boundary_edges << " non-manifold "
                                << r.non_manifold_edges << " rejected " << r.rejected_faces;
    for (size_t i = 0; i < m.positions.size(); ++i) EXPECT_GT(glm::dot(m.normals[i], m.positions[i]), 0.0f);
  }
}

// Two patches glued along a random rational B-spline border. The second patch carries the border
// the other way round, with mirrored and shifted knots, as another CAD face would. With knots that
// mirror exactly (dyadic values) the border samples must be the same floats from both sides; with
// arbitrary knots they differ by rounding and the snapping weld must still close the seam.
TEST(NurbsTessellation, RandomSharedBordersWeld) {
  std::mt19937 rng(21);
  std::uniform_real_distribution<float> c(-1.0f, 1.0f), w(0.5f, 2.0f), gap(0.05f, 1.0f);
  std::uniform_int_distribution<int> deg(2, 3), extra(0, 4), eighths(1, 8);
  for (int trial = 0; trial < 80; ++trial) {
    const bool dyadic = trial % 2 == 0;
    const uint32_t p = deg(rng), n = p + 1 + extra(rng);
    std::vector<glm::vec4> border(n);
    for (uint32_t i = 0; i < n; ++i) border[i] = {3.0f * i / n + 0.2f * c(rng), 0.3f * c(rng), 0.5f * c(rng), w(rng)};
    std::vector<float> knots(n + p + 1);
    float x = dyadic ? 0.0f : 0.3f * c(rng);
    for (uint32_t i = 0; i < knots.size(); ++i) {
      if (i > p && i <= n) x += dyadic ? eighths(rng) / 8.0f : gap(rng);
      knots[i] = x;
    }
    const float mirror = knots.front() + knots.back() + (dyadic ? 0.375f : 0.37f);
    std::vector<float> mirrored(knots.size());
    for (size_t i = 0; i < knots.size(); ++i) mirrored[i] = mirror - knots[knots.size() - 1 - i];

    NurbsPatch a = makePatch(p, 1, n, 2, {});
    a.knots_u = knots;
    NurbsPatch b = makePatch(p, 1, n, 2, {});
    b.knots_u = mirrored;
    for (uint32_t i = 0; i < n; ++i) a.control_points.push_back(border[i]);
    for (uint32_t i = 0; i < n; ++i) a.control_points.push_back(border[i] + glm::vec4(0, 1, 0.2f, 0));
    for (uint32_t i = 0; i < n; ++i) b.control_points.push_back(border[n - 1 - i]);
    for (uint32_t i = 0; i < n; ++i) b.control_points.push_back(border[n - 1 - i] + glm::vec4(0, -1, 0.1f, 0));
    ASSERT_EQ(validateNurbsPatch(a), "");
    ASSERT_EQ(validateNurbsPatch(b), "");

    const float tol = 0.0005f;
    const TriangleMesh ma = tessellateSet({{a}}, tol), mb = tessellateSet({{b}}, tol), both = tessellateSet({{a, b}}, tol);
    // Vertices of A's mesh that B's mesh also has: the shared border samples (exactly, and
    // within 1e-5, far below the sample spacing).
    std::set<std::array<float, 3>> in_b;
    for (const glm::vec3& q : mb.positions) in_b.insert({q.x, q.y, q.z});
    size_t shared_exact = 0, shared = 0;
    for (const glm::vec3& q : ma.positions) {
      shared_exact += in_b.count({q.x, q.y, q.z});
      bool near = false;
      for (const glm::vec3& o : mb.positions) near |= glm::distance(q, o) < 1e-5f;
      shared += near;
    }
    if (dyadic) {
      EXPECT_EQ(shared_exact, shared) << "exactly mirrored knots give identical floats, trial " << trial;
    }
    const MeshTopologyReport ra = checkWatertight(ma), rb = checkWatertight(mb), r = checkWatertight(both);
    ASSERT_GE(shared, 3u) << trial;
    EXPECT_EQ(both.positions.size(), ma.positions.size() + mb.positions.size() - shared) << trial;
    EXPECT_EQ(r.boundary_edges, ra.boundary_edges + rb.boundary_edges - 2 * (shared - 1)) << trial;
    EXPECT_EQ(r.non_manifold_edges, 0u);
    EXPECT_EQ(r.rejected_faces, 0u);
  }
}

NurbsPatch randomPatch(std::mt19937& rng) {
  std::uniform_int_distribution<int> deg(1, 4), extra(0, 4), coin(0, 3);
  std::uniform_real_distribution<float> c(-2.0f, 2.0f), w(0.2f, 3.0f), gap(0.0f, 1.0f);
  NurbsPatch p;
  p.degree_u = deg(rng);
  p.degree_v = deg(rng);
  p.count_u = p.degree_u + 1 + extra(rng);
  p.count_v = p.degree_v + 1 + extra(rng);
  auto knots = [&](uint32_t d, uint32_t n) {
    if (coin(rng) != 0) {
      const float a = c(rng);
      return clampedKnots(d, n, a, a + 0.5f + 2.0f * gap(rng));
    }
    // Unclamped, with repeated knots (multiplicity <= degree) outside and inside the domain.
    std::vector<float> k(n + d + 1);
    float x = c(rng);
    uint32_t multiplicity = 0;
    for (uint32_t i = 0; i < k.size(); ++i) {
      const bool repeat = i > 0 && multiplicity < d && coin(rng) == 0 && !(i == n && k[d] == x);
      if (!repeat) x += gap(rng) + 0.05f;
      multiplicity = repeat ? multiplicity + 1 : 1;
      k[i] = x;
    }
    return k;
  };
  p.knots_u = knots(p.degree_u, p.count_u);
  p.knots_v = knots(p.degree_v, p.count_v);
  for (uint32_t i = 0; i < p.count_u * p.count_v; ++i) p.control_points.push_back({c(rng), c(rng), c(rng), w(rng)});
  return p;
}

TEST(NurbsTessellation, CountEqualsAppendedTriangles) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> log_tol(-2.5f, 0.0f);
  size_t valid_sets = 0;
  for (int i = 0; i < 200; ++i) {
    NurbsPatchSet set;
    const int patches = 1 + i % 4;
    for (int k = 0; k < patches; ++k) set.patches.push_back(randomPatch(rng));
    const float tol = std::pow(10.0f, log_tol(rng));
    const uint64_t expect = nurbsTriangleCount(set, tol);
    TriangleMesh m;
    m.positions = {{0, 0, 0}};  // appending after existing data without normals
    tessellateNurbs(set, tol, m);
    ASSERT_EQ(m.triangleCount(), expect) << i;
    EXPECT_TRUE(m.normals.empty());
    expectWellFormed(m);
    valid_sets += expect > 0;
  }
  EXPECT_EQ(valid_sets, 200u);
  // Also through the Geometry dispatch.
  const NurbsPatchSet cyl = closedCylinder(1.0f, 1.0f);
  EXPECT_EQ(triangleCount(Geometry{cyl}, 0.01f), nurbsConformingTriangleCount(cyl, 0.01f));
}

TEST(NurbsTessellation, HostileInputIsBounded) {
  // Huge coordinates at a tiny tolerance, many spans: the set is coarsened to the work bound.
  NurbsPatch p;
  p.degree_u = p.degree_v = 3;
  p.count_u = p.count_v = 600;
  p.knots_u = clampedKnots(3, 600);
  p.knots_v = clampedKnots(3, 600);
  std::mt19937 rng(9);
  std::uniform_real_distribution<float> c(-1e30f, 1e30f);
  for (uint32_t i = 0; i < 600 * 600; ++i) p.control_points.push_back({c(rng), c(rng), c(rng), 1.0f});
  const NurbsPatchSet set{{p}};
  const auto start = std::chrono::steady_clock::now();
  const uint64_t n = nurbsTriangleCount(set, 1e-30f);
  EXPECT_LE(n, uint64_t{1} << 23);
  EXPECT_GT(n, 0u);
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 10.0);
  // Extreme but valid weights and coordinates: same count as built, finite output.
  std::uniform_real_distribution<float> log_w(-6.0f, 6.0f), big(-1e20f, 1e20f);
  for (int i = 0; i < 50; ++i) {
    NurbsPatch q = randomPatch(rng);
    for (glm::vec4& cp : q.control_points) cp = {i % 2 ? big(rng) : cp.x, cp.y, cp.z, std::pow(10.0f, log_w(rng))};
    ASSERT_EQ(validateNurbsPatch(q), "");
    // Weight ratios up to 1e12 inflate the rational factor of the segment bound; a coarse
    // tolerance keeps this a test of robustness rather than of the work cap.
    const float tol = 1e30f;
    const TriangleMesh m = tessellateSet({{q}}, tol);
    EXPECT_EQ(m.triangleCount(), nurbsTriangleCount({{q}}, tol));
    for (const glm::vec3& v : m.positions) ASSERT_TRUE(std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z));
  }
  // Bad tolerances give the coarsest plan, not a failure.
  for (float tol : {0.0f, -1.0f, NAN, INFINITY}) {
    const NurbsPatchSet cyl = closedCylinder(1.0f, 1.0f);
    const TriangleMesh m = tessellateSet(cyl, tol);
    EXPECT_EQ(m.triangleCount(), nurbsTriangleCount(cyl, tol));
    EXPECT_TRUE(checkWatertight(m).watertight());
  }
}

}  // namespace
}  // namespace tw
