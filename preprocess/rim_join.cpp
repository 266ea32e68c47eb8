// Joining the rims of a group that almost meet. See rim_join.h.
#include "rim_join.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "edge_counts.h"
#include "union_find.h"
#include "vertex_cell_grid.h"

namespace tw {

float joinNearRims(std::span<const glm::vec3> positions, std::vector<uint32_t>& tris,
                   std::vector<uint32_t>& ids, std::span<const uint8_t> candidate,
                   float tolerance) {
  if (!(tolerance > 0.0f) || std::count(candidate.begin(), candidate.end(), 1) < 2) return 0.0f;
  // The candidates on a rim.
  std::vector<uint32_t> rims;
  for (const EdgeCount& e : countEdges(tris, positions.size()))
    if (e.count != 2)
      for (uint32_t v : {uint32_t(e.key >> 32), uint32_t(e.key)})
        if (candidate[v]) rims.push_back(v);
  std::sort(rims.begin(), rims.end());
  rims.erase(std::unique(rims.begin(), rims.end()), rims.end());
  if (rims.size() < 2) return 0.0f;

  // Sets of rim vertices within the tolerance, each onto its smallest vertex.
  const VertexCellGrid grid(positions, rims, tolerance);
  UnionFind joined(positions.size());
  bool any = false;
  for (uint32_t v : rims)
    grid.forEachWithin(positions[v], v, [&](uint32_t w) {
      joined.unite(v, w);
      any = true;
      return true;
    });
  if (!any) return 0.0f;
  std::vector<uint32_t> onto(positions.size());
  std::iota(onto.begin(), onto.end(), 0u);
  std::vector<uint32_t> smallest(positions.size(), std::numeric_limits<uint32_t>::max());
  for (uint32_t v : rims) smallest[joined.find(v)] = std::min(smallest[joined.find(v)], v);
  float moved = 0.0f;
  for (uint32_t v : rims) {
    onto[v] = smallest[joined.find(v)];
    const glm::vec3 d = glm::abs(positions[v] - positions[onto[v]]);
    moved = std::max({moved, d.x, d.y, d.z});
  }

  // The triangles, renumbered; those that collapsed dropped.
  size_t kept = 0;
  for (size_t t = 0; t < ids.size(); ++t) {
    const uint32_t a = onto[tris[3 * t]], b = onto[tris[3 * t + 1]], c = onto[tris[3 * t + 2]];
    if (a == b || b == c || a == c) continue;
    tris[3 * kept] = a;
    tris[3 * kept + 1] = b;
    tris[3 * kept + 2] = c;
    ids[kept++] = ids[t];
  }
  tris.resize(3 * kept);
  ids.resize(kept);
  return moved * std::sqrt(3.0f);
}

}  // namespace tw
