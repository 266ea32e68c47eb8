// Snapping full-resolution vertices to their clusters' package grid and welding what coincides.
// See grid_weld.h for why.
#include "grid_weld.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <unordered_map>

#include <glm/common.hpp>

#include "package_format.h"

namespace tw {

uint32_t clusterPositionShift(std::span<const glm::vec3> positions, double position_step_m,
                              uint32_t min_shift) {
  double lo[3], hi[3];
  for (int a = 0; a < 3; ++a) {
    lo[a] = std::numeric_limits<double>::max();
    hi[a] = -std::numeric_limits<double>::max();
  }
  for (const glm::vec3& p : positions)
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], double(p[a]));
      hi[a] = std::max(hi[a], double(p[a]));
    }
  for (uint32_t shift = min_shift; shift <= pkg::kMaxPositionShift; ++shift) {
    const double cell = std::ldexp(position_step_m, int(shift));
    bool fits = true;
    for (int a = 0; a < 3 && fits; ++a) {
      double glo = std::nearbyint(lo[a] / cell), ghi = std::nearbyint(hi[a] / cell);
      fits = glo >= -2147483648.0 && glo <= 2147483647.0 && ghi - glo <= 65535.0;
    }
    if (fits) return shift;
  }
  return pkg::kMaxPositionShift + 1;
}

GridWeld weldOnPackageGrid(std::span<const glm::vec3> positions,
                           std::span<const uint32_t> indices, const TriangleClusters& clusters,
                           std::span<const uint8_t> keep, double position_step_m) {
  if (!keep.empty() && keep.size() != positions.size())
    throw std::invalid_argument("weldOnPackageGrid: keep must be empty or one per position");
  for (uint32_t v : indices)
    if (v >= positions.size()) throw std::invalid_argument("weldOnPackageGrid: index out of range");
  const size_t triangle_count = indices.size() / 3;
  for (uint32_t t : clusters.triangles)
    if (t >= triangle_count)
      throw std::invalid_argument("weldOnPackageGrid: cluster triangle out of range");

  // Coarsest shift per vertex among the clusters using it (kNoShift: unused).
  constexpr uint32_t kNoShift = std::numeric_limits<uint32_t>::max();
  std::vector<uint32_t> vertex_shift(positions.size(), kNoShift);
  std::vector<glm::vec3> corners;
  for (size_t c = 0; c < clusters.clusterCount(); ++c) {
    corners.clear();
    for (uint32_t i = clusters.offsets[c]; i < clusters.offsets[c + 1]; ++i)
      for (int k = 0; k < 3; ++k) corners.push_back(positions[indices[3 * clusters.triangles[i] + k]]);
    const uint32_t shift =
        std::min<uint32_t>(clusterPositionShift(corners, position_step_m), pkg::kMaxPositionShift);
    for (uint32_t i = clusters.offsets[c]; i < clusters.offsets[c + 1]; ++i)
      for (int k = 0; k < 3; ++k) {
        uint32_t& s = vertex_shift[indices[3 * clusters.triangles[i] + k]];
        s = s == kNoShift ? shift : std::max(s, shift);
      }
  }

  // 1. Vertices closer than one base step (float noise: a pipe's end and its elbow's, a ulp
  // apart, which a pointwise snap can still round apart) join the first earlier vertex within
  // that distance per axis; seam vertices never move, so they never join. Joining the first
  // representative, not a chain, bounds every move by one step.
  const double tolerance = position_step_m;
  std::vector<uint32_t> representative(positions.size());
  for (size_t v = 0; v < positions.size(); ++v) representative[v] = uint32_t(v);
  // The candidates sorted by tolerance cell (then index), and each cell's range found through a
  // flat open-addressing table: the 27 neighbouring cells of a vertex are probed without a map
  // of vectors (one allocation per cell). Within a cell the earlier vertices come first, so the
  // first representative found is the one the index-order scan would find.
  struct Cell {
    int64_t x, y, z;
    auto operator<=>(const Cell&) const = default;
  };
  std::vector<Cell> cell_of(positions.size());
  std::vector<uint32_t> order;
  order.reserve(positions.size());
  for (size_t v = 0; v < positions.size(); ++v) {
    const glm::vec3& p = positions[v];
    if (vertex_shift[v] == kNoShift || !std::isfinite(p.x + p.y + p.z)) continue;
    cell_of[v] = {int64_t(std::floor(double(p.x) / tolerance)),
                  int64_t(std::floor(double(p.y) / tolerance)),
                  int64_t(std::floor(double(p.z) / tolerance))};
    order.push_back(uint32_t(v));
  }
  std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
    return cell_of[a] < cell_of[b] || (cell_of[a] == cell_of[b] && a < b);
  });
  auto hashCell = [](const Cell& c) {
    return uint64_t(c.x) * 0x9E3779B97F4A7C15ull ^ uint64_t(c.y) * 0xC2B2AE3D27D4EB4Full ^
           uint64_t(c.z) * 0x165667B19E3779F9ull;
  };
  size_t table_size = 16;
  while (table_size < 2 * order.size()) table_size *= 2;
  constexpr uint32_t kEmptySlot = std::numeric_limits<uint32_t>::max();
  std::vector<uint32_t> first_in_cell(table_size, kEmptySlot);  // index into order
  auto slotOf = [&](const Cell& c) {
    size_t i = size_t(hashCell(c)) & (table_size - 1);
    while (first_in_cell[i] != kEmptySlot && cell_of[order[first_in_cell[i]]] != c)
      i = (i + 1) & (table_size - 1);
    return i;
  };
  for (size_t i = 0; i < order.size(); ++i)
    if (i == 0 || cell_of[order[i]] != cell_of[order[i - 1]]) first_in_cell[slotOf(cell_of[order[i]])] = uint32_t(i);

  // In index order, as the tolerance demands: a vertex joins the first earlier representative
  // within the tolerance, scanning the neighbouring cells z, y, x.
  std::vector<uint32_t> by_index = order;
  std::sort(by_index.begin(), by_index.end());
  for (uint32_t v : by_index) {
    const bool movable = keep.empty() || keep[v] == 0;
    if (!movable) continue;
    const Cell& c = cell_of[v];
    const glm::dvec3 p(positions[v]);
    for (int64_t z = c.z - 1; z <= c.z + 1 && representative[v] == v; ++z)
      for (int64_t y = c.y - 1; y <= c.y + 1 && representative[v] == v; ++y)
        for (int64_t x = c.x - 1; x <= c.x + 1 && representative[v] == v; ++x) {
          const Cell n{x, y, z};
          const uint32_t first = first_in_cell[slotOf(n)];
          if (first == kEmptySlot) continue;
          for (size_t i = first; i < order.size() && cell_of[order[i]] == n; ++i) {
            const uint32_t r = order[i];
            if (r >= v) break;
            if (representative[r] != r) continue;
            const glm::dvec3 d = glm::abs(glm::dvec3(positions[r]) - p);
            if (std::max({d.x, d.y, d.z}) <= tolerance) {
              representative[v] = r;
              break;
            }
          }
        }
  }
  for (size_t v = 0; v < positions.size(); ++v) {
    const uint32_t r = representative[v];
    if (r != v && vertex_shift[v] != kNoShift)
      vertex_shift[r] = std::max(vertex_shift[r], vertex_shift[v]);
  }

  // 2. Each representative snapped to the coarsest grid among the clusters of its vertices, then
  // equal positions welded.
  GridWeld weld;
  weld.remap.resize(positions.size());
  weld.positions.reserve(positions.size());
  struct Bits {
    uint32_t x, y, z;
    bool operator==(const Bits&) const = default;
  };
  struct BitsHash {
    size_t operator()(const Bits& b) const {
      return size_t((uint64_t(b.x) * 0x9E3779B97F4A7C15ull) ^
                    (uint64_t(b.y) * 0xC2B2AE3D27D4EB4Full) ^ (uint64_t(b.z) * 0x165667B19E3779F9ull));
    }
  };
  std::unordered_map<Bits, uint32_t, BitsHash> first;
  first.reserve(positions.size());
  for (size_t v = 0; v < positions.size(); ++v) {
    if (representative[v] != v) continue;
    glm::vec3 p = positions[v];
    const bool snap = vertex_shift[v] != kNoShift && (keep.empty() || keep[v] == 0);
    if (snap) {
      const double cell = std::ldexp(position_step_m, int(vertex_shift[v]));
      for (int a = 0; a < 3; ++a) {
        if (!std::isfinite(p[a])) continue;
        p[a] = float(std::nearbyint(double(p[a]) / cell) * cell);
        if (p[a] == 0.0f) p[a] = 0.0f;  // -0 and +0 are one position
      }
    }
    const Bits key{std::bit_cast<uint32_t>(p.x), std::bit_cast<uint32_t>(p.y),
                   std::bit_cast<uint32_t>(p.z)};
    auto [it, fresh] = first.try_emplace(key, uint32_t(weld.positions.size()));
    if (fresh) weld.positions.push_back(p);
    weld.remap[v] = it->second;
  }
  for (size_t v = 0; v < positions.size(); ++v) {
    weld.remap[v] = weld.remap[representative[v]];
    weld.moved_vertices += weld.positions[weld.remap[v]] != positions[v];
  }
  weld.merged_vertices = positions.size() - weld.positions.size();
  return weld;
}

}  // namespace tw
