// Per-level fronts of a package's mesh DAG, from its cluster and group records alone (see
// dag_levels.h).
#include "dag_levels.h"

#include <algorithm>

namespace tw {

DagLevels dagLevels(const PackageView& view) {
  DagLevels out;
  const auto clusters = view.clusters();
  const auto groups = view.groups();
  uint32_t top = 0;
  for (const pkg::ClusterRecord& c : clusters)
    if (c.kind == static_cast<uint8_t>(pkg::ClusterKind::Mesh)) top = std::max<uint32_t>(top, c.level);
  // A cluster is in the fronts from its own level to its parent group's level (the group that
  // replaces it produces level parent + 1); a root is in every front from its level up.
  std::vector<int64_t> triangles(size_t(top) + 2, 0), count(size_t(top) + 2, 0);
  out.levels.resize(size_t(top) + 1);
  for (const pkg::ClusterRecord& c : clusters) {
    if (c.kind != static_cast<uint8_t>(pkg::ClusterKind::Mesh)) continue;
    const bool root = c.parent_group == pkg::kNone || c.parent_group >= groups.size();
    out.root_clusters += root;
    const uint32_t last = root ? top : std::clamp<uint32_t>(groups[c.parent_group].level, c.level, top);
    triangles[c.level] += c.triangle_count;
    triangles[size_t(last) + 1] -= c.triangle_count;
    ++count[c.level];
    --count[size_t(last) + 1];
    for (uint32_t l = c.level; l <= last; ++l)
      out.levels[l].max_error = std::max(out.levels[l].max_error, c.error);
  }
  int64_t running_triangles = 0, running_count = 0;
  for (size_t l = 0; l < out.levels.size(); ++l) {
    running_triangles += triangles[l];
    running_count += count[l];
    out.levels[l].triangles = uint64_t(running_triangles);
    out.levels[l].clusters = uint32_t(running_count);
  }
  for (size_t l = 1; l < out.levels.size(); ++l) {
    const DagLevel& below = out.levels[l - 1];
    DagLevel& level = out.levels[l];
    level.ratio = below.triangles ? double(level.triangles) / double(below.triangles) : 0.0;
    if (below.triangles > DagLevels::kHalvingFloor &&
        (level.ratio < DagLevels::kHalvingMin || level.ratio > DagLevels::kHalvingMax))
      out.halves = false;
    if (level.max_error < below.max_error) out.errors_monotone = false;
  }
  return out;
}

}  // namespace tw
