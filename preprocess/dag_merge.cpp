// Merging brick DAGs: concatenation, exact weld of the brick roots, and the shared level loop.
// See dag_merge.h for the contract.
#include "dag_merge.h"

#include <algorithm>
#include <cmath>
#include <unordered_map>

#include "position_key.h"

namespace tw {

namespace {

void addStats(DagBuildStats& to, const DagBuildStats& from) {
  to.input_triangles += from.input_triangles;
  to.skipped_triangles += from.skipped_triangles;
  to.groups_locked += from.groups_locked;
  to.groups_sloppy += from.groups_sloppy;
  to.groups_dropped += from.groups_dropped;
  to.groups_pass_through += from.groups_pass_through;
  to.locked_results_rejected += from.locked_results_rejected;
  to.sloppy_results_rejected += from.sloppy_results_rejected;
  to.level_retries += from.level_retries;
  to.levels_below_shrink += from.levels_below_shrink;
}

}  // namespace

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

  // The front: every brick root, its vertices welded by exact position across bricks.
  std::unordered_map<PositionKey, uint32_t, PositionHash> weld;
  std::vector<glm::vec3> positions;
  std::vector<uint32_t> front_ids;
  std::vector<std::vector<uint32_t>> front_tris;
  glm::vec3 lo(INFINITY), hi(-INFINITY);
  for (uint32_t id = 0; id < dag.clusters.size(); ++id) {
    const DagCluster& c = dag.clusters[id];
    if (c.parent_group != kNoGroup) continue;
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
  return dag;
}

}  // namespace tw
