// Near-coincident vertices of different groups, by a hashed grid of tolerance-sized cells (see
// near_group_vertices.h).
#include "near_group_vertices.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include "grid_weld.h"
#include "package_format.h"
#include "page_codec.h"

namespace tw {
namespace {

constexpr uint32_t kEmpty = std::numeric_limits<uint32_t>::max();

size_t cellHash(int64_t x, int64_t y, int64_t z) {
  return size_t(uint64_t(x) * 0x9E3779B97F4A7C15ull ^ uint64_t(y) * 0xC2B2AE3D27D4EB4Full ^
                uint64_t(z) * 0x165667B19E3779F9ull);
}

}  // namespace

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
  // Cells a little over twice the tolerance: a vertex within the tolerance of another lies in
  // the other's cell or in the neighbour on the nearer side of each axis (8 cells, not 27). The
  // margin covers float rounding in the distance test.
  const double inv = 1.0 / (2.125 * double(tolerance));
  entries_.reserve(vertices.size());
  for (uint32_t v : vertices) {
    const glm::vec3& p = positions[v];
    if (!std::isfinite(p.x + p.y + p.z)) continue;
    Entry e{};
    int64_t* cell[3] = {&e.x, &e.y, &e.z};
    for (int axis = 0; axis < 3; ++axis) {
      const double scaled = double(p[axis]) * inv;
      const double floor = std::floor(scaled);
      *cell[axis] = int64_t(floor);
      e.side[axis] = scaled - floor < 0.5 ? -1 : 1;
    }
    e.vertex = v;
    entries_.push_back(e);
  }
  tbb::parallel_sort(entries_.begin(), entries_.end());
  size_t table_size = 16;
  while (table_size < 2 * entries_.size()) table_size *= 2;
  first_.assign(table_size, kEmpty);
  for (size_t i = 0; i < entries_.size(); ++i) {
    const Entry& e = entries_[i];
    if (i > 0 && entries_[i - 1].x == e.x && entries_[i - 1].y == e.y && entries_[i - 1].z == e.z)
      continue;
    first_[slotOf(e.x, e.y, e.z)] = uint32_t(i);
  }
  listPairs(positions);
}

size_t NearVertexIndex::slotOf(int64_t x, int64_t y, int64_t z) const {
  const size_t mask = first_.size() - 1;
  size_t i = cellHash(x, y, z) & mask;
  while (first_[i] != kEmpty) {
    const Entry& e = entries_[first_[i]];
    if (e.x == x && e.y == y && e.z == z) break;
    i = (i + 1) & mask;
  }
  return i;
}

template <typename Visit>
void NearVertexIndex::forEachNear(const Entry& e, std::span<const glm::vec3> positions,
                                  Visit&& visit) const {
  const glm::vec3& p = positions[e.vertex];
  for (int corner = 0; corner < 8; ++corner) {
    const int64_t x = e.x + ((corner & 1) ? e.side[0] : 0);
    const int64_t y = e.y + ((corner & 2) ? e.side[1] : 0);
    const int64_t z = e.z + ((corner & 4) ? e.side[2] : 0);
    const uint32_t start = first_[slotOf(x, y, z)];
    if (start == kEmpty) continue;
    for (size_t i = start; i < entries_.size(); ++i) {
      const Entry& other = entries_[i];
      if (other.x != x || other.y != y || other.z != z) break;
      if (other.vertex == e.vertex) continue;
      const glm::vec3 d = glm::abs(positions[other.vertex] - p);
      if (std::max({d.x, d.y, d.z}) <= tolerance_ && !visit(other.vertex)) return;
    }
  }
}

void NearVertexIndex::listPairs(std::span<const glm::vec3> positions) {
  // Which entries have any neighbour at all (most have none), in parallel; then their pairs.
  std::vector<uint8_t> has_neighbour(entries_.size(), 0);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, entries_.size(), 4096),
                    [&](const tbb::blocked_range<size_t>& range) {
                      for (size_t i = range.begin(); i != range.end(); ++i)
                        forEachNear(entries_[i], positions,
                                    [&](uint32_t) { return !(has_neighbour[i] = 1); });
                    });
  constexpr size_t kMostPairsPerVertex = 16;
  const size_t most_pairs = kMostPairsPerVertex * entries_.size();
  for (size_t i = 0; i < entries_.size() && !search_each_time_; ++i) {
    if (!has_neighbour[i]) continue;
    forEachNear(entries_[i], positions, [&](uint32_t w) {
      pairs_.emplace_back(entries_[i].vertex, w);
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
  tbb::parallel_for(tbb::blocked_range<size_t>(0, entries_.size(), 4096),
                    [&](const tbb::blocked_range<size_t>& range) {
                      for (size_t i = range.begin(); i != range.end(); ++i) {
                        const uint32_t v = entries_[i].vertex;
                        if (owner[v] == multi) continue;
                        bool found = false;
                        forEachNear(entries_[i], positions,
                                    [&](uint32_t w) { return !(found = owner[w] != owner[v]); });
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
