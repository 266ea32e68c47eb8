// Per parametric instance, the scales at which it can show at all (shownScales), and per
// cluster a sphere around its instances, so that a far view tests one by one only the instances
// its distance lets show.
//
// Why: from outside the 50M plant every one of its 9,421 parametric clusters is in view, and the
// per-instance choice tested all 602,735 instances each frame to draw about 47,000 (the 5M
// plant: 60,017 to draw about 19,000). Each test reads the instance's 68-byte bounds. Here a
// cluster whose every instance lies at scales (pixels per metre) below k_max and above k_min
// tests only those that show somewhere in [k_min, k_max]: about 57,000 a frame at 50M.
// Conservative: an instance left out here is one the choice would leave out, and the others are
// still tested one by one in instance order, so the frame is the same.
//
// A cluster keeps its instances sorted twice: by the scale from which each shows, and those with
// a gap by the scale where the gap starts, each with the largest end of the next few gaps. A far
// view reads about the entries that can show, not one per instance: reading the 50M plant's
// 602,735 a frame was the runtime's costliest loop.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "package_format.h"
#include "parametric_instance_forms.h"

namespace tw {

class InstanceScaleIndex {
 public:
  // The thresholds (InstanceLodView's) the index was built for.
  struct Thresholds {
    double thin_px = 0.0, min_thin_px = 0.0, min_feature_px = 0.0;
    bool operator==(const Thresholds&) const = default;
  };

  // Takes the scales of every instance of every parametric cluster of `clusters` (instance
  // ranges already checked against `bounds`, whose index is the instance's) for `thresholds`;
  // on TBB.
  void build(std::span<const pkg::ClusterRecord> clusters,
             std::span<const instance_forms::InstanceBounds> bounds, const Thresholds& thresholds);
  bool builtFor(const Thresholds& thresholds) const { return built_ && thresholds_ == thresholds; }

  // The instances of cluster `cluster` that may show with its anchor at `anchor_eye` from the
  // eye, pixel_scale and near_m as the choice takes them: false when every valid instance may
  // (visit them all); otherwise `out` holds those that may, in instance order, and `skipped` the
  // valid ones left out.
  bool select(uint32_t cluster, const glm::vec3& anchor_eye, double pixel_scale, double near_m,
              std::vector<uint32_t>& out, uint32_t& skipped) const;

 private:
  struct ClusterEntry {
    glm::vec3 centre{0.0f};  // of a sphere holding its valid instances' spheres, anchor-relative
    float radius = 0.0f;
    float shown_all = 0.0f;  // the scale from which every valid instance may show
    uint32_t first = 0, count = 0;  // its instances; its entries in shown_from_ and gaps_
    uint32_t valid = 0;
    uint32_t gap_count = 0;  // its entries in gaps_
  };
  // An instance's ShownScales, widened by a margin for the choice's float arithmetic. Not valid:
  // never shown (from infinite, no gap).
  struct ShownFrom {
    float from;
    uint32_t instance;
  };
  struct Gap {
    float gap_from, gap_to;
    float ahead_to;  // the largest gap_to of this entry and the kGapSkip - 1 after it (cluster's)
    uint32_t instance;
  };
  // A gap of a tube's or a box's is [mt / L, t / L) for its length L (shownScales), so by
  // ascending gap_from the gaps also end nearly in order: the ones a far view is already past
  // come first, and are passed kGapSkip at a time.
  static constexpr uint32_t kGapSkip = 8;
  std::vector<ClusterEntry> clusters_;  // by cluster index; count 0 for the others
  // A cluster's [first, first + count): its instances by ascending `from`.
  std::vector<ShownFrom> shown_from_;
  // A cluster's [first, first + gap_count): its instances with a gap, by ascending `gap_from`.
  std::vector<Gap> gaps_;
  Thresholds thresholds_;
  bool built_ = false;
};

}  // namespace tw
