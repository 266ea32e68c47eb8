// Conforming NURBS tessellation (the seed system's shared-border algorithm): see
// nurbs_conforming.h and docs/nurbs.md.
//
// Stages, all sequential so that the output is deterministic:
//  1. validate every patch; plan each interior grid N x M from second differences of the surface
//     on a sample grid (coarsening the tolerance if the set would exceed kMaxSetTriangles);
//  2. corners: patch corners closer than eps (relative to the set's size) form one cluster and
//     one output vertex, so corners where 3 or 4 patches meet are exact;
//  3. adjacency: two borders are shared when their end corners are in the same clusters and
//     the samples of each lie on the other curve within eps, whatever the direction, degree or
//     knot spacing of either side; patches are flipped where needed so shared borders run
//     opposite ways (consistent orientation);
//  4. border strings: the first patch to reach a border places its points (as many equal
//     parameter steps as the interior grid has along it, more if the partner's grid is finer
//     there, then bisection until the chordal error is below tolerance); the partner reuses the
//     very same vertices;
//  5. per patch: the interior grid, then one strip per side zipping the border string to the
//     grid's outer ring, keeping the two advancing fronts level in the parameter plane (always
//     correctly oriented, since both chains advance monotonically along parallel lines there).
#include "nurbs_conforming.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstddef>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <vector>

#include "nurbs.h"
#include "position_key.h"
#include "union_find.h"

namespace tw {
namespace {

// Work limits against hostile control nets (the role kMaxArcSegments plays for primitives).
constexpr uint32_t kMaxGridSegments = 512;                  // per direction of one patch
constexpr uint32_t kMaxBorderSegments = 2048;               // per border string
constexpr uint64_t kMaxSetTriangles = uint64_t{1} << 23;    // else the tolerance is coarsened
constexpr uint64_t kMaxSetBisections = uint64_t{1} << 22;   // border points added by bisection, whole set
constexpr int kBorderSamples = 16;                          // segments of a border's sample polyline
constexpr int kMaxBisectionDepth = 20;
constexpr ptrdiff_t kMaxCandidates = 64;  // borders tried as the partner of one border
// The interior-error bound uses sampled second differences; this margin covers what the samples
// miss between them.
constexpr double kCurvatureSafety = 1.25;
// Adjacency distance relative to the diagonal of the set's bounding box.
constexpr double kRelativeEps = 1e-5;

constexpr uint32_t kNone = UINT32_MAX;

// A patch with its domain: evaluation at normalised parameters (x, y) in [0, 1]^2, and along its
// four sides in counter-clockwise order (side s runs from corner s to corner s + 1, corners
// (0,0), (1,0), (1,1), (0,1)), with t in [0, 1].
struct PatchEval {
  const NurbsPatch* patch = nullptr;
  NurbsDomain dom{};

  float paramU(double x) const {
    if (!(x > 0.0)) return dom.u0;
    if (x >= 1.0) return dom.u1;
    return static_cast<float>(dom.u0 + (static_cast<double>(dom.u1) - dom.u0) * x);
  }
  float paramV(double y) const {
    if (!(y > 0.0)) return dom.v0;
    if (y >= 1.0) return dom.v1;
    return static_cast<float>(dom.v0 + (static_cast<double>(dom.v1) - dom.v0) * y);
  }
  glm::vec3 at(double x, double y, glm::vec3* normal = nullptr) const {
    return evaluateNurbs(*patch, paramU(x), paramV(y), normal);
  }
  static glm::dvec2 sideParam(int side, double t) {
    switch (side) {
      case 0: return {t, 0.0};
      case 1: return {1.0, t};
      case 2: return {1.0 - t, 1.0};
      default: return {0.0, 1.0 - t};
    }
  }
  glm::vec3 border(int side, double t, glm::vec3* normal = nullptr) const {
    const glm::dvec2 xy = sideParam(side, t);
    return at(xy.x, xy.y, normal);
  }
};

double dist(const glm::vec3& a, const glm::vec3& b) { return glm::length(glm::dvec3(a) - glm::dvec3(b)); }

double distToSegment(const glm::vec3& p, const glm::vec3& a, const glm::vec3& b) {
  const glm::dvec3 ab = glm::dvec3(b) - glm::dvec3(a), ap = glm::dvec3(p) - glm::dvec3(a);
  const double len2 = glm::dot(ab, ab);
  const double s = len2 > 0.0 ? std::clamp(glm::dot(ap, ab) / len2, 0.0, 1.0) : 0.0;
  return glm::length(ap - s * ab);
}

// Segment count from a real number, saturating (NaN and infinity give `cap`).
uint32_t segmentsFor(double need, uint32_t lo, uint32_t cap) {
  if (!(need < static_cast<double>(cap))) return cap;
  return std::max(lo, static_cast<uint32_t>(std::ceil(std::max(need, 0.0))));
}

// ---------------------------------------------------------------------------------------------
// Interior planning.

struct Curvature {
  double uu = 0.0, uv = 0.0, vv = 0.0;  // max |S_xx|, |S_xy|, |S_yy| in normalised parameters
};

uint32_t distinctSpans(const std::vector<float>& k, uint32_t p, uint32_t n) {
  uint32_t spans = 0;
  for (uint32_t s = p; s < n; ++s)
    if (k[s] < k[s + 1]) ++spans;
  return std::max(spans, 1u);
}

Curvature sampleCurvature(const PatchEval& e) {
  const NurbsPatch& p = *e.patch;
  const int ku = static_cast<int>(std::clamp(4u * distinctSpans(p.knots_u, p.degree_u, p.count_u), 8u, 64u));
  const int kv = static_cast<int>(std::clamp(4u * distinctSpans(p.knots_v, p.degree_v, p.count_v), 8u, 64u));
  std::vector<glm::dvec3> pts(static_cast<size_t>(ku + 1) * (kv + 1));
  auto at = [&](int i, int j) -> glm::dvec3& { return pts[static_cast<size_t>(j) * (ku + 1) + i]; };
  for (int j = 0; j <= kv; ++j)
    for (int i = 0; i <= ku; ++i) at(i, j) = glm::dvec3(e.at(static_cast<double>(i) / ku, static_cast<double>(j) / kv));
  Curvature c;
  const double su = static_cast<double>(ku) * ku, sv = static_cast<double>(kv) * kv, suv = static_cast<double>(ku) * kv;
  // Second differences; the values one sample in from each end are extrapolated linearly to the
  // end, where a cubic's second derivative peaks.
  std::vector<glm::dvec3> d(static_cast<size_t>(std::max(ku, kv) + 1));
  for (int j = 0; j <= kv; ++j) {
    for (int i = 1; i < ku; ++i) d[i] = (at(i - 1, j) - 2.0 * at(i, j) + at(i + 1, j)) * su;
    d[0] = ku >= 3 ? 2.0 * d[1] - d[2] : d[1];
    d[ku] = ku >= 3 ? 2.0 * d[ku - 1] - d[ku - 2] : d[ku - 1];
    for (int i = 0; i <= ku; ++i) c.uu = std::max(c.uu, glm::length(d[i]));
  }
  for (int i = 0; i <= ku; ++i) {
    for (int j = 1; j < kv; ++j) d[j] = (at(i, j - 1) - 2.0 * at(i, j) + at(i, j + 1)) * sv;
    d[0] = kv >= 3 ? 2.0 * d[1] - d[2] : d[1];
    d[kv] = kv >= 3 ? 2.0 * d[kv - 1] - d[kv - 2] : d[kv - 1];
    for (int j = 0; j <= kv; ++j) c.vv = std::max(c.vv, glm::length(d[j]));
  }
  for (int j = 0; j < kv; ++j)
    for (int i = 0; i < ku; ++i)
      c.uv = std::max(c.uv, glm::length((at(i + 1, j + 1) - at(i + 1, j) - at(i, j + 1) + at(i, j)) * suv));
  return c;
}

// Grid segments so that (uu hu^2 + 2 uv hu hv + vv hv^2) / 8, the interpolation error bound of a
// triangle with legs hu = 1/N and hv = 1/M, stays within the tolerance.
void planGrid(const Curvature& c, double tolerance, uint32_t& n, uint32_t& m) {
  const double uu = c.uu * kCurvatureSafety, uv = c.uv * kCurvatureSafety, vv = c.vv * kCurvatureSafety;
  n = segmentsFor(std::sqrt(uu / (4.0 * tolerance)), 2, kMaxGridSegments);
  m = segmentsFor(std::sqrt(vv / (4.0 * tolerance)), 2, kMaxGridSegments);
  for (int iteration = 0; iteration < 8; ++iteration) {
    const double hu = 1.0 / n, hv = 1.0 / m;
    const double err = (uu * hu * hu + 2.0 * uv * hu * hv + vv * hv * hv) / 8.0;
    if (!(err > tolerance)) break;
    const double f = std::max(std::sqrt(err / tolerance), 1.01);
    const uint32_t n2 = segmentsFor(n * f, 2, kMaxGridSegments), m2 = segmentsFor(m * f, 2, kMaxGridSegments);
    if (n2 == n && m2 == m) break;
    n = n2;
    m = m2;
  }
}

// ---------------------------------------------------------------------------------------------
// Corners and adjacency.

using CellKey = GridCellKey;
using CellHash = GridCellHash;

// Clusters of points closer than eps (transitively); returns the root (smallest index) of each.
std::vector<uint32_t> clusterPoints(const std::vector<glm::vec3>& points, double eps) {
  UnionFind uf(points.size());
  const double cell = 2.0 * eps;
  std::unordered_map<CellKey, std::vector<uint32_t>, CellHash> grid;
  std::unordered_map<CellKey, std::vector<uint32_t>, CellHash> exact;  // points off the grid
  for (uint32_t i = 0; i < points.size(); ++i) {
    const glm::dvec3 q = glm::floor(glm::dvec3(points[i]) / cell);
    const bool gridded = cell > 0.0 && std::abs(q.x) < 1e15 && std::abs(q.y) < 1e15 && std::abs(q.z) < 1e15;
    if (!gridded) {
      const CellKey key{static_cast<int64_t>(std::bit_cast<uint32_t>(points[i].x + 0.0f)),
                        static_cast<int64_t>(std::bit_cast<uint32_t>(points[i].y + 0.0f)),
                        static_cast<int64_t>(std::bit_cast<uint32_t>(points[i].z + 0.0f))};
      auto& list = exact[key];
      if (!list.empty()) uf.unite(list.front(), i);
      list.push_back(i);
      continue;
    }
    const CellKey key{static_cast<int64_t>(q.x), static_cast<int64_t>(q.y), static_cast<int64_t>(q.z)};
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const auto it = grid.find(CellKey{key.x + dx, key.y + dy, key.z + dz});
          if (it == grid.end()) continue;
          // A cell is 2 eps wide: more than a few dozen corners in one is not CAD data, and
          // comparing with all of them would be quadratic.
          const size_t count = std::min<size_t>(it->second.size(), kMaxCandidates);
          for (size_t k = 0; k < count; ++k)
            if (dist(points[i], points[it->second[k]]) <= eps) uf.unite(i, it->second[k]);
        }
    grid[key].push_back(i);
  }
  std::vector<uint32_t> root(points.size());
  for (uint32_t i = 0; i < points.size(); ++i) root[i] = uf.find(i);
  return root;
}

// Distance from q to side `side` of a patch (whose sample polyline is `samples`, kBorderSamples
// + 1 points), and the parameter t of the closest point: nearest sample, then golden-section
// search on the two sample intervals around it.
double searchSide(const PatchEval& e, int side, const glm::vec3& q, int around, double& t_out) {
  double lo = std::max(0, around - 1) / static_cast<double>(kBorderSamples);
  double hi = std::min(kBorderSamples, around + 1) / static_cast<double>(kBorderSamples);
  constexpr double kGolden = 0.6180339887498949;
  double a = hi - kGolden * (hi - lo), b = lo + kGolden * (hi - lo);
  double fa = dist(e.border(side, a), q), fb = dist(e.border(side, b), q);
  for (int it = 0; it < 28; ++it) {
    if (fa < fb) {
      hi = b, b = a, fb = fa;
      a = hi - kGolden * (hi - lo);
      fa = dist(e.border(side, a), q);
    } else {
      lo = a, a = b, fa = fb;
      b = lo + kGolden * (hi - lo);
      fb = dist(e.border(side, b), q);
    }
  }
  t_out = fa < fb ? a : b;
  return std::min(fa, fb);
}

// Distance from q to side `side` of a patch (whose sample polyline is `samples`, kBorderSamples
// + 1 points), and the parameter t of the closest point: nearest sample, then golden-section
// search on the two sample intervals around it (around both ends when the side is a loop).
double projectOnSide(const PatchEval& e, int side, const glm::vec3* samples, const glm::vec3& q, double& t_out,
                     glm::vec3* normal) {
  int nearest = 0;
  double best = dist(samples[0], q);
  for (int k = 1; k <= kBorderSamples; ++k)
    if (const double d = dist(samples[k], q); d < best) best = d, nearest = k;
  double t = static_cast<double>(nearest) / kBorderSamples, found;
  if (const double d = searchSide(e, side, q, nearest, found); d < best) best = d, t = found;
  const bool loop = samples[0] == samples[kBorderSamples];
  if (loop && (nearest == 0 || nearest == kBorderSamples))
    if (const double d = searchSide(e, side, q, kBorderSamples - nearest, found); d < best) best = d, t = found;
  t_out = t;
  if (normal) e.border(side, t, normal);
  return best;
}

// Does every sample of border a lie on border b (within eps)? `opposite`: the two run in
// opposite directions, so sample k of a is expected near sample kBorderSamples - k of b.
bool liesOn(const std::vector<PatchEval>& evals, const std::vector<glm::vec3>& samples, uint32_t a, uint32_t b,
            bool opposite, double eps) {
  const glm::vec3* sa = &samples[static_cast<size_t>(a) * (kBorderSamples + 1)];
  const glm::vec3* sb = &samples[static_cast<size_t>(b) * (kBorderSamples + 1)];
  for (int k = 1; k < kBorderSamples; ++k) {
    if (dist(sa[k], sb[opposite ? kBorderSamples - k : k]) <= eps) continue;  // same parameterisation
    double t;
    if (!(projectOnSide(evals[b / 4], static_cast<int>(b % 4), sb, sa[k], t, nullptr) <= eps)) return false;
  }
  return true;
}

// ---------------------------------------------------------------------------------------------
// Output.

class Emitter {
 public:
  Emitter(TriangleMesh& out, ConformingTessellationStats& stats)
      : out_(out), stats_(stats), base_(static_cast<uint32_t>(out.positions.size())),
        with_normals_(out.normals.size() == out.positions.size()) {}

  uint32_t vertex(const glm::vec3& p) {
    const auto index = static_cast<uint32_t>(out_.positions.size());
    out_.positions.push_back(p);
    normals_.push_back(glm::vec3(0.0f));
    return index;
  }
  // Vertices from before this emitter (placed by someone else) keep their normals.
  void addNormal(uint32_t v, const glm::vec3& n) {
    if (v >= base_) normals_[v - base_] += n;
  }
  const glm::vec3& position(uint32_t v) const { return out_.positions[v]; }
  void triangle(uint32_t a, uint32_t b, uint32_t c, bool flipped) {
    if (a == b || b == c || a == c) return;  // a collapsed border (pole) seen from its fan
    if (flipped) std::swap(b, c);
    out_.indices.insert(out_.indices.end(), {a, b, c});
    ++stats_.triangles;
  }
  void finish() {
    if (!with_normals_) return;
    out_.normals.reserve(out_.positions.size());
    for (const glm::vec3& n : normals_) {
      const float len = glm::length(n);
      out_.normals.push_back(len > 1e-12f && std::isfinite(len) ? n / len : glm::vec3(0.0f, 0.0f, 1.0f));
    }
  }

 private:
  TriangleMesh& out_;
  ConformingTessellationStats& stats_;
  uint32_t base_;
  bool with_normals_;
  std::vector<glm::vec3> normals_;
};

// A border string in the counter-clockwise order of the patch that placed it.
struct BorderString {
  std::vector<uint32_t> vertices;
  std::vector<double> params;  // t of each vertex on the placing side
  bool placed = false;
};

// Places the points of side `side` of a patch: `segments` equal parameter steps (aligned with
// the interior grid's lines when `segments` is the grid's count along the side, so the strip
// triangles are shaped like grid triangles), then bisection while the curve leaves the chord by
// more than the tolerance. End points are the corner vertices; returns the interior parameters.
// `bisections` is the set's remaining budget of points added by bisection.
void placeBorder(const PatchEval& e, int side, double tolerance, uint32_t segments, uint64_t& bisections,
                 std::vector<double>& params, std::vector<glm::vec3>& points) {
  std::vector<double> seeds;
  for (uint32_t i = 0; i <= segments; ++i) seeds.push_back(static_cast<double>(i) / segments);
  seeds.back() = 1.0;

  // Bisection, depth first and left first so points come out in order.
  params.clear();
  points.clear();
  struct Segment {
    double t0, t1;
    glm::vec3 p0, p1, mid;
    int depth;
  };
  std::vector<Segment> stack;
  glm::vec3 prev = e.border(side, 0.0);
  for (size_t s = 0; s + 1 < seeds.size(); ++s) {
    const double t0 = seeds[s], t1 = seeds[s + 1];
    const glm::vec3 p1 = e.border(side, t1);
    stack.push_back({t0, t1, prev, p1, e.border(side, 0.5 * (t0 + t1)), 0});
    prev = p1;
    while (!stack.empty()) {
      Segment g = stack.back();
      stack.pop_back();
      const double tm = 0.5 * (g.t0 + g.t1);
      const glm::vec3 q1 = e.border(side, 0.5 * (g.t0 + tm)), q3 = e.border(side, 0.5 * (tm + g.t1));
      const double dev = std::max({distToSegment(g.mid, g.p0, g.p1), distToSegment(q1, g.p0, g.p1),
                                   distToSegment(q3, g.p0, g.p1)});
      const bool room = points.size() + stack.size() + seeds.size() < kMaxBorderSegments && bisections > 0;
      if (dev > tolerance && g.depth < kMaxBisectionDepth && room) {
        --bisections;
        stack.push_back({tm, g.t1, g.mid, g.p1, q3, g.depth + 1});  // right half done second
        stack.push_back({g.t0, tm, g.p0, g.mid, q1, g.depth + 1});
        continue;
      }
      if (g.t1 < 1.0) {
        params.push_back(g.t1);
        points.push_back(g.p1);
      }
    }
  }
}

// A chain of vertices along one side, with each vertex's parameter t along the side.
struct Chain {
  const std::vector<uint32_t>* vertices = nullptr;
  const std::vector<double>* t = nullptr;
};

// Joins a border chain to the inner chain beside it (both counter-clockwise, interior on the
// left) with one strip. The walk keeps the two advancing fronts level in the parameter plane
// (the chain whose next edge midpoint comes first advances), so each strip triangle spans about
// one grid cell across and one step along, like the grid's own triangles, however sheared the
// surface is in space.
void zip(const Chain& border, const Chain& inner, Emitter& emit, bool flipped) {
  const std::vector<uint32_t>& bv = *border.vertices;
  const std::vector<uint32_t>& iv = *inner.vertices;
  const std::vector<double>& bt = *border.t;
  const std::vector<double>& it = *inner.t;
  const size_t nb = bv.size() - 1, ni = iv.size() - 1;
  size_t i = 0, j = 0;
  while (i < nb || j < ni) {
    const bool advance_border = j == ni || (i < nb && bt[i] + bt[i + 1] <= it[j] + it[j + 1]);
    if (advance_border) {
      emit.triangle(bv[i], bv[i + 1], iv[j], flipped);
      ++i;
    } else {
      emit.triangle(bv[i], iv[j + 1], iv[j], flipped);
      ++j;
    }
  }
}

// The inside of one patch: the interior grid of n x m cells (vertices i = 1 .. n-1,
// j = 1 .. m-1), then one strip per side between the side's border string and the grid's outer
// ring. `sign` orients the normals, `flip` the triangles.
void meshInside(const PatchEval& e, uint32_t n, uint32_t m, const std::array<Chain, 4>& sides,
                float sign, bool flip, Emitter& emit, ConformingTessellationStats& stats) {
  std::vector<uint32_t> grid, inner;
  std::vector<double> inner_t;
  // Interior grid (i = 1 .. n-1, j = 1 .. m-1).
  grid.resize(size_t{n - 1} * (m - 1));
  auto g = [&](uint32_t a, uint32_t c) { return grid[size_t{c - 1} * (n - 1) + (a - 1)]; };
  for (uint32_t c = 1; c < m; ++c)
    for (uint32_t a = 1; a < n; ++a) {
      glm::vec3 normal;
      const glm::vec3 p = e.at(static_cast<double>(a) / n, static_cast<double>(c) / m, &normal);
      const uint32_t v = emit.vertex(p);
      emit.addNormal(v, sign * normal);
      grid[size_t{c - 1} * (n - 1) + (a - 1)] = v;
      ++stats.interior_vertices;
    }
  for (uint32_t c = 1; c + 1 < m; ++c)
    for (uint32_t a = 1; a + 1 < n; ++a) {
      const uint32_t v00 = g(a, c), v10 = g(a + 1, c), v11 = g(a + 1, c + 1), v01 = g(a, c + 1);
      if (dist(emit.position(v00), emit.position(v11)) <= dist(emit.position(v10), emit.position(v01))) {
        emit.triangle(v00, v10, v11, flip);
        emit.triangle(v00, v11, v01, flip);
      } else {
        emit.triangle(v00, v10, v01, flip);
        emit.triangle(v10, v11, v01, flip);
      }
    }
  // One strip per side, between the border string and the grid's outer ring.
  for (int s = 0; s < 4; ++s) {
    inner.clear();
    inner_t.clear();
    auto push = [&](uint32_t a, uint32_t c, double t) {
      inner.push_back(g(a, c));
      inner_t.push_back(t);
    };
    switch (s) {
      case 0:
        for (uint32_t a = 1; a < n; ++a) push(a, 1, static_cast<double>(a) / n);
        break;
      case 1:
        for (uint32_t c = 1; c < m; ++c) push(n - 1, c, static_cast<double>(c) / m);
        break;
      case 2:
        for (uint32_t a = n - 1; a >= 1; --a) push(a, m - 1, 1.0 - static_cast<double>(a) / n);
        break;
      default:
        for (uint32_t c = m - 1; c >= 1; --c) push(1, c, 1.0 - static_cast<double>(c) / m);
        break;
    }
    zip(sides[s], Chain{&inner, &inner_t}, emit, flip);
  }
}

}  // namespace

void tessellateNurbsConforming(const NurbsPatchSet& set, float chordal_tolerance, TriangleMesh& out,
                               ConformingTessellationStats* stats_out) {
  ConformingTessellationStats stats;
  const size_t patch_count = set.patches.size();
  for (size_t i = 0; i < patch_count; ++i)
    if (std::string reason = validateNurbsPatch(set.patches[i]); !reason.empty())
      throw std::invalid_argument("NURBS patch " + std::to_string(i) + ": " + reason);
  if (patch_count == 0) {
    if (stats_out) *stats_out = stats;
    return;
  }
  if (patch_count > (size_t{1} << 28)) throw std::invalid_argument("NURBS patch set too large");
  stats.patches = static_cast<uint32_t>(patch_count);

  std::vector<PatchEval> evals(patch_count);
  for (size_t i = 0; i < patch_count; ++i) evals[i] = {&set.patches[i], nurbsDomain(set.patches[i])};

  // Border sample polylines and the set's size.
  const size_t border_count = 4 * patch_count;
  std::vector<glm::vec3> samples(border_count * (kBorderSamples + 1));
  glm::dvec3 lo(INFINITY), hi(-INFINITY);
  double magnitude = 0.0;
  for (size_t b = 0; b < border_count; ++b)
    for (int k = 0; k <= kBorderSamples; ++k) {
      const glm::vec3 p = evals[b / 4].border(static_cast<int>(b % 4), static_cast<double>(k) / kBorderSamples);
      samples[b * (kBorderSamples + 1) + k] = p;
      lo = glm::min(lo, glm::dvec3(p));
      hi = glm::max(hi, glm::dvec3(p));
      magnitude = std::max({magnitude, std::abs(static_cast<double>(p.x)), std::abs(static_cast<double>(p.y)),
                            std::abs(static_cast<double>(p.z))});
    }
  auto sampleOf = [&](size_t border, int k) -> const glm::vec3& { return samples[border * (kBorderSamples + 1) + k]; };
  // Coincidence distance: relative to the set's size, and above float rounding at its magnitude.
  double eps = std::max(kRelativeEps * glm::length(hi - lo), 1e-6 * magnitude);
  if (!std::isfinite(eps)) eps = 0.0;

  // 1. Interior grids, coarsening the tolerance while the set would be too large.
  double tolerance = std::isfinite(chordal_tolerance) && chordal_tolerance > 0.0f ? chordal_tolerance : INFINITY;
  std::vector<Curvature> curvature(patch_count);
  for (size_t i = 0; i < patch_count; ++i) curvature[i] = sampleCurvature(evals[i]);
  std::vector<uint32_t> grid_n(patch_count), grid_m(patch_count);
  for (int attempt = 0;; ++attempt) {
    uint64_t total = 0;
    for (size_t i = 0; i < patch_count; ++i) {
      planGrid(curvature[i], tolerance, grid_n[i], grid_m[i]);
      total += 2 * uint64_t{grid_n[i]} * grid_m[i] + 4 * uint64_t{grid_n[i] + grid_m[i]};
    }
    if (total <= kMaxSetTriangles || attempt >= 24 || !std::isfinite(tolerance)) break;
    tolerance *= 4.0;
  }

  // 2. Corner clusters. Corner c of patch i is point 4 i + c; side s starts at corner s.
  std::vector<glm::vec3> corners(border_count);
  for (size_t b = 0; b < border_count; ++b) corners[b] = sampleOf(b, 0);
  const std::vector<uint32_t> cluster = clusterPoints(corners, eps);
  auto startCluster = [&](size_t b) { return cluster[b]; };
  auto endCluster = [&](size_t b) { return cluster[(b / 4) * 4 + (b % 4 + 1) % 4]; };

  // Poles: sides that collapse to a point.
  std::vector<char> pole(border_count, 0);
  for (size_t b = 0; b < border_count; ++b) {
    bool collapsed = startCluster(b) == endCluster(b);
    for (int k = 1; k <= kBorderSamples && collapsed; ++k) collapsed = dist(sampleOf(b, k), sampleOf(b, 0)) <= eps;
    pole[b] = collapsed;
  }

  // 3. Adjacency: candidates share their end clusters.
  std::vector<uint32_t> partner(border_count, kNone);
  std::vector<char> opposite(border_count, 1);
  {
    std::unordered_map<uint64_t, std::vector<uint32_t>> by_ends;
    auto keyOf = [&](size_t b) {
      const uint64_t a = startCluster(b), z = endCluster(b);
      return (std::min(a, z) << 32) | std::max(a, z);
    };
    for (size_t b = 0; b < border_count; ++b)
      if (!pole[b]) by_ends[keyOf(b)].push_back(static_cast<uint32_t>(b));
    for (size_t a = 0; a < border_count; ++a) {
      if (pole[a] || partner[a] != kNone) continue;
      // Candidates after a, in border order; a few dozen at most (more borders between the
      // same two corners is not CAD data, and would make this quadratic).
      const std::vector<uint32_t>& list = by_ends[keyOf(a)];
      const auto from = std::upper_bound(list.begin(), list.end(), static_cast<uint32_t>(a));
      const auto to = list.end() - from > kMaxCandidates ? from + kMaxCandidates : list.end();
      for (auto it = from; it != to; ++it) {
        const uint32_t b = *it;
        if (partner[b] != kNone) continue;
        std::array<bool, 2> directions{true, false};  // opposite first: the consistent case
        size_t tries = 2;
        if (startCluster(a) != endCluster(a)) {
          directions[0] = startCluster(a) == endCluster(b);
          tries = 1;
        }
        for (size_t d = 0; d < tries; ++d) {
          const bool opp = directions[d];
          if (liesOn(evals, samples, static_cast<uint32_t>(a), b, opp, eps) &&
              liesOn(evals, samples, b, static_cast<uint32_t>(a), opp, eps)) {
            partner[a] = b;
            partner[b] = static_cast<uint32_t>(a);
            opposite[a] = opposite[b] = opp;
            ++stats.shared_borders;
            break;
          }
        }
        if (partner[a] != kNone) break;
      }
    }
  }

  // Orientation: a patch whose shared border runs the same way as its neighbour's is flipped
  // (breadth first from the lowest patch of each connected group; non-orientable sets keep the
  // first choice).
  std::vector<char> flipped(patch_count, 0), seen(patch_count, 0);
  {
    std::vector<uint32_t> queue;
    for (size_t start = 0; start < patch_count; ++start) {
      if (seen[start]) continue;
      seen[start] = 1;
      queue.assign(1, static_cast<uint32_t>(start));
      for (size_t q = 0; q < queue.size(); ++q) {
        const uint32_t i = queue[q];
        for (int s = 0; s < 4; ++s) {
          const uint32_t b = partner[size_t{i} * 4 + s];
          if (b == kNone) continue;
          const uint32_t j = b / 4;
          if (seen[j]) continue;
          seen[j] = 1;
          flipped[j] = flipped[i] != !opposite[size_t{i} * 4 + s];
          queue.push_back(j);
        }
      }
    }
  }

  // 4 and 5. Vertices and triangles, patch by patch.
  Emitter emit(out, stats);
  {
    uint64_t estimate = 0;
    for (size_t i = 0; i < patch_count; ++i) estimate += 2 * uint64_t{grid_n[i]} * grid_m[i] + 4 * uint64_t{grid_n[i] + grid_m[i]};
    out.indices.reserve(out.indices.size() + static_cast<size_t>(std::min<uint64_t>(3 * estimate, 3 * kMaxSetTriangles)));
    out.positions.reserve(out.positions.size() + static_cast<size_t>(std::min<uint64_t>(estimate / 2 + 16, kMaxSetTriangles)));
  }
  std::vector<uint32_t> cluster_vertex(border_count, kNone);
  std::vector<BorderString> strings(border_count);
  std::vector<double> params;
  std::vector<glm::vec3> points;
  uint64_t bisections = kMaxSetBisections;
  for (size_t i = 0; i < patch_count; ++i) {
    const PatchEval& e = evals[i];
    const bool flip = flipped[i];
    const float sign = flip ? -1.0f : 1.0f;
    const uint32_t n = grid_n[i], m = grid_m[i];
    // Corners: one vertex per cluster, at the position of the cluster's first corner.
    std::array<uint32_t, 4> corner_vertex{};
    for (int c = 0; c < 4; ++c) {
      const uint32_t root = cluster[4 * i + c];
      if (cluster_vertex[root] == kNone) {
        cluster_vertex[root] = emit.vertex(corners[root]);
        ++stats.border_vertices;
      }
      corner_vertex[c] = cluster_vertex[root];
      glm::vec3 normal;
      e.border(c, 0.0, &normal);
      emit.addNormal(corner_vertex[c], sign * normal);
    }
    // Border strings.
    for (int s = 0; s < 4; ++s) {
      const size_t b = 4 * i + s;
      BorderString& str = strings[b];
      const uint32_t first = corner_vertex[s], last = corner_vertex[(s + 1) % 4];
      if (pole[b]) {
        str.vertices.assign(1, first);
        str.params.assign(1, 0.0);
        str.placed = true;
        continue;
      }
      const uint32_t other = partner[b];
      if (other != kNone && strings[other].placed) {
        // Reuse the partner's vertices; only this side's normals are new.
        const BorderString& theirs = strings[other];
        const size_t count = theirs.vertices.size();
        str.vertices.resize(count);
        str.params.resize(count);
        for (size_t k = 0; k < count; ++k) {
          const size_t from = opposite[b] ? count - 1 - k : k;
          str.vertices[k] = theirs.vertices[from];
          str.params[k] = opposite[b] ? 1.0 - theirs.params[from] : theirs.params[from];
        }
        str.vertices.front() = first;  // the same clusters, so the same vertices already
        str.vertices.back() = last;
        for (size_t k = 1; k + 1 < count; ++k) {
          const glm::vec3 p = out.positions[str.vertices[k]];
          glm::vec3 normal;
          // The same parameterisation as the partner (the usual case) needs no projection.
          if (!(dist(e.border(s, str.params[k], &normal), p) <= eps))
            projectOnSide(e, s, &sampleOf(b, 0), p, str.params[k], &normal);
          emit.addNormal(str.vertices[k], sign * normal);
        }
        str.params.front() = 0.0;
        str.params.back() = 1.0;
        for (size_t k = 1; k < count; ++k) str.params[k] = std::clamp(str.params[k], str.params[k - 1], 1.0);
        str.placed = true;
        continue;
      }
      // Place: as many steps as the interior grid has along this side; more if the partner's
      // grid is finer there (its spacing then bounds the edge length).
      auto along = [&](size_t border) { return border % 2 == 0 ? grid_n[border / 4] : grid_m[border / 4]; };
      auto length = [&](size_t border) {
        double len = 0.0;
        for (int k = 1; k <= kBorderSamples; ++k) len += dist(sampleOf(border, k - 1), sampleOf(border, k));
        return len;
      };
      uint32_t segments = along(b);
      if (other != kNone)
        segments = std::max(segments, segmentsFor(length(b) * along(other) / length(other), 1, kMaxBorderSegments / 2));
      placeBorder(e, s, tolerance, segments, bisections, params, points);
      str.vertices.clear();
      str.vertices.push_back(first);
      str.params.assign(1, 0.0);
      str.params.insert(str.params.end(), params.begin(), params.end());
      str.params.push_back(1.0);
      for (size_t k = 0; k < points.size(); ++k) {
        const uint32_t v = emit.vertex(points[k]);
        ++stats.border_vertices;
        glm::vec3 normal;
        e.border(s, params[k], &normal);
        emit.addNormal(v, sign * normal);
        str.vertices.push_back(v);
      }
      str.vertices.push_back(last);
      str.placed = true;
    }
    std::array<Chain, 4> sides;
    for (int s = 0; s < 4; ++s) sides[s] = Chain{&strings[4 * i + s].vertices, &strings[4 * i + s].params};
    meshInside(e, n, m, sides, sign, flip, emit, stats);
  }
  emit.finish();
  if (stats_out) *stats_out = stats;
}

bool tessellatePatchInside(const NurbsPatch& patch, const std::array<PatchSideString, 4>& sides,
                           float chordal_tolerance, bool flip, TriangleMesh& out,
                           ConformingTessellationStats* stats_out) {
  uint32_t n = 2, m = 2;
  if (!planPatchGrid(patch, chordal_tolerance, n, m)) return false;
  for (const PatchSideString& side : sides) {
    if (side.vertices.empty() || side.vertices.size() != side.t.size()) return false;
    for (uint32_t v : side.vertices)
      if (v >= out.positions.size()) return false;
  }
  for (int s = 0; s < 4; ++s)  // each side ends where the next begins
    if (sides[s].vertices.back() != sides[(s + 1) % 4].vertices.front()) return false;
  const PatchEval e{&patch, nurbsDomain(patch)};
  ConformingTessellationStats stats;
  stats.patches = 1;
  Emitter emit(out, stats);
  std::array<Chain, 4> chains;
  for (int s = 0; s < 4; ++s) chains[s] = Chain{&sides[s].vertices, &sides[s].t};
  meshInside(e, n, m, chains, flip ? -1.0f : 1.0f, flip, emit, stats);
  emit.finish();
  if (stats_out) *stats_out = stats;
  return true;
}

bool planPatchGrid(const NurbsPatch& patch, float chordal_tolerance, uint32_t& n, uint32_t& m) {
  if (!validateNurbsPatch(patch).empty()) return false;
  const PatchEval e{&patch, nurbsDomain(patch)};
  const double tolerance =
      std::isfinite(chordal_tolerance) && chordal_tolerance > 0.0f ? chordal_tolerance : INFINITY;
  planGrid(sampleCurvature(e), tolerance, n, m);
  return true;
}

uint64_t nurbsConformingTriangleCount(const NurbsPatchSet& patches, float chordal_tolerance) {
  ConformingTessellationStats stats;
  TriangleMesh scratch;
  tessellateNurbsConforming(patches, chordal_tolerance, scratch, &stats);
  return scratch.triangleCount();
}

}  // namespace tw
