// Snapping full-resolution vertices to their clusters' package grid and welding what coincides.
// See grid_weld.h for why.
#include "grid_weld.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <glm/common.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include "package_format.h"
#include "vertex_cell_grid.h"

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
                           std::span<const uint8_t> keep, double position_step_m,
                           double noise_tolerance_m) {
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

  // 1. Vertices closer than the noise tolerance (float noise: a pipe's end and its elbow's, a ulp
  // apart, which a pointwise snap can still round apart; an ulp of a world coordinate of 290 m is
  // two base steps) join the earliest vertex within that distance per axis that has not joined
  // another; seam vertices never move, so they never join. Joining a representative, not a
  // chain, bounds every move by the tolerance.
  const double tolerance = noise_tolerance_m > 0.0 ? noise_tolerance_m : position_step_m;
  std::vector<uint32_t> representative(positions.size());
  for (size_t v = 0; v < positions.size(); ++v) representative[v] = uint32_t(v);
  std::vector<uint32_t> used;
  used.reserve(positions.size());
  for (size_t v = 0; v < positions.size(); ++v)
    if (vertex_shift[v] != kNoShift) used.push_back(uint32_t(v));
  // Which movable vertices have any earlier vertex within reach, in parallel (nearly all have
  // none); then, in index order, each of those joins the earliest one still a representative.
  const VertexCellGrid grid(positions, used, tolerance);
  std::vector<uint8_t> has_earlier(positions.size(), 0);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, used.size(), 4096),
                    [&](const tbb::blocked_range<size_t>& range) {
                      for (size_t i = range.begin(); i != range.end(); ++i) {
                        const uint32_t v = used[i];
                        if (!keep.empty() && keep[v] != 0) continue;
                        has_earlier[v] = grid.smallestWithin(positions[v], v, [](uint32_t) {
                          return true;
                        }) != VertexCellGrid::kNone;
                      }
                    });
  for (uint32_t v : used) {
    if (!has_earlier[v]) continue;
    const uint32_t r = grid.smallestWithin(positions[v], v,
                                           [&](uint32_t w) { return representative[w] == w; });
    if (r != VertexCellGrid::kNone) representative[v] = r;
  }
  for (size_t v = 0; v < positions.size(); ++v) {
    const uint32_t r = representative[v];
    if (r != v && vertex_shift[v] != kNoShift)
      vertex_shift[r] = std::max(vertex_shift[r], vertex_shift[v]);
  }

  // 2. Each representative snapped to the coarsest grid among the clusters of its vertices, then
  // equal positions welded.
  std::vector<uint32_t> representatives;
  for (size_t v = 0; v < positions.size(); ++v)
    if (representative[v] == v) representatives.push_back(uint32_t(v));
  std::vector<glm::vec3> snapped(positions.begin(), positions.end());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, representatives.size(), 4096),
                    [&](const tbb::blocked_range<size_t>& range) {
                      for (size_t i = range.begin(); i != range.end(); ++i) {
                        const uint32_t v = representatives[i];
                        if (vertex_shift[v] == kNoShift || (!keep.empty() && keep[v] != 0))
                          continue;
                        const double cell = std::ldexp(position_step_m, int(vertex_shift[v]));
                        glm::vec3& p = snapped[v];
                        for (int a = 0; a < 3; ++a) {
                          if (!std::isfinite(p[a])) continue;
                          p[a] = float(std::nearbyint(double(p[a]) / cell) * cell);
                          if (p[a] == 0.0f) p[a] = 0.0f;  // -0 and +0 are one position
                        }
                      }
                    });
  // Equal bits welded, numbered in order of first use: sorted by bits then vertex, each run's
  // first vertex stands for the run.
  struct Keyed {
    uint32_t x, y, z, vertex;
    bool operator<(const Keyed& o) const {
      return x != o.x ? x < o.x : y != o.y ? y < o.y : z != o.z ? z < o.z : vertex < o.vertex;
    }
  };
  std::vector<Keyed> keyed(representatives.size());
  for (size_t i = 0; i < representatives.size(); ++i) {
    const glm::vec3& p = snapped[representatives[i]];
    keyed[i] = {std::bit_cast<uint32_t>(p.x), std::bit_cast<uint32_t>(p.y),
                std::bit_cast<uint32_t>(p.z), representatives[i]};
  }
  tbb::parallel_sort(keyed.begin(), keyed.end());
  std::vector<uint32_t> run_head(positions.size(), kNoShift);
  for (size_t i = 0; i < keyed.size(); ++i) {
    const bool same = i > 0 && keyed[i].x == keyed[i - 1].x && keyed[i].y == keyed[i - 1].y &&
                      keyed[i].z == keyed[i - 1].z;
    run_head[keyed[i].vertex] = same ? run_head[keyed[i - 1].vertex] : keyed[i].vertex;
  }
  GridWeld weld;
  weld.remap.resize(positions.size());
  weld.positions.reserve(representatives.size());
  for (uint32_t v : representatives) {
    const uint32_t head = run_head[v];
    if (head == v) {
      weld.remap[v] = uint32_t(weld.positions.size());
      weld.positions.push_back(snapped[v]);
    } else {
      weld.remap[v] = weld.remap[head];  // the head is earlier: already numbered
    }
  }
  for (size_t v = 0; v < positions.size(); ++v) {
    weld.remap[v] = weld.remap[representative[v]];
    weld.moved_vertices += weld.positions[weld.remap[v]] != positions[v];
  }
  weld.merged_vertices = positions.size() - weld.positions.size();
  return weld;
}

}  // namespace tw
