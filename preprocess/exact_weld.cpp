// Exact welding and directed edge counts for the topology checks: see exact_weld.h.
#include "exact_weld.h"

#include <algorithm>

#include "position_key.h"

namespace tw {

WeldedTriangles weldExactly(const TriangleMesh& mesh) {
  WeldedTriangles out;
  const size_t vertex_count = mesh.positions.size();
  // One vertex per distinct position, created when a face first uses it.
  std::unordered_map<PositionKey, uint32_t, PositionHash> welded;
  welded.reserve(vertex_count);
  std::vector<uint32_t> remap(vertex_count, UINT32_MAX);
  auto weld = [&](uint32_t index) {
    if (remap[index] == UINT32_MAX) {
      const auto [it, inserted] = welded.try_emplace(positionKeyOf(mesh.positions[index]),
                                                     static_cast<uint32_t>(out.points.size()));
      if (inserted) out.points.push_back(mesh.positions[index]);
      remap[index] = it->second;
    }
    return remap[index];
  };
  out.triangles.reserve(mesh.indices.size() / 3);
  out.sources.reserve(mesh.indices.size() / 3);
  for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
    const uint32_t i0 = mesh.indices[t], i1 = mesh.indices[t + 1], i2 = mesh.indices[t + 2];
    if (i0 >= vertex_count || i1 >= vertex_count || i2 >= vertex_count) {
      ++out.skipped;
      continue;
    }
    const uint32_t a = weld(i0), b = weld(i1), c = weld(i2);
    if (a == b || b == c || c == a) {
      ++out.skipped;
      continue;
    }
    out.triangles.push_back({a, b, c});
    out.sources.push_back(static_cast<uint32_t>(t / 3));
  }
  return out;
}

std::unordered_map<uint64_t, EdgeUse> countEdgeUses(
    std::span<const std::array<uint32_t, 3>> triangles) {
  std::unordered_map<uint64_t, EdgeUse> edges;
  edges.reserve(triangles.size() * 2);
  for (const auto& tri : triangles)
    for (int e = 0; e < 3; ++e) {
      const uint32_t a = tri[e], b = tri[(e + 1) % 3];
      EdgeUse& use = edges[(uint64_t{std::min(a, b)} << 32) | std::max(a, b)];
      ++(a < b ? use.forward : use.backward);
    }
  return edges;
}

}  // namespace tw
