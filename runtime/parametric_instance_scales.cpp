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
using instance_forms::ShownScales;

namespace {

// The choice works in float; the index keeps a margin so rounding never leaves out an instance
// the choice would draw.
constexpr double kLower = 1.0 - 1e-3, kUpper = 1.0 + 1e-3;

}  // namespace

void InstanceScaleIndex::build(std::span<const pkg::ClusterRecord> clusters,
                               std::span<const InstanceBounds> bounds,
                               const Thresholds& thresholds) {
  clusters_.assign(clusters.size(), ClusterEntry{});
  shown_from_.assign(bounds.size(), ShownFrom{INFINITY, 0});
  gaps_.assign(bounds.size(), Gap{0.0f, 0.0f, 0.0f, 0});
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
      Gap* const gaps = gaps_.data() + entry.first;
      float radius = 0.0f, shown_all = 0.0f;
      for (uint32_t k = 0; k < entry.count; ++k) {
        const InstanceBounds& b = members[k];
        shown_from[k].instance = entry.first + k;
        if (!(b.flags & kValid)) continue;  // never shown: the choice skips it too
        ++entry.valid;
        radius = std::max(radius, glm::length(b.centre - entry.centre) + b.radius);
        const ShownScales s = instance_forms::shownScales(b, thresholds.thin_px,
                                                          thresholds.min_thin_px,
                                                          thresholds.min_feature_px);
        shown_from[k].from = float(s.from * kLower);
        if (s.gap_from < s.gap_to)
          gaps[entry.gap_count++] = {float(s.gap_from * kLower), float(s.gap_to * kUpper), 0.0f,
                                     entry.first + k};
        shown_all = std::max(shown_all, shown_from[k].from);
      }
      entry.radius = radius * float(kUpper) + 1e-6f;
      entry.shown_all = shown_all;
      std::sort(shown_from, shown_from + entry.count,
                [](const ShownFrom& a, const ShownFrom& b) { return a.from < b.from; });
      std::sort(gaps, gaps + entry.gap_count,
                [](const Gap& a, const Gap& b) { return a.gap_from < b.gap_from; });
      for (uint32_t k = entry.gap_count; k-- > 0;) {
        gaps[k].ahead_to = gaps[k].gap_to;
        for (uint32_t n = k + 1; n < std::min(k + kGapSkip, entry.gap_count); ++n)
          gaps[k].ahead_to = std::max(gaps[k].ahead_to, gaps[n].gap_to);
      }
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
  // Every instance's nearest point lies between these distances, so its scale between these.
  const double distance = glm::length(anchor_eye + entry.centre);
  const double scale_max = pixel_scale / std::max(distance - double(entry.radius), near_m);
  if (scale_max >= double(entry.shown_all)) return false;
  const double scale_min = pixel_scale / std::max(distance + double(entry.radius), near_m);
  out.clear();
  // Those shown from a scale at most scale_max, then those whose gap reaches into
  // [scale_min, scale_max]; each list ends at its first entry that starts above scale_max, and
  // the gaps pass by kGapSkip those that all end at or below scale_min.
  const ShownFrom* const shown_from = shown_from_.data() + entry.first;
  for (uint32_t k = 0; k < entry.count && double(shown_from[k].from) <= scale_max; ++k)
    out.push_back(shown_from[k].instance);
  const size_t shown = out.size();
  const Gap* const gaps = gaps_.data() + entry.first;
  for (uint32_t k = 0; k < entry.gap_count && double(gaps[k].gap_from) <= scale_max;) {
    if (double(gaps[k].ahead_to) <= scale_min) {
      k += kGapSkip;
      continue;
    }
    if (double(gaps[k].gap_to) > scale_min) out.push_back(gaps[k].instance);
    ++k;
  }
  // Instance order, as the choice visits them; an instance in both lists once.
  std::sort(out.begin(), out.end());
  if (out.size() != shown) out.erase(std::unique(out.begin(), out.end()), out.end());
  skipped = entry.valid - uint32_t(out.size());
  return true;
}

}  // namespace tw
