// Near-coincident vertices of different groups, from the pairs a vertex cell grid finds (see
// near_group_vertices.h).
#include "near_group_vertices.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "grid_weld.h"
#include "package_format.h"
#include "page_codec.h"

namespace tw {

float packageGridTolerance(const glm::vec3& extent, double position_step_m) {
  const glm::vec3 corners[2] = {glm::vec3(0.0f), extent};
  const uint32_t shift = std::min<uint32_t>(clusterPositionShift(corners, position_step_m),
                                            pkg::kMaxPositionShift);
  return float(2.0 * quantizationErrorM(position_step_m, shift));
}

NearVertexIndex::NearVertexIndex(std::span<const glm::vec3> positions,
                                 std::span<const uint32_t> vertices, float tolerance)
    : tolerance_(tolerance) {
  if (!(tolerance > 0.0f)) return;
  grid_ = VertexCellGrid(positions, vertices, tolerance);
  // Which entries have any neighbour at all (most have none), in parallel; then their pairs.
  std::vector<uint8_t> has_neighbour(grid_.size(), 0);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, grid_.size(), 4096),
                    [&](const tbb::blocked_range<size_t>& range) {
                      for (size_t i = range.begin(); i != range.end(); ++i) {
                        const uint32_t v = grid_.vertex(i);
                        grid_.forEachWithin(positions[v], v,
                                            [&](uint32_t) { return !(has_neighbour[i] = 1); });
                      }
                    });
  near_any_.assign(positions.size(), 0);
  for (size_t i = 0; i < grid_.size(); ++i)
    if (has_neighbour[i]) near_any_[grid_.vertex(i)] = 1;
  constexpr size_t kMostPairsPerVertex = 16;
  const size_t most_pairs = kMostPairsPerVertex * grid_.size();
  for (size_t i = 0; i < grid_.size() && !search_each_time_; ++i) {
    if (!has_neighbour[i]) continue;
    const uint32_t v = grid_.vertex(i);
    grid_.forEachWithin(positions[v], v, [&](uint32_t w) {
      pairs_.emplace_back(v, w);
      return !(search_each_time_ = pairs_.size() > most_pairs);
    });
  }
  if (search_each_time_) pairs_ = {};
}

void NearVertexIndex::markNearOtherGroups(std::span<const glm::vec3> positions,
                                          std::span<const uint32_t> owner, uint32_t multi,
                                          std::vector<uint8_t>& near) const {
  if (!search_each_time_) {
    for (const auto& [v, w] : pairs_)
      if (owner[v] != multi && owner[w] != owner[v]) near[v] = 1;
    return;
  }
  // Each entry writes only its own vertex's flag (vertices are indexed once).
  tbb::parallel_for(tbb::blocked_range<size_t>(0, grid_.size(), 4096),
                    [&](const tbb::blocked_range<size_t>& range) {
                      for (size_t i = range.begin(); i != range.end(); ++i) {
                        const uint32_t v = grid_.vertex(i);
                        if (owner[v] == multi) continue;
                        bool found = false;
                        grid_.forEachWithin(positions[v], v, [&](uint32_t w) {
                          return !(found = owner[w] != owner[v]);
                        });
                        if (found) near[v] = 1;
                      }
                    });
}

void markVerticesNearOtherGroups(std::span<const glm::vec3> positions,
                                 std::span<const uint32_t> vertices,
                                 std::span<const uint32_t> owner, uint32_t multi,
                                 float tolerance, std::vector<uint8_t>& near) {
  NearVertexIndex(positions, vertices, tolerance).markNearOtherGroups(positions, owner, multi, near);
}

}  // namespace tw
