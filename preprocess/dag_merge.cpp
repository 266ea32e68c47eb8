// Merging brick DAGs: concatenation, exact weld of the brick roots, and the shared level loop.
// See dag_merge.h for the contract.
#include "dag_merge.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <unordered_map>

#include "position_key.h"

namespace tw {

void addStats(DagBuildStats& to, const DagBuildStats& from) {
  to.input_triangles += from.input_triangles;
  to.skipped_triangles += from.skipped_triangles;
  to.groups_locked += from.groups_locked;
  to.groups_sloppy += from.groups_sloppy;
  to.groups_dropped += from.groups_dropped;
  to.groups_pass_through += from.groups_pass_through;
  to.groups_proxy += from.groups_proxy;
  to.proxy_results_rejected += from.proxy_results_rejected;
  to.proxies_skipped += from.proxies_skipped;
  to.locked_results_rejected += from.locked_results_rejected;
  to.sloppy_results_rejected += from.sloppy_results_rejected;
  to.level_retries += from.level_retries;
  to.groups_kept_on_retry += from.groups_kept_on_retry;
  to.levels_below_shrink += from.levels_below_shrink;
}

void countLevels(ClusterDag& dag) {
  uint32_t top = 0;
  for (const DagCluster& c : dag.clusters) top = std::max(top, c.level);
  dag.triangles_per_level.assign(dag.clusters.empty() ? 0 : top + 1, 0);
  dag.clusters_per_level.assign(dag.triangles_per_level.size(), 0);
  dag.root_triangles = 0;
  for (const DagCluster& c : dag.clusters) {
    dag.triangles_per_level[c.level] += c.triangleCount();
    ++dag.clusters_per_level[c.level];
    if (c.parent_group == kNoGroup) dag.root_triangles += c.triangleCount();
  }
}

MergedRoots mergeBrickRoots(std::vector<DagCluster> roots, const DagOptions& options) {
  MergedRoots merged;
  merged.front_count = uint32_t(roots.size());
  merged.dag.clusters = std::move(roots);
  ClusterDag& dag = merged.dag;
  if (dag.clusters.empty()) {
    dag.stats.root_within_limit = true;
    return merged;
  }

  // The front: every brick root, its vertices welded by exact position across bricks.
  std::unordered_map<PositionKey, uint32_t, PositionHash> weld;
  std::vector<glm::vec3> positions;
  std::vector<uint32_t> front_ids;
  std::vector<std::vector<uint32_t>> front_tris;
  glm::vec3 lo(INFINITY), hi(-INFINITY);
  for (uint32_t id = 0; id < dag.clusters.size(); ++id) {
    DagCluster& c = dag.clusters[id];
    if (c.parent_group != kNoGroup)
      throw std::invalid_argument("mergeBrickRoots: a root cluster has a parent group");
    c.group = kNoGroup;  // the brick's own groups are not part of this DAG
    std::vector<uint32_t> global(c.positions.size());
    for (size_t v = 0; v < c.positions.size(); ++v) {
      auto [it, inserted] = weld.emplace(positionKeyOf(c.positions[v]), uint32_t(positions.size()));
      if (inserted) {
        positions.push_back(c.positions[v] + glm::vec3(0.0f));  // -0 -> +0, as the weld does
        lo = glm::min(lo, c.positions[v]);
        hi = glm::max(hi, c.positions[v]);
      }
      global[v] = it->second;
    }
    std::vector<uint32_t> tris(c.indices.size());
    for (size_t i = 0; i < c.indices.size(); ++i) tris[i] = global[c.indices[i]];
    front_ids.push_back(id);
    front_tris.push_back(std::move(tris));
  }
  const float epsilon = std::max(glm::length(hi - lo) * 1e-6f, 1e-12f);
  continueClusterDag(dag, positions, std::move(front_ids), std::move(front_tris), options, epsilon);
  return merged;
}

void appendMergedLevels(MergedRoots& merged, std::span<const uint32_t> front_ids,
                        uint32_t cluster_base, uint32_t group_base,
                        std::vector<DagCluster>& clusters, std::vector<DagGroup>& groups) {
  const uint32_t front = merged.front_count;
  auto cluster_id = [&](uint32_t id) { return id < front ? front_ids[id] : cluster_base + id - front; };
  auto group_id = [&](uint32_t g) { return g == kNoGroup ? kNoGroup : group_base + g; };
  for (uint32_t i = front; i < merged.dag.clusters.size(); ++i) {
    DagCluster& c = merged.dag.clusters[i];
    c.group = group_id(c.group);
    c.parent_group = group_id(c.parent_group);
    clusters.push_back(std::move(c));
  }
  for (DagGroup& g : merged.dag.groups) {
    for (uint32_t& child : g.children) child = cluster_id(child);
    for (uint32_t& made : g.clusters) made = cluster_id(made);
    groups.push_back(std::move(g));
  }
}

ClusterDag mergeBrickDags(std::vector<ClusterDag> bricks, const DagOptions& options) {
  ClusterDag dag;
  for (ClusterDag& brick : bricks) {
    addStats(dag.stats, brick.stats);
    if (brick.clusters.empty()) continue;
    const uint32_t cluster_base = uint32_t(dag.clusters.size());
    const uint32_t group_base = uint32_t(dag.groups.size());
    for (DagCluster& c : brick.clusters) {
      if (c.group != kNoGroup) c.group += group_base;
      if (c.parent_group != kNoGroup) c.parent_group += group_base;
      dag.clusters.push_back(std::move(c));
    }
    for (DagGroup& g : brick.groups) {
      for (uint32_t& child : g.children) child += cluster_base;
      for (uint32_t& made : g.clusters) made += cluster_base;
      dag.groups.push_back(std::move(g));
    }
    brick = ClusterDag{};  // release the brick's memory as we go
  }
  if (dag.clusters.empty()) {
    dag.stats.root_within_limit = true;
    return dag;
  }

  std::vector<uint32_t> root_ids;
  std::vector<DagCluster> roots;
  for (uint32_t id = 0; id < dag.clusters.size(); ++id)
    if (dag.clusters[id].parent_group == kNoGroup) {
      root_ids.push_back(id);
      roots.push_back(dag.clusters[id]);
    }
  MergedRoots merged = mergeBrickRoots(std::move(roots), options);

  // Back into the bricks' numbering: roots are root_ids, merged clusters and groups follow.
  const uint32_t cluster_base = uint32_t(dag.clusters.size());
  const uint32_t group_base = uint32_t(dag.groups.size());
  const uint32_t front = merged.front_count;
  auto group_id = [&](uint32_t g) { return g == kNoGroup ? kNoGroup : group_base + g; };
  for (uint32_t i = 0; i < front; ++i) {
    const DagCluster& from = merged.dag.clusters[i];
    DagCluster& to = dag.clusters[root_ids[i]];
    to.parent_group = group_id(from.parent_group);
    to.parent_error = from.parent_error;
    to.parent_lod_center = from.parent_lod_center;
    to.parent_lod_radius = from.parent_lod_radius;
  }
  appendMergedLevels(merged, root_ids, cluster_base, group_base, dag.clusters, dag.groups);
  addStats(dag.stats, merged.dag.stats);
  dag.stats.root_within_limit = merged.dag.stats.root_within_limit;
  countLevels(dag);
  return dag;
}

}  // namespace tw
