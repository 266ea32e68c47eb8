// The scales at which a parametric instance shows (shownScales) against the choice they are
// derived from (the small-feature test and chooseForm), and InstanceScaleIndex against testing
// every instance: nothing the choice would draw may be left out, and little else kept in.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "package_format.h"
#include "parametric_instance_forms.h"
#include "parametric_instance_scales.h"

namespace tw {
namespace {

using namespace instance_forms;

constexpr double kThinPx = 1.0, kMinThinPx = 0.4, kMinFeaturePx = 1.0;

// What the per-instance choice decides at scale k (pixels per metre at the nearest point), in its
// own arithmetic (ParametricInstanceMeshes: the feature test in double, the form in float).
bool chosen(const InstanceBounds& b, double k) {
  if (2.0 * double(b.radius) * k < kMinFeaturePx) return false;
  const float metres_per_px = static_cast<float>(1.0 / k);
  const Form f = chooseForm(b, 1.0f * metres_per_px, float(kThinPx) * metres_per_px,
                            float(kMinThinPx) * metres_per_px);
  return f.shape != Shape::None;
}

// Random instances of every type, sizes from millimetres to tens of metres.
InstanceBounds randomBounds(std::mt19937& rng) {
  std::uniform_int_distribution<int> type(0, 6);
  std::uniform_real_distribution<float> log_size(-3.0f, 1.5f);
  auto size = [&] { return std::pow(10.0f, log_size(rng)); };
  InstanceBounds b;
  b.type = uint8_t(type(rng));
  b.flags = kValid;
  b.size = {size(), size(), size()};
  if (surfaceOf(b.type) == Shape::Torus) {
    b.size[1] = std::min(b.size[1], b.size[0]);
    b.size[2] = 1.5708f;
  }
  b.radius = std::sqrt(b.size[0] * b.size[0] + b.size[1] * b.size[1] + b.size[2] * b.size[2]);
  return b;
}

bool within(const ShownScales& s, double k) {
  return k >= s.from || (s.gap_from <= k && k < s.gap_to);
}

TEST(ShownScales, AgreeWithTheChoiceAtEveryScale) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> log_scale(-3.0, 4.0);
  int shown = 0, hidden = 0, gaps = 0, in_gap = 0;
  for (int n = 0; n < 20000; ++n) {
    const InstanceBounds b = randomBounds(rng);
    const ShownScales s = shownScales(b, kThinPx, kMinThinPx, kMinFeaturePx);
    gaps += s.gap_from < s.gap_to;
    for (int j = 0; j < 20; ++j) {
      const double k = std::pow(10.0, log_scale(rng));
      const bool kept = chosen(b, k);
      // Away from the range ends (float rounding there), the choice and the scales agree.
      const bool clear = within(s, k * (1.0 + 1e-4)) == within(s, k * (1.0 - 1e-4));
      if (!clear) continue;
      EXPECT_EQ(kept, within(s, k)) << "type " << int(b.type) << " size " << b.size[0] << " "
                                    << b.size[1] << " " << b.size[2] << " k " << k;
      shown += kept;
      hidden += !kept;
      in_gap += kept && k < s.from;
    }
  }
  // Every case was met: shown and hidden, and points below a thin thing's `from`.
  EXPECT_GT(shown, 10000);
  EXPECT_GT(hidden, 10000);
  EXPECT_GT(gaps, 1000);
  EXPECT_GT(in_gap, 100);
}

TEST(ShownScales, InvalidInstancesNeverShowAndZeroSizedOnesFollowTheFeatureTest) {
  InstanceBounds invalid;
  EXPECT_TRUE(std::isinf(shownScales(invalid, kThinPx, kMinThinPx, kMinFeaturePx).from));
  InstanceBounds flat;  // a box of zero thickness both ways across: a ribbon of zero width
  flat.flags = kValid;
  flat.type = uint8_t(pkg::PrimitiveType::Box);
  flat.size = {2.0f, 0.0f, 0.0f};
  flat.radius = 2.0f;
  const ShownScales s = shownScales(flat, kThinPx, kMinThinPx, kMinFeaturePx);
  EXPECT_DOUBLE_EQ(s.from, kMinFeaturePx / 4.0);
  EXPECT_TRUE(chosen(flat, 0.3));
  EXPECT_FALSE(chosen(flat, 0.2));
}

// Clusters of random instances seen from random eyes: select() keeps every instance the choice
// draws from there (with its own distance), lists each once in instance order, and leaves most
// of the others out when the cluster is far.
TEST(InstanceScaleIndex, KeepsEveryInstanceTheChoiceDrawsAndLeavesOutTheRest) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> offset(-20.0f, 20.0f);
  std::vector<InstanceBounds> bounds;
  std::vector<pkg::ClusterRecord> clusters(60);
  for (size_t c = 0; c < clusters.size(); ++c) {
    pkg::ClusterRecord& r = clusters[c];
    r.kind = uint8_t(c % 5 == 4 ? pkg::ClusterKind::Mesh : pkg::ClusterKind::Parametric);
    if (r.kind == uint8_t(pkg::ClusterKind::Mesh)) continue;
    r.instance_first = uint32_t(bounds.size());
    r.instance_count = 64;
    for (int k = 0; k < 64; ++k) {
      InstanceBounds b = randomBounds(rng);
      b.centre = glm::vec3(offset(rng), offset(rng), 0.2f * offset(rng));
      if (k % 17 == 3) b.flags = 0;  // not drawable: skipped by the choice and the index
      bounds.push_back(b);
    }
  }
  InstanceScaleIndex index;
  const InstanceScaleIndex::Thresholds thresholds{kThinPx, kMinThinPx, kMinFeaturePx};
  index.build(clusters, bounds, thresholds);
  EXPECT_TRUE(index.builtFor(thresholds));
  EXPECT_FALSE(index.builtFor({kThinPx, 0.5, kMinFeaturePx}));

  const double pixel_scale = 720.0 / (2.0 * std::tan(0.5 * 1.0)), near_m = 0.05;
  std::uniform_real_distribution<double> log_distance(0.0, 3.5);
  std::vector<uint32_t> selected;
  uint64_t drawn = 0, visited = 0, valid_total = 0, selections = 0;
  for (int n = 0; n < 400; ++n) {
    const double distance = std::pow(10.0, log_distance(rng));
    const glm::vec3 anchor_eye = glm::normalize(glm::vec3(offset(rng), offset(rng), offset(rng))) *
                                 float(distance);
    for (uint32_t c = 0; c < clusters.size(); ++c) {
      const pkg::ClusterRecord& r = clusters[c];
      uint32_t skipped = 0;
      const bool some = index.select(c, anchor_eye, pixel_scale, near_m, selected, skipped);
      if (r.kind == uint8_t(pkg::ClusterKind::Mesh)) {
        EXPECT_FALSE(some);
        continue;
      }
      uint32_t valid = 0;
      for (uint32_t i = r.instance_first; i < r.instance_first + r.instance_count; ++i) {
        const InstanceBounds& b = bounds[i];
        if (!(b.flags & kValid)) continue;
        ++valid;
        const glm::vec3 centre = anchor_eye + b.centre;
        const double k = pixel_scale / std::max(double(glm::length(centre)) - b.radius, near_m);
        if (!chosen(b, k)) continue;
        ++drawn;
        if (some) {
          EXPECT_TRUE(std::binary_search(selected.begin(), selected.end(), i))
              << "cluster " << c << " instance " << i << " at " << distance << " m";
        }
      }
      valid_total += valid;
      if (!some) {
        visited += valid;
        continue;
      }
      ++selections;
      EXPECT_TRUE(std::is_sorted(selected.begin(), selected.end()));
      EXPECT_EQ(std::adjacent_find(selected.begin(), selected.end()), selected.end());
      for (uint32_t i : selected) {
        EXPECT_GE(i, r.instance_first);
        EXPECT_LT(i, r.instance_first + r.instance_count);
        EXPECT_TRUE(bounds[i].flags & kValid);
      }
      EXPECT_EQ(skipped + selected.size(), valid);
      visited += selected.size();
    }
  }
  EXPECT_GT(selections, 1000u);
  EXPECT_GT(drawn, 10000u);
  // Of the instances not drawn, most are never visited; visits come close to what is drawn.
  EXPECT_LT(visited - drawn, (valid_total - drawn) / 2);
  EXPECT_LT(double(visited), 1.25 * double(drawn));
}

}  // namespace
}  // namespace tw
