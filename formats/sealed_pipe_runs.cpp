// Sealed pipe runs: end discs matched on a sorted cell index, runs by union-find. See sealed_pipe_runs.h.
#include "sealed_pipe_runs.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <glm/glm.hpp>

#include "union_find.h"

namespace tw {
namespace {

// Directions this close to (anti)parallel count as such: 0.045 degrees.
constexpr double kParallelCos = 1.0 - 3e-7;

// The instance's linear map as a uniform scale times a rotation (mirroring allowed): the scale,
// or 0 when the map shears or stretches one axis more than another.
double uniformScale(const glm::dmat3& linear) {
  const double a = glm::length(linear[0]), b = glm::length(linear[1]), c = glm::length(linear[2]);
  const double s = std::max({a, b, c});
  if (!(s > 0.0) || !std::isfinite(s)) return 0.0;
  if (std::abs(a - s) > 1e-5 * s || std::abs(b - s) > 1e-5 * s || std::abs(c - s) > 1e-5 * s)
    return 0.0;
  const double e = 1e-5 * s * s;
  if (std::abs(glm::dot(linear[0], linear[1])) > e || std::abs(glm::dot(linear[0], linear[2])) > e ||
      std::abs(glm::dot(linear[1], linear[2])) > e)
    return 0.0;
  return s;
}

glm::dmat3 linearOf(const pkg::InstanceRecord& in) {
  const float* l = in.linear;
  return glm::dmat3(l[0], l[1], l[2], l[3], l[4], l[5], l[6], l[7], l[8]);
}

struct Disc {
  glm::dvec3 centre;
  glm::dvec3 normal;  // unit, pointing out of the part
  double radius;
  uint32_t part;      // index into the open parts
};

// A solid that may hold a disc: a cylinder (base centre, unit axis, height, radius) or a box
// (centre, unit axes, half sizes), in metres. A closed one (a capped cylinder, a box) closes the
// disc; an open cylinder (a part) joins the disc's run to its own, whose inside the disc opens
// into.
struct Holder {
  bool box = false;
  glm::dvec3 base;  // the box's centre
  glm::dmat3 axes;  // cylinders: axes[2] is the axis
  glm::dvec3 size;  // cylinders: (radius, -, height); boxes: half sizes
  uint32_t instance;
  uint32_t part;    // kNoPart for a closed solid
  glm::dvec3 lo, hi;  // world-axis box
};
constexpr uint32_t kNoPart = UINT32_MAX;

// How far a disc reaches along a unit direction from its centre.
double discReach(const Disc& d, const glm::dvec3& direction) {
  const double c = std::min(1.0, std::abs(glm::dot(d.normal, direction)));
  return d.radius * std::sqrt(1.0 - c * c);
}

// Whether the whole disc lies inside the holder's solid (its surface included, within the
// tolerance), tested on the disc's reach along the holder's axes (and, for a cylinder, its
// centre's distance from the axis plus its radius).
bool discInside(const Disc& d, const Holder& h, double tolerance) {
  const glm::dvec3 p = d.centre - h.base;
  if (h.box) {
    for (int k = 0; k < 3; ++k)
      if (std::abs(glm::dot(p, h.axes[k])) + discReach(d, h.axes[k]) > h.size[k] + tolerance)
        return false;
    return true;
  }
  const glm::dvec3& axis = h.axes[2];
  const double along = glm::dot(p, axis), reach = discReach(d, axis);
  if (along - reach < -tolerance || along + reach > h.size.z + tolerance) return false;
  return glm::length(p - along * axis) + d.radius <= h.size.x + tolerance;
}

Holder cylinderHolder(const glm::dvec3& base, const glm::dvec3& axis, double height,
                      double radius, uint32_t instance, uint32_t part) {
  Holder h;
  h.base = base;
  h.axes[2] = axis;
  h.size = {radius, 0.0, height};
  h.instance = instance;
  h.part = part;
  const glm::dvec3 top = base + axis * height;
  h.lo = glm::min(base, top) - glm::dvec3(radius);
  h.hi = glm::max(base, top) + glm::dvec3(radius);
  return h;
}

glm::i64vec3 cellOf(const glm::dvec3& p, double cell) {
  return glm::i64vec3(std::floor(p.x / cell), std::floor(p.y / cell), std::floor(p.z / cell));
}

// Items under integer grid cells: (cell, item) pairs sorted once, then every item under the cells
// of a box visited by binary search.
class CellIndex {
 public:
  void add(const glm::i64vec3& cell, uint32_t item) { entries_.push_back({key(cell), item}); }
  void sort() { std::sort(entries_.begin(), entries_.end()); }
  bool empty() const { return entries_.empty(); }
  // A row of cells along x has consecutive keys (unless it wraps): one search a row.
  template <typename Visit>
  void visit(const glm::i64vec3& lo, const glm::i64vec3& hi, Visit&& visit) const {
    for (int64_t z = lo.z; z <= hi.z; ++z)
      for (int64_t y = lo.y; y <= hi.y; ++y) {
        const uint64_t first = key({lo.x, y, z}), last = key({hi.x, y, z});
        if (last >= first && last - first == uint64_t(hi.x - lo.x)) {
          visitKeys(first, last, visit);
        } else {
          for (int64_t x = lo.x; x <= hi.x; ++x) visitKeys(key({x, y, z}), key({x, y, z}), visit);
        }
      }
  }

 private:
  template <typename Visit>
  void visitKeys(uint64_t first, uint64_t last, Visit& visit) const {
    auto it = std::lower_bound(entries_.begin(), entries_.end(), std::pair<uint64_t, uint32_t>(first, 0));
    for (; it != entries_.end() && it->first <= last; ++it) visit(it->second);
  }
  // 21 bits an axis, wrapping: a collision only costs a comparison.
  static uint64_t key(const glm::i64vec3& c) {
    constexpr uint64_t mask = (uint64_t(1) << 21) - 1;
    return (uint64_t(c.x) & mask) | ((uint64_t(c.y) & mask) << 21) | ((uint64_t(c.z) & mask) << 42);
  }
  std::vector<std::pair<uint64_t, uint32_t>> entries_;
};

}  // namespace

std::vector<uint8_t> findSealedRuns(std::span<const pkg::InstanceRecord> instances,
                                    SealedRunStats* stats) {
  std::vector<uint8_t> roles(instances.size(), 0);
  std::vector<uint32_t> parts;  // instance of each open part
  std::vector<Disc> discs;
  std::vector<Holder> holders;
  for (uint32_t i = 0; i < instances.size(); ++i) {
    const pkg::InstanceRecord& in = instances[i];
    const glm::dmat3 linear = linearOf(in);
    const double s = uniformScale(linear);
    if (s == 0.0) continue;
    const glm::dvec3 origin(in.origin[0], in.origin[1], in.origin[2]);
    if (!std::isfinite(origin.x) || !std::isfinite(origin.y) || !std::isfinite(origin.z)) continue;
    const float* p = in.params;
    const auto type = static_cast<pkg::PrimitiveType>(in.type);
    const bool capped = (in.flags & pkg::kInstanceCapped) != 0;
    const glm::dvec3 z = glm::normalize(linear[2]);
    if (type == pkg::PrimitiveType::Cylinder || type == pkg::PrimitiveType::Cone) {
      const double height = type == pkg::PrimitiveType::Cylinder ? p[1] : p[2];
      const double r0 = p[0], r1 = type == pkg::PrimitiveType::Cylinder ? p[0] : p[1];
      if (!(height > 0.0) || !(r0 >= 0.0) || !(r1 >= 0.0) || !std::isfinite(height) ||
          !std::isfinite(r0) || !std::isfinite(r1))
        continue;
      const bool holds = type == pkg::PrimitiveType::Cylinder && r0 > 0.0;
      if (capped) {
        if (holds) holders.push_back(cylinderHolder(origin, z, height * s, r0 * s, i, kNoPart));
        continue;
      }
      const uint32_t part = uint32_t(parts.size());
      parts.push_back(i);
      if (holds) holders.push_back(cylinderHolder(origin, z, height * s, r0 * s, i, part));
      discs.push_back({origin, -z, r0 * s, part});
      discs.push_back({origin + linear * glm::dvec3(0.0, 0.0, height), z, r1 * s, part});
    } else if (type == pkg::PrimitiveType::Box) {
      const glm::dvec3 half = s * glm::dvec3(p[0], p[1], p[2]);
      if (!(half.x > 0.0 && half.y > 0.0 && half.z > 0.0) || !std::isfinite(half.x + half.y + half.z))
        continue;
      Holder h;
      h.box = true;
      h.base = origin;
      h.axes = glm::dmat3(glm::normalize(linear[0]), glm::normalize(linear[1]), z);
      h.size = half;
      h.instance = i;
      h.part = kNoPart;
      const glm::dvec3 extent = glm::abs(h.axes[0]) * half.x + glm::abs(h.axes[1]) * half.y +
                                glm::abs(h.axes[2]) * half.z;
      h.lo = origin - extent;
      h.hi = origin + extent;
      holders.push_back(h);
    } else if (type == pkg::PrimitiveType::TorusSegment) {
      const double major = p[0], minor = p[1], sweep = p[2];
      if (!(major > 0.0) || !(minor > 0.0) || !(sweep > 0.0) || !std::isfinite(major) ||
          !std::isfinite(minor) || sweep >= 2.0 * std::numbers::pi)
        continue;  // a full torus has no ends: it is closed by itself
      const uint32_t part = uint32_t(parts.size());
      parts.push_back(i);
      const glm::dvec3 start = origin + linear * glm::dvec3(major, 0.0, 0.0);
      const glm::dvec3 end =
          origin + linear * glm::dvec3(major * std::cos(sweep), major * std::sin(sweep), 0.0);
      // The arc turns counter-clockwise about +Z from +X: its tangent at the start is +Y.
      discs.push_back({start, -glm::normalize(linear[1]), minor * s, part});
      discs.push_back(
          {end, glm::normalize(linear * glm::dvec3(-std::sin(sweep), std::cos(sweep), 0.0)),
           minor * s, part});
    }
  }

  // Discs sorted by the grid cell of their centre. A partner within the tolerance lies in a cell
  // the tolerance box around the disc's centre touches: one cell, unless the centre is that close
  // to a cell's side.
  const double tolerance = kJoinToleranceM;
  const double cell = 64.0 * tolerance;
  CellIndex disc_cells;
  for (uint32_t d = 0; d < discs.size(); ++d) disc_cells.add(cellOf(discs[d].centre, cell), d);
  disc_cells.sort();
  UnionFind runs(parts.size());
  std::vector<uint8_t> joined(discs.size(), 0);  // met by a partner disc
  for (uint32_t d = 0; d < discs.size(); ++d) {
    const Disc& a = discs[d];
    disc_cells.visit(cellOf(a.centre - tolerance, cell), cellOf(a.centre + tolerance, cell),
                     [&](uint32_t e) {
                       const Disc& b = discs[e];
                       if (b.part == a.part || glm::length(a.centre - b.centre) > tolerance ||
                           std::abs(a.radius - b.radius) > tolerance ||
                           glm::dot(a.normal, b.normal) > -kParallelCos)
                         return;
                       joined[d] = 1;
                       runs.unite(a.part, b.part);
                     });
  }

  // Holders hold the discs left open. Small ones look for them under the cells of a 0.5 m grid
  // their box covers; the discs still open then look for large ones (decks, long members) under
  // their cell of an 8 m grid. A disc takes every holder that holds it, not the first one found:
  // the result must not depend on the order of the instances (the preprocessor searches them in
  // input order, `terawalk verify` in package order), and joining every run whose solid holds the
  // end only makes the sealing harder to reach.
  std::vector<uint8_t> held(discs.size(), 0);
  std::vector<std::pair<uint32_t, uint32_t>> closing;  // (part, holder) of each closed disc
  auto hold = [&](uint32_t d, uint32_t k) {
    const Holder& h = holders[k];
    if (joined[d] || discs[d].part == h.part || !discInside(discs[d], h, tolerance)) return;
    held[d] = 1;
    if (h.part == kNoPart)
      closing.emplace_back(discs[d].part, k);
    else
      runs.unite(discs[d].part, h.part);
  };
  const double small_cell = 0.5, large_cell = 8.0;
  CellIndex open_cells;
  for (uint32_t d = 0; d < discs.size(); ++d)
    if (!joined[d]) open_cells.add(cellOf(discs[d].centre, small_cell), d);
  open_cells.sort();
  CellIndex large_holders;
  for (uint32_t k = 0; k < holders.size() && !open_cells.empty(); ++k) {
    const Holder& h = holders[k];
    const glm::dvec3 lo = h.lo - tolerance, hi = h.hi + tolerance;
    glm::i64vec3 a = cellOf(lo, small_cell), b = cellOf(hi, small_cell);
    glm::i64vec3 span = b - a + glm::i64vec3(1);
    if (span.x * span.y * span.z <= 64) {
      open_cells.visit(a, b, [&](uint32_t d) { hold(d, k); });
      continue;
    }
    a = cellOf(lo, large_cell);
    b = cellOf(hi, large_cell);
    span = b - a + glm::i64vec3(1);
    if (span.x * span.y * span.z > 4096) continue;  // holds nothing here
    for (int64_t z = a.z; z <= b.z; ++z)
      for (int64_t y = a.y; y <= b.y; ++y)
        for (int64_t x = a.x; x <= b.x; ++x) large_holders.add({x, y, z}, k);
  }
  large_holders.sort();
  for (uint32_t d = 0; d < discs.size() && !large_holders.empty(); ++d) {
    if (joined[d] || held[d]) continue;
    const glm::i64vec3 c = cellOf(discs[d].centre, large_cell);
    large_holders.visit(c, c, [&](uint32_t k) { hold(d, k); });
  }

  // A run is sealed when every disc of every part is.
  std::vector<uint8_t> run_open(parts.size(), 0);
  for (uint32_t d = 0; d < discs.size(); ++d)
    if (!joined[d] && !held[d]) run_open[runs.find(discs[d].part)] = 1;
  SealedRunStats counts;
  counts.open_parts = parts.size();
  for (uint32_t part = 0; part < parts.size(); ++part) {
    const uint32_t root = runs.find(part);
    if (root == part) {
      ++counts.runs;
      counts.sealed_runs += !run_open[part];
    }
    if (!run_open[root]) roles[parts[part]] |= kSealedRunMember;
  }
  for (const auto& [part, holder] : closing)
    if (!run_open[runs.find(part)]) roles[holders[holder].instance] |= kSealedRunCloser;
  for (uint8_t role : roles) {
    counts.sealed_members += (role & kSealedRunMember) != 0;
    counts.closers += (role & kSealedRunCloser) != 0;
  }
  if (stats) *stats = counts;
  return roles;
}

}  // namespace tw
