// Profiles with holes into prisms. See profile_prism.h.
#include "profile_prism.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

namespace tw {
namespace {

double cross(const glm::dvec2& a, const glm::dvec2& b, const glm::dvec2& c) {
  return (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
}

// Whether the open segments pq and rs cross (touching at an end does not count).
bool crosses(const glm::dvec2& p, const glm::dvec2& q, const glm::dvec2& r, const glm::dvec2& s) {
  const double d1 = cross(p, q, r), d2 = cross(p, q, s), d3 = cross(r, s, p), d4 = cross(r, s, q);
  return ((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0));
}

}  // namespace

double loopArea2(const std::vector<glm::dvec2>& loop) {
  double a = 0.0;
  for (size_t i = 0; i < loop.size(); ++i) {
    const glm::dvec2 p = loop[i], q = loop[(i + 1) % loop.size()];
    a += p.x * q.y - q.x * p.y;
  }
  return a;
}

std::vector<uint32_t> triangulateProfile(const std::vector<glm::dvec2>& outer,
                                         const std::vector<std::vector<glm::dvec2>>& holes) {
  // Every point, by its index in the concatenation; loops as index lists, wound as needed.
  std::vector<glm::dvec2> p(outer);
  std::vector<uint32_t> ring(outer.size());
  std::iota(ring.begin(), ring.end(), 0u);
  if (loopArea2(outer) < 0.0) std::reverse(ring.begin(), ring.end());
  std::vector<std::vector<uint32_t>> hole_loops;
  for (const auto& hole : holes) {
    std::vector<uint32_t> loop(hole.size());
    std::iota(loop.begin(), loop.end(), uint32_t(p.size()));
    p.insert(p.end(), hole.begin(), hole.end());
    if (hole.size() < 3) continue;
    if (loopArea2(hole) > 0.0) std::reverse(loop.begin(), loop.end());  // clockwise
    hole_loops.push_back(std::move(loop));
  }
  if (ring.size() < 3) return {};
  // Bridge the holes, rightmost first, each from its rightmost vertex to the nearest vertex of
  // the ring the bridge does not cross any edge to.
  std::sort(hole_loops.begin(), hole_loops.end(), [&](const auto& a, const auto& b) {
    auto maxX = [&](const std::vector<uint32_t>& l) {
      double m = -std::numeric_limits<double>::infinity();
      for (uint32_t i : l) m = std::max(m, p[i].x);
      return m;
    };
    return maxX(a) > maxX(b);
  });
  for (const std::vector<uint32_t>& hole : hole_loops) {
    size_t m = 0;
    for (size_t i = 1; i < hole.size(); ++i)
      if (p[hole[i]].x > p[hole[m]].x) m = i;
    const glm::dvec2 from = p[hole[m]];
    size_t best = ring.size();
    double best_distance = std::numeric_limits<double>::infinity();
    for (size_t r = 0; r < ring.size(); ++r) {
      const glm::dvec2 to = p[ring[r]];
      const double d = glm::length(to - from);
      if (d >= best_distance) continue;
      bool blocked = false;
      for (size_t e = 0; e < ring.size() && !blocked; ++e)
        blocked = crosses(from, to, p[ring[e]], p[ring[(e + 1) % ring.size()]]);
      for (size_t e = 0; e < hole.size() && !blocked; ++e)
        blocked = crosses(from, to, p[hole[e]], p[hole[(e + 1) % hole.size()]]);
      if (!blocked) {
        best = r;
        best_distance = d;
      }
    }
    if (best == ring.size()) continue;  // no visible vertex: leave the hole filled
    std::vector<uint32_t> joined(ring.begin(), ring.begin() + long(best) + 1);
    for (size_t k = 0; k <= hole.size(); ++k) joined.push_back(hole[(m + k) % hole.size()]);
    joined.insert(joined.end(), ring.begin() + long(best), ring.end());
    ring = std::move(joined);
  }
  // Ear clipping over the joined ring (bridge vertices appear twice).
  std::vector<uint32_t> triangles;
  size_t guard = 0;
  const size_t limit = 4 * ring.size() * ring.size() + 16;
  while (ring.size() > 3 && guard++ < limit) {
    bool clipped = false;
    for (size_t i = 0; i < ring.size() && !clipped; ++i) {
      const uint32_t a = ring[(i + ring.size() - 1) % ring.size()], b = ring[i],
                     c = ring[(i + 1) % ring.size()];
      if (cross(p[a], p[b], p[c]) <= 0.0) continue;
      bool inside = false;
      for (uint32_t q : ring) {
        if (p[q] == p[a] || p[q] == p[b] || p[q] == p[c]) continue;
        if (cross(p[a], p[b], p[q]) >= 0 && cross(p[b], p[c], p[q]) >= 0 &&
            cross(p[c], p[a], p[q]) >= 0) {
          inside = true;
          break;
        }
      }
      if (inside) continue;
      triangles.insert(triangles.end(), {a, b, c});
      ring.erase(ring.begin() + long(i));
      clipped = true;
    }
    if (!clipped) break;
  }
  for (size_t i = 1; i + 1 < ring.size(); ++i)  // the last ear, or a fan of what would not clip
    triangles.insert(triangles.end(), {ring[0], ring[i], ring[i + 1]});
  return triangles;
}

size_t appendProfilePrism(const std::vector<glm::dvec2>& outer,
                          const std::vector<std::vector<glm::dvec2>>& holes,
                          const glm::dvec3& sweep, TriangleMesh& out) {
  const std::vector<uint32_t> cap = triangulateProfile(outer, holes);
  if (cap.empty()) return 0;
  std::vector<glm::dvec2> all(outer);
  std::vector<std::pair<size_t, size_t>> loops{{0, outer.size()}};
  for (const auto& hole : holes) {
    loops.push_back({all.size(), hole.size()});
    all.insert(all.end(), hole.begin(), hole.end());
  }
  const uint32_t base = uint32_t(out.positions.size());
  const uint32_t n = uint32_t(all.size());
  for (const glm::dvec2& q : all) out.positions.push_back(glm::vec3(q.x, q.y, 0.0));
  for (const glm::dvec2& q : all) out.positions.push_back(glm::vec3(glm::dvec3(q, 0.0) + sweep));
  const size_t before = out.indices.size();
  for (size_t t = 0; t < cap.size(); t += 3) {
    out.indices.insert(out.indices.end(), {base + cap[t], base + cap[t + 2], base + cap[t + 1]});
    out.indices.insert(out.indices.end(),
                       {base + n + cap[t], base + n + cap[t + 1], base + n + cap[t + 2]});
  }
  // Sides: the outer loop counter-clockwise, holes clockwise, so each quad faces out.
  for (size_t l = 0; l < loops.size(); ++l) {
    const auto [first, count] = loops[l];
    if (count < 3) continue;
    std::vector<glm::dvec2> loop(all.begin() + long(first), all.begin() + long(first + count));
    const bool ccw = loopArea2(loop) > 0.0;
    const bool want_ccw = l == 0;
    for (size_t i = 0; i < count; ++i) {
      uint32_t a = base + uint32_t(first + i), b = base + uint32_t(first + (i + 1) % count);
      if (ccw != want_ccw) std::swap(a, b);
      out.indices.insert(out.indices.end(), {a, b, b + n, a, b + n, a + n});
    }
  }
  return (out.indices.size() - before) / 3;
}

}  // namespace tw
