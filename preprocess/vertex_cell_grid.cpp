// The cell grid behind the near-vertex searches (see vertex_cell_grid.h).
#include "vertex_cell_grid.h"

#include <tbb/parallel_sort.h>

namespace tw {
namespace {

// Cells of 2.125 distances: the far side of a cell is always more than one distance (plus float
// rounding of the positions) away, so only the nearer neighbour per axis can hold a match.
constexpr double kCellPerDistance = 2.125;

size_t cellHash(int64_t x, int64_t y, int64_t z) {
  return size_t(uint64_t(x) * 0x9E3779B97F4A7C15ull ^ uint64_t(y) * 0xC2B2AE3D27D4EB4Full ^
                uint64_t(z) * 0x165667B19E3779F9ull);
}

}  // namespace

VertexCellGrid::VertexCellGrid(std::span<const glm::vec3> positions,
                               std::span<const uint32_t> vertices, double distance)
    : positions_(positions), distance_(distance),
      inverse_cell_(1.0 / (kCellPerDistance * distance)) {
  entries_.reserve(vertices.size());
  for (uint32_t v : vertices) {
    const glm::vec3& p = positions[v];
    if (!std::isfinite(p.x + p.y + p.z)) continue;
    entries_.push_back({{int64_t(std::floor(double(p.x) * inverse_cell_)),
                         int64_t(std::floor(double(p.y) * inverse_cell_)),
                         int64_t(std::floor(double(p.z) * inverse_cell_))},
                        v});
  }
  tbb::parallel_sort(entries_.begin(), entries_.end(), [](const Entry& a, const Entry& b) {
    if (a.cell.x != b.cell.x) return a.cell.x < b.cell.x;
    if (a.cell.y != b.cell.y) return a.cell.y < b.cell.y;
    if (a.cell.z != b.cell.z) return a.cell.z < b.cell.z;
    return a.vertex < b.vertex;
  });
  size_t table_size = 16;
  while (table_size < 2 * entries_.size()) table_size *= 2;
  first_.assign(table_size, kEmpty);
  for (size_t i = 0; i < entries_.size(); ++i)
    if (i == 0 || !(entries_[i - 1].cell == entries_[i].cell))
      first_[slotOf(entries_[i].cell)] = uint32_t(i);
}

size_t VertexCellGrid::slotOf(const Cell& c) const {
  const size_t mask = first_.size() - 1;
  size_t i = cellHash(c.x, c.y, c.z) & mask;
  while (first_[i] != kEmpty && !(entries_[first_[i]].cell == c)) i = (i + 1) & mask;
  return i;
}

}  // namespace tw
