// PvsMapping on a small multi-level package, against an independent brute-force reading of its
// contract (occlusion/pvs_mapping.h): the whole front makes everything visible, the empty set only
// the parametric clusters, one front cluster its own descendants and ancestors and nothing far
// away, and random sets (with ids off the front) at every level agree with the brute force.
#include <gtest/gtest.h>

#include <algorithm>
#include <functional>
#include <random>

#include "dag_front.h"
#include "package_view.h"
#include "preprocess_driver.h"
#include "pvs_mapping.h"
#include "test_support.h"
#include "tws_writer.h"

namespace tw {
namespace {

namespace fs = std::filesystem;

bool isMesh(const pkg::ClusterRecord& r) {
  return r.kind == static_cast<uint8_t>(pkg::ClusterKind::Mesh);
}

// Nine finely subdivided boxes in a row (so the DAG has several levels and clusters far apart)
// and a few pipes (parametric clusters), preprocessed once per program.
const PackageView& package() {
  static const PackageView view = [] {
    const fs::path dir = test::processScratchDir("pvs-mapping");
    const fs::path scene = dir / "scene.tws";
    TwsWriter writer(scene);
    writer.onLayer(0, {"structure", 0xff336699u});
    uint32_t id = 0;
    for (int i = 0; i < 9; ++i) {
      SceneObject object;
      object.info.id = id++;
      object.info.name = "block " + std::to_string(i);
      object.info.transform.origin = {i * 10.0, 0.0, 2.0};
      object.geometry = test::subdividedBox(glm::vec3(2.0f, 2.0f, 2.0f), 16);
      writer.onObject(object);
    }
    for (int i = 0; i < 3; ++i) {
      SceneObject pipe;
      pipe.info.id = id++;
      pipe.info.name = "pipe " + std::to_string(i);
      pipe.info.transform.origin = {i * 30.0, 5.0, 0.0};
      pipe.geometry = Primitive{Cylinder{0.2f, 6.0f, true}};
      writer.onObject(pipe);
    }
    writer.finish();
    PreprocessOptions options;
    options.inputs = {scene};
    options.output = dir / "pvs.twk";
    options.cluster_size = 128;
    options.visibility = false;
    runPreprocess(options);
    return PackageView::open(options.output);
  }();
  return view;
}

// The contract read literally, one cluster at a time with recursion (no sweeps, no CSR).
class BruteForce {
 public:
  BruteForce(const PackageView& view, uint32_t level, const std::vector<uint32_t>& set)
      : view_(view), level_(level), memo_(view.clusters().size(), -1) {
    for (uint32_t id : set)
      if (id < view.clusters().size() && inFront(id)) in_set_.push_back(id);
    std::sort(in_set_.begin(), in_set_.end());
  }
  bool inFront(uint32_t c) const {
    const auto& r = view_.clusters()[c];
    return isMesh(r) && r.level <= level_ &&
           (r.parent_group == pkg::kNone || view_.groups()[r.parent_group].level >= level_);
  }
  bool visible(uint32_t c) {
    if (memo_[c] >= 0) return memo_[c];
    const auto& r = view_.clusters()[c];
    bool v = false;
    if (!isMesh(r)) {
      v = true;
    } else if (inFront(c)) {
      v = std::binary_search(in_set_.begin(), in_set_.end(), c);
    } else if (r.level > level_) {  // above: any child of the producing group
      for (uint32_t k = 0; k < view_.clusters().size() && !v; ++k)
        if (view_.clusters()[k].parent_group == r.group) v = visible(k);
    } else {  // below: any cluster the parent group produced
      const auto& g = view_.groups()[r.parent_group];
      for (uint32_t k = g.first_cluster; k < g.first_cluster + g.cluster_count && !v; ++k)
        v = visible(k);
    }
    memo_[c] = v;
    return v;
  }
  std::vector<uint8_t> all() {
    std::vector<uint8_t> out(view_.clusters().size());
    for (uint32_t c = 0; c < out.size(); ++c) out[c] = visible(c);
    return out;
  }

 private:
  const PackageView& view_;
  uint32_t level_;
  std::vector<uint32_t> in_set_;
  std::vector<int> memo_;
};

// Clusters that only groups which produced nothing lead to from the front: no front cluster
// stands for them, so no visible set can reach them (pvs_mapping.h: "any cluster its parent
// group produced").
std::vector<uint8_t> unreachable(const PackageView& view, uint32_t level) {
  const DagFront front = dagFront(view, level);
  BruteForce all(view, level, front.clusters);
  std::vector<uint8_t> out = all.all();
  for (uint8_t& v : out) v = !v;
  return out;
}

TEST(PvsMapping, PackageHasSeveralLevelsAndParametricClusters) {
  const PackageView& view = package();
  EXPECT_GE(view.header().level_count, 3u);
  uint32_t parametric = 0;
  for (const auto& c : view.clusters()) parametric += !isMesh(c);
  EXPECT_GT(parametric, 0u);
}

TEST(PvsMapping, WholeFrontMakesEveryClusterVisible) {
  const PackageView& view = package();
  std::vector<uint8_t> flags;
  for (uint32_t level = 0; level < view.header().level_count; ++level) {
    const DagFront front = dagFront(view, level);
    ASSERT_FALSE(front.clusters.empty());
    PvsMapping mapping(view, level, {});
    mapping.flags(front.clusters, flags);
    ASSERT_EQ(flags.size(), view.clusters().size());
    const std::vector<uint8_t> dropped = unreachable(view, level);
    uint32_t flagged = 0;
    for (uint32_t c = 0; c < flags.size(); ++c) {
      EXPECT_EQ(flags[c], dropped[c] ? 0 : 1) << "level " << level << " cluster " << c;
      flagged += flags[c];
    }
    // Nearly everything: only parts dropped below the front can be missing.
    EXPECT_GE(flagged, flags.size() * 9 / 10) << "level " << level;
  }
}

TEST(PvsMapping, EmptySetLeavesOnlyParametricClusters) {
  const PackageView& view = package();
  std::vector<uint8_t> flags;
  for (uint32_t level = 0; level < view.header().level_count; ++level) {
    PvsMapping mapping(view, level, {});
    mapping.flags({}, flags);
    for (uint32_t c = 0; c < flags.size(); ++c)
      EXPECT_EQ(flags[c], isMesh(view.clusters()[c]) ? 0 : 1) << "level " << level << " " << c;
  }
}

// Every cluster reachable from `c` by following `step` (children of producing groups, or
// produced clusters of parent groups), `c` excluded.
std::vector<uint32_t> closure(uint32_t c, const std::function<std::vector<uint32_t>(uint32_t)>& step) {
  std::vector<uint32_t> out, stack = {c};
  std::vector<bool> seen(package().clusters().size());
  while (!stack.empty()) {
    uint32_t x = stack.back();
    stack.pop_back();
    for (uint32_t y : step(x))
      if (!seen[y]) {
        seen[y] = true;
        out.push_back(y);
        stack.push_back(y);
      }
  }
  return out;
}

TEST(PvsMapping, OneFrontClusterShowsItsDescendantsAndAncestorsOnly) {
  const PackageView& view = package();
  const auto clusters = view.clusters();
  const auto groups = view.groups();
  const uint32_t level = 1;
  const DagFront front = dagFront(view, level);
  // A front cluster with both a producing group (finer clusters below) and a parent group
  // (coarser clusters above).
  uint32_t chosen = pkg::kNone;
  for (uint32_t c : front.clusters)
    if (clusters[c].group != pkg::kNone && clusters[c].parent_group != pkg::kNone) {
      chosen = c;
      break;
    }
  ASSERT_NE(chosen, pkg::kNone);
  std::vector<uint8_t> flags;
  PvsMapping mapping(view, level, {});
  mapping.flags(std::vector<uint32_t>{chosen}, flags);
  EXPECT_EQ(flags[chosen], 1);

  // Below: the children of its producing group, and theirs, down to level 0.
  auto childrenOfGroupOf = [&](uint32_t c) {
    std::vector<uint32_t> out;
    if (clusters[c].group == pkg::kNone || clusters[c].level > level) return out;
    for (uint32_t k = 0; k < clusters.size(); ++k)
      if (clusters[k].parent_group == clusters[c].group) out.push_back(k);
    return out;
  };
  const std::vector<uint32_t> below = closure(chosen, childrenOfGroupOf);
  ASSERT_FALSE(below.empty());
  for (uint32_t c : below) {
    EXPECT_LT(clusters[c].level, clusters[chosen].level);
    EXPECT_EQ(flags[c], 1) << "descendant " << c;
  }
  // Above: what its parent group produced, and what their parent groups produced.
  auto producedByParentOf = [&](uint32_t c) {
    std::vector<uint32_t> out;
    if (clusters[c].parent_group == pkg::kNone) return out;
    const auto& g = groups[clusters[c].parent_group];
    for (uint32_t k = g.first_cluster; k < g.first_cluster + g.cluster_count; ++k) out.push_back(k);
    return out;
  };
  const std::vector<uint32_t> above = closure(chosen, producedByParentOf);
  ASSERT_FALSE(above.empty());
  for (uint32_t c : above) {
    EXPECT_GT(clusters[c].level, level);
    EXPECT_EQ(flags[c], 1) << "ancestor " << c;
  }

  // The front cluster farthest from it is not visible, nor is anything below it.
  auto centre = [&](uint32_t c) {
    return glm::vec3(clusters[c].center[0], clusters[c].center[1], clusters[c].center[2]);
  };
  uint32_t far = chosen;
  for (uint32_t c : front.clusters)
    if (glm::distance(centre(c), centre(chosen)) > glm::distance(centre(far), centre(chosen)))
      far = c;
  ASSERT_GT(glm::distance(centre(far), centre(chosen)), 40.0f);
  EXPECT_EQ(flags[far], 0);
  for (uint32_t c : closure(far, childrenOfGroupOf)) EXPECT_EQ(flags[c], 0) << "far descendant " << c;

  // Exactly what the brute force says, and few clusters overall.
  EXPECT_EQ(flags, BruteForce(view, level, {chosen}).all());
  uint32_t mesh_flagged = 0, mesh = 0;
  for (uint32_t c = 0; c < clusters.size(); ++c)
    if (isMesh(clusters[c])) {
      ++mesh;
      mesh_flagged += flags[c];
    }
  EXPECT_LT(mesh_flagged, mesh / 4);
}

TEST(PvsMapping, RandomSetsAgreeWithBruteForceAtEveryLevel) {
  const PackageView& view = package();
  std::mt19937 rng(7);
  std::vector<uint8_t> flags;
  for (uint32_t level = 0; level < view.header().level_count; ++level) {
    PvsMapping mapping(view, level, {});  // one mapping, reused: no state may leak between calls
    const DagFront front = dagFront(view, level);
    for (int trial = 0; trial < 6; ++trial) {
      std::vector<uint32_t> set;
      for (uint32_t c : front.clusters)
        if (rng() % 4 == 0) set.push_back(c);
      // Ids the mapping must ignore: off the front (any level), parametric, out of range.
      for (int k = 0; k < 5; ++k) set.push_back(rng() % view.clusters().size());
      set.push_back(uint32_t(view.clusters().size()));
      set.push_back(0xfffffff0u);
      std::shuffle(set.begin(), set.end(), rng);
      mapping.flags(set, flags);
      EXPECT_EQ(flags, BruteForce(view, level, set).all()) << "level " << level << " trial "
                                                           << trial;
    }
  }
}

}  // namespace
}  // namespace tw
