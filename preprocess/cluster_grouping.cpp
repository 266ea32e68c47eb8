// Grouping a level's clusters for simplification: METIS k-way on the cluster adjacency graph.
// See cluster_grouping.h.
#include "cluster_grouping.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <unordered_map>

#include <metis.h>

#include "edge_counts.h"
#include "object_sets.h"

namespace tw {

namespace {

constexpr uint32_t kUnowned = std::numeric_limits<uint32_t>::max();

uint32_t morton3(glm::vec3 unit) {
  auto spread = [](uint32_t x) {
    x &= 0x3ff;
    x = (x | (x << 16)) & 0x030000ff;
    x = (x | (x << 8)) & 0x0300f00f;
    x = (x | (x << 4)) & 0x030c30c3;
    x = (x | (x << 2)) & 0x09249249;
    return x;
  };
  auto q = [](float f) { return uint32_t(std::clamp(f, 0.0f, 1.0f) * 1023.0f); };
  return spread(q(unit.x)) | (spread(q(unit.y)) << 1) | (spread(q(unit.z)) << 2);
}

}  // namespace

std::vector<std::vector<uint32_t>> groupClusters(
    std::span<const std::span<const uint32_t>> cluster_tris, std::span<const glm::vec3> centers,
    uint32_t group_size, size_t vertex_count) {
  const size_t n = cluster_tris.size();
  std::vector<std::vector<uint32_t>> groups;
  if (n <= group_size) {
    groups.emplace_back(n);
    std::iota(groups[0].begin(), groups[0].end(), 0u);
    return groups;
  }

  // Clusters sharing vertices; weight = number of shared vertices (a proxy for border length).
  // Per vertex, the clusters using it in ascending order: a counting sort by vertex (clusters
  // are visited in order, and last_cluster drops repeats within one cluster).
  std::vector<uint32_t> last_cluster(vertex_count, kUnowned);
  std::vector<uint32_t> offsets(vertex_count + 1, 0);
  for (size_t c = 0; c < n; ++c)
    for (uint32_t v : cluster_tris[c])
      if (last_cluster[v] != uint32_t(c)) {
        last_cluster[v] = uint32_t(c);
        ++offsets[v + 1];
      }
  for (size_t v = 0; v < vertex_count; ++v) offsets[v + 1] += offsets[v];
  std::vector<uint32_t> vertex_clusters(offsets[vertex_count]);
  {
    std::vector<uint32_t> fill(offsets.begin(), offsets.end() - 1);
    std::fill(last_cluster.begin(), last_cluster.end(), kUnowned);
    for (size_t c = 0; c < n; ++c)
      for (uint32_t v : cluster_tris[c])
        if (last_cluster[v] != uint32_t(c)) {
          last_cluster[v] = uint32_t(c);
          vertex_clusters[fill[v]++] = uint32_t(c);
        }
  }
  // Edge weights: one key per shared vertex and cluster pair, counted after sorting.
  std::vector<uint64_t> links;
  for (size_t v = 0; v < vertex_count; ++v)
    for (uint32_t a = offsets[v]; a < offsets[v + 1]; ++a)
      for (uint32_t b = a + 1; b < offsets[v + 1]; ++b)
        links.push_back(edgeKey(vertex_clusters[a], vertex_clusters[b]));
  // Weak links between neighbours in Morton order, so disconnected parts group by proximity.
  glm::vec3 lo(INFINITY), hi(-INFINITY);
  for (const glm::vec3& c : centers) {
    lo = glm::min(lo, c);
    hi = glm::max(hi, c);
  }
  glm::vec3 extent = glm::max(hi - lo, glm::vec3(1e-30f));
  std::vector<std::pair<uint32_t, uint32_t>> order(n);
  for (size_t c = 0; c < n; ++c) order[c] = {morton3((centers[c] - lo) / extent), uint32_t(c)};
  std::sort(order.begin(), order.end());
  for (size_t i = 0; i + 1 < n; ++i) {
    links.push_back(edgeKey(order[i].second, order[i + 1].second));
    if (i + 2 < n) links.push_back(edgeKey(order[i].second, order[i + 2].second));
  }

  std::sort(links.begin(), links.end());
  std::vector<std::pair<uint64_t, uint32_t>> edges;
  for (size_t i = 0; i < links.size();) {
    size_t j = i + 1;
    while (j < links.size() && links[j] == links[i]) ++j;
    edges.emplace_back(links[i], uint32_t(j - i));
    i = j;
  }
  std::vector<idx_t> xadj(n + 1, 0);
  for (const auto& [key, w] : edges) {
    ++xadj[(key >> 32) + 1];
    ++xadj[uint32_t(key) + 1];
  }
  for (size_t i = 0; i < n; ++i) xadj[i + 1] += xadj[i];
  const size_t arcs = static_cast<size_t>(xadj[n]);
  std::vector<idx_t> adjncy(arcs), adjwgt(arcs);
  std::vector<idx_t> fill(xadj.begin(), xadj.end() - 1);
  for (const auto& [key, w] : edges) {
    uint32_t a = uint32_t(key >> 32), b = uint32_t(key);
    adjncy[size_t(fill[a])] = idx_t(b);
    adjwgt[size_t(fill[a]++)] = idx_t(w);
    adjncy[size_t(fill[b])] = idx_t(a);
    adjwgt[size_t(fill[b]++)] = idx_t(w);
  }
  std::vector<idx_t> vwgt(n);
  for (size_t c = 0; c < n; ++c) vwgt[c] = std::max<idx_t>(1, idx_t(cluster_tris[c].size() / 3));

  idx_t nvtxs = idx_t(n), ncon = 1, nparts = idx_t((n + group_size - 1) / group_size), edgecut = 0;
  // METIS keeps its random generator in global state (GKlib), so calls must not run at the same
  // time: grouping sets in parallel made packages differ from run to run.
  idx_t metis_options[METIS_NOPTIONS];
  METIS_SetDefaultOptions(metis_options);
  metis_options[METIS_OPTION_SEED] = 42;
  metis_options[METIS_OPTION_NUMBERING] = 0;
  std::vector<idx_t> part(n, 0);
  int rc = METIS_PartGraphKway(&nvtxs, &ncon, xadj.data(), adjncy.data(), vwgt.data(), nullptr,
                               adjwgt.data(), &nparts, nullptr, nullptr, metis_options, &edgecut,
                               part.data());
  if (rc != METIS_OK) {
    // Fallback: runs of group_size clusters in Morton order.
    for (size_t i = 0; i < n; ++i) part[order[i].second] = idx_t(i / group_size);
  }
  groups.resize(size_t(nparts));
  for (size_t c = 0; c < n; ++c) groups[size_t(part[c])].push_back(uint32_t(c));
  groups.erase(std::remove_if(groups.begin(), groups.end(), [](const auto& g) { return g.empty(); }),
               groups.end());
  return groups;
}

std::vector<std::vector<uint32_t>> groupClustersByObject(
    std::span<const std::span<const uint32_t>> cluster_tris,
    std::span<const std::span<const uint32_t>> cluster_ids, std::span<const glm::vec3> centers,
    uint32_t group_size, uint32_t large_triangles, size_t vertex_count) {
  const size_t n = cluster_tris.size();
  // The object of each single-object cluster, and the triangles such clusters hold per object.
  std::vector<uint32_t> owner(n, kNoObject);
  std::unordered_map<uint32_t, uint64_t> owned_triangles;
  for (size_t c = 0; c < n; ++c) {
    const auto ids = cluster_ids[c];
    if (ids.empty() || !std::all_of(ids.begin(), ids.end(), [&](uint32_t id) { return id == ids[0]; }))
      continue;
    owner[c] = ids[0];
    owned_triangles[ids[0]] += ids.size();
  }
  const std::vector<std::vector<uint32_t>> sets = setsByLargeObject(
      n, [&](size_t c) { return owner[c]; },
      [&](uint32_t object) { return owned_triangles[object] >= large_triangles; });
  if (sets.size() <= 1) return groupClusters(cluster_tris, centers, group_size, vertex_count);

  // Each set with its own compact vertex numbering, so that many small sets cost what one does.
  std::vector<uint32_t> local(vertex_count, kUnowned);
  std::vector<std::vector<uint32_t>> groups;
  for (const std::vector<uint32_t>& set : sets) {
    std::vector<uint32_t> touched;
    std::vector<std::vector<uint32_t>> set_tris(set.size());
    std::vector<glm::vec3> set_centers;
    for (size_t k = 0; k < set.size(); ++k) {
      for (uint32_t v : cluster_tris[set[k]]) {
        if (local[v] == kUnowned) {
          local[v] = uint32_t(touched.size());
          touched.push_back(v);
        }
        set_tris[k].push_back(local[v]);
      }
      set_centers.push_back(centers[set[k]]);
    }
    std::vector<std::span<const uint32_t>> spans(set_tris.begin(), set_tris.end());
    for (std::vector<uint32_t>& group :
         groupClusters(spans, set_centers, std::min<uint32_t>(group_size, uint32_t(set.size())),
                       touched.size())) {
      for (uint32_t& member : group) member = set[member];
      groups.push_back(std::move(group));
    }
    for (uint32_t v : touched) local[v] = kUnowned;
  }
  return groups;
}

}  // namespace tw
