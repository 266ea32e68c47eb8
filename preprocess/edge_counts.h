// Edge bookkeeping for the LOD DAG builder: edge keys, per-edge triangle counts as sorted
// vectors, and the crack-freedom rule every simplified group must pass. Sorting flat key lists
// is several times cheaper than hash maps built and freed per candidate, and lookups are binary
// searches; per-thread scratch buffers remove most allocator traffic.
#pragma once

#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

namespace tw {

// An undirected edge as one 64-bit key (smaller vertex in the high half).
inline uint64_t edgeKey(uint32_t a, uint32_t b) {
  if (a > b) std::swap(a, b);
  return (uint64_t(a) << 32) | b;
}

struct EdgeCount {
  uint64_t key;
  uint32_t count;
};
using EdgeCounts = std::vector<EdgeCount>;  // sorted by key

// Sorts edge keys (vertices below vertex_count) from `unsorted` into `keys`: a counting sort on
// the smaller vertex, then each vertex's few keys sorted; the same order as a full sort, at a
// fraction of the cost. `offsets` is scratch.
void bucketSortEdgeKeys(const std::vector<uint64_t>& unsorted, size_t vertex_count,
                        std::vector<uint64_t>& keys, std::vector<uint32_t>& offsets);

// The sorted edge keys of a triangle list (local vertices below vertex_count), one per triangle
// side, duplicates kept.
void sortedEdgeKeys(const std::vector<uint32_t>& tris, size_t vertex_count,
                    std::vector<uint64_t>& keys);

// How many triangles use each edge of `tris`.
EdgeCounts countEdges(const std::vector<uint32_t>& tris, size_t vertex_count);

// The count of edge e in counts, 0 when absent.
uint32_t edgeCount(const EdgeCounts& counts, uint64_t e);

bool containsSorted(const std::vector<uint64_t>& sorted, uint64_t e);

// The crack-freedom rule every candidate must pass: each edge in `shared` (sorted; edges shared
// with another group) keeps its triangle count, and no edge of `out_tris` is used exactly once
// unless it already was in `in`.
//
// Not checked, on purpose: a new edge joining two locked border vertices. meshopt creates them all
// the time (an interior vertex collapsing onto the border), so forbidding them stalls
// simplification. Where a neighbour joins the same two vertices on its side, a cut holds a pinch:
// an edge with four triangles (two opposite slivers), closed but not manifold. No hole appears.
//
// With `locked` (one flag per vertex: never moves), an edge used once that `in` did not use once
// is also accepted when both its vertices lie on rim edges of `in` (used other than exactly
// twice) and not both are locked: the outline of a part's own opening, simplified (a strip
// between two rims may narrow to nothing; the shared edges keep their counts, so the
// neighbouring groups' side is intact). Outlines then only ever join vertices that were on a
// rim of the input, level after level (docs/preprocess.md, "Rims").
bool borderPreserved(const EdgeCounts& in, const std::vector<uint64_t>& shared,
                     const std::vector<uint32_t>& out_tris, size_t vertex_count,
                     const std::vector<uint8_t>* locked = nullptr);

}  // namespace tw
