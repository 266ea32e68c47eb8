// Maps a view cell's sampled visible set (candidate clusters of one DAG front, visibility_section.h)
// onto every cluster of the package, so the runtime's `pvs` mode can filter whatever cut it draws:
// - a front cluster is visible when it is in the set;
// - a cluster below the front (finer) is visible when any cluster its parent group produced is
//   (recursively up to the front): the front clusters it simplifies into were seen; when that
//   group produced nothing (dropped small parts), no front cluster stands for it and it is kept;
// - a cluster above the front (coarser) is visible when any child of the group that produced it
//   is (recursively down to the front);
// - a parametric cluster the section lists as a candidate (kParametricCandidates: every one of
//   its instances was sampled) is visible when it is in the set; any other parametric cluster
//   always is.
// Sampling misses things, so this is aggressive, not conservative: the runtime reports its pixel
// loss.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "package_view.h"

namespace tw {

class PvsMapping {
 public:
  // Indexes the DAG (groups by level, children). The view must outlive the mapping.
  // parametric_candidates: the section's list (VisibilityView::parametricCandidates), ids of
  // parametric clusters; empty for sections without it.
  PvsMapping(const PackageView& view, uint32_t candidate_level,
             std::span<const uint32_t> parametric_candidates);

  // out[c] = 1 when cluster c is potentially visible, for every cluster of the package.
  // `visible_candidates` are cluster ids (any order; ids not in the front are ignored).
  // O(clusters + groups) per call; no allocation once `out` and the scratch have grown.
  void flags(std::span<const uint32_t> visible_candidates, std::vector<uint8_t>& out) const;

 private:
  const PackageView* view_;
  uint32_t candidate_level_;
  std::vector<uint8_t> parametric_candidate_;  // per cluster
  std::vector<uint32_t> groups_descending_;  // group ids by level, highest first
  std::vector<uint32_t> child_offsets_, children_;  // CSR children per group
  mutable std::vector<uint8_t> group_visible_;
};

}  // namespace tw
