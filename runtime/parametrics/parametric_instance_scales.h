// Per parametric instance, the scale from which it can show at all (shownFrom), and per
// cluster a sphere around its instances, so that a far view tests one by one only the instances
// its distance lets show.
//
// Why: from outside the 50M plant every one of its 9,421 parametric clusters is in view, and the
// per-instance choice tested all 602,735 instances each frame to draw about 47,000 (the 5M
// plant: 60,017 to draw about 19,000). Each test reads the instance's 68-byte bounds. Here a
// cluster whose every instance lies at scales (pixels per metre) below k_max and above k_min
// tests only those that show from a scale at most k_max.
// Conservative: an instance left out here is one the choice would leave out, and the others are
// still tested one by one in instance order, so the frame is the same.
//
// A cluster keeps its instances sorted by the scale from which each shows, so a far view reads
// about the entries that can show, not one per instance: reading the 50M plant's 602,735 a frame
// was the runtime's costliest loop.
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
    uint32_t first = 0, count = 0;  // its instances; its entries in shown_from_
    uint32_t valid = 0;
  };
  // An instance's shownFrom, lowered by a margin for the choice's float arithmetic. Not valid:
  // never shown (infinite).
  struct ShownFrom {
    float from;
    uint32_t instance;
  };
  std::vector<ClusterEntry> clusters_;  // by cluster index; count 0 for the others
  // A cluster's [first, first + count): its instances by ascending `from`.
  std::vector<ShownFrom> shown_from_;
  Thresholds thresholds_;
  bool built_ = false;
};

}  // namespace tw
