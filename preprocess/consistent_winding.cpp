// Consistent winding of a mesh piece before it is simplified: see consistent_winding.h.
#include "consistent_winding.h"

#include <algorithm>
#include <cmath>

#include "exact_weld.h"

namespace tw {
namespace {

// One use of an undirected edge: by which triangle, and whether from its lower welded vertex.
struct EdgeUseEntry {
  uint64_t key;
  uint32_t triangle;
  bool forward;
};

// Triangles joined through an edge, and whether they must end up with opposite "turned" states (the
// edge used in the same direction by both) or equal ones.
struct Link {
  uint32_t to;
  bool differ;
};

}  // namespace

std::vector<uint32_t> trianglesToTurn(const TriangleMesh& mesh, WindingReport* report) {
  WindingReport local;
  WindingReport& out = report ? *report : local;
  out = {};
  const WeldedTriangles welded = weldExactly(mesh);
  const auto n = static_cast<uint32_t>(welded.triangles.size());
  out.triangles = n;
  if (n == 0) return {};

  std::vector<EdgeUseEntry> uses;
  uses.reserve(size_t{3} * n);
  for (uint32_t t = 0; t < n; ++t)
    for (int e = 0; e < 3; ++e) {
      const uint32_t a = welded.triangles[t][e], b = welded.triangles[t][(e + 1) % 3];
      uses.push_back({(uint64_t{std::min(a, b)} << 32) | std::max(a, b), t, a < b});
    }
  std::sort(uses.begin(), uses.end(), [](const EdgeUseEntry& x, const EdgeUseEntry& y) {
    return x.key != y.key ? x.key < y.key : x.triangle < y.triangle;
  });

  // Joins through edges used by exactly two triangles; a triangle with any other edge is on an
  // open border (or a non-manifold junction), which makes its piece open.
  struct Join {
    uint32_t a, b;
    bool differ;
  };
  std::vector<Join> joins;
  std::vector<uint8_t> open_edge(n, 0);
  for (size_t i = 0; i < uses.size();) {
    size_t j = i;
    while (j < uses.size() && uses[j].key == uses[i].key) ++j;
    if (j - i == 2 && uses[i].triangle != uses[i + 1].triangle) {
      joins.push_back(
          {uses[i].triangle, uses[i + 1].triangle, uses[i].forward == uses[i + 1].forward});
    } else {
      for (size_t k = i; k < j; ++k) open_edge[uses[k].triangle] = 1;
    }
    i = j;
  }
  // The joins as adjacency lists (links[first[t] .. first[t + 1]) are triangle t's).
  std::vector<uint32_t> first(n + 1, 0);
  for (const Join& join : joins) ++first[join.a + 1], ++first[join.b + 1];
  for (uint32_t t = 0; t < n; ++t) first[t + 1] += first[t];
  std::vector<Link> links(first[n]);
  std::vector<uint32_t> fill(first.begin(), first.end() - 1);
  for (const Join& join : joins) {
    links[fill[join.a]++] = {join.b, join.differ};
    links[fill[join.b]++] = {join.a, join.differ};
  }

  const std::vector<glm::vec3>& points = welded.points;
  std::vector<uint8_t> turned(n, 0), visited(n, 0);
  std::vector<uint32_t> piece, queue;
  std::vector<uint32_t> result;
  for (uint32_t seed = 0; seed < n; ++seed) {
    if (visited[seed]) continue;
    ++out.pieces;
    piece.clear();
    queue.assign(1, seed);
    visited[seed] = 1;
    uint64_t conflicts = 0;
    bool open = false;
    for (size_t q = 0; q < queue.size(); ++q) {
      const uint32_t t = queue[q];
      piece.push_back(t);
      open = open || open_edge[t];
      for (uint32_t l = first[t]; l < first[t + 1]; ++l) {
        const Link& link = links[l];
        const uint8_t want = turned[t] ^ uint8_t(link.differ);
        if (!visited[link.to]) {
          visited[link.to] = 1;
          turned[link.to] = want;
          queue.push_back(link.to);
        } else if (turned[link.to] != want) {
          ++conflicts;
        }
      }
    }
    out.conflicts += conflicts / 2;  // each disagreeing edge is seen from both sides

    // Which way round the whole piece goes: outward when closed, else as most of its area was.
    const glm::dvec3 origin(points[welded.triangles[seed][0]]);
    double volume = 0.0, area_kept = 0.0, area_turned = 0.0, extent = 0.0;
    for (uint32_t t : piece) {
      const glm::dvec3 p0 = glm::dvec3(points[welded.triangles[t][0]]) - origin;
      const glm::dvec3 p1 = glm::dvec3(points[welded.triangles[t][1]]) - origin;
      const glm::dvec3 p2 = glm::dvec3(points[welded.triangles[t][2]]) - origin;
      const double v = glm::dot(p0, glm::cross(p1, p2)) / 6.0;
      volume += turned[t] ? -v : v;
      const double area = 0.5 * glm::length(glm::cross(p1 - p0, p2 - p0));
      (turned[t] ? area_turned : area_kept) += area;
      extent = std::max({extent, glm::length(p1), glm::length(p2)});
    }
    bool reverse_piece = area_turned > area_kept;
    // A closed piece with a clear volume faces out; a flat double sheet has none to go by.
    if (!open && conflicts == 0 && std::abs(volume) > 1e-9 * extent * extent * extent)
      reverse_piece = volume < 0.0;
    for (uint32_t t : piece)
      if (turned[t] != uint8_t(reverse_piece)) result.push_back(welded.sources[t]);
  }
  std::sort(result.begin(), result.end());
  out.turned = result.size();
  return result;
}

void turnTriangles(TriangleMesh& mesh, const std::vector<uint32_t>& triangles) {
  for (uint32_t t : triangles) {
    const size_t i = size_t{3} * t;
    if (i + 2 < mesh.indices.size()) std::swap(mesh.indices[i + 1], mesh.indices[i + 2]);
  }
}

}  // namespace tw
