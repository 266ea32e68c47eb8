// Vertex clustering with locked vertices: the grid search, the representative of each cell, the
// remapped triangles and the cancellation of folded pairs. See locked_vertex_clustering.h.
#include "locked_vertex_clustering.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>

#include "edge_counts.h"

namespace tw {

namespace {

constexpr uint64_t kLockedCell = uint64_t(1) << 63;
constexpr uint64_t kRimCell = uint64_t(1) << 62;
constexpr uint32_t kMaxGridCells = 1u << 20;  // 21 bits per axis in a cell key

// Plane quadric a x + b y + c z + d = 0, symmetric 4x4 stored as its 10 distinct entries.
struct Quadric {
  std::array<double, 10> q{};

  static Quadric plane(const glm::dvec3& n, double d, double weight) {
    Quadric out;
    out.q = {n.x * n.x, n.x * n.y, n.x * n.z, n.x * d, n.y * n.y,
             n.y * n.z, n.y * d,   n.z * n.z, n.z * d, d * d};
    for (double& v : out.q) v *= weight;
    return out;
  }
  void add(const Quadric& o) {
    for (size_t i = 0; i < q.size(); ++i) q[i] += o.q[i];
  }
  double evaluate(const glm::dvec3& p) const {
    return q[0] * p.x * p.x + 2 * q[1] * p.x * p.y + 2 * q[2] * p.x * p.z + 2 * q[3] * p.x +
           q[4] * p.y * p.y + 2 * q[5] * p.y * p.z + 2 * q[6] * p.y + q[7] * p.z * p.z +
           2 * q[8] * p.z + q[9];
  }
};

// Each vertex's quadric: the area-weighted planes of the triangles using it.
std::vector<Quadric> vertexQuadrics(std::span<const glm::vec3> positions,
                                    std::span<const uint32_t> tris) {
  std::vector<Quadric> quadrics(positions.size());
  for (size_t i = 0; i + 2 < tris.size(); i += 3) {
    const glm::dvec3 a(positions[tris[i]]), b(positions[tris[i + 1]]), c(positions[tris[i + 2]]);
    glm::dvec3 n = glm::cross(b - a, c - a);
    const double twice_area = glm::length(n);
    if (!(twice_area > 0.0)) continue;
    n /= twice_area;
    const Quadric q = Quadric::plane(n, -glm::dot(n, a), 0.5 * twice_area);
    for (int k = 0; k < 3; ++k) quadrics[tris[i + k]].add(q);
  }
  return quadrics;
}

// The grid over the triangles' bounding box: `cells` cubes along the longest axis.
struct Grid {
  glm::vec3 origin{0.0f};
  float extent = 0.0f;
};

Grid gridOver(std::span<const glm::vec3> positions, std::span<const uint32_t> tris) {
  glm::vec3 lo(INFINITY), hi(-INFINITY);
  for (uint32_t v : tris) {
    lo = glm::min(lo, positions[v]);
    hi = glm::max(hi, positions[v]);
  }
  const glm::vec3 size = hi - lo;
  return {lo, std::max({size.x, size.y, size.z, 1e-30f})};
}

// One key per vertex: its cell of a grid of `cells` cubes along the longest axis (a fraction of
// a cube may be left over), or a cell of its own when locked.
void cellKeys(std::span<const glm::vec3> positions, std::span<const uint8_t> roles,
              const Grid& grid, double cells, std::vector<uint64_t>& keys) {
  keys.resize(positions.size());
  const float scale = float(cells / double(grid.extent));
  const float last = float(std::ceil(cells) - 1.0);
  for (size_t v = 0; v < positions.size(); ++v) {
    if (roles[v] & kLockedVertex) {
      keys[v] = kLockedCell | v;
      continue;
    }
    uint64_t key = 0;
    for (int k = 0; k < 3; ++k) {
      const float cell = std::floor((positions[v][k] - grid.origin[k]) * scale);
      const uint64_t i = uint64_t(std::clamp(cell, 0.0f, last));
      key = (key << 21) | i;
    }
    keys[v] = (roles[v] & kRimVertex) ? key | kRimCell : key;
  }
}

size_t survivingTriangles(std::span<const uint32_t> tris, const std::vector<uint64_t>& keys) {
  size_t count = 0;
  for (size_t i = 0; i + 2 < tris.size(); i += 3) {
    const uint64_t a = keys[tris[i]], b = keys[tris[i + 1]], c = keys[tris[i + 2]];
    count += a != b && b != c && a != c;
  }
  return count;
}

// Per vertex, the vertex its cell merges it onto: the member with the smallest summed quadric.
std::vector<uint32_t> cellRepresentatives(std::span<const glm::vec3> positions,
                                          const std::vector<Quadric>& quadrics,
                                          const std::vector<uint64_t>& keys) {
  std::vector<uint32_t> order(positions.size());
  for (uint32_t v = 0; v < order.size(); ++v) order[v] = v;
  std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
    return keys[a] < keys[b] || (keys[a] == keys[b] && a < b);
  });
  std::vector<uint32_t> rep(positions.size());
  for (size_t i = 0; i < order.size();) {
    size_t j = i + 1;
    while (j < order.size() && keys[order[j]] == keys[order[i]]) ++j;
    uint32_t best = order[i];
    if (j - i > 1) {
      Quadric cell;
      for (size_t k = i; k < j; ++k) cell.add(quadrics[order[k]]);
      double best_cost = INFINITY;
      for (size_t k = i; k < j; ++k) {
        const double cost = cell.evaluate(glm::dvec3(positions[order[k]]));
        if (cost < best_cost) {
          best_cost = cost;
          best = order[k];
        }
      }
    }
    for (size_t k = i; k < j; ++k) rep[order[k]] = best;
    i = j;
  }
  return rep;
}

// Remaps the triangles, drops degenerate ones, and cancels pairs of opposite triangles on the
// same three vertices where at least one of the run moved (a fold the merge created), unless two
// of the three are locked: their edge may be shared with another group, which counts on it.
void remapTriangles(std::span<const uint32_t> tris, const std::vector<uint32_t>& rep,
                    std::span<const uint8_t> roles, VertexClusteringResult& out) {
  struct Entry {
    std::array<uint32_t, 3> sorted;
    uint32_t triangle;
    bool even;   // the remapped corner order is an even permutation of `sorted`
    bool moved;  // a corner moved
  };
  std::vector<Entry> entries;
  for (uint32_t t = 0; 3 * size_t(t) + 2 < tris.size(); ++t) {
    const uint32_t a = rep[tris[3 * t]], b = rep[tris[3 * t + 1]], c = rep[tris[3 * t + 2]];
    if (a == b || b == c || a == c) continue;
    const bool moved = a != tris[3 * t] || b != tris[3 * t + 1] || c != tris[3 * t + 2];
    // Rotate the smallest first; then the order of the other two gives the orientation.
    std::array<uint32_t, 3> r = {a, b, c};
    if (b < a && b < c) r = {b, c, a};
    if (c < a && c < b) r = {c, a, b};
    const bool even = r[1] < r[2];
    entries.push_back({{r[0], std::min(r[1], r[2]), std::max(r[1], r[2])}, t, even, moved});
  }
  std::sort(entries.begin(), entries.end(), [](const Entry& x, const Entry& y) {
    return x.sorted < y.sorted || (x.sorted == y.sorted && x.triangle < y.triangle);
  });
  std::vector<uint8_t> cancelled(entries.size(), 0);
  for (size_t i = 0; i < entries.size();) {
    size_t j = i + 1;
    bool any_moved = entries[i].moved;
    while (j < entries.size() && entries[j].sorted == entries[i].sorted) {
      any_moved = any_moved || entries[j].moved;
      ++j;
    }
    int locked_corners = 0;
    for (uint32_t v : entries[i].sorted) locked_corners += (roles[v] & kLockedVertex) != 0;
    if (any_moved && j - i > 1 && locked_corners < 2) {
      std::vector<size_t> even, odd;
      for (size_t k = i; k < j; ++k) (entries[k].even ? even : odd).push_back(k);
      for (size_t k = 0; k < std::min(even.size(), odd.size()); ++k)
        cancelled[even[k]] = cancelled[odd[k]] = 1;
    }
    i = j;
  }
  std::vector<uint32_t> kept;
  for (size_t k = 0; k < entries.size(); ++k)
    if (!cancelled[k]) kept.push_back(entries[k].triangle);
  std::sort(kept.begin(), kept.end());
  out.tris.clear();
  out.source_triangle = kept;
  for (uint32_t t : kept)
    for (int k = 0; k < 3; ++k) out.tris.push_back(rep[tris[3 * t + k]]);
}

}  // namespace

VertexClusteringResult simplifyByLockedVertexClustering(std::span<const glm::vec3> positions,
                                                        std::span<const uint32_t> tris,
                                                        std::span<const uint8_t> roles,
                                                        size_t target_triangles,
                                                        size_t most_triangles) {
  VertexClusteringResult out;
  if (tris.empty()) return out;
  most_triangles = std::max(most_triangles, target_triangles);
  const Grid grid = gridOver(positions, tris);

  // A binary search over whole cell counts finds the largest grid whose surviving triangles are
  // within the target (the count grows, roughly, with the grid).
  std::vector<uint64_t> keys;
  uint32_t lo = 1, hi = kMaxGridCells;
  uint32_t best = 1;
  while (lo <= hi) {
    const uint32_t mid = lo + (hi - lo) / 2;
    cellKeys(positions, roles, grid, mid, keys);
    if (survivingTriangles(tris, keys) <= target_triangles) {
      best = mid;
      lo = mid + 1;
    } else {
      hi = mid - 1;
    }
  }
  const std::vector<Quadric> quadrics = vertexQuadrics(positions, tris);
  auto clusterAt = [&](double cells) {
    VertexClusteringResult result;
    cellKeys(positions, roles, grid, cells, keys);
    result.grid_cells = cells;
    const std::vector<uint32_t> rep = cellRepresentatives(positions, quadrics, keys);
    remapTriangles(tris, rep, roles, result);
    for (uint32_t v : tris)
      result.error = std::max(result.error, glm::length(positions[v] - positions[rep[v]]));
    return result;
  };
  out = clusterAt(best);
  // A coarse grid moves in large steps, though (5 to 6 cells along the longest axis can double
  // the survivors), and on thin parts many survivors cancel (a tube flattened into two opposite
  // sheets): below kRefinedBelow cells the sizes between the search's grid and one more cell are
  // tried in sixteenths, and the result taken is the one whose triangles are nearest the target
  // without passing most_triangles (of equal distances, the finer grid). A coarse group then
  // comes down near its target, not far below it.
  // Only a result well short of its target is refined, until it is no longer; only grids whose
  // survivors (an upper bound of what remains) exceed what it kept are clustered.
  constexpr uint32_t kRefinedBelow = 64;
  constexpr int kSteps = 16;
  constexpr double kShortOfTarget = 0.8;
  auto count = [](const VertexClusteringResult& r) { return r.tris.size() / 3; };
  if (best < kRefinedBelow && double(count(out)) < kShortOfTarget * double(target_triangles)) {
    auto distance = [&](const VertexClusteringResult& r) {
      const size_t n = count(r);
      return n > target_triangles ? n - target_triangles : target_triangles - n;
    };
    for (int step = 1; step < kSteps; ++step) {
      const double cells = best + double(step) / kSteps;
      cellKeys(positions, roles, grid, cells, keys);
      if (survivingTriangles(tris, keys) <= count(out)) continue;
      VertexClusteringResult finer = clusterAt(cells);
      if (count(finer) <= most_triangles && distance(finer) <= distance(out))
        out = std::move(finer);
      if (double(count(out)) >= kShortOfTarget * double(target_triangles)) break;
    }
  }
  return out;
}

void markRimVertices(std::span<const uint32_t> tris, std::vector<uint8_t>& roles) {
  // Each directed use as (edge, +1 or -1); an edge whose signs do not sum to zero is unbalanced.
  std::vector<std::pair<uint64_t, int>> uses;
  uses.reserve(tris.size());
  for (size_t i = 0; i + 2 < tris.size(); i += 3)
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = tris[i + k], b = tris[i + (k + 1) % 3];
      uses.emplace_back(edgeKey(a, b), a < b ? 1 : -1);
    }
  std::sort(uses.begin(), uses.end());
  for (size_t i = 0; i < uses.size();) {
    size_t j = i;
    int sum = 0;
    while (j < uses.size() && uses[j].first == uses[i].first) sum += uses[j++].second;
    if (sum != 0)
      for (uint32_t v : {uint32_t(uses[i].first >> 32), uint32_t(uses[i].first)})
        roles[v] |= kRimVertex;
    i = j;
  }
}

}  // namespace tw
