// The scales at which parametric instances show, and the selection of a cluster's instances by
// them. See parametric_instance_scales.h.
#include "parametric_instance_scales.h"

#include <algorithm>
#include <cmath>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace tw {

using instance_forms::InstanceBounds;
using instance_forms::kValid;

namespace {

// The choice works in float; the index keeps a margin so rounding never leaves out an instance
// the choice would draw.
constexpr double kLower = 1.0 - 1e-3, kUpper = 1.0 + 1e-3;  // scales; the cluster's radius

}  // namespace

void InstanceScaleIndex::build(std::span<const pkg::ClusterRecord> clusters,
                               std::span<const InstanceBounds> bounds,
                               const Thresholds& thresholds) {
  clusters_.assign(clusters.size(), ClusterEntry{});
  shown_from_.assign(bounds.size(), ShownFrom{INFINITY, 0});
  tbb::parallel_for(tbb::blocked_range<size_t>(0, clusters.size(), 64),
                    [&](const tbb::blocked_range<size_t>& range) {
    for (size_t c = range.begin(); c != range.end(); ++c) {
      const pkg::ClusterRecord& r = clusters[c];
      if (r.kind != uint8_t(pkg::ClusterKind::Parametric) || r.instance_first > bounds.size() ||
          r.instance_count > bounds.size() - r.instance_first)
        continue;
      ClusterEntry& entry = clusters_[c];
      entry.first = r.instance_first;
      entry.count = r.instance_count;
      const std::span<const InstanceBounds> members = bounds.subspan(r.instance_first, r.instance_count);
      // The sphere: centred on the valid instances' box, wide enough for each one's sphere.
      glm::vec3 lo(INFINITY), hi(-INFINITY);
      for (const InstanceBounds& b : members) {
        if (!(b.flags & kValid)) continue;
        lo = glm::min(lo, b.centre - b.radius);
        hi = glm::max(hi, b.centre + b.radius);
      }
      entry.centre = lo.x <= hi.x ? 0.5f * (lo + hi) : glm::vec3(0.0f);
      ShownFrom* const shown_from = shown_from_.data() + entry.first;
      float radius = 0.0f, shown_all = 0.0f;
      for (uint32_t k = 0; k < entry.count; ++k) {
        const InstanceBounds& b = members[k];
        shown_from[k].instance = entry.first + k;
        if (!(b.flags & kValid)) continue;  // never shown: the choice skips it too
        ++entry.valid;
        radius = std::max(radius, glm::length(b.centre - entry.centre) + b.radius);
        shown_from[k].from = float(instance_forms::shownFrom(b, thresholds.thin_px,
                                                             thresholds.min_thin_px,
                                                             thresholds.min_feature_px) *
                                   kLower);
        shown_all = std::max(shown_all, shown_from[k].from);
      }
      entry.radius = radius * float(kUpper) + 1e-6f;
      entry.shown_all = shown_all;
      std::sort(shown_from, shown_from + entry.count,
                [](const ShownFrom& a, const ShownFrom& b) { return a.from < b.from; });
    }
  });
  thresholds_ = thresholds;
  built_ = true;
}

bool InstanceScaleIndex::select(uint32_t cluster, const glm::vec3& anchor_eye, double pixel_scale,
                                double near_m, std::vector<uint32_t>& out,
                                uint32_t& skipped) const {
  if (cluster >= clusters_.size()) return false;
  const ClusterEntry& entry = clusters_[cluster];
  if (entry.count == 0) return false;
  // No instance's nearest point is nearer than distance - radius: none is seen at a larger scale.
  const double distance = glm::length(anchor_eye + entry.centre);
  const double scale_max = pixel_scale / std::max(distance - double(entry.radius), near_m);
  if (scale_max >= double(entry.shown_all)) return false;
  out.clear();
  // Those shown from a scale at most scale_max: the list ends at its first entry above it.
  const ShownFrom* const shown_from = shown_from_.data() + entry.first;
  for (uint32_t k = 0; k < entry.count && double(shown_from[k].from) <= scale_max; ++k)
    out.push_back(shown_from[k].instance);
  std::sort(out.begin(), out.end());  // instance order, as the choice visits them
  skipped = entry.valid - uint32_t(out.size());
  return true;
}

}  // namespace tw
