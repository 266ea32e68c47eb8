// DAG fronts of a package. See dag_front.h.
#include "dag_front.h"

namespace tw {

DagFront dagFront(const PackageView& view, uint32_t level) {
  DagFront front;
  front.level = level;
  const auto clusters = view.clusters();
  const auto groups = view.groups();
  for (uint32_t c = 0; c < clusters.size(); ++c) {
    const pkg::ClusterRecord& r = clusters[c];
    if (r.kind != static_cast<uint8_t>(pkg::ClusterKind::Mesh) || r.level > level) continue;
    if (r.parent_group != pkg::kNone && groups[r.parent_group].level < level) continue;
    front.clusters.push_back(c);
    front.triangles += r.triangle_count;
  }
  return front;
}

DagFront finestFrontWithin(const PackageView& view, uint64_t max_triangles) {
  const uint32_t levels = view.header().level_count;
  DagFront front;
  for (uint32_t level = 0; level < levels; ++level) {
    front = dagFront(view, level);
    if (front.triangles <= max_triangles) return front;
  }
  return front;
}

}  // namespace tw
