// Per-level figures of a package's mesh DAG, from its cluster records alone (see dag_levels.h).
#include "dag_levels.h"

#include <algorithm>

namespace tw {

DagLevels dagLevels(const PackageView& view) {
  DagLevels out;
  for (const pkg::ClusterRecord& c : view.clusters()) {
    if (c.kind != static_cast<uint8_t>(pkg::ClusterKind::Mesh)) continue;
    if (c.level >= out.levels.size()) out.levels.resize(size_t(c.level) + 1);
    DagLevel& level = out.levels[c.level];
    level.triangles += c.triangle_count;
    ++level.clusters;
    level.max_error = std::max(level.max_error, c.error);
    out.root_clusters += c.parent_group == pkg::kNone;
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
