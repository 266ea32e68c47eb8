// The visible-set mapping from one DAG front onto every cluster. See pvs_mapping.h.
//
// Two sweeps over the groups settle every cluster off the front in O(clusters + groups):
// - downward (groups of level < V, highest first): a group's children are visible when any
//   cluster it produced is; those produced clusters are front clusters or children of a higher
//   group below V, already settled;
// - upward (groups of level >= V, lowest first): a group's produced clusters are visible when any
//   of its children is; those children are front clusters or clusters produced by a lower group
//   at or above V, already settled.
#include "pvs_mapping.h"

#include <algorithm>
#include <numeric>

namespace tw {
namespace {

bool isMesh(const pkg::ClusterRecord& r) {
  return r.kind == static_cast<uint8_t>(pkg::ClusterKind::Mesh);
}

}  // namespace

PvsMapping::PvsMapping(const PackageView& view, uint32_t candidate_level,
                       std::span<const uint32_t> parametric_candidates)
    : view_(&view), candidate_level_(candidate_level) {
  const auto clusters = view.clusters();
  parametric_candidate_.assign(clusters.size(), 0);
  for (uint32_t id : parametric_candidates)
    if (id < clusters.size() && !isMesh(clusters[id])) parametric_candidate_[id] = 1;
  const auto groups = view.groups();
  groups_descending_.resize(groups.size());
  std::iota(groups_descending_.begin(), groups_descending_.end(), 0u);
  std::stable_sort(groups_descending_.begin(), groups_descending_.end(),
                   [&](uint32_t a, uint32_t b) { return groups[a].level > groups[b].level; });
  // Children as CSR: count, prefix sum, fill.
  child_offsets_.assign(groups.size() + 1, 0);
  for (const pkg::ClusterRecord& c : clusters)
    if (c.parent_group != pkg::kNone) ++child_offsets_[c.parent_group + 1];
  for (size_t g = 0; g < groups.size(); ++g) child_offsets_[g + 1] += child_offsets_[g];
  children_.resize(child_offsets_.back());
  std::vector<uint32_t> next(child_offsets_.begin(), child_offsets_.end() - 1);
  for (uint32_t c = 0; c < clusters.size(); ++c)
    if (clusters[c].parent_group != pkg::kNone) children_[next[clusters[c].parent_group]++] = c;
  group_visible_.assign(groups.size(), 0);
}

void PvsMapping::flags(std::span<const uint32_t> visible_candidates,
                       std::vector<uint8_t>& out) const {
  const auto clusters = view_->clusters();
  const auto groups = view_->groups();
  const uint32_t v = candidate_level_;
  out.assign(clusters.size(), 0);
  // Parametric clusters that were not candidates are always drawn.
  for (uint32_t c = 0; c < clusters.size(); ++c)
    if (!isMesh(clusters[c]) && !parametric_candidate_[c]) out[c] = 1;

  // Front clusters: mesh, level <= V, root or simplified by a group at or above V; parametric
  // candidates stand for themselves.
  for (uint32_t id : visible_candidates) {
    if (id >= clusters.size()) continue;
    const pkg::ClusterRecord& r = clusters[id];
    if (!isMesh(r)) {
      out[id] = 1;  // a candidate stands for itself; any other parametric cluster is 1 already
      continue;
    }
    if (r.level > v) continue;
    if (r.parent_group != pkg::kNone && groups[r.parent_group].level < v) continue;
    out[id] = 1;
  }

  auto childrenOf = [&](uint32_t g) {
    return std::span<const uint32_t>(children_).subspan(child_offsets_[g],
                                                        child_offsets_[g + 1] - child_offsets_[g]);
  };
  // Below the front: highest groups first.
  for (uint32_t g : groups_descending_) {
    const pkg::GroupRecord& group = groups[g];
    if (group.level >= v) continue;
    // A group that produced nothing (its small parts were dropped) has no front cluster standing
    // for its children: the sampling could not see them, so they are kept.
    uint8_t seen = group.cluster_count == 0 ? 1 : 0;
    for (uint32_t c = group.first_cluster; c < group.first_cluster + group.cluster_count && !seen;
         ++c)
      seen = out[c];
    group_visible_[g] = seen;
    for (uint32_t child : childrenOf(g))
      if (isMesh(clusters[child])) out[child] = seen;
  }
  // Above the front: lowest groups first.
  for (auto it = groups_descending_.rbegin(); it != groups_descending_.rend(); ++it) {
    const uint32_t g = *it;
    const pkg::GroupRecord& group = groups[g];
    if (group.level < v) continue;
    uint8_t seen = 0;
    for (uint32_t child : childrenOf(g))
      if (out[child]) {
        seen = 1;
        break;
      }
    group_visible_[g] = seen;
    for (uint32_t c = group.first_cluster; c < group.first_cluster + group.cluster_count; ++c)
      if (isMesh(clusters[c])) out[c] = seen;
  }
}

}  // namespace tw
