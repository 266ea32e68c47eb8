// Tests of primitive tessellation: exact counts, chordal error, watertightness, outward normals
// and bounded work on hostile parameters.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <unordered_map>

#include "tessellate.h"
#include "watertight_check.h"

namespace tw {
namespace {

constexpr double kPi = std::numbers::pi;

double sagitta(double radius, double angle) { return radius * (1.0 - std::cos(angle / 2.0)); }

// Structural validity: indices in range, normals absent or one per position and unit length.
void expectWellFormed(const TriangleMesh& m) {
  ASSERT_EQ(m.indices.size() % 3, 0u);
  for (uint32_t i : m.indices) ASSERT_LT(i, m.positions.size());
  ASSERT_TRUE(m.normals.empty() || m.normals.size() == m.positions.size());
  for (const glm::vec3& n : m.normals) ASSERT_NEAR(glm::length(n), 1.0f, 1e-4f);
  for (const glm::vec3& p : m.positions) ASSERT_TRUE(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z));
}

TriangleMesh build(const Primitive& p, float tol) {
  TriangleMesh m;
  tessellatePrimitive(p, tol, m);
  return m;
}

// Signed volume by the divergence theorem: positive when faces wind counter-clockwise seen from
// outside.
double signedVolume(const TriangleMesh& m) {
  double v = 0.0;
  for (size_t t = 0; t < m.indices.size(); t += 3) {
    const glm::dvec3 a = m.positions[m.indices[t]], b = m.positions[m.indices[t + 1]], c = m.positions[m.indices[t + 2]];
    v += glm::dot(a, glm::cross(b, c)) / 6.0;
  }
  return v;
}

// Every non-degenerate triangle's winding agrees with the normals of its vertices.
void expectWindingMatchesNormals(const TriangleMesh& m) {
  ASSERT_EQ(m.normals.size(), m.positions.size());
  size_t bad = 0;
  for (size_t t = 0; t < m.indices.size(); t += 3) {
    const uint32_t i0 = m.indices[t], i1 = m.indices[t + 1], i2 = m.indices[t + 2];
    const glm::vec3 face = glm::cross(m.positions[i1] - m.positions[i0], m.positions[i2] - m.positions[i0]);
    if (glm::length(face) < 1e-12f) continue;
    const glm::vec3 avg = m.normals[i0] + m.normals[i1] + m.normals[i2];
    if (glm::dot(face, avg) <= 0.0f) ++bad;
  }
  EXPECT_EQ(bad, 0u);
}

// Largest distance from an edge midpoint to the surface, given the surface's distance function.
template <typename Distance>
double maxEdgeMidpointError(const TriangleMesh& m, Distance distance) {
  double worst = 0.0;
  for (size_t t = 0; t < m.indices.size(); t += 3)
    for (int e = 0; e < 3; ++e) {
      const glm::dvec3 a = m.positions[m.indices[t + e]], b = m.positions[m.indices[t + (e + 1) % 3]];
      worst = std::max(worst, distance(0.5 * (a + b), a, b));
    }
  return worst;
}

TEST(ArcSegments, DefaultToleranceKeepsAHundredMillimetrePipeAtSixteen) {
  EXPECT_EQ(arcSegments(0.1f, static_cast<float>(2 * kPi), kDefaultChordalTolerance), 16u);
}

TEST(ArcSegments, FewestSegmentsWithinTolerance) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> log_r(-3.0f, 3.0f), sweep_d(0.01f, static_cast<float>(2 * kPi)),
      log_tol(-5.0f, 0.0f);
  for (int i = 0; i < 20000; ++i) {
    const float r = std::pow(10.0f, log_r(rng)), sweep = sweep_d(rng), tol = std::pow(10.0f, log_tol(rng));
    const uint32_t n = arcSegments(r, sweep, tol);
    ASSERT_GE(n, 1u);
    ASSERT_LE(n, kMaxArcSegments);
    if (n < kMaxArcSegments) {
      EXPECT_LE(sagitta(r, sweep / n), tol * (1 + 1e-5)) << r << " " << sweep << " " << tol;
    }
    if (n > 1 && n < kMaxArcSegments) {
      EXPECT_GT(sagitta(r, sweep / (n - 1)), tol * (1 - 1e-5)) << r << " " << sweep;
    }
  }
}

TEST(ArcSegments, MinimumForBadInputAndCapForHostileInput) {
  const float full = static_cast<float>(2 * kPi);
  EXPECT_EQ(arcSegments(1.0f, full, 10.0f), 3u);
  EXPECT_EQ(arcSegments(1.0f, 1.0f, 10.0f), 1u);
  EXPECT_EQ(arcSegments(-1.0f, full, 0.01f), 3u);
  EXPECT_EQ(arcSegments(NAN, full, 0.01f), 3u);
  EXPECT_EQ(arcSegments(1.0f, full, 0.0f), 3u);
  EXPECT_EQ(arcSegments(1.0f, full, -1.0f), 3u);
  EXPECT_EQ(arcSegments(1.0f, full, NAN), 3u);
  EXPECT_EQ(arcSegments(INFINITY, full, 0.01f), 3u);
  EXPECT_EQ(arcSegments(1.0f, NAN, 0.01f), 1u);
  EXPECT_EQ(arcSegments(1.0f, -1.0f, 0.01f), 1u);
  EXPECT_EQ(arcSegments(1.0f, INFINITY, 0.01f), 1u);
  EXPECT_EQ(arcSegments(1e30f, full, 1e-30f), kMaxArcSegments);
  EXPECT_EQ(arcSegments(1e30f, 1e30f, 1e-30f), kMaxArcSegments);
  EXPECT_EQ(arcSegments(1.0f, full, 1e-38f), kMaxArcSegments);
}

// Random primitives of every type, including edge cases (zero radii, axis points, open sweeps,
// clockwise and duplicated profile points).
class PrimitiveFactory {
 public:
  explicit PrimitiveFactory(uint32_t seed) : rng_(seed) {}
  float uni(float a, float b) { return std::uniform_real_distribution<float>(a, b)(rng_); }
  int pick(int n) { return std::uniform_int_distribution<int>(0, n - 1)(rng_); }

  Primitive make(int type) {
    switch (type) {
      case 0: return Cylinder{uni(0.01f, 3.0f), uni(0.01f, 10.0f), pick(2) == 0};
      case 1: {
        Cone c{uni(0.0f, 3.0f), uni(0.0f, 3.0f), uni(0.01f, 5.0f), pick(2) == 0};
        if (pick(4) == 0) c.radius_top = 0.0f;
        if (pick(6) == 0) c.radius_bottom = 0.0f;
        if (c.radius_bottom == 0.0f && c.radius_top == 0.0f) c.radius_bottom = 0.5f;
        return c;
      }
      case 2: return Sphere{uni(0.01f, 5.0f)};
      case 3: {
        const float major = uni(0.1f, 5.0f);
        return TorusSegment{major, uni(0.01f, 0.99f) * major, pick(4) == 0 ? static_cast<float>(2 * kPi) : uni(0.05f, 6.2f)};
      }
      case 4: return Box{{uni(0.01f, 4.0f), uni(0.01f, 4.0f), uni(0.01f, 4.0f)}};
      case 5: {
        Extrusion e;
        const int k = 3 + pick(40);
        for (int i = 0; i < k; ++i) {  // star-shaped, hence simple
          const float a = static_cast<float>(2 * kPi * i / k), r = uni(0.2f, 2.0f);
          e.profile.push_back({r * std::cos(a), r * std::sin(a)});
          if (pick(10) == 0) e.profile.push_back(e.profile.back());  // duplicate
        }
        if (pick(3) == 0) std::reverse(e.profile.begin(), e.profile.end());  // clockwise
        if (pick(4) == 0) e.profile.push_back(e.profile.front());            // explicitly closed
        e.height = uni(0.01f, 5.0f);
        return e;
      }
      default: {
        Revolution r;
        const int k = 2 + pick(12);
        const bool from_axis = pick(2) == 0, to_axis = pick(2) == 0;
        for (int i = 0; i < k; ++i) {
          float radius = uni(0.0f, 2.0f);
          if ((i == 0 && from_axis) || (i == k - 1 && to_axis) || pick(8) == 0) radius = 0.0f;
          r.profile.push_back({radius, static_cast<float>(i) * uni(0.1f, 1.0f)});
          if (pick(10) == 0) r.profile.push_back(r.profile.back());
        }
        if (k == 2) r.profile[pick(2)].x = 1.0f;  // never entirely on the axis
        r.profile[k / 2].x = std::max(r.profile[k / 2].x, 0.1f);
        if (pick(3) == 0) std::reverse(r.profile.begin(), r.profile.end());
        r.sweep_rad = pick(3) == 0 ? static_cast<float>(2 * kPi) : uni(0.05f, 6.2f);
        return r;
      }
    }
  }

 private:
  std::mt19937 rng_;
};

TEST(PrimitiveTessellation, CountEqualsAppendedTrianglesForEveryType) {
  PrimitiveFactory f(42);
  for (int type = 0; type < 7; ++type)
    for (int i = 0; i < 300; ++i) {
      const Primitive p = f.make(type);
      const float tol = std::pow(10.0f, f.uni(-3.0f, -0.3f));
      const TriangleMesh m = build(p, tol);
      ASSERT_EQ(m.triangleCount(), primitiveTriangleCount(p, tol)) << "type " << type << " #" << i;
      ASSERT_GT(m.triangleCount(), 0u) << "type " << type << " #" << i;
      expectWellFormed(m);
    }
}

TEST(PrimitiveTessellation, AppendsAfterExistingGeometry) {
  const Primitive cyl = Cylinder{0.5f, 2.0f, true};
  TriangleMesh first = build(Sphere{1.0f}, 0.01f);
  const size_t base_vertices = first.positions.size(), base_indices = first.indices.size();
  tessellatePrimitive(cyl, 0.01f, first);
  const TriangleMesh alone = build(cyl, 0.01f);
  ASSERT_EQ(first.indices.size(), base_indices + alone.indices.size());
  for (size_t i = 0; i < alone.indices.size(); ++i)
    EXPECT_EQ(first.indices[base_indices + i], alone.indices[i] + base_vertices);
  expectWellFormed(first);

  // Positions without normals stay without normals: the invariant "empty or one per position".
  TriangleMesh bare;
  bare.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  bare.indices = {0, 1, 2};
  tessellatePrimitive(cyl, 0.01f, bare);
  EXPECT_TRUE(bare.normals.empty());
  EXPECT_EQ(bare.triangleCount(), 1 + primitiveTriangleCount(cyl, 0.01f));
  expectWellFormed(bare);
}

TEST(PrimitiveTessellation, CylinderEdgesWithinChordalTolerance) {
  for (float tol : {0.0005f, 0.002f, 0.01f, 0.1f}) {
    const float r = 0.35f;
    const TriangleMesh m = build(Cylinder{r, 1.5f, true}, tol);
    // Only edges on the curved wall: both ends on the rim radius.
    const double err = maxEdgeMidpointError(m, [&](const glm::dvec3& mid, const glm::dvec3& a, const glm::dvec3& b) {
      if (std::abs(std::hypot(a.x, a.y) - r) > 1e-5 || std::abs(std::hypot(b.x, b.y) - r) > 1e-5) return 0.0;
      return std::abs(std::hypot(mid.x, mid.y) - r);
    });
    EXPECT_LE(err, tol * (1 + 1e-4)) << tol;
    EXPECT_GT(err, tol * 0.3) << "tessellation much finer than needed at " << tol;
  }
}

TEST(PrimitiveTessellation, CurvedSurfaceErrorsWithinTolerance) {
  const float tol = 0.002f;
  // Sphere: ring and meridian edges within tolerance; quad diagonals of this doubly curved
  // surface within twice the tolerance (documented in docs/tessellation.md).
  const float R = 0.8f;
  const TriangleMesh s = build(Sphere{R}, tol);
  const double sphere_err = maxEdgeMidpointError(s, [&](const glm::dvec3& mid, const glm::dvec3& a, const glm::dvec3& b) {
    const double d = R - glm::length(mid);
    return (std::abs(a.z - b.z) < 1e-7) ? d : d / 2.0;
  });
  EXPECT_LE(sphere_err, tol * (1 + 1e-3));

  const TorusSegment t{1.2f, 0.3f, 1.3f};
  const TriangleMesh tm = build(t, tol);
  auto torus_distance = [&](const glm::dvec3& p) {
    return std::abs(std::hypot(std::hypot(p.x, p.y) - t.major_radius, p.z) - t.minor_radius);
  };
  const double torus_err = maxEdgeMidpointError(tm, [&](const glm::dvec3& mid, const glm::dvec3& a, const glm::dvec3& b) {
    const bool same_azimuth = std::abs(std::atan2(a.y, a.x) - std::atan2(b.y, b.x)) < 1e-6;
    const bool same_ring = std::abs(a.z - b.z) < 1e-7 && std::abs(std::hypot(a.x, a.y) - std::hypot(b.x, b.y)) < 1e-6;
    const double d = torus_distance(mid);
    return same_azimuth || same_ring ? d : d / 2.0;
  });
  EXPECT_LE(torus_err, tol * (1 + 1e-3));
}

Extrusion iProfile() {
  // An I-beam section 0.2 wide, 0.3 high, 0.02 web and flanges: concave, counter-clockwise.
  Extrusion e;
  e.profile = {{-0.1f, -0.15f}, {0.1f, -0.15f}, {0.1f, -0.13f}, {0.01f, -0.13f}, {0.01f, 0.13f}, {0.1f, 0.13f},
               {0.1f, 0.15f},   {-0.1f, 0.15f}, {-0.1f, 0.13f}, {-0.01f, 0.13f}, {-0.01f, -0.13f}, {-0.1f, -0.13f}};
  e.height = 2.0f;
  return e;
}

TEST(PrimitiveTessellation, ClosedPrimitivesAreWatertightWithOutwardNormals) {
  const float tol = 0.002f;
  Revolution vessel;  // a closed vessel: bottom centre, wall, shoulder, top centre
  vessel.profile = {{0.0f, 0.0f}, {1.0f, 0.0f}, {1.0f, 2.0f}, {0.5f, 2.5f}, {0.0f, 2.5f}};
  const double i_area = 2 * 0.2 * 0.02 + 0.02 * 0.26;
  struct Case {
    const char* name;
    Primitive p;
    double volume;      // exact solid volume
    double rel_margin;  // polygonal approximation stays below the true volume by at most this
  };
  const std::vector<Case> cases = {
      {"capped cylinder", Cylinder{0.5f, 2.0f, true}, kPi * 0.25 * 2.0, 0.01},
      {"capped cone", Cone{0.6f, 0.0f, 1.0f, true}, kPi * 0.36 / 3.0, 0.01},
      {"capped frustum", Cone{0.6f, 0.2f, 1.0f, true}, kPi * (0.36 + 0.12 + 0.04) / 3.0, 0.01},
      {"sphere", Sphere{0.7f}, 4.0 / 3.0 * kPi * 0.343, 0.02},
      {"box", Box{{0.5f, 1.0f, 1.5f}}, 6.0, 1e-6},
      {"I-beam extrusion", iProfile(), i_area * 2.0, 1e-5},
      {"full torus", TorusSegment{1.0f, 0.2f, static_cast<float>(2 * kPi)}, 2 * kPi * kPi * 0.04, 0.02},
      {"revolved vessel", vessel, kPi * 2.0 + kPi * 0.5 / 3.0 * (1.0 + 0.5 + 0.25), 0.01},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    const TriangleMesh m = build(c.p, tol);
    expectWellFormed(m);
    const MeshTopologyReport r = checkWatertight(m);
    EXPECT_TRUE(r.watertight()) << "boundary " << r.boundary_edges << " non-manifold " << r.non_manifold_edges
                                << " rejected " << r.rejected_faces << " degenerate " << r.degenerate_faces;
    const double v = signedVolume(m);
    EXPECT_GT(v, 0.0) << "inward winding";
    EXPECT_LE(v, c.volume * (1 + 1e-5));
    EXPECT_GE(v, c.volume * (1 - c.rel_margin));
    expectWindingMatchesNormals(m);
  }
}

// The top cap of an extrusion: triangles facing +Z whose vertices are all at the top.
std::vector<std::array<glm::vec3, 3>> topCap(const TriangleMesh& m, float h) {
  std::vector<std::array<glm::vec3, 3>> cap;
  for (size_t t = 0; t < m.indices.size(); t += 3) {
    const glm::vec3 a = m.positions[m.indices[t]], b = m.positions[m.indices[t + 1]], c = m.positions[m.indices[t + 2]];
    if (a.z == h && b.z == h && c.z == h) cap.push_back({a, b, c});
  }
  return cap;
}

TEST(PrimitiveTessellation, ConcaveCapsAreProperlyTriangulated) {
  // A fan would also have the right signed area and topology; only non-overlapping triangles have
  // every area non-negative and the absolute areas summing to the polygon's area.
  std::vector<Extrusion> profiles = {iProfile()};
  profiles.push_back({{{0, 0}, {3, 0}, {3, 1}, {1, 1}, {1, 3}, {0, 3}}, 1.0f});                      // L
  profiles.push_back({{{0, 0}, {3, 0}, {3, 3}, {2, 3}, {2, 1}, {1, 1}, {1, 3}, {0, 3}}, 1.0f});      // U
  Extrusion comb;  // 40 teeth
  comb.profile.push_back({0, 0});
  comb.profile.push_back({80, 0});
  for (int i = 39; i >= 0; --i) {
    comb.profile.push_back({2.0f * i + 1.5f, 1});
    comb.profile.push_back({2.0f * i + 1.5f, 5});
    comb.profile.push_back({2.0f * i + 0.5f, 5});
    comb.profile.push_back({2.0f * i + 0.5f, 1});
  }
  comb.height = 1.0f;
  profiles.push_back(comb);
  std::mt19937 rng(17);
  for (int s = 0; s < 50; ++s) {  // random star polygons (simple, usually concave), both windings
    Extrusion e;
    const int k = 5 + s * 3;
    for (int i = 0; i < k; ++i) {
      const float a = static_cast<float>(2 * kPi * i / k), r = std::uniform_real_distribution<float>(0.2f, 2.0f)(rng);
      e.profile.push_back({r * std::cos(a), r * std::sin(a)});
    }
    if (s % 2) std::reverse(e.profile.begin(), e.profile.end());
    profiles.push_back(e);
  }
  for (size_t i = 0; i < profiles.size(); ++i) {
    const Extrusion& e = profiles[i];
    const TriangleMesh m = build(e, 0.01f);
    double area = 0.0;
    for (size_t j = 0; j < e.profile.size(); ++j) {
      const glm::dvec2 a = e.profile[j], b = e.profile[(j + 1) % e.profile.size()];
      area += 0.5 * (a.x * b.y - b.x * a.y);
    }
    double sum_abs = 0.0;
    size_t negative = 0;
    for (const auto& t : topCap(m, e.height)) {
      const double z = 0.5 * glm::cross(glm::dvec3(t[1] - t[0]), glm::dvec3(t[2] - t[0])).z;
      sum_abs += std::abs(z);
      negative += z < -1e-9;
    }
    EXPECT_EQ(negative, 0u) << "profile " << i;
    EXPECT_NEAR(sum_abs, std::abs(area), 1e-4 * std::abs(area)) << "profile " << i;
    EXPECT_TRUE(checkWatertight(m).watertight()) << "profile " << i;
  }
}

// Renderers cull an extrusion's back faces only when its triangles enclose the solid: simple
// profiles in either winding, with repeated points, yes; profiles that cross, touch or fold back
// on themselves, or are degenerate, no.
TEST(PrimitiveTessellation, ExtrusionEnclosesItsSolidOnlyWhenTheProfileIsSimple) {
  using Profile = std::vector<glm::vec2>;
  auto encloses = [](const Profile& p) { return extrusionEnclosesSolid(std::span(p)); };
  Profile beam = iProfile().profile;
  EXPECT_TRUE(encloses(beam));
  std::reverse(beam.begin(), beam.end());
  EXPECT_TRUE(encloses(beam));  // clockwise: the tessellation turns it round
  EXPECT_TRUE(encloses({{0, 0}, {1, 0}, {1, 0}, {0, 1}, {0, 0}}));  // a repeat and a closing copy
  EXPECT_TRUE(encloses({{0, 0}, {2, 0}, {2, 2}, {1, 2}, {1, 1}, {0, 1}}));  // L-shaped (concave)
  EXPECT_FALSE(encloses({{0, 0}, {1, 1}, {1, 0}, {0, 1}}));   // bow tie: two edges cross
  EXPECT_FALSE(encloses({{0, 0}, {2, 0}, {2, 2}, {1, 0}, {0, 2}}));  // a corner touches an edge
  EXPECT_FALSE(encloses({{0, 0}, {2, 0}, {1, 0}, {1, 1}}));   // folds back along its first edge
  EXPECT_FALSE(encloses({{0, 0}, {1, 0}, {2, 0}}));           // no area
  EXPECT_FALSE(encloses({{0, 0}, {1, 0}}));                   // too few points
  EXPECT_FALSE(encloses({{0, 0}, {1, 0}, {NAN, 1}}));         // not finite
  Profile many;  // a simple polygon with more points than are checked
  for (size_t i = 0; i <= kMaxSolidCheckPoints; ++i) {
    const float a = float(2.0 * kPi * double(i) / double(kMaxSolidCheckPoints + 1));
    many.push_back({std::cos(a), std::sin(a)});
  }
  EXPECT_FALSE(encloses(many));
  many.resize(kMaxSolidCheckPoints);
  EXPECT_TRUE(encloses(many));
}

TEST(PrimitiveTessellation, ConvexPrimitiveNormalsPointAwayFromCentre) {
  for (const Primitive& p : {Primitive{Sphere{1.0f}}, Primitive{Box{{1.0f, 2.0f, 0.5f}}}}) {
    const TriangleMesh m = build(p, 0.01f);
    for (size_t i = 0; i < m.positions.size(); ++i) EXPECT_GT(glm::dot(m.normals[i], m.positions[i]), 0.0f);
  }
  const TriangleMesh c = build(Cylinder{1.0f, 2.0f, true}, 0.01f);
  for (size_t i = 0; i < c.positions.size(); ++i)
    EXPECT_GT(glm::dot(c.normals[i], c.positions[i] - glm::vec3(0, 0, 1)), 0.0f);
}

TEST(PrimitiveTessellation, OpenPrimitivesHaveTheExpectedBoundary) {
  const float tol = 0.002f;
  const uint32_t n = arcSegments(0.5f, static_cast<float>(2 * kPi), tol);
  const MeshTopologyReport cyl = checkWatertight(build(Cylinder{0.5f, 1.0f, false}, tol));
  EXPECT_EQ(cyl.boundary_edges, 2u * n);
  EXPECT_EQ(cyl.non_manifold_edges, 0u);

  const TorusSegment elbow{0.3f, 0.1f, static_cast<float>(kPi / 2)};
  const uint32_t minor = arcSegments(0.1f, static_cast<float>(2 * kPi), tol);
  const MeshTopologyReport t = checkWatertight(build(elbow, tol));
  EXPECT_EQ(t.boundary_edges, 2u * minor) << "elbow ends are open rings matching a pipe";
  EXPECT_EQ(t.non_manifold_edges, 0u);
  EXPECT_EQ(t.rejected_faces, 0u);
  EXPECT_EQ(minor, arcSegments(0.1f, static_cast<float>(2 * kPi), tol)) << "same ring as a cylinder of the pipe";

  // The elbow starts on +X in the XZ plane and ends after sweep_rad about +Z.
  const TriangleMesh m = build(elbow, tol);
  bool start_ring = false, end_ring = false;
  for (const glm::vec3& p : m.positions) {
    start_ring |= std::abs(p.y) < 1e-6f && std::abs(p.x - 0.4f) < 1e-6f;
    end_ring |= std::abs(p.x) < 1e-6f && std::abs(p.y - 0.4f) < 1e-6f;
  }
  EXPECT_TRUE(start_ring);
  EXPECT_TRUE(end_ring);
}

TEST(PrimitiveTessellation, InvalidPrimitivesGiveNothing) {
  const float tol = 0.01f;
  std::vector<Primitive> bad = {
      Cylinder{-1.0f, 1.0f, true},  Cylinder{1.0f, 0.0f, true},   Cylinder{NAN, 1.0f, true},
      Cylinder{1.0f, INFINITY, true}, Cone{0.0f, 0.0f, 1.0f, true}, Cone{-0.1f, 1.0f, 1.0f, true},
      Sphere{0.0f},                 Sphere{-2.0f},                Sphere{NAN},
      TorusSegment{1.0f, 0.0f, 1.0f}, TorusSegment{1.0f, 2.0f, 1.0f}, TorusSegment{1.0f, 0.2f, 0.0f},
      TorusSegment{1.0f, 0.2f, NAN}, Box{{1.0f, 0.0f, 1.0f}},     Box{{NAN, 1.0f, 1.0f}},
      Extrusion{{{0, 0}, {1, 0}}, 1.0f}, Extrusion{{{0, 0}, {1, 0}, {2, 0}}, 1.0f},
      Extrusion{{{0, 0}, {1, 0}, {0, 1}}, -1.0f}, Extrusion{{{0, 0}, {NAN, 0}, {0, 1}}, 1.0f},
      Extrusion{{{0, 0}, {0, 0}, {0, 0}, {1, 1}}, 1.0f},
      Revolution{{{1, 0}}, 1.0f},   Revolution{{{0, 0}, {0, 1}}, 1.0f}, Revolution{{{-1, 0}, {1, 1}}, 1.0f},
      Revolution{{{1, 0}, {1, 1}}, 0.0f}, Revolution{{{1, 0}, {1, NAN}}, 1.0f},
  };
  for (size_t i = 0; i < bad.size(); ++i) {
    EXPECT_EQ(primitiveTriangleCount(bad[i], tol), 0u) << i;
    TriangleMesh m;
    tessellatePrimitive(bad[i], tol, m);
    EXPECT_EQ(m.triangleCount(), 0u) << i;
    EXPECT_TRUE(m.positions.empty()) << i;
  }
}

TEST(PrimitiveTessellation, HostileParametersStayBounded) {
  const float huge = 1e30f, tiny = 1e-30f;
  const uint64_t bound = uint64_t{1} << 22;
  Revolution long_profile;
  for (int i = 0; i < 60000; ++i) long_profile.profile.push_back({1.0f + (i % 2), static_cast<float>(i)});
  Revolution too_long = long_profile;
  too_long.profile.resize(70000, {1.0f, 1.0f});
  Extrusion many;
  for (int i = 0; i < 60000; ++i) {
    const float a = static_cast<float>(2 * kPi * i / 60000);
    const float r = i % 2 ? 1.0f : 0.5f;  // a non-convex star beyond the ear-clipping limit
    many.profile.push_back({r * std::cos(a), r * std::sin(a)});
  }
  Extrusion bowtie{{{0, 0}, {1, 1}, {1, 0}, {0, 1}, {-1, 3}}, 1.0f};  // self-intersecting
  const std::vector<Primitive> hostile = {
      Cylinder{huge, huge, true}, Cone{huge, huge, huge, true}, Sphere{huge}, TorusSegment{huge, huge / 2, huge},
      Box{{huge, huge, huge}}, long_profile, too_long, many, bowtie, Revolution{{{huge, -huge}, {huge, huge}}, huge}};
  for (size_t i = 0; i < hostile.size(); ++i) {
    const uint64_t count = primitiveTriangleCount(hostile[i], tiny);
    EXPECT_LE(count, bound) << i;
  }
  EXPECT_EQ(primitiveTriangleCount(too_long, tiny), 0u);
  // Build a few of them for real: same count, no crash.
  for (const Primitive& p : {hostile[0], hostile[2], hostile[7], hostile[8]}) {
    const TriangleMesh m = build(p, tiny);
    EXPECT_EQ(m.triangleCount(), primitiveTriangleCount(p, tiny));
  }
}

TEST(PrimitiveTessellation, GeometryDispatch) {
  TriangleMesh mesh;
  mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  mesh.indices = {0, 1, 2};
  const Geometry g_mesh = mesh, g_prim = Primitive{Box{}};
  EXPECT_EQ(triangleCount(g_mesh, 0.01f), 1u);
  EXPECT_EQ(triangleCount(g_prim, 0.01f), 12u);
  TriangleMesh out;
  tessellate(g_prim, 0.01f, out);
  tessellate(g_mesh, 0.01f, out);
  EXPECT_EQ(out.triangleCount(), 13u);
  expectWellFormed(out);  // the mesh without normals got computed ones
  EXPECT_EQ(out.indices.back(), 24u + 2u);
}

TEST(PrimitiveTessellation, CountIsCheap) {
  // Counting must not build: a million counts of a fine sphere finish quickly.
  const Primitive p = Sphere{1.0f};
  uint64_t total = 0;
  for (int i = 0; i < 1000000; ++i) total += primitiveTriangleCount(p, 0.001f + 1e-9f * (i % 7));
  EXPECT_GT(total, 0u);
}

}  // namespace
}  // namespace tw
