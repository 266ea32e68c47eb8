// Edge keys and counts for the LOD DAG builder. See edge_counts.h.
#include "edge_counts.h"

#include <algorithm>

namespace tw {
namespace {

// Per-thread scratch: processGroup runs once per group per candidate level, so reusing the
// buffers removes most of the allocator traffic.
struct EdgeScratch {
  std::vector<uint64_t> keys;
  std::vector<uint64_t> unsorted;
  std::vector<uint32_t> offsets;
};
EdgeScratch& edgeScratch() {
  thread_local EdgeScratch scratch;
  return scratch;
}

}  // namespace

void bucketSortEdgeKeys(const std::vector<uint64_t>& unsorted, size_t vertex_count,
                        std::vector<uint64_t>& keys, std::vector<uint32_t>& offsets) {
  offsets.assign(vertex_count + 1, 0);
  for (uint64_t k : unsorted) ++offsets[size_t(k >> 32) + 1];
  for (size_t v = 0; v < vertex_count; ++v) offsets[v + 1] += offsets[v];
  keys.resize(unsorted.size());
  for (uint64_t k : unsorted) keys[offsets[size_t(k >> 32)]++] = k;
  // offsets[v] now ends bucket v, so bucket v spans [offsets[v - 1], offsets[v]).
  uint32_t begin = 0;
  for (size_t v = 0; v < vertex_count; ++v) {
    const uint32_t end = offsets[v];
    if (end - begin > 16) {
      std::sort(keys.begin() + begin, keys.begin() + end);
    } else {
      for (uint32_t i = begin + 1; i < end; ++i) {
        uint64_t k = keys[i];
        uint32_t j = i;
        for (; j > begin && keys[j - 1] > k; --j) keys[j] = keys[j - 1];
        keys[j] = k;
      }
    }
    begin = end;
  }
}

void sortedEdgeKeys(const std::vector<uint32_t>& tris, size_t vertex_count,
                    std::vector<uint64_t>& keys) {
  EdgeScratch& scratch = edgeScratch();
  std::vector<uint64_t>& unsorted = scratch.unsorted;
  unsorted.clear();
  for (size_t t = 0; t + 2 < tris.size(); t += 3) {
    unsorted.push_back(edgeKey(tris[t], tris[t + 1]));
    unsorted.push_back(edgeKey(tris[t + 1], tris[t + 2]));
    unsorted.push_back(edgeKey(tris[t + 2], tris[t]));
  }
  bucketSortEdgeKeys(unsorted, vertex_count, keys, scratch.offsets);
}

EdgeCounts countEdges(const std::vector<uint32_t>& tris, size_t vertex_count) {
  std::vector<uint64_t>& keys = edgeScratch().keys;
  sortedEdgeKeys(tris, vertex_count, keys);
  EdgeCounts counts;
  counts.reserve(keys.size() / 2 + 1);
  for (size_t i = 0; i < keys.size();) {
    size_t j = i + 1;
    while (j < keys.size() && keys[j] == keys[i]) ++j;
    counts.push_back({keys[i], uint32_t(j - i)});
    i = j;
  }
  return counts;
}

uint32_t edgeCount(const EdgeCounts& counts, uint64_t e) {
  auto it = std::lower_bound(counts.begin(), counts.end(), e,
                             [](const EdgeCount& c, uint64_t key) { return c.key < key; });
  return it != counts.end() && it->key == e ? it->count : 0u;
}

bool containsSorted(const std::vector<uint64_t>& sorted, uint64_t e) {
  return std::binary_search(sorted.begin(), sorted.end(), e);
}

bool borderPreserved(const EdgeCounts& in, const std::vector<uint64_t>& shared,
                     const std::vector<uint32_t>& out_tris, size_t vertex_count,
                     const std::vector<uint8_t>* locked) {
  std::vector<uint64_t>& keys = edgeScratch().keys;
  sortedEdgeKeys(out_tris, vertex_count, keys);
  for (uint64_t e : shared) {
    auto [lo, hi] = std::equal_range(keys.begin(), keys.end(), e);
    if (uint32_t(hi - lo) != edgeCount(in, e)) return false;
  }
  std::vector<uint8_t> on_rim;
  if (locked) {
    on_rim.assign(vertex_count, 0);
    for (const EdgeCount& ec : in)
      if (ec.count != 2) on_rim[uint32_t(ec.key >> 32)] = on_rim[uint32_t(ec.key)] = 1;
  }
  auto rimOutline = [&](uint64_t e) {
    if (!locked) return false;
    const uint32_t a = uint32_t(e >> 32), b = uint32_t(e);
    if (a >= vertex_count || b >= vertex_count) return false;  // a far proxy's new vertex
    return on_rim[a] && on_rim[b] && !((*locked)[a] && (*locked)[b]);
  };
  for (size_t i = 0; i < keys.size();) {
    size_t j = i + 1;
    while (j < keys.size() && keys[j] == keys[i]) ++j;
    if (j - i == 1 && edgeCount(in, keys[i]) != 1 && !rimOutline(keys[i])) return false;
    i = j;
  }
  return true;
}

}  // namespace tw
