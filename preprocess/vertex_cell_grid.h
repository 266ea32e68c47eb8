// Vertices within a small distance of each other, found through a grid of cells a little over
// twice that distance: a vertex's neighbours lie in its own cell or in the cell on the nearer
// side of each axis, so a search reads 8 cells, not 27, and each cell is one run of a sorted
// array reached through a flat open-addressing table (no map of vectors).
//
// Why: the level-0 grid weld (grid_weld.h) and the DAG's near-group test (near_group_vertices.h)
// both ask "which vertices lie within d of this one, on every axis" for hundreds of thousands of
// vertices, with d far below the vertex spacing, so nearly every search finds nothing.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include <glm/glm.hpp>

namespace tw {

class VertexCellGrid {
 public:
  VertexCellGrid() = default;
  // `vertices`: indices into positions, each once; non-finite positions are left out. The
  // distance must be > 0. Sorts on TBB.
  VertexCellGrid(std::span<const glm::vec3> positions, std::span<const uint32_t> vertices,
                 double distance);

  size_t size() const { return entries_.size(); }
  uint32_t vertex(size_t entry) const { return entries_[entry].vertex; }

  // Calls visit(w) for each indexed vertex w other than `self` whose position lies within the
  // distance of p on every axis (compared in double), in grid order, until visit returns false.
  template <typename Visit>
  void forEachWithin(const glm::vec3& p, uint32_t self, Visit&& visit) const;

  // The smallest indexed vertex w < below within the distance of p for which accept(w) holds,
  // or kNone. Each cell's run is read in vertex order and left at its first match.
  static constexpr uint32_t kNone = std::numeric_limits<uint32_t>::max();
  template <typename Accept>
  uint32_t smallestWithin(const glm::vec3& p, uint32_t below, Accept&& accept) const;

 private:
  struct Cell {
    int64_t x, y, z;
    bool operator==(const Cell&) const = default;
  };
  struct Entry {
    Cell cell;
    uint32_t vertex;
  };
  static constexpr uint32_t kEmpty = std::numeric_limits<uint32_t>::max();
  size_t slotOf(const Cell& c) const;
  // The 8 cells a vertex within the distance of p may lie in, each called with its first entry.
  template <typename VisitCell>
  void forEachCell(const glm::vec3& p, VisitCell&& visit_cell) const;

  std::span<const glm::vec3> positions_;
  double distance_ = 0.0, inverse_cell_ = 0.0;
  std::vector<Entry> entries_;   // sorted by cell, then vertex
  std::vector<uint32_t> first_;  // a cell's first entry, or kEmpty
};

template <typename VisitCell>
void VertexCellGrid::forEachCell(const glm::vec3& p, VisitCell&& visit_cell) const {
  if (entries_.empty() || !std::isfinite(p.x + p.y + p.z)) return;
  int64_t base[3];
  int side[3];
  for (int axis = 0; axis < 3; ++axis) {
    const double scaled = double(p[axis]) * inverse_cell_;
    const double floor = std::floor(scaled);
    base[axis] = int64_t(floor);
    side[axis] = scaled - floor < 0.5 ? -1 : 1;
  }
  for (int corner = 0; corner < 8; ++corner) {
    const Cell c{base[0] + ((corner & 1) ? side[0] : 0), base[1] + ((corner & 2) ? side[1] : 0),
                 base[2] + ((corner & 4) ? side[2] : 0)};
    const uint32_t start = first_[slotOf(c)];
    if (start != kEmpty && !visit_cell(c, size_t(start))) return;
  }
}

template <typename Visit>
void VertexCellGrid::forEachWithin(const glm::vec3& p, uint32_t self, Visit&& visit) const {
  const glm::dvec3 q(p);
  forEachCell(p, [&](const Cell& c, size_t start) {
    for (size_t i = start; i < entries_.size() && entries_[i].cell == c; ++i) {
      const uint32_t w = entries_[i].vertex;
      if (w == self) continue;
      const glm::dvec3 d = glm::abs(glm::dvec3(positions_[w]) - q);
      if (std::max({d.x, d.y, d.z}) <= distance_ && !visit(w)) return false;
    }
    return true;
  });
}

template <typename Accept>
uint32_t VertexCellGrid::smallestWithin(const glm::vec3& p, uint32_t below,
                                        Accept&& accept) const {
  const glm::dvec3 q(p);
  uint32_t best = kNone;
  forEachCell(p, [&](const Cell& c, size_t start) {
    for (size_t i = start; i < entries_.size() && entries_[i].cell == c; ++i) {
      const uint32_t w = entries_[i].vertex;
      if (w >= below || w >= best) break;
      const glm::dvec3 d = glm::abs(glm::dvec3(positions_[w]) - q);
      if (std::max({d.x, d.y, d.z}) <= distance_ && accept(w)) {
        best = w;
        break;
      }
    }
    return true;
  });
  return best;
}

}  // namespace tw
