// The scale from which a parametric instance shows (shownFrom) against the choice it is
// derived from (the small-feature test and chooseForm), and InstanceScaleIndex against testing
// every instance: nothing the choice would draw may be left out, and little else kept in.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "package_format.h"
#include "parametrics/parametric_instance_forms.h"
#include "parametrics/parametric_instance_scales.h"

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

TEST(ShownFrom, AgreesWithTheChoiceAtEveryScale) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> log_scale(-3.0, 4.0);
  int shown = 0, hidden = 0, points = 0;
  for (int n = 0; n < 20000; ++n) {
    const InstanceBounds b = randomBounds(rng);
    const double from = shownFrom(b, kThinPx, kMinThinPx, kMinFeaturePx);
    for (int j = 0; j < 20; ++j) {
      const double k = std::pow(10.0, log_scale(rng));
      const bool kept = chosen(b, k);
      // Away from the threshold (float rounding there), the choice and the scale agree.
      if (std::abs(k / from - 1.0) < 1e-4) continue;
      EXPECT_EQ(kept, k >= from) << "type " << int(b.type) << " size " << b.size[0] << " "
                                 << b.size[1] << " " << b.size[2] << " k " << k;
      shown += kept;
      hidden += !kept;
      const float metres_per_px = static_cast<float>(1.0 / k);
      points += kept && chooseForm(b, metres_per_px, float(kThinPx) * metres_per_px,
                                   float(kMinThinPx) * metres_per_px).shape == Shape::Point;
    }
  }
  // Every case was met: shown, hidden, and shown as a point.
  EXPECT_GT(shown, 10000);
  EXPECT_GT(hidden, 10000);
  EXPECT_GT(points, 1000);
}

// Whatever shows at a scale shows at every larger one: nearer never hides what farther drew.
// (Points used to be judged by their largest size and ribbons by their second: a rail post 1 m
// long and 5 cm thick was a pixel from 1.7 m a pixel and nothing from 1 m a pixel to 12 cm.)
TEST(ShownFrom, WhatShowsAtOneScaleShowsAtEveryLargerOne) {
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> log_scale(-3.0, 4.0);
  int checked = 0;
  for (int n = 0; n < 20000; ++n) {
    const InstanceBounds b = randomBounds(rng);
    const double k = std::pow(10.0, log_scale(rng));
    if (!chosen(b, k)) continue;
    for (double larger : {1.01, 1.5, 3.0, 10.0, 100.0}) {
      EXPECT_TRUE(chosen(b, k * larger)) << "type " << int(b.type) << " size " << b.size[0]
                                         << " " << b.size[1] << " " << b.size[2] << " k " << k
                                         << " then " << k * larger;
      ++checked;
    }
  }
  EXPECT_GT(checked, 20000);
}

// Thin in all three directions: a point only when its second largest size shows.
TEST(ShownFrom, APointStandsForItsSecondLargestSize) {
  auto box = [](float x, float y, float z) {
    InstanceBounds b;
    b.flags = kValid;
    b.type = uint8_t(pkg::PrimitiveType::Box);
    b.size = {0.5f * x, 0.5f * y, 0.5f * z};
    b.radius = 0.5f * std::sqrt(x * x + y * y + z * z);
    return b;
  };
  auto tube = [](float diameter, float length) {
    InstanceBounds b;
    b.flags = kValid;
    b.type = uint8_t(pkg::PrimitiveType::Cylinder);
    b.size = {0.5f * diameter, length, 0.0f};
    b.radius = 0.5f * std::sqrt(diameter * diameter + length * length);
    return b;
  };
  auto form = [](const InstanceBounds& b, double k) {
    const float metres_per_px = static_cast<float>(1.0 / k);
    return chooseForm(b, metres_per_px, float(kThinPx) * metres_per_px,
                      float(kMinThinPx) * metres_per_px).shape;
  };
  // Seen at 0.8 px a metre (a far view of a large plant): every one of them is under a pixel.
  const double k = 0.8;
  EXPECT_EQ(form(box(1.2f, 0.05f, 0.05f), k), Shape::None);   // a rail post: 0.04 px thick
  EXPECT_EQ(form(box(1.2f, 1.0f, 0.03f), k), Shape::Point);   // a grating panel: 0.96 x 0.8 px
  EXPECT_EQ(form(tube(1.0f, 0.05f), k), Shape::Point);        // a flange seen face on: 0.8 px
  EXPECT_EQ(form(tube(0.05f, 1.2f), k), Shape::None);         // a pipe stub: 0.04 px thick
  EXPECT_FALSE(chosen(box(1.2f, 0.05f, 0.05f), k));
  EXPECT_TRUE(chosen(box(1.2f, 1.0f, 0.03f), k));
  // Each shows from the scale at which its second largest size is min_thin_px.
  EXPECT_NEAR(shownFrom(box(1.2f, 0.05f, 0.05f), kThinPx, kMinThinPx, 0.0), kMinThinPx / 0.05,
              1e-4);
  EXPECT_NEAR(shownFrom(tube(1.0f, 0.05f), kThinPx, kMinThinPx, 0.0), kMinThinPx / 1.0, 1e-6);
}

TEST(ShownFrom, InvalidInstancesNeverShowAndZeroSizedOnesFollowTheFeatureTest) {
  InstanceBounds invalid;
  EXPECT_TRUE(std::isinf(shownFrom(invalid, kThinPx, kMinThinPx, kMinFeaturePx)));
  InstanceBounds flat;  // a box of zero thickness both ways across: a ribbon of zero width
  flat.flags = kValid;
  flat.type = uint8_t(pkg::PrimitiveType::Box);
  flat.size = {2.0f, 0.0f, 0.0f};
  flat.radius = 2.0f;
  EXPECT_DOUBLE_EQ(shownFrom(flat, kThinPx, kMinThinPx, kMinFeaturePx), kMinFeaturePx / 4.0);
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
