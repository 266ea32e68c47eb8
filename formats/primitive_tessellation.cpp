// Tessellation of the parametric primitives of scene.h at a chordal tolerance, and the exact
// triangle counts that go with it (used to count "equivalent triangles" without building them).
//
// Cylinders, cones, spheres, torus segments and revolutions are all surfaces of revolution about
// +Z, so they share one engine: a list of profile "strips" (rows of (r, z) with an (r, z) normal)
// swept by a table of angles. Rows on the axis (r == 0) close into fans. Boxes and extrusions are
// built directly. Counting mirrors the same rules without touching memory.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <numbers>
#include <vector>

#include "nurbs_conforming.h"
#include "tessellate.h"

namespace tw {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;
// Work bound for one primitive: revolutions with long profiles lower their angular count to fit.
constexpr uint64_t kMaxPrimitiveTriangles = uint64_t{1} << 22;
// Longest profile an extrusion or a revolution may have; longer ones produce nothing.
constexpr size_t kMaxProfilePoints = size_t{1} << 16;
// Ear clipping is quadratic (cubic in the worst case); beyond this, non-convex caps are fanned.
constexpr size_t kMaxEarClipPoints = 1024;

bool positiveFinite(float x) { return std::isfinite(x) && x > 0.0f; }
bool nonNegativeFinite(float x) { return std::isfinite(x) && x >= 0.0f; }

// A sweep this close to a full turn is a full turn: the last column wraps onto the first.
bool isFullTurn(double sweep_rad) { return sweep_rad >= kTwoPi * (1.0 - 1e-5); }

// Makes room for `extra` more elements keeping geometric growth: callers append many primitives
// to one mesh, and an exact reserve per call would copy the whole mesh every time.
template <typename T>
void reserveMore(std::vector<T>& v, uint64_t extra) {
  const uint64_t need = v.size() + extra;
  if (need > v.capacity()) v.reserve(static_cast<size_t>(std::max<uint64_t>(need, 2 * uint64_t{v.capacity()})));
}

// Appends vertices and triangles to the caller's mesh. Normals are written when the mesh keeps
// them (it is empty, or already has one normal per position); a mesh that holds positions but no
// normals stays without normals, so the "empty or one per position" invariant always holds.
class Appender {
 public:
  Appender(TriangleMesh& out, uint64_t vertices, uint64_t triangles)
      : out_(out), with_normals_(out.normals.size() == out.positions.size()) {
    reserveMore(out_.positions, vertices);
    if (with_normals_) reserveMore(out_.normals, vertices);
    reserveMore(out_.indices, 3 * triangles);
  }
  uint32_t vertex(const glm::vec3& p, const glm::vec3& n) {
    out_.positions.push_back(p);
    if (with_normals_) out_.normals.push_back(n);
    return static_cast<uint32_t>(out_.positions.size() - 1);
  }
  uint32_t nextVertex() const { return static_cast<uint32_t>(out_.positions.size()); }
  void triangle(uint32_t a, uint32_t b, uint32_t c) {
    out_.indices.push_back(a);
    out_.indices.push_back(b);
    out_.indices.push_back(c);
  }

 private:
  TriangleMesh& out_;
  bool with_normals_;
};

// ---------------------------------------------------------------------------------------------
// Surfaces of revolution.

// One profile row: radius and height, and the outward normal in the (r, z) half-plane.
struct RevRow {
  float r, z, nr, nz;
};

// Angular sampling of a sweep: `segments` steps; a full turn wraps (no duplicated seam column).
struct Sweep {
  uint32_t segments = 0;
  bool full = false;
  double sweep_rad = 0.0;
  uint32_t columns() const { return full ? segments : segments + 1; }
};

// Triangles one band between two rows contributes per angular step.
uint32_t bandWeight(float r0, float r1) { return (r0 == 0.0f ? 0u : 1u) + (r1 == 0.0f ? 0u : 1u); }

// cos/sin of every column angle, computed in double so that seams and caps agree bit for bit
// (every strip of a primitive reads the same table).
struct TrigTable {
  std::vector<float> cos_a, sin_a;
  uint32_t segments = 0;
  bool full = false;
  double sweep_rad = -1.0;

  void fill(const Sweep& s) {
    segments = s.segments;
    full = s.full;
    sweep_rad = s.sweep_rad;
    const uint32_t n = s.columns();
    cos_a.resize(n);
    sin_a.resize(n);
    for (uint32_t i = 0; i < n; ++i) {
      const double a = s.sweep_rad * static_cast<double>(i) / static_cast<double>(s.segments);
      cos_a[i] = static_cast<float>(std::cos(a));
      sin_a[i] = static_cast<float>(std::sin(a));
    }
  }
};

// The table for `s`, kept per thread: plants repeat the same pipe sizes, so consecutive calls
// usually reuse it without allocating or calling cos/sin. Valid until the next call.
const TrigTable& trigTable(const Sweep& s) {
  thread_local TrigTable table;
  if (table.segments != s.segments || table.full != s.full || table.sweep_rad != s.sweep_rad) table.fill(s);
  return table;
}

// Emits the rows of one strip around the sweep and the bands between consecutive rows (and
// between the last and the first row when `closed`). Bands are ordered so that (d/dangle) x
// (d/drow) points along the rows' normals, which the caller orients outward.
void revolveStrip(const RevRow* rows, size_t count, bool closed, const Sweep& sweep,
                  const TrigTable& trig, Appender& app) {
  if (count < 2) return;
  const uint32_t cols = sweep.columns();
  // A row on the axis whose normal is the axis itself (a cap centre, a pole) is one vertex;
  // other rows get one vertex per column.
  auto single = [](const RevRow& row) { return row.r == 0.0f && row.nr == 0.0f; };
  const uint32_t first = app.nextVertex();
  for (size_t j = 0; j < count; ++j) {
    const RevRow& row = rows[j];
    if (single(row)) {
      app.vertex(glm::vec3(0.0f, 0.0f, row.z), glm::vec3(0.0f, 0.0f, row.nz));
      continue;
    }
    for (uint32_t i = 0; i < cols; ++i) {
      const float c = trig.cos_a[i], s = trig.sin_a[i];
      // Rows on the axis get exact zeros (never -0) so coincident apex points weld by bits.
      const glm::vec3 p = row.r == 0.0f ? glm::vec3(0.0f, 0.0f, row.z)
                                        : glm::vec3(row.r * c, row.r * s, row.z);
      app.vertex(p, glm::vec3(row.nr * c, row.nr * s, row.nz));
    }
  }
  const size_t bands = closed ? count : count - 1;
  uint32_t row0 = first;
  for (size_t j = 0; j < bands; ++j) {
    const size_t j1 = (j + 1) % count;
    const uint32_t width0 = single(rows[j]) ? 1u : cols;
    const uint32_t row1 = j1 == 0 ? first : row0 + width0;
    const bool axis0 = rows[j].r == 0.0f, axis1 = rows[j1].r == 0.0f;
    const uint32_t step0 = width0 == 1 ? 0u : 1u, step1 = single(rows[j1]) ? 0u : 1u;
    if (!(axis0 && axis1)) {
      for (uint32_t i = 0; i < sweep.segments; ++i) {
        const uint32_t i1 = sweep.full ? (i + 1) % cols : i + 1;
        const uint32_t a = row0 + i * step0, b = row0 + i1 * step0, c = row1 + i1 * step1, d = row1 + i * step1;
        if (!axis0) app.triangle(a, b, c);
        if (!axis1) app.triangle(a, c, d);
      }
    }
    row0 = row1;
  }
}

Sweep makeSweep(float radius, double sweep_rad, float tolerance) {
  Sweep s;
  s.full = isFullTurn(sweep_rad);
  s.sweep_rad = s.full ? kTwoPi : sweep_rad;
  s.segments = arcSegments(radius, static_cast<float>(s.sweep_rad), tolerance);
  return s;
}

// ---- cylinder and cone: up to three two-row strips (bottom cap, side, top cap)

struct ConeRows {
  std::array<RevRow, 6> rows{};
  std::array<uint8_t, 3> strip_begin{}, strip_size{};
  size_t strips = 0;
  void add(RevRow a, RevRow b) {
    strip_begin[strips] = static_cast<uint8_t>(2 * strips);
    strip_size[strips] = 2;
    rows[2 * strips] = a;
    rows[2 * strips + 1] = b;
    ++strips;
  }
};

bool validCone(float rb, float rt, float h) {
  return nonNegativeFinite(rb) && nonNegativeFinite(rt) && positiveFinite(h) && (rb > 0 || rt > 0);
}

ConeRows coneRows(float rb, float rt, float h, bool capped) {
  ConeRows c;
  // Side normal: right-hand normal of the profile direction (rt - rb, h) in the (r, z) plane.
  const double len = std::hypot(static_cast<double>(h), static_cast<double>(rb) - rt);
  const float nr = static_cast<float>(h / len), nz = static_cast<float>((rb - static_cast<double>(rt)) / len);
  if (capped && rb > 0) c.add({0.0f, 0.0f, 0.0f, -1.0f}, {rb, 0.0f, 0.0f, -1.0f});
  c.add({rb, 0.0f, nr, nz}, {rt, h, nr, nz});
  if (capped && rt > 0) c.add({rt, h, 0.0f, 1.0f}, {0.0f, h, 0.0f, 1.0f});
  return c;
}

uint64_t coneCount(float rb, float rt, float h, bool capped, float tolerance) {
  if (!validCone(rb, rt, h)) return 0;
  const uint64_t n = arcSegments(std::max(rb, rt), static_cast<float>(kTwoPi), tolerance);
  uint64_t weight = bandWeight(rb, rt);
  if (capped) weight += (rb > 0 ? 1 : 0) + (rt > 0 ? 1 : 0);
  return weight * n;
}

void coneBuild(float rb, float rt, float h, bool capped, float tolerance, TriangleMesh& out) {
  if (!validCone(rb, rt, h)) return;
  const Sweep sweep = makeSweep(std::max(rb, rt), kTwoPi, tolerance);
  const TrigTable& trig = trigTable(sweep);
  const ConeRows c = coneRows(rb, rt, h, capped);
  Appender app(out, uint64_t{2} * c.strips * sweep.columns(), coneCount(rb, rt, h, capped, tolerance));
  for (size_t s = 0; s < c.strips; ++s)
    revolveStrip(&c.rows[c.strip_begin[s]], c.strip_size[s], false, sweep, trig, app);
}

// ---- sphere: one strip pole to pole with smooth normals

bool validSphere(const Sphere& s) { return positiveFinite(s.radius); }

uint32_t sphereRows(const Sphere& s, float tolerance) {
  return std::max(2u, arcSegments(s.radius, static_cast<float>(std::numbers::pi), tolerance));
}

uint64_t sphereCount(const Sphere& s, float tolerance) {
  if (!validSphere(s)) return 0;
  const uint64_t n = arcSegments(s.radius, static_cast<float>(kTwoPi), tolerance);
  const uint64_t m = sphereRows(s, tolerance);
  return 2 * n * (m - 1);
}

void sphereBuild(const Sphere& s, float tolerance, TriangleMesh& out) {
  if (!validSphere(s)) return;
  const Sweep sweep = makeSweep(s.radius, kTwoPi, tolerance);
  const TrigTable& trig = trigTable(sweep);
  const uint32_t m = sphereRows(s, tolerance);
  std::vector<RevRow> rows(m + 1);
  for (uint32_t j = 0; j <= m; ++j) {
    const double phi = -0.5 * std::numbers::pi + std::numbers::pi * j / m;
    const float c = (j == 0 || j == m) ? 0.0f : static_cast<float>(std::cos(phi));
    const float sn = j == 0 ? -1.0f : j == m ? 1.0f : static_cast<float>(std::sin(phi));
    rows[j] = {s.radius * c, s.radius * sn, c, sn};
  }
  Appender app(out, uint64_t{m + 1} * sweep.columns(), sphereCount(s, tolerance));
  revolveStrip(rows.data(), rows.size(), false, sweep, trig, app);
}

// ---- torus segment: a closed circular strip swept about +Z, open ends (a pipe elbow)

bool validTorus(const TorusSegment& t) {
  return positiveFinite(t.major_radius) && positiveFinite(t.minor_radius) &&
         t.minor_radius < t.major_radius && positiveFinite(t.sweep_rad);
}

uint64_t torusCount(const TorusSegment& t, float tolerance) {
  if (!validTorus(t)) return 0;
  const Sweep sweep = makeSweep(t.major_radius + t.minor_radius, t.sweep_rad, tolerance);
  const uint64_t minor = arcSegments(t.minor_radius, static_cast<float>(kTwoPi), tolerance);
  return 2 * minor * sweep.segments;
}

void torusBuild(const TorusSegment& t, float tolerance, TriangleMesh& out) {
  if (!validTorus(t)) return;
  const Sweep sweep = makeSweep(t.major_radius + t.minor_radius, t.sweep_rad, tolerance);
  const TrigTable& trig = trigTable(sweep);
  const uint32_t minor = arcSegments(t.minor_radius, static_cast<float>(kTwoPi), tolerance);
  std::vector<RevRow> rows(minor);
  for (uint32_t k = 0; k < minor; ++k) {
    const double phi = kTwoPi * k / minor;
    const float c = static_cast<float>(std::cos(phi)), s = static_cast<float>(std::sin(phi));
    // Counter-clockwise in the (r, z) plane: material on the left, so normals point out.
    rows[k] = {t.major_radius + t.minor_radius * c, t.minor_radius * s, c, s};
  }
  Appender app(out, uint64_t{minor} * sweep.columns(), torusCount(t, tolerance));
  revolveStrip(rows.data(), rows.size(), true, sweep, trig, app);
}

// ---- revolution of a polyline profile: one flat-shaded strip per profile segment

bool validRevolution(const Revolution& r) {
  if (r.profile.size() < 2 || r.profile.size() > kMaxProfilePoints) return false;
  if (!positiveFinite(r.sweep_rad)) return false;
  bool off_axis = false;
  for (const glm::vec2& p : r.profile) {
    if (!nonNegativeFinite(p.x) || !std::isfinite(p.y)) return false;
    off_axis |= p.x > 0.0f;
  }
  return off_axis;
}

// Twice the signed area of the profile closed through the axis (last point -> (0, z_last) ->
// (0, z_first) -> first point): positive when the material lies to the left of the profile
// direction, the convention of a counter-clockwise outline. Open shells (a pipe wall) come out
// positive when they face away from the axis, which is what they mean.
double revolutionOrientation(const std::vector<glm::vec2>& profile) {
  double area2 = 0.0;
  for (size_t i = 0; i + 1 < profile.size(); ++i) {
    const glm::dvec2 a = profile[i], b = profile[i + 1];
    area2 += a.x * b.y - b.x * a.y;
  }
  const glm::dvec2 first = profile.front(), last = profile.back();
  return area2 + last.x * last.y - first.x * first.y;
}

// Angular steps: from the tolerance at the largest radius, lowered so the primitive stays within
// kMaxPrimitiveTriangles; `weight` is the triangles per step.
uint32_t revolutionSegments(const Revolution& r, float tolerance, uint64_t weight, bool full) {
  float max_r = 0.0f;
  for (const glm::vec2& p : r.profile) max_r = std::max(max_r, p.x);
  uint32_t n = arcSegments(max_r, full ? static_cast<float>(kTwoPi) : r.sweep_rad, tolerance);
  const uint32_t min_n = full ? 3u : 1u;
  if (weight > 0 && uint64_t{n} * weight > kMaxPrimitiveTriangles)
    n = static_cast<uint32_t>(std::max<uint64_t>(min_n, kMaxPrimitiveTriangles / weight));
  return n;
}

uint64_t revolutionWeight(const Revolution& r) {
  uint64_t weight = 0;
  for (size_t i = 0; i + 1 < r.profile.size(); ++i) {
    const glm::vec2 a = r.profile[i], b = r.profile[i + 1];
    if (a == b) continue;
    weight += bandWeight(a.x, b.x);
  }
  return weight;
}

uint64_t revolutionCount(const Revolution& r, float tolerance) {
  if (!validRevolution(r)) return 0;
  const uint64_t weight = revolutionWeight(r);
  return weight * revolutionSegments(r, tolerance, weight, isFullTurn(r.sweep_rad));
}

void revolutionBuild(const Revolution& r, float tolerance, TriangleMesh& out) {
  if (!validRevolution(r)) return;
  const uint64_t weight = revolutionWeight(r);
  Sweep sweep;
  sweep.full = isFullTurn(r.sweep_rad);
  sweep.sweep_rad = sweep.full ? kTwoPi : r.sweep_rad;
  sweep.segments = revolutionSegments(r, tolerance, weight, sweep.full);
  const TrigTable& trig = trigTable(sweep);
  const bool flip = revolutionOrientation(r.profile) < 0.0;
  const size_t k = r.profile.size();
  Appender app(out, uint64_t{2} * (k - 1) * sweep.columns(), weight * sweep.segments);
  for (size_t i = 0; i + 1 < k; ++i) {
    glm::vec2 a = r.profile[i], b = r.profile[i + 1];
    if (a == b) continue;
    if (flip) std::swap(a, b);  // walk the profile with the material on the left
    const double dr = static_cast<double>(b.x) - a.x, dz = static_cast<double>(b.y) - a.y;
    const double len = std::hypot(dr, dz);
    const float nr = static_cast<float>(dz / len), nz = static_cast<float>(-dr / len);
    const RevRow rows[2] = {{a.x, a.y, nr, nz}, {b.x, b.y, nr, nz}};
    revolveStrip(rows, 2, false, sweep, trig, app);
  }
}

// ---------------------------------------------------------------------------------------------
// Box: 6 faces of 4 vertices (hard edges), 12 triangles.

bool validBox(const Box& b) {
  return positiveFinite(b.half_extents.x) && positiveFinite(b.half_extents.y) &&
         positiveFinite(b.half_extents.z);
}

void boxBuild(const Box& b, TriangleMesh& out) {
  if (!validBox(b)) return;
  Appender app(out, 24, 12);
  const glm::vec3 h = b.half_extents;
  // Each face: normal axis n and tangents u, v with u x v = n.
  struct Face {
    glm::vec3 n, u, v;
  };
  static constexpr std::array<Face, 6> kFaces = {{
      {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}},
      {{-1, 0, 0}, {0, 0, 1}, {0, 1, 0}},
      {{0, 1, 0}, {0, 0, 1}, {1, 0, 0}},
      {{0, -1, 0}, {1, 0, 0}, {0, 0, 1}},
      {{0, 0, 1}, {1, 0, 0}, {0, 1, 0}},
      {{0, 0, -1}, {0, 1, 0}, {1, 0, 0}},
  }};
  static constexpr std::array<glm::vec2, 4> kCorners = {{{-1, -1}, {1, -1}, {1, 1}, {-1, 1}}};
  for (const Face& f : kFaces) {
    uint32_t idx[4];
    for (int c = 0; c < 4; ++c)
      idx[c] = app.vertex(h * (f.n + kCorners[c].x * f.u + kCorners[c].y * f.v), f.n);
    app.triangle(idx[0], idx[1], idx[2]);
    app.triangle(idx[0], idx[2], idx[3]);
  }
}

// ---------------------------------------------------------------------------------------------
// Extrusion: side quads with flat normals, caps triangulated by ear clipping.

// Number of profile points once consecutive duplicates (and a closing copy of the first point)
// are dropped; `out`, when given, receives them.
size_t cleanProfile(const std::vector<glm::vec2>& profile, std::vector<glm::dvec2>* out) {
  size_t kept = 0;
  glm::vec2 last{};
  for (size_t i = 0; i < profile.size(); ++i) {
    if (kept > 0 && profile[i] == last) continue;
    last = profile[i];
    ++kept;
    if (out) out->push_back(glm::dvec2(last));
  }
  if (kept > 1 && last == profile.front()) {
    --kept;
    if (out) out->pop_back();
  }
  return kept;
}

bool validExtrusion(const Extrusion& e) {
  if (e.profile.size() < 3 || e.profile.size() > kMaxProfilePoints) return false;
  if (!positiveFinite(e.height)) return false;
  for (const glm::vec2& p : e.profile)
    if (!std::isfinite(p.x) || !std::isfinite(p.y)) return false;
  if (cleanProfile(e.profile, nullptr) < 3) return false;
  const double area2 = profileSignedArea2(e.profile);
  return std::isfinite(area2) && area2 != 0.0;
}

uint64_t extrusionCount(const Extrusion& e) {
  if (!validExtrusion(e)) return 0;
  const uint64_t k = cleanProfile(e.profile, nullptr);
  return 2 * k + 2 * (k - 2);
}

double cross2(const glm::dvec2& a, const glm::dvec2& b, const glm::dvec2& c) {
  return (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
}

// Triangulates a simple counter-clockwise polygon into exactly k - 2 triangles (index triples
// appended to `tris`). Convex polygons and very long outlines are fanned; others are ear-clipped.
// A polygon that is not simple still gets k - 2 triangles (forced clips), never a hang.
void triangulatePolygon(const std::vector<glm::dvec2>& p, std::vector<uint32_t>& tris) {
  const size_t k = p.size();
  bool convex = true;
  for (size_t i = 0; i < k && convex; ++i)
    convex = cross2(p[(i + k - 1) % k], p[i], p[(i + 1) % k]) >= 0.0;
  if (convex || k > kMaxEarClipPoints) {
    for (size_t i = 1; i + 1 < k; ++i)
      tris.insert(tris.end(), {0u, static_cast<uint32_t>(i), static_cast<uint32_t>(i + 1)});
    return;
  }
  std::vector<uint32_t> prev(k), next(k);
  for (size_t i = 0; i < k; ++i) {
    prev[i] = static_cast<uint32_t>((i + k - 1) % k);
    next[i] = static_cast<uint32_t>((i + 1) % k);
  }
  auto isEar = [&](uint32_t a, uint32_t v, uint32_t c) {
    if (cross2(p[a], p[v], p[c]) <= 0.0) return false;
    for (uint32_t r = next[c]; r != a; r = next[r]) {
      const glm::dvec2& q = p[r];
      if (q == p[a] || q == p[v] || q == p[c]) continue;
      if (cross2(p[a], p[v], q) >= 0.0 && cross2(p[v], p[c], q) >= 0.0 && cross2(p[c], p[a], q) >= 0.0)
        return false;  // another vertex inside or on the candidate ear
    }
    return true;
  };
  size_t remaining = k;
  uint32_t v = 0;
  size_t tried = 0;
  uint32_t fallback = v;
  double fallback_score = std::numeric_limits<double>::infinity();
  while (remaining > 3) {
    const uint32_t a = prev[v], c = next[v];
    bool clip = isEar(a, v, c);
    if (!clip) {
      // Remember the least harmful vertex to force out if a whole pass finds no ear: the one
      // closest to collinear, preferring convex corners.
      const double cr = cross2(p[a], p[v], p[c]);
      const double score = cr >= 0.0 ? cr : 1e300 - cr;
      if (score < fallback_score) {
        fallback_score = score;
        fallback = v;
      }
      if (++tried >= remaining) {
        v = fallback;
        clip = true;
      }
    }
    if (clip) {
      const uint32_t pa = prev[v], nc = next[v];
      tris.insert(tris.end(), {pa, v, nc});
      next[pa] = nc;
      prev[nc] = pa;
      --remaining;
      v = nc;
      tried = 0;
      fallback = v;
      fallback_score = std::numeric_limits<double>::infinity();
    } else {
      v = next[v];
    }
  }
  tris.insert(tris.end(), {prev[v], v, next[v]});
}

void extrusionBuild(const Extrusion& e, TriangleMesh& out) {
  if (!validExtrusion(e)) return;
  std::vector<glm::dvec2> pts;
  pts.reserve(e.profile.size());
  cleanProfile(e.profile, &pts);
  if (profileSignedArea2(e.profile) < 0.0) std::reverse(pts.begin(), pts.end());
  const size_t k = pts.size();
  std::vector<uint32_t> cap;
  cap.reserve(3 * (k - 2));
  triangulatePolygon(pts, cap);

  Appender app(out, 6 * k, 4 * k - 4);
  const float h = e.height;
  // Sides: one quad per edge with its own vertices (hard edges at profile corners).
  for (size_t i = 0; i < k; ++i) {
    const glm::vec2 a(pts[i]), b(pts[(i + 1) % k]);
    const glm::dvec2 d = pts[(i + 1) % k] - pts[i];
    const double len = std::hypot(d.x, d.y);
    const glm::vec3 n = len > 0 ? glm::vec3(static_cast<float>(d.y / len), static_cast<float>(-d.x / len), 0.0f)
                                : glm::vec3(0.0f);
    const uint32_t a0 = app.vertex({a, 0.0f}, n), b0 = app.vertex({b, 0.0f}, n);
    const uint32_t b1 = app.vertex({b, h}, n), a1 = app.vertex({a, h}, n);
    app.triangle(a0, b0, b1);
    app.triangle(a0, b1, a1);
  }
  // Caps: the bottom faces -Z, so its triangles are reversed.
  const uint32_t bottom = app.nextVertex();
  for (size_t i = 0; i < k; ++i) app.vertex({glm::vec2(pts[i]), 0.0f}, {0, 0, -1});
  const uint32_t top = app.nextVertex();
  for (size_t i = 0; i < k; ++i) app.vertex({glm::vec2(pts[i]), h}, {0, 0, 1});
  for (size_t t = 0; t + 2 < cap.size(); t += 3) {
    app.triangle(bottom + cap[t], bottom + cap[t + 2], bottom + cap[t + 1]);
    app.triangle(top + cap[t], top + cap[t + 1], top + cap[t + 2]);
  }
}

// ---------------------------------------------------------------------------------------------
// Meshes pass through (with the same normal rule as everything else).

void meshAppend(const TriangleMesh& mesh, TriangleMesh& out) {
  const bool out_empty = out.positions.empty();
  const bool with_normals = out.normals.size() == out.positions.size();
  const uint32_t base = static_cast<uint32_t>(out.positions.size());
  out.positions.insert(out.positions.end(), mesh.positions.begin(), mesh.positions.end());
  if (with_normals) {
    if (mesh.normals.size() == mesh.positions.size()) {
      out.normals.insert(out.normals.end(), mesh.normals.begin(), mesh.normals.end());
    } else if (!out_empty) {
      // Out keeps normals, the mesh has none: area-weighted vertex normals.
      const size_t first = out.normals.size();
      out.normals.resize(out.positions.size(), glm::vec3(0.0f));
      for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
        const uint32_t i0 = mesh.indices[t], i1 = mesh.indices[t + 1], i2 = mesh.indices[t + 2];
        if (i0 >= mesh.positions.size() || i1 >= mesh.positions.size() || i2 >= mesh.positions.size()) continue;
        const glm::vec3 n = glm::cross(mesh.positions[i1] - mesh.positions[i0], mesh.positions[i2] - mesh.positions[i0]);
        out.normals[first + i0] += n;
        out.normals[first + i1] += n;
        out.normals[first + i2] += n;
      }
      for (size_t i = first; i < out.normals.size(); ++i) {
        const float len = glm::length(out.normals[i]);
        out.normals[i] = len > 0.0f ? out.normals[i] / len : glm::vec3(0, 0, 1);
      }
    }
  }
  if (out_empty && mesh.colors.size() == mesh.positions.size()) out.colors = mesh.colors;
  reserveMore(out.indices, mesh.indices.size());
  for (uint32_t i : mesh.indices) out.indices.push_back(base + i);
}

}  // namespace

namespace {

// Sign of the turn a -> b -> c (exact for float inputs: their differences and products fit a
// double).
int turn(const glm::dvec2& a, const glm::dvec2& b, const glm::dvec2& c) {
  const double t = cross2(a, b, c);
  return (t > 0.0) - (t < 0.0);
}

// Whether collinear point q lies on the closed segment a-b.
bool onSegment(const glm::dvec2& a, const glm::dvec2& b, const glm::dvec2& q) {
  return std::min(a.x, b.x) <= q.x && q.x <= std::max(a.x, b.x) && std::min(a.y, b.y) <= q.y &&
         q.y <= std::max(a.y, b.y);
}

// Whether the closed segments a-b and c-d share a point.
bool segmentsMeet(const glm::dvec2& a, const glm::dvec2& b, const glm::dvec2& c, const glm::dvec2& d) {
  const int t1 = turn(a, b, c), t2 = turn(a, b, d), t3 = turn(c, d, a), t4 = turn(c, d, b);
  if (t1 * t2 < 0 && t3 * t4 < 0) return true;
  return (t1 == 0 && onSegment(a, b, c)) || (t2 == 0 && onSegment(a, b, d)) ||
         (t3 == 0 && onSegment(c, d, a)) || (t4 == 0 && onSegment(c, d, b));
}

}  // namespace

double profileSignedArea2(std::span<const glm::vec2> profile) {
  double area2 = 0.0;
  const size_t k = profile.size();
  for (size_t i = 0; i < k; ++i) {
    const glm::dvec2 a = profile[i], b = profile[(i + 1) % k];
    area2 += a.x * b.y - b.x * a.y;
  }
  return area2;
}

bool extrusionEnclosesSolid(std::span<const glm::vec2> profile) {
  if (profile.size() > kMaxSolidCheckPoints) return false;
  Extrusion e{std::vector<glm::vec2>(profile.begin(), profile.end()), 1.0f};
  if (!validExtrusion(e)) return false;
  std::vector<glm::dvec2> p;
  cleanProfile(e.profile, &p);
  const size_t k = p.size();
  for (size_t i = 0; i < k; ++i) {
    const glm::dvec2 &a = p[i], &b = p[(i + 1) % k];
    for (size_t j = i + 1; j < k; ++j) {
      const glm::dvec2 &c = p[j], &d = p[(j + 1) % k];
      if (j == i + 1) {  // b == c: they may only turn there, not fold back along each other
        if (turn(a, b, d) == 0 && glm::dot(a - b, d - b) > 0.0) return false;
      } else if (i == 0 && j == k - 1) {  // d == a
        if (turn(c, a, b) == 0 && glm::dot(c - a, b - a) > 0.0) return false;
      } else if (segmentsMeet(a, b, c, d)) {
        return false;
      }
    }
  }
  return true;
}

uint32_t arcSegments(float radius, float sweep_rad, float tolerance) {
  const bool full = std::isfinite(sweep_rad) && isFullTurn(sweep_rad);
  const uint32_t min_segments = full ? 3u : 1u;
  if (!positiveFinite(radius) || !positiveFinite(sweep_rad) || !positiveFinite(tolerance)) return min_segments;
  // Largest angle whose sagitta r (1 - cos(theta / 2)) stays within the tolerance:
  // 1 - cos(theta / 2) = 2 sin^2(theta / 4) = x  =>  theta = 4 asin(sqrt(x / 2)), precise for tiny x.
  const double x = static_cast<double>(tolerance) / radius;
  if (x >= 2.0) return min_segments;  // even a half-turn chord stays within tolerance
  const double theta_max = 4.0 * std::asin(std::sqrt(0.5 * x));
  const double sweep = std::min(static_cast<double>(sweep_rad), kTwoPi);
  const double n = std::ceil(sweep / theta_max * (1.0 - 1e-9));
  if (!(n < kMaxArcSegments)) return kMaxArcSegments;
  return std::max(min_segments, static_cast<uint32_t>(n));
}

uint64_t primitiveTriangleCount(const Primitive& primitive, float tolerance) {
  struct Visitor {
    float tol;
    uint64_t operator()(const Cylinder& c) const { return coneCount(c.radius, c.radius, c.height, c.capped, tol); }
    uint64_t operator()(const Cone& c) const {
      return coneCount(c.radius_bottom, c.radius_top, c.height, c.capped, tol);
    }
    uint64_t operator()(const Sphere& s) const { return sphereCount(s, tol); }
    uint64_t operator()(const TorusSegment& t) const { return torusCount(t, tol); }
    uint64_t operator()(const Box& b) const { return validBox(b) ? 12 : 0; }
    uint64_t operator()(const Extrusion& e) const { return extrusionCount(e); }
    uint64_t operator()(const Revolution& r) const { return revolutionCount(r, tol); }
  };
  return std::visit(Visitor{tolerance}, primitive);
}

void tessellatePrimitive(const Primitive& primitive, float tolerance, TriangleMesh& out) {
  struct Visitor {
    float tol;
    TriangleMesh& out;
    void operator()(const Cylinder& c) const { coneBuild(c.radius, c.radius, c.height, c.capped, tol, out); }
    void operator()(const Cone& c) const { coneBuild(c.radius_bottom, c.radius_top, c.height, c.capped, tol, out); }
    void operator()(const Sphere& s) const { sphereBuild(s, tol, out); }
    void operator()(const TorusSegment& t) const { torusBuild(t, tol, out); }
    void operator()(const Box& b) const { boxBuild(b, out); }
    void operator()(const Extrusion& e) const { extrusionBuild(e, out); }
    void operator()(const Revolution& r) const { revolutionBuild(r, tol, out); }
  };
  std::visit(Visitor{tolerance, out}, primitive);
}

void tessellate(const Geometry& geometry, float tolerance, TriangleMesh& out) {
  if (const auto* mesh = std::get_if<TriangleMesh>(&geometry)) {
    meshAppend(*mesh, out);
  } else if (const auto* primitive = std::get_if<Primitive>(&geometry)) {
    tessellatePrimitive(*primitive, tolerance, out);
  } else if (const auto* nurbs = std::get_if<NurbsPatchSet>(&geometry)) {
    tessellateNurbsConforming(*nurbs, tolerance, out);
  }
}

uint64_t triangleCount(const Geometry& geometry, float tolerance) {
  if (const auto* mesh = std::get_if<TriangleMesh>(&geometry)) return mesh->triangleCount();
  if (const auto* primitive = std::get_if<Primitive>(&geometry)) return primitiveTriangleCount(*primitive, tolerance);
  if (const auto* nurbs = std::get_if<NurbsPatchSet>(&geometry))
    return nurbsConformingTriangleCount(*nurbs, tolerance);
  return 0;
}

}  // namespace tw
