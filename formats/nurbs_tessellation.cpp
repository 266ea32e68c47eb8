// Crack-free tessellation of NURBS patch sets at a chordal tolerance (ENVIRON's algorithm).
//
// Each patch samples its four border curves with a segment count and parameter values that depend
// only on that border curve's own data, evaluated in a canonical direction, so the patch on the
// other side of a shared border produces the very same floats. The interior is a regular grid
// sized by the patch's own needs, joined to the border samples by one strip of triangles per side.
// Border vertices are welded across the whole set (by exact position bits, and within a tiny snap
// distance for borders whose knots agree only up to rounding), which makes a set of patches that
// closes up a watertight indexed mesh. Counting runs the same plan without evaluating the surface.
#include <algorithm>
#include <bit>
#include <cmath>
#include <unordered_map>
#include <vector>

#include "nurbs.h"
#include "position_key.h"
#include "tessellate.h"

namespace tw {
namespace {

// Segment limits. A span never needs more than kMaxSpanSegments; a curve or grid direction over
// kMaxCurveSegments is scaled down (each non-empty knot span keeps at least one segment).
constexpr uint32_t kMaxSpanSegments = 1024;
constexpr uint32_t kMaxCurveSegments = 1024;
// A set whose plan exceeds this many triangles is re-planned at a coarser tolerance (x4 each
// time), so hostile control nets cannot demand unbounded work.
constexpr uint64_t kMaxSetTriangles = uint64_t{1} << 23;

enum Side : int { kBottom = 0, kRight = 1, kTop = 2, kLeft = 3 };

// A B-spline curve with homogeneous control points (w x, w y, w z, w) and knots normalised so its
// domain is [0, 1]. Products of two floats are exact in double, so homogeneous points built from
// the same float data are bitwise equal whichever patch builds them.
struct Curve {
  uint32_t degree = 1;
  std::vector<glm::dvec4> h;
  std::vector<double> t;
  size_t count() const { return h.size(); }
};

glm::dvec4 homogeneous(const glm::vec4& cp) {
  const double w = cp.w;
  return {cp.x * w, cp.y * w, cp.z * w, w};
}

// Knot span s in [p, n - 1] with t[s] <= x < t[s + 1]; the last non-empty span at the end.
uint32_t findSpan(const std::vector<double>& t, uint32_t p, uint32_t n, double x) {
  if (x >= t[n]) {
    uint32_t s = n - 1;
    while (s > p && !(t[s] < t[n])) --s;
    return s;
  }
  if (x <= t[p]) {
    uint32_t s = p;
    while (s + 1 < n && !(t[s] < t[s + 1])) ++s;
    return s;
  }
  uint32_t lo = p, hi = n;
  while (hi - lo > 1) {
    const uint32_t mid = lo + (hi - lo) / 2;
    if (x < t[mid])
      hi = mid;
    else
      lo = mid;
  }
  return lo;
}

// de Boor's algorithm on homogeneous points: the curve point at x in span s. `pts(i)` yields the
// i-th homogeneous control point.
template <typename Points>
glm::dvec4 deBoor(const Points& pts, const std::vector<double>& t, uint32_t p, uint32_t s, double x) {
  glm::dvec4 d[16];
  for (uint32_t j = 0; j <= p; ++j) d[j] = pts(j + s - p);
  for (uint32_t r = 1; r <= p; ++r)
    for (uint32_t j = p; j >= r; --j) {
      const uint32_t i = j + s - p;
      const double den = t[i + 1 + p - r] - t[i];
      const double alpha = den != 0.0 ? (x - t[i]) / den : 0.0;
      d[j] = (1.0 - alpha) * d[j - 1] + alpha * d[j];
    }
  return d[p];
}

// Normalised knots: (k - k[p]) / (k[n] - k[p]) forwards; reversed, the mirror image computed as
// (k[n] - k[m - i]) / (k[n] - k[p]) so that a border given the other way round by the neighbour
// normalises to the same numbers.
void normaliseKnots(const std::vector<float>& k, uint32_t p, uint32_t n, bool reversed, std::vector<double>& t) {
  const size_t m = k.size() - 1;
  const double k0 = k[p], k1 = k[n], len = k1 - k0;
  t.resize(k.size());
  for (size_t i = 0; i <= m; ++i) t[i] = reversed ? (k1 - k[m - i]) / len : (k[i] - k0) / len;
}

// Segments each knot span of a curve needs for the chordal tolerance, from the bound
// |C - chord| <= h^2 / 8 max|C''|, with max|C''| bounded by the second-derivative control points
// of the span (convex hull property), times w_max / w_min for rational spans (a heuristic; the
// tests check it on exact circles). counts[s - p] for span s; empty spans get 0.
template <typename Points>
void spanSegments(const Points& pts, uint32_t n, const std::vector<double>& t, uint32_t p, double tolerance,
                  std::vector<uint32_t>& counts) {
  counts.assign(n - p, 0);
  const double inv8tol = std::isfinite(tolerance) && tolerance > 0.0 ? 1.0 / (8.0 * tolerance) : 0.0;
  for (uint32_t s = p; s < n; ++s) {
    const double span = t[s + 1] - t[s];
    if (!(span > 0.0)) continue;
    double m2 = 0.0, w_min = INFINITY, w_max = 0.0;
    for (uint32_t i = s - p; i <= s; ++i) {
      const double w = pts(i).w;
      w_min = std::min(w_min, w);
      w_max = std::max(w_max, w);
    }
    if (p >= 2 && inv8tol > 0.0) {
      // Second-derivative control points i = s-p .. s-2 from the Cartesian control points.
      auto cart = [&](uint32_t i) {
        const glm::dvec4 h = pts(i);
        return glm::dvec3(h) / h.w;
      };
      auto d1 = [&](uint32_t i) {  // first-derivative control point
        const double den = t[i + p + 1] - t[i + 1];
        return den > 0.0 ? (static_cast<double>(p) / den) * (cart(i + 1) - cart(i)) : glm::dvec3(0.0);
      };
      for (uint32_t i = s - p; i + 2 <= s; ++i) {
        const double den = t[i + p + 1] - t[i + 2];
        if (!(den > 0.0)) continue;
        const glm::dvec3 d2 = (static_cast<double>(p - 1) / den) * (d1(i + 1) - d1(i));
        m2 = std::max(m2, glm::length(d2));
      }
    }
    const double need = span * std::sqrt(m2 * (w_max / w_min) * inv8tol);
    uint32_t c = 1;
    if (need >= kMaxSpanSegments)
      c = kMaxSpanSegments;
    else if (need > 1.0)
      c = static_cast<uint32_t>(std::ceil(need));
    counts[s - p] = c;
  }
}

// Scales per-span counts down when their sum exceeds kMaxCurveSegments (every non-empty span
// keeps one). Depends only on the multiset of counts and their order, so both sides of a border
// agree.
uint32_t capCounts(std::vector<uint32_t>& counts) {
  uint64_t total = 0;
  for (uint32_t c : counts) total += c;
  if (total > kMaxCurveSegments) {
    uint64_t capped = 0;
    for (uint32_t& c : counts) {
      if (c == 0) continue;
      c = static_cast<uint32_t>(std::max<uint64_t>(1, uint64_t{c} * kMaxCurveSegments / total));
      capped += c;
    }
    total = capped;
  }
  return static_cast<uint32_t>(total);
}

// One border of a patch in canonical form, with its samples' plan.
struct Border {
  Curve curve;
  bool reversed = false;  // canonical order runs against the patch parameter
  bool point = false;     // the whole border is a single point (a pole)
  std::vector<uint32_t> counts;
  uint32_t segments = 0;  // 0 for a point
};

bool lexLess(const glm::dvec4& a, const glm::dvec4& b) {
  if (a.x != b.x) return a.x < b.x;
  if (a.y != b.y) return a.y < b.y;
  if (a.z != b.z) return a.z < b.z;
  return a.w < b.w;
}

// Homogeneous control points of the patch's border on `side`, in the patch's increasing
// parameter order. Clamped knots give the border row itself; otherwise the rows are blended at
// the domain end with de Boor.
void borderControlPoints(const NurbsPatch& patch, Side side, std::vector<glm::dvec4>& out, std::vector<double>& scratch) {
  const bool along_u = side == kBottom || side == kTop;
  const uint32_t n_along = along_u ? patch.count_u : patch.count_v;
  const uint32_t n_across = along_u ? patch.count_v : patch.count_u;
  const uint32_t p_across = along_u ? patch.degree_v : patch.degree_u;
  const std::vector<float>& k_across = along_u ? patch.knots_v : patch.knots_u;
  const bool at_end = side == kTop || side == kRight;
  auto at = [&](uint32_t along, uint32_t across) {
    const size_t index = along_u ? size_t{across} * patch.count_u + along : size_t{along} * patch.count_u + across;
    return homogeneous(patch.control_points[index]);
  };
  out.resize(n_along);
  const bool clamped = at_end ? k_across[n_across] == k_across[n_across + p_across] : k_across[0] == k_across[p_across];
  if (clamped) {
    const uint32_t row = at_end ? n_across - 1 : 0;
    for (uint32_t i = 0; i < n_along; ++i) out[i] = at(i, row);
    return;
  }
  normaliseKnots(k_across, p_across, n_across, false, scratch);
  const double x = at_end ? 1.0 : 0.0;
  const uint32_t s = findSpan(scratch, p_across, n_across, x);
  for (uint32_t i = 0; i < n_along; ++i)
    out[i] = deBoor([&](uint32_t j) { return at(i, j); }, scratch, p_across, s, x);
}

void planBorder(const NurbsPatch& patch, Side side, double tolerance, Border& b, std::vector<glm::dvec4>& raw,
                std::vector<double>& scratch) {
  const bool along_u = side == kBottom || side == kTop;
  const uint32_t p = along_u ? patch.degree_u : patch.degree_v;
  const uint32_t n = along_u ? patch.count_u : patch.count_v;
  borderControlPoints(patch, side, raw, scratch);
  // Canonical direction: the control sequence or its reverse, whichever is lexicographically
  // smaller, so both patches along a border walk it the same way.
  b.reversed = false;
  for (uint32_t i = 0; i < n / 2; ++i) {
    const glm::dvec4 &a = raw[i], &z = raw[n - 1 - i];
    if (a == z) continue;
    b.reversed = lexLess(z, a);
    break;
  }
  b.curve.degree = p;
  b.curve.h.resize(n);
  for (uint32_t i = 0; i < n; ++i) b.curve.h[i] = raw[b.reversed ? n - 1 - i : i];
  normaliseKnots(along_u ? patch.knots_u : patch.knots_v, p, n, b.reversed, b.curve.t);
  b.point = true;
  const glm::dvec3 first = glm::dvec3(b.curve.h[0]) / b.curve.h[0].w;
  for (uint32_t i = 1; i < n && b.point; ++i)
    b.point = glm::dvec3(b.curve.h[i]) / b.curve.h[i].w == first;
  if (b.point) {
    b.counts.clear();
    b.segments = 0;
    return;
  }
  const Curve& c = b.curve;
  spanSegments([&](uint32_t i) { return c.h[i]; }, n, c.t, p, tolerance, b.counts);
  b.segments = capCounts(b.counts);
}

// Grid parameters along one direction of a patch: per span the most any row (or column) needs.
void planDirection(const NurbsPatch& patch, bool along_u, double tolerance, std::vector<uint32_t>& counts,
                   std::vector<uint32_t>& row_counts, std::vector<double>& t) {
  const uint32_t p = along_u ? patch.degree_u : patch.degree_v;
  const uint32_t n = along_u ? patch.count_u : patch.count_v;
  const uint32_t rows = along_u ? patch.count_v : patch.count_u;
  normaliseKnots(along_u ? patch.knots_u : patch.knots_v, p, n, false, t);
  counts.assign(n - p, 0);
  for (uint32_t r = 0; r < rows; ++r) {
    auto pts = [&](uint32_t i) {
      const size_t index = along_u ? size_t{r} * patch.count_u + i : size_t{i} * patch.count_u + r;
      return homogeneous(patch.control_points[index]);
    };
    spanSegments(pts, n, t, p, tolerance, row_counts);
    for (size_t s = 0; s < counts.size(); ++s) counts[s] = std::max(counts[s], row_counts[s]);
  }
  capCounts(counts);
}

// Everything about one patch that fixes its triangle count and its vertices.
struct PatchPlan {
  Border borders[4];
  std::vector<uint32_t> counts_u, counts_v, row_counts;
  std::vector<double> t_u, t_v;  // normalised knots of the patch
  uint32_t nu = 0, nv = 0;       // grid segments (>= 2 each)
  std::vector<glm::dvec4> raw;
  std::vector<double> scratch;

  uint64_t triangles() const {
    uint64_t t = 2 * uint64_t{nu - 2} * (nv - 2) + 2 * uint64_t{nu - 2} + 2 * uint64_t{nv - 2};
    for (const Border& b : borders) t += b.segments;
    return t;
  }
};

uint32_t gridSegments(const std::vector<uint32_t>& counts) {
  uint32_t total = 0;
  for (uint32_t c : counts) total += c;
  return std::max(total, 2u);
}

void planPatch(const NurbsPatch& patch, double tolerance, PatchPlan& plan) {
  for (int s = 0; s < 4; ++s) planBorder(patch, static_cast<Side>(s), tolerance, plan.borders[s], plan.raw, plan.scratch);
  planDirection(patch, true, tolerance, plan.counts_u, plan.row_counts, plan.t_u);
  planDirection(patch, false, tolerance, plan.counts_v, plan.row_counts, plan.t_v);
  plan.nu = gridSegments(plan.counts_u);
  plan.nv = gridSegments(plan.counts_v);
}

// Sample parameters in [0, 1] of a plan's spans (`segments` + 1 values, ending exactly on 1).
void sampleParameters(const std::vector<double>& t, uint32_t p, const std::vector<uint32_t>& counts,
                      uint32_t segments, std::vector<double>& out) {
  out.clear();
  for (size_t s = 0; s < counts.size(); ++s) {
    const double a = t[s + p], b = t[s + p + 1];
    for (uint32_t i = 0; i < counts[s]; ++i) out.push_back(a + (b - a) * i / counts[s]);
  }
  out.push_back(1.0);
  if (segments == 2 && out.size() == 2) out.insert(out.begin() + 1, 0.5);  // a single span: split it
}

// The tolerance the set is actually built at: the requested one, coarsened until the set fits
// kMaxSetTriangles. Returns the total triangle count at that tolerance.
uint64_t planSet(const NurbsPatchSet& set, float requested, double& tolerance, PatchPlan& plan) {
  tolerance = std::isfinite(requested) && requested > 0.0f ? requested : INFINITY;
  for (int attempt = 0;; ++attempt) {
    uint64_t total = 0;
    for (const NurbsPatch& patch : set.patches) {
      if (!validateNurbsPatch(patch).empty()) continue;
      planPatch(patch, tolerance, plan);
      total += plan.triangles();
    }
    if (total <= kMaxSetTriangles || attempt >= 24 || !std::isfinite(tolerance)) return total;
    tolerance *= 4.0;
  }
}

// ---------------------------------------------------------------------------------------------
// Building.

// Room for `extra` more elements with geometric growth (callers append many sets to one mesh).
template <typename T>
void reserveMore(std::vector<T>& v, uint64_t extra) {
  const uint64_t need = v.size() + extra;
  if (need > v.capacity()) v.reserve(static_cast<size_t>(std::max<uint64_t>(need, 2 * uint64_t{v.capacity()})));
}


// Where the floats of a shared border cannot agree bit for bit (knot vectors that only match up
// to rounding, unclamped borders), the two sides still land within a few ulps of each other. Border
// vertices therefore also weld to an existing border vertex within `snap` (a cell grid with
// 27-neighbour lookup). The snap distance is tiny: a few parts per million of the set's coordinate
// magnitude, and never more than a quarter of the tolerance.
class SetBuilder {
 public:
  SetBuilder(TriangleMesh& out, uint64_t triangles, double snap)
      : out_(out), with_normals_(out.normals.size() == out.positions.size()), snap_(snap) {
    reserveMore(out_.indices, 3 * triangles);
    reserveMore(out_.positions, triangles / 2 + 16);
    if (with_normals_) reserveMore(out_.normals, triangles / 2 + 16);
  }

  // A border vertex: one per distinct position in the set; normals of the patches meeting there
  // are averaged.
  uint32_t borderVertex(const glm::vec3& p, const glm::vec3& n) {
    const PositionKey key = positionKeyOf(p);
    if (const auto it = exact_.find(key); it != exact_.end()) return reuse(it->second, n);
    CellKey cell;
    const bool gridded = cellOf(p, cell);
    if (gridded) {
      for (int dz = -1; dz <= 1; ++dz)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            const auto range = cells_.equal_range(CellKey{cell.x + dx, cell.y + dy, cell.z + dz});
            for (auto it = range.first; it != range.second; ++it) {
              const glm::vec3 d = glm::abs(out_.positions[it->second] - p);
              if (std::max({d.x, d.y, d.z}) <= snap_) {
                exact_.emplace(key, it->second);
                return reuse(it->second, n);
              }
            }
          }
    }
    const uint32_t index = vertex(p, n);
    exact_.emplace(key, index);
    if (gridded) cells_.emplace(cell, index);
    border_.push_back(index);
    return index;
  }
  uint32_t vertex(const glm::vec3& p, const glm::vec3& n) {
    out_.positions.push_back(p);
    if (with_normals_) out_.normals.push_back(n);
    return static_cast<uint32_t>(out_.positions.size() - 1);
  }
  void triangle(uint32_t a, uint32_t b, uint32_t c) { out_.indices.insert(out_.indices.end(), {a, b, c}); }

  void finish() {
    if (!with_normals_) return;
    for (uint32_t i : border_) {
      const float len = glm::length(out_.normals[i]);
      out_.normals[i] = len > 1e-6f ? out_.normals[i] / len : glm::vec3(0.0f, 0.0f, 1.0f);
    }
  }

 private:
  struct CellKey {
    int64_t x, y, z;
    bool operator==(const CellKey&) const = default;
  };
  struct CellHash {
    size_t operator()(const CellKey& k) const {
      return PositionHash{}(PositionKey{static_cast<uint32_t>(k.x ^ (k.x >> 32)), static_cast<uint32_t>(k.y ^ (k.y >> 32)),
                                        static_cast<uint32_t>(k.z ^ (k.z >> 32))});
    }
  };

  bool cellOf(const glm::vec3& p, CellKey& cell) const {
    if (!(snap_ > 0.0)) return false;
    const glm::dvec3 q = glm::floor(glm::dvec3(p) / snap_);
    constexpr double kLimit = 1e15;  // beyond this the grid would overflow; exact welding only
    if (!(std::abs(q.x) < kLimit && std::abs(q.y) < kLimit && std::abs(q.z) < kLimit)) return false;
    cell = {static_cast<int64_t>(q.x), static_cast<int64_t>(q.y), static_cast<int64_t>(q.z)};
    return true;
  }
  uint32_t reuse(uint32_t index, const glm::vec3& n) {
    if (with_normals_) out_.normals[index] += n;
    return index;
  }

  TriangleMesh& out_;
  bool with_normals_;
  double snap_;
  std::unordered_map<PositionKey, uint32_t, PositionHash> exact_;
  std::unordered_multimap<CellKey, uint32_t, CellHash> cells_;
  std::vector<uint32_t> border_;
};

// A polyline of vertices with the running parameter used to zip it to its neighbour.
struct Chain {
  std::vector<uint32_t> index;
  std::vector<double> run;
  void clear() {
    index.clear();
    run.clear();
  }
};

// Joins a border chain to the inner chain beside it (both in the patch's counter-clockwise
// direction, the interior on their left) with border.size() + inner.size() - 2 triangles.
void zip(const Chain& border, const Chain& inner, SetBuilder& builder) {
  const size_t nb = border.index.size() - 1, ni = inner.index.size() - 1;
  size_t i = 0, j = 0;
  while (i < nb || j < ni) {
    const bool advance_border =
        j == ni || (i < nb && border.run[i] + border.run[i + 1] < inner.run[j] + inner.run[j + 1]);
    if (advance_border) {
      builder.triangle(border.index[i], border.index[i + 1], inner.index[j]);
      ++i;
    } else {
      builder.triangle(border.index[i], inner.index[j + 1], inner.index[j]);
      ++j;
    }
  }
}

struct BuildScratch {
  std::vector<double> params, us, vs;
  std::vector<uint32_t> grid;
  Chain border, inner;
};

void buildPatch(const NurbsPatch& patch, const PatchPlan& plan, SetBuilder& builder, BuildScratch& sc) {
  const NurbsDomain dom = nurbsDomain(patch);
  const double du = static_cast<double>(dom.u1) - dom.u0, dv = static_cast<double>(dom.v1) - dom.v0;
  sampleParameters(plan.t_u, patch.degree_u, plan.counts_u, plan.nu, sc.us);
  sampleParameters(plan.t_v, patch.degree_v, plan.counts_v, plan.nv, sc.vs);
  const uint32_t nu = plan.nu, nv = plan.nv;

  // Interior grid (i = 1 .. nu-1, j = 1 .. nv-1).
  sc.grid.resize(size_t{nu - 1} * (nv - 1));
  auto gridAt = [&](uint32_t i, uint32_t j) { return sc.grid[size_t{j - 1} * (nu - 1) + (i - 1)]; };
  for (uint32_t j = 1; j < nv; ++j)
    for (uint32_t i = 1; i < nu; ++i) {
      glm::vec3 n;
      const float u = static_cast<float>(dom.u0 + du * sc.us[i]), v = static_cast<float>(dom.v0 + dv * sc.vs[j]);
      const glm::vec3 p = evaluateNurbs(patch, u, v, &n);
      sc.grid[size_t{j - 1} * (nu - 1) + (i - 1)] = builder.vertex(p, n);
    }
  for (uint32_t j = 1; j + 1 < nv; ++j)
    for (uint32_t i = 1; i + 1 < nu; ++i) {
      const uint32_t a = gridAt(i, j), b = gridAt(i + 1, j), c = gridAt(i + 1, j + 1), d = gridAt(i, j + 1);
      builder.triangle(a, b, c);
      builder.triangle(a, c, d);
    }

  for (int side = 0; side < 4; ++side) {
    const Border& b = plan.borders[side];
    const bool backwards = side == kTop || side == kLeft;  // counter-clockwise runs against the parameter
    // Border samples in canonical order, then placed in the patch's counter-clockwise order.
    sc.params.clear();
    if (b.point)
      sc.params.push_back(0.0);
    else
      sampleParameters(b.curve.t, b.curve.degree, b.counts, b.segments, sc.params);
    const size_t count = sc.params.size();
    sc.border.clear();
    for (size_t k = 0; k < count; ++k) {
      // Walk in counter-clockwise order: index into the canonical samples accordingly.
      const size_t ccw = backwards != b.reversed ? count - 1 - k : k;
      const double tc = sc.params[ccw];
      const double frac = b.reversed ? 1.0 - tc : tc;  // position along the patch parameter
      const Curve& c = b.curve;
      glm::dvec4 h;
      if (b.point) {
        h = c.h[0];
      } else {
        const uint32_t n = static_cast<uint32_t>(c.count());
        const uint32_t s = findSpan(c.t, c.degree, n, tc);
        h = deBoor([&](uint32_t i) { return c.h[i]; }, c.t, c.degree, s, tc);
      }
      const glm::vec3 pos(glm::dvec3(h) / h.w);
      const double u = side == kLeft ? 0.0 : side == kRight ? 1.0 : frac;
      const double v = side == kBottom ? 0.0 : side == kTop ? 1.0 : frac;
      glm::vec3 normal;
      evaluateNurbs(patch, static_cast<float>(dom.u0 + du * u), static_cast<float>(dom.v0 + dv * v), &normal);
      sc.border.index.push_back(builder.borderVertex(pos, normal));
      sc.border.run.push_back(backwards ? -frac : frac);
    }
    // The inner chain beside this side, in the same direction.
    sc.inner.clear();
    auto push = [&](uint32_t i, uint32_t j, double run) {
      sc.inner.index.push_back(gridAt(i, j));
      sc.inner.run.push_back(run);
    };
    switch (side) {
      case kBottom:
        for (uint32_t i = 1; i < nu; ++i) push(i, 1, sc.us[i]);
        break;
      case kRight:
        for (uint32_t j = 1; j < nv; ++j) push(nu - 1, j, sc.vs[j]);
        break;
      case kTop:
        for (uint32_t i = nu - 1; i >= 1; --i) push(i, nv - 1, -sc.us[i]);
        break;
      default:
        for (uint32_t j = nv - 1; j >= 1; --j) push(1, j, -sc.vs[j]);
        break;
    }
    zip(sc.border, sc.inner, builder);
  }
}

// Snap distance for border welding (see SetBuilder): 2e-6 of the largest control point coordinate,
// a few dozen float ulps there, capped at a quarter of the tolerance.
double snapDistance(const NurbsPatchSet& set, double tolerance) {
  double magnitude = 0.0;
  for (const NurbsPatch& patch : set.patches) {
    if (!validateNurbsPatch(patch).empty()) continue;
    for (const glm::vec4& cp : patch.control_points)
      magnitude = std::max({magnitude, std::abs(static_cast<double>(cp.x)), std::abs(static_cast<double>(cp.y)),
                            std::abs(static_cast<double>(cp.z))});
  }
  return std::min(2e-6 * magnitude, 0.25 * tolerance);
}

}  // namespace

uint64_t nurbsTriangleCount(const NurbsPatchSet& patches, float tolerance) {
  PatchPlan plan;
  double effective = 0.0;
  return planSet(patches, tolerance, effective, plan);
}

void tessellateNurbs(const NurbsPatchSet& patches, float tolerance, TriangleMesh& out) {
  PatchPlan plan;
  double effective = 0.0;
  const uint64_t total = planSet(patches, tolerance, effective, plan);
  if (total == 0) return;
  SetBuilder builder(out, total, snapDistance(patches, effective));
  BuildScratch scratch;
  for (const NurbsPatch& patch : patches.patches) {
    if (!validateNurbsPatch(patch).empty()) continue;
    planPatch(patch, effective, plan);
    buildPatch(patch, plan, builder, scratch);
  }
  builder.finish();
}

}  // namespace tw
