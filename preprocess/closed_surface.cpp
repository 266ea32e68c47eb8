// Closed-surface test for back-face culling: see closed_surface.h.
#include "closed_surface.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <vector>

#include "exact_weld.h"

namespace tw {
namespace {

uint64_t directedKey(uint32_t from, uint32_t to) { return (uint64_t{from} << 32) | to; }

// Union-find over welded vertices, with path halving.
uint32_t findRoot(std::vector<uint32_t>& parent, uint32_t v) {
  while (parent[v] != v) {
    parent[v] = parent[parent[v]];
    v = parent[v];
  }
  return v;
}

}  // namespace

ClosedSurfaceReport checkClosedSurface(const TriangleMesh& mesh) {
  ClosedSurfaceReport report;
  const WeldedTriangles welded = weldExactly(mesh);
  report.triangles = welded.triangles.size();
  report.skipped = welded.skipped;
  if (welded.triangles.empty()) return report;

  // Closed and consistently oriented: every directed edge occurs once, and so does its reverse.
  std::vector<uint64_t> edges;
  edges.reserve(3 * welded.triangles.size());
  for (const auto& t : welded.triangles)
    for (int e = 0; e < 3; ++e) edges.push_back(directedKey(t[e], t[(e + 1) % 3]));
  std::sort(edges.begin(), edges.end());
  for (size_t i = 0; i < edges.size(); ++i) {
    const bool repeated = (i > 0 && edges[i - 1] == edges[i]) ||
                          (i + 1 < edges.size() && edges[i + 1] == edges[i]);
    const uint64_t reverse = directedKey(uint32_t(edges[i]), uint32_t(edges[i] >> 32));
    if (repeated || !std::binary_search(edges.begin(), edges.end(), reverse))
      ++report.unpaired_edges;
  }

  // Pieces, and the volume each encloses (divergence theorem; exact for a closed surface from
  // any reference point, taken at the bounding box centre to keep the products small).
  const std::vector<glm::vec3>& points = welded.points;
  std::vector<uint32_t> parent(points.size());
  std::iota(parent.begin(), parent.end(), 0u);
  for (const auto& t : welded.triangles) {
    const uint32_t a = findRoot(parent, t[0]);
    parent[findRoot(parent, t[1])] = a;
    parent[findRoot(parent, t[2])] = a;
  }
  glm::dvec3 lo(INFINITY), hi(-INFINITY);
  for (const glm::vec3& p : points) {
    lo = glm::min(lo, glm::dvec3(p));
    hi = glm::max(hi, glm::dvec3(p));
  }
  const glm::dvec3 centre = 0.5 * (lo + hi);
  std::vector<double> volume(points.size(), 0.0);
  std::vector<glm::dvec3> piece_lo(points.size(), glm::dvec3(INFINITY));
  std::vector<glm::dvec3> piece_hi(points.size(), glm::dvec3(-INFINITY));
  for (const auto& t : welded.triangles) {
    const uint32_t root = findRoot(parent, t[0]);
    const glm::dvec3 p0 = glm::dvec3(points[t[0]]) - centre;
    const glm::dvec3 p1 = glm::dvec3(points[t[1]]) - centre;
    const glm::dvec3 p2 = glm::dvec3(points[t[2]]) - centre;
    volume[root] += glm::dot(p0, glm::cross(p1, p2)) / 6.0;
    for (const glm::dvec3& p : {p0, p1, p2}) {
      piece_lo[root] = glm::min(piece_lo[root], p);
      piece_hi[root] = glm::max(piece_hi[root], p);
    }
  }
  for (uint32_t v = 0; v < points.size(); ++v) {
    if (findRoot(parent, v) != v || !(piece_lo[v].x <= piece_hi[v].x)) continue;
    ++report.components;
    // "Clearly positive": a flat double-sided sheet (zero volume) or a rounding residue must
    // not pass. The threshold is relative to the piece's own box.
    const double diagonal = glm::length(piece_hi[v] - piece_lo[v]);
    if (!(volume[v] > 1e-9 * diagonal * diagonal * diagonal)) ++report.inward_components;
  }
  return report;
}

}  // namespace tw
