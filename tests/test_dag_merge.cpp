// Tests for brick DAGs and their merge: seams locked with lock_open_boundaries stay identical at
// every level (any cut of one brick meets any cut of its neighbour, on a sphere and on CAD-like
// boxes, where the unlocked build cracks), open components stay out of the sloppy/drop
// fallbacks, merged DAGs give watertight cuts at every threshold with monotone errors, shrinking
// levels and a small root, brick roots of different depths merge under the relaxed level rule
// (the package view accepts it and decoded cuts stay closed), merging is deterministic, and the
// real bunny keeps exactly its own boundary when built as bricks.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <map>
#include <random>
#include <unordered_map>
#include <unordered_set>

#include "cluster_dag.h"
#include "dag_merge.h"
#include "obj_reader.h"
#include "package_assembly.h"
#include "package_view.h"
#include "package_writer.h"
#include "test_support.h"

namespace {

using tw::ClusterDag;
using tw::DagCluster;
using tw::DagInput;
using tw::DagOptions;

struct Mesh {
  std::vector<glm::vec3> positions;
  std::vector<uint32_t> indices;
  std::vector<uint32_t> ids;

  DagInput input() const { return {positions, indices, ids}; }
  size_t triangles() const { return indices.size() / 3; }
  glm::vec3 centroid(size_t t) const {
    return (positions[indices[3 * t]] + positions[indices[3 * t + 1]] +
            positions[indices[3 * t + 2]]) /
           3.0f;
  }
};

Mesh icosphere(int subdivisions, float radius = 1.0f) {
  const float t = (1.0f + std::sqrt(5.0f)) / 2.0f;
  Mesh m;
  m.positions = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                 {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  m.indices = {0, 11, 5, 0, 5,  1, 0, 1, 7, 0, 7,  10, 0, 10, 11, 1, 5, 9, 5, 11,
               4, 11, 10, 2, 10, 7, 6, 7, 1, 8, 3, 9, 4, 3, 4,  2, 3, 2, 6, 3,
               6, 8, 3, 8,  9, 4, 9, 5, 2, 4, 11, 6, 2, 10, 8, 6, 7, 9, 8, 1};
  for (int s = 0; s < subdivisions; ++s) {
    std::map<std::pair<uint32_t, uint32_t>, uint32_t> mid;
    auto midpoint = [&](uint32_t a, uint32_t b) {
      auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      m.positions.push_back(0.5f * (m.positions[a] + m.positions[b]));
      return mid[key] = uint32_t(m.positions.size() - 1);
    };
    std::vector<uint32_t> next;
    for (size_t i = 0; i < m.indices.size(); i += 3) {
      uint32_t a = m.indices[i], b = m.indices[i + 1], c = m.indices[i + 2];
      uint32_t ab = midpoint(a, b), bc = midpoint(b, c), ca = midpoint(c, a);
      next.insert(next.end(), {a, ab, ca, b, bc, ab, c, ca, bc, ab, bc, ca});
    }
    m.indices = std::move(next);
  }
  for (auto& p : m.positions) p = glm::normalize(p) * radius;
  m.ids.assign(m.triangles(), 0);
  return m;
}

Mesh loadObj(const std::filesystem::path& path) {
  tw::test::CollectingSink sink;
  tw::readObj(path, sink);
  Mesh m;
  glm::dvec3 origin(0.0);
  bool first = true;
  for (const auto& object : sink.objects) {
    const auto* mesh = std::get_if<tw::TriangleMesh>(&object.geometry);
    if (!mesh) continue;
    if (first) origin = object.info.transform.origin;
    first = false;
    uint32_t base = uint32_t(m.positions.size());
    for (const glm::vec3& p : mesh->positions)
      m.positions.push_back(glm::vec3(object.info.transform.apply(p) - origin));
    for (uint32_t i : mesh->indices) m.indices.push_back(base + i);
    for (size_t t = 0; t < mesh->triangleCount(); ++t) m.ids.push_back(0);
  }
  return m;
}

// The bricking step, done here: brick b gets the triangles whose centroid `brickOf` maps to b.
// Positions are shared (the DAG builder ignores unused vertices), exactly as a brick would carry
// them: bit-identical on both sides of a seam.
std::vector<Mesh> cutIntoBricks(const Mesh& m, size_t brick_count,
                                const std::function<size_t(glm::vec3)>& brickOf) {
  std::vector<Mesh> bricks(brick_count);
  for (Mesh& b : bricks) b.positions = m.positions;
  for (size_t t = 0; t < m.triangles(); ++t) {
    Mesh& b = bricks[brickOf(m.centroid(t))];
    b.indices.insert(b.indices.end(), m.indices.begin() + 3 * t, m.indices.begin() + 3 * t + 3);
    b.ids.push_back(m.ids[t]);
  }
  return bricks;
}

// Exact-position weld shared by every mesh it sees (-0 == +0).
class Welder {
 public:
  uint32_t id(const glm::vec3& p) {
    Key k{bits(p.x), bits(p.y), bits(p.z)};
    return map_.emplace(k, uint32_t(map_.size())).first->second;
  }

 private:
  struct Key {
    uint32_t x, y, z;
    bool operator==(const Key&) const = default;
  };
  struct Hash {
    size_t operator()(const Key& k) const {
      return (size_t(k.x) * 0x9E3779B97F4A7C15ull) ^ (size_t(k.y) * 0xC2B2AE3D27D4EB4Full) ^
             (size_t(k.z) * 0x165667B19E3779F9ull);
    }
  };
  static uint32_t bits(float f) {
    if (f == 0.0f) f = 0.0f;
    uint32_t u;
    std::memcpy(&u, &f, 4);
    return u;
  }
  std::unordered_map<Key, uint32_t, Hash> map_;
};

// Counts welded edge uses over the triangles it is fed; boundary() = edges used once.
class EdgeCounter {
 public:
  explicit EdgeCounter(Welder& welder) : welder_(welder) {}
  void add(glm::vec3 a, glm::vec3 b, glm::vec3 c) {
    uint32_t ia = welder_.id(a), ib = welder_.id(b), ic = welder_.id(c);
    if (ia == ib || ib == ic || ia == ic) return;
    ++counts_[key(ia, ib)];
    ++counts_[key(ib, ic)];
    ++counts_[key(ic, ia)];
  }
  void addCluster(const DagCluster& c) {
    for (size_t i = 0; i < c.indices.size(); i += 3)
      add(c.positions[c.indices[i]], c.positions[c.indices[i + 1]], c.positions[c.indices[i + 2]]);
  }
  void addCut(const ClusterDag& dag, const std::vector<uint32_t>& cut) {
    for (uint32_t c : cut) addCluster(dag.clusters[c]);
  }
  void addMesh(const Mesh& m) {
    for (size_t i = 0; i < m.indices.size(); i += 3)
      add(m.positions[m.indices[i]], m.positions[m.indices[i + 1]], m.positions[m.indices[i + 2]]);
  }
  uint32_t count(glm::vec3 a, glm::vec3 b) const {
    auto it = counts_.find(key(welder_.id(a), welder_.id(b)));
    return it == counts_.end() ? 0 : it->second;
  }
  std::unordered_set<uint64_t> boundary() const {
    std::unordered_set<uint64_t> out;
    for (const auto& [e, n] : counts_)
      if (n == 1) out.insert(e);
    return out;
  }
  // Welded vertices of edges not used exactly twice: where openings' outlines may run.
  std::unordered_set<uint32_t> rim() const {
    std::unordered_set<uint32_t> out;
    for (const auto& [e, n] : counts_)
      if (n != 2) out.insert({uint32_t(e >> 32), uint32_t(e)});
    return out;
  }

 private:
  static uint64_t key(uint32_t a, uint32_t b) {
    if (a > b) std::swap(a, b);
    return (uint64_t(a) << 32) | b;
  }
  Welder& welder_;
  std::unordered_map<uint64_t, uint32_t> counts_;
};

// Thresholds from 0 to past the root error, plus a few group errors exactly (the boundary case).
std::vector<float> thresholds(const ClusterDag& dag, int steps) {
  float top = 0.0f;
  for (const auto& c : dag.clusters) top = std::max(top, c.error);
  std::vector<float> taus;
  for (int i = 0; i < steps; ++i) taus.push_back(top * 1.2f * float(i) / float(steps - 1));
  for (size_t g = 0; g < dag.groups.size(); g += std::max<size_t>(1, dag.groups.size() / 6))
    taus.push_back(dag.groups[g].error);
  return taus;
}

std::vector<ClusterDag> buildBricks(const std::vector<Mesh>& bricks, const DagOptions& options) {
  std::vector<ClusterDag> dags;
  for (const Mesh& b : bricks) dags.push_back(tw::buildClusterDag(b.input(), options));
  return dags;
}

// The merged DAG's structure: monotone errors, level rule (child <= group level, produced =
// group level + 1), every cluster reachable as described, nested spheres, small root.
void expectMergedWellFormed(const ClusterDag& dag, uint64_t input_triangles,
                            const DagOptions& options) {
  ASSERT_FALSE(dag.clusters.empty());
  uint64_t level0 = 0, roots = 0;
  for (const DagCluster& c : dag.clusters) {
    level0 += c.level == 0 ? c.triangleCount() : 0;
    roots += c.parent_group == tw::kNoGroup ? c.triangleCount() : 0;
    EXPECT_LT(c.error, c.parent_error);
    EXPECT_EQ(c.level == 0, c.group == tw::kNoGroup);
    EXPECT_LE(c.triangleCount(), options.cluster_size);
    if (c.group != tw::kNoGroup) {
      EXPECT_EQ(dag.groups[c.group].error, c.error);
      EXPECT_EQ(dag.groups[c.group].level + 1, c.level);
    }
    if (c.parent_group == tw::kNoGroup) {
      EXPECT_TRUE(std::isinf(c.parent_error));
    } else {
      EXPECT_EQ(dag.groups[c.parent_group].error, c.parent_error);
      EXPECT_LE(c.level, dag.groups[c.parent_group].level);
    }
  }
  EXPECT_EQ(level0, input_triangles);
  EXPECT_EQ(roots, dag.root_triangles);
  EXPECT_LE(dag.root_triangles, options.max_root_triangles);
  EXPECT_TRUE(dag.stats.root_within_limit);
  for (const tw::DagGroup& g : dag.groups) {
    uint64_t in = 0, out = 0;
    for (uint32_t child : g.children) {
      const DagCluster& c = dag.clusters[child];
      EXPECT_GT(g.error, c.error);
      in += c.triangleCount();
      EXPECT_LE(glm::length(c.lod_center - g.sphere_center) + c.lod_radius,
                g.sphere_radius * (1.0f + 1e-5f) + 1e-6f);
    }
    for (uint32_t made : g.clusters) out += dag.clusters[made].triangleCount();
    EXPECT_LE(out, in);  // no group grows
  }
  // Levels shrink: every level holds fewer triangles than the one below.
  for (size_t l = 1; l < dag.triangles_per_level.size(); ++l)
    EXPECT_LT(dag.triangles_per_level[l], dag.triangles_per_level[l - 1]) << "level " << l;
}

void report(const char* name, const ClusterDag& dag, double seconds) {
  std::string levels;
  for (size_t l = 0; l < dag.levelCount(); ++l)
    levels += (l ? " " : "") + std::to_string(dag.triangles_per_level[l]) + "/" +
              std::to_string(dag.clusters_per_level[l]);
  std::printf("[ merge ] %s: %u levels (triangles/clusters: %s), root %llu triangles, %zu groups, "
              "%.3f s\n",
              name, dag.levelCount(), levels.c_str(), (unsigned long long)dag.root_triangles,
              dag.groups.size(), seconds);
}

double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// Scattered closed boxes (free for the fallbacks) and open quads (two triangles, four open
// edges: what a brick seam looks like to one component).
Mesh boxesAndQuads(uint32_t count, uint32_t seed, bool quads = true) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> where(0.0f, 20.0f), size(0.05f, 0.3f);
  static const uint32_t kFaces[36] = {0, 2, 1, 0, 3, 2, 4, 5, 6, 4, 6, 7, 0, 1, 5, 0, 5, 4,
                                      1, 2, 6, 1, 6, 5, 2, 3, 7, 2, 7, 6, 3, 0, 4, 3, 4, 7};
  Mesh m;
  for (uint32_t b = 0; b < count; ++b) {
    glm::vec3 lo(where(rng), where(rng), where(rng));
    glm::vec3 hi = lo + glm::vec3(size(rng), size(rng), size(rng));
    uint32_t base = uint32_t(m.positions.size());
    m.positions.insert(m.positions.end(), {{lo.x, lo.y, lo.z}, {hi.x, lo.y, lo.z},
                                           {hi.x, hi.y, lo.z}, {lo.x, hi.y, lo.z},
                                           {lo.x, lo.y, hi.z}, {hi.x, lo.y, hi.z},
                                           {hi.x, hi.y, hi.z}, {lo.x, hi.y, hi.z}});
    if (quads && b % 4 == 0) {  // an open quad: the bottom face only
      m.indices.insert(m.indices.end(), {base, base + 2, base + 1, base, base + 3, base + 2});
      m.ids.insert(m.ids.end(), {b, b});
      continue;
    }
    for (uint32_t f : kFaces) m.indices.push_back(base + f);
    for (int t = 0; t < 12; ++t) m.ids.push_back(b);
  }
  return m;
}

// Builds the two halves of `m` as separate DAGs and counts the threshold pairs whose union of
// cuts has boundary edges (the input is closed, so any is a crack along the seam).
int seamCracks(const Mesh& m, const std::function<size_t(glm::vec3)>& half,
               const DagOptions& options, int steps) {
  auto halves = cutIntoBricks(m, 2, half);
  auto dags = buildBricks(halves, options);
  EXPECT_GT(dags[0].levelCount(), 3u);
  EXPECT_GT(dags[1].levelCount(), 3u);
  Welder welder;
  EdgeCounter seam(welder);
  seam.addMesh(halves[0]);
  EXPECT_GT(seam.boundary().size(), 50u);
  int cracked = 0, pairs = 0;
  for (float t0 : thresholds(dags[0], steps)) {
    auto cut0 = tw::selectCut(dags[0], t0);
    for (float t1 : thresholds(dags[1], steps)) {
      EdgeCounter both(welder);
      both.addCut(dags[0], cut0);
      both.addCut(dags[1], tw::selectCut(dags[1], t1));
      cracked += !both.boundary().empty();
      ++pairs;
    }
  }
  EXPECT_GT(pairs, 100);
  return cracked;
}

TEST(DagMerge, LockedSeamsMeetAtAnyPairOfThresholds) {
  DagOptions options;
  options.lock_open_boundaries = true;
  options.cluster_size = 128;
  Mesh sphere = icosphere(5);  // 20480 triangles
  EXPECT_EQ(seamCracks(sphere, [](glm::vec3 c) { return c.z + 0.3f * c.x < 0.1f; }, options, 10),
            0);

  // Disconnected CAD-like parts: boxes cut by the seam are open halves, which the fallbacks
  // would otherwise treat as free (their open edges as rims that may move).
  Mesh boxes = boxesAndQuads(3000, 9, false);
  auto half = [](glm::vec3 c) { return c.x < 10.0f; };
  options.cluster_size = 256;
  options.max_root_triangles = 2048;  // force the fallbacks to work hard
  EXPECT_EQ(seamCracks(boxes, half, options, 10), 0);
}

TEST(DagMerge, LockedBrickRootKeepsItsWholeSeam) {
  // The coarsest cut of a locked brick still holds every open edge of its input, while it shrank.
  Mesh sphere = icosphere(4);
  auto halves = cutIntoBricks(sphere, 2, [](glm::vec3 c) { return c.z < 0.0f; });
  DagOptions locked;
  locked.lock_open_boundaries = true;
  ClusterDag dag = tw::buildClusterDag(halves[0].input(), locked);
  Welder welder;
  EdgeCounter input(welder);
  input.addMesh(halves[0]);
  EdgeCounter root(welder);
  std::vector<uint32_t> roots;
  for (uint32_t c = 0; c < dag.clusters.size(); ++c)
    if (dag.clusters[c].parent_group == tw::kNoGroup) roots.push_back(c);
  root.addCut(dag, roots);
  EXPECT_EQ(root.boundary(), input.boundary());
  EXPECT_LT(dag.root_triangles, halves[0].triangles() / 2);
}

TEST(DagMerge, LockKeepsOpenComponentsOutOfTheFallbacks) {
  Mesh m = boxesAndQuads(4000, 5);
  Welder welder;
  EdgeCounter input(welder);
  input.addMesh(m);
  const auto open = input.boundary();
  ASSERT_EQ(open.size(), 1000u * 4u);
  for (int fallback = 0; fallback < 2; ++fallback) {
    DagOptions options;
    options.allow_sloppy = fallback == 0;
    options.allow_drop = fallback == 1;
    options.max_root_triangles = 4096;  // force the fallbacks to work hard

    options.lock_open_boundaries = true;
    ClusterDag locked = tw::buildClusterDag(m.input(), options);
    EXPECT_LT(locked.root_triangles, m.triangles() / 2);  // the boxes still shrink
    for (float tau : thresholds(locked, 20)) {
      EdgeCounter cut(welder);
      cut.addCut(locked, tw::selectCut(locked, tau));
      EXPECT_EQ(cut.boundary(), open) << "fallback " << fallback << ", tau " << tau;
    }

    // Without the lock, dropping takes open quads too: the coarsest cut loses open edges.
    // (Sloppy happens to leave these quads whole, so only the drop case can show it.)
    if (fallback == 0) continue;
    options.lock_open_boundaries = false;
    ClusterDag free = tw::buildClusterDag(m.input(), options);
    EdgeCounter root(welder);
    std::vector<uint32_t> roots;
    for (uint32_t c = 0; c < free.clusters.size(); ++c)
      if (free.clusters[c].parent_group == tw::kNoGroup) roots.push_back(c);
    ASSERT_FALSE(roots.empty());
    root.addCut(free, roots);
    EXPECT_LT(root.boundary().size(), open.size()) << "fallback " << fallback;
  }
}

// A seam edge is locked whatever its count in this brick: a non-manifold edge (three plates of a
// bracket meeting on a line) used three times here and once in the neighbouring brick is where
// the two bricks meet. Small brackets are exactly what the drop and sloppy fallbacks take.
TEST(DagMerge, NonManifoldSeamEdgesAreLockedWhateverTheirCount) {
  Mesh m;
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> size(0.05f, 0.2f);
  std::vector<std::pair<glm::vec3, glm::vec3>> seam;
  std::uniform_real_distribution<float> where(1.0f, 20.0f);
  for (uint32_t b = 0; b < 3000; ++b) {
    // Three fins of 2x2 quads on a segment along x; one bracket in ten sits on the seam, the
    // line y = z = 0, the others elsewhere.
    const bool on_seam = b % 10 == 0;
    const glm::vec3 base = on_seam ? glm::vec3(0.5f * float(b / 10), 0, 0)
                                   : glm::vec3(where(rng), where(rng), where(rng));
    const float length = 0.3f, reach = size(rng);
    const glm::vec3 out[3] = {{0, reach, 0}, {0, 0, reach}, {0, -reach, 0}};
    if (on_seam) {
      seam.push_back({base, base + glm::vec3(0.5f * length, 0, 0)});
      seam.push_back({base + glm::vec3(0.5f * length, 0, 0), base + glm::vec3(length, 0, 0)});
    }
    for (const glm::vec3& o : out) {
      const uint32_t first = uint32_t(m.positions.size());
      for (int j = 0; j <= 2; ++j)
        for (int i = 0; i <= 2; ++i)
          m.positions.push_back(base + glm::vec3(length * 0.5f * float(i), 0, 0) +
                                o * (0.5f * float(j)));
      for (int j = 0; j < 2; ++j)
        for (int i = 0; i < 2; ++i) {
          const uint32_t a = first + uint32_t(3 * j + i), c = a + 3;
          m.indices.insert(m.indices.end(), {a, a + 1, c + 1, a, c + 1, c});
          m.ids.insert(m.ids.end(), {b, b});
        }
    }
  }
  Welder welder;
  EdgeCounter input(welder);
  input.addMesh(m);
  for (const auto& [a, b] : seam) ASSERT_EQ(input.count(a, b), 3u);

  DagOptions options;
  options.lock_open_boundaries = true;
  options.is_seam_edge = [](const glm::vec3& a, const glm::vec3& b) {
    return a.y == 0.0f && a.z == 0.0f && b.y == 0.0f && b.z == 0.0f;
  };
  options.max_root_triangles = 4096;  // force the fallbacks to work hard
  ClusterDag dag = tw::buildClusterDag(m.input(), options);
  ASSERT_GT(dag.levelCount(), 2u);
  EXPECT_LT(dag.root_triangles, m.triangles() / 4);
  for (float tau : thresholds(dag, 20)) {
    EdgeCounter cut(welder);
    cut.addCut(dag, tw::selectCut(dag, tau));
    size_t moved = 0;
    for (const auto& [a, b] : seam) moved += cut.count(a, b) != 3u;
    EXPECT_EQ(moved, 0u) << "tau " << tau;
  }
}

TEST(DagMerge, MergedSphereBricksAreWatertightAtEveryThreshold) {
  Mesh sphere = icosphere(6);  // 81920 triangles
  // Eight octants, and one of them split again into a small cap so brick depths differ.
  auto brickOf = [](glm::vec3 c) -> size_t {
    if (c.x > 0.97f) return 8;
    return size_t(c.x > 0.0f) | size_t(c.y > 0.0f) << 1 | size_t(c.z > 0.0f) << 2;
  };
  auto bricks = cutIntoBricks(sphere, 9, brickOf);
  DagOptions brick_options;
  brick_options.lock_open_boundaries = true;
  auto start = std::chrono::steady_clock::now();
  auto dags = buildBricks(bricks, brick_options);
  const double brick_seconds = secondsSince(start);
  uint32_t min_depth = 1000, max_depth = 0;
  uint64_t brick_roots = 0;
  for (const ClusterDag& d : dags) {
    min_depth = std::min(min_depth, d.levelCount());
    max_depth = std::max(max_depth, d.levelCount());
    brick_roots += d.root_triangles;
    std::printf("[ merge ] brick: %u levels, %llu -> %llu triangles\n", d.levelCount(),
                (unsigned long long)d.triangles_per_level[0], (unsigned long long)d.root_triangles);
  }
  EXPECT_LT(min_depth, max_depth) << "bricks should stop at different depths";

  start = std::chrono::steady_clock::now();
  ClusterDag merged = tw::mergeBrickDags(std::move(dags), DagOptions{});
  const double merge_seconds = secondsSince(start);
  report("icosphere 9 bricks", merged, merge_seconds);
  std::printf("[ merge ] brick builds %.3f s, brick roots %llu triangles\n", brick_seconds,
              (unsigned long long)brick_roots);
  expectMergedWellFormed(merged, sphere.triangles(), DagOptions{});
  EXPECT_LT(merged.root_triangles, brick_roots / 2) << "the merge must shrink the brick roots";
  EXPECT_LE(merged.root_triangles, 4096u);

  bool mixed = false;
  for (const tw::DagGroup& g : merged.groups)
    for (uint32_t child : g.children) mixed |= merged.clusters[child].level != g.level;
  EXPECT_TRUE(mixed) << "some merged group should join brick roots of different levels";

  Welder welder;
  auto taus = thresholds(merged, 30);
  for (float tau : taus) {
    EdgeCounter cut(welder);
    auto selected = tw::selectCut(merged, tau);
    ASSERT_FALSE(selected.empty());
    cut.addCut(merged, selected);
    EXPECT_EQ(cut.boundary().size(), 0u) << "tau " << tau;
  }
}

TEST(DagMerge, MergedDagIsAValidPackage) {
  Mesh sphere = icosphere(5);
  auto bricks = cutIntoBricks(sphere, 3, [](glm::vec3 c) -> size_t {
    return c.x > 0.7f ? 2 : c.y > 0.0f ? 1 : 0;  // a small cap: a shallower brick
  });
  DagOptions brick_options;
  brick_options.lock_open_boundaries = true;
  ClusterDag merged = tw::mergeBrickDags(buildBricks(bricks, brick_options));
  tw::PackageStorage storage;
  storage.addLayer(tw::Layer{"default", 0xff808080u});
  tw::ObjectInfo info;
  info.name = "sphere";
  storage.addObject(info, glm::vec3(-1.0f), glm::vec3(1.0f));
  tw::addDagToPackage(merged, storage);
  auto path = tw::test::scratchDir() / "merged.twk";
  tw::writePackage(storage, path);
  auto view = tw::PackageView::open(path, tw::PackageView::Verify::All);
  ASSERT_EQ(view.clusters().size(), merged.clusters.size());
  bool below = false;  // a child whose level is below its parent group's: the relaxed rule
  for (const auto& c : view.clusters())
    if (c.parent_group != tw::pkg::kNone) below |= c.level < view.groups()[c.parent_group].level;
  EXPECT_TRUE(below);

  // Decoded (quantized) cuts of the package stay closed.
  std::vector<std::vector<glm::vec3>> corners(view.clusters().size());
  std::vector<uint8_t> scratch;
  tw::DecodedCluster decoded;
  for (uint32_t c = 0; c < corners.size(); ++c) {
    view.decodeCluster(c, view.loadPage(view.clusters()[c].page, scratch), decoded);
    for (uint32_t i : decoded.indices) corners[c].push_back(decoded.positions[i]);
  }
  Welder welder;
  for (float tau : thresholds(merged, 10)) {
    EdgeCounter cut(welder);
    for (uint32_t c = 0; c < corners.size(); ++c) {
      const auto& r = view.clusters()[c];
      if (!(r.error <= tau && tau < r.parent_error)) continue;
      for (size_t i = 0; i + 2 < corners[c].size(); i += 3)
        cut.add(corners[c][i], corners[c][i + 1], corners[c][i + 2]);
    }
    EXPECT_EQ(cut.boundary().size(), 0u) << "tau " << tau;
  }
}

TEST(DagMerge, Deterministic) {
  Mesh sphere = icosphere(4);
  auto bricks = cutIntoBricks(sphere, 4, [](glm::vec3 c) {
    return size_t(c.x > 0.1f) | size_t(c.y > -0.2f) << 1;
  });
  DagOptions brick_options;
  brick_options.lock_open_boundaries = true;
  ClusterDag a = tw::mergeBrickDags(buildBricks(bricks, brick_options));
  ClusterDag b = tw::mergeBrickDags(buildBricks(bricks, brick_options));
  ASSERT_EQ(a.clusters.size(), b.clusters.size());
  ASSERT_EQ(a.groups.size(), b.groups.size());
  for (size_t c = 0; c < a.clusters.size(); ++c) {
    EXPECT_EQ(a.clusters[c].positions, b.clusters[c].positions);
    EXPECT_EQ(a.clusters[c].indices, b.clusters[c].indices);
    EXPECT_EQ(a.clusters[c].error, b.clusters[c].error);
  }
}

TEST(DagMerge, EmptyAndSingleBrick) {
  ClusterDag none = tw::mergeBrickDags({});
  EXPECT_TRUE(none.clusters.empty());
  EXPECT_TRUE(none.stats.root_within_limit);

  Mesh sphere = icosphere(3);
  std::vector<ClusterDag> one;
  one.push_back(tw::buildClusterDag(sphere.input()));
  one.push_back(ClusterDag{});
  const size_t clusters = one[0].clusters.size();
  ClusterDag merged = tw::mergeBrickDags(std::move(one));
  // A finished DAG has nothing left to merge: it comes back unchanged.
  EXPECT_EQ(merged.clusters.size(), clusters);
  expectMergedWellFormed(merged, sphere.triangles(), DagOptions{});
}

TEST(DagMerge, BunnyBricksKeepExactlyTheInputBoundary) {
  Mesh bunny = loadObj(tw::test::sharedDataDir() / "stanford-bunny.obj");
  ASSERT_EQ(bunny.triangles(), 69451u);
  glm::vec3 lo(INFINITY), hi(-INFINITY);
  for (const glm::vec3& p : bunny.positions) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  const glm::vec3 mid = 0.5f * (lo + hi);
  auto bricks = cutIntoBricks(bunny, 4, [mid](glm::vec3 c) {
    return size_t(c.x > mid.x) | size_t(c.z > mid.z) << 1;
  });
  DagOptions brick_options;
  brick_options.lock_open_boundaries = true;
  auto start = std::chrono::steady_clock::now();
  auto dags = buildBricks(bricks, brick_options);
  ClusterDag merged = tw::mergeBrickDags(std::move(dags));
  report("bunny 4 bricks", merged, secondsSince(start));
  expectMergedWellFormed(merged, bunny.triangles(), DagOptions{});

  // Every cut's boundary is the input's: its base openings, whose rims coarse cuts may
  // simplify (an edge between two of its rim vertices), and nothing along the brick seams.
  Welder welder;
  EdgeCounter input(welder);
  input.addMesh(bunny);
  const auto input_boundary = input.boundary();
  const auto input_rim = input.rim();
  ASSERT_GT(input_boundary.size(), 0u);
  int exact = 0, cuts = 0;
  for (float tau : thresholds(merged, 30)) {
    EdgeCounter cut(welder);
    cut.addCut(merged, tw::selectCut(merged, tau));
    auto boundary = cut.boundary();
    exact += boundary == input_boundary;
    ++cuts;
    size_t foreign = 0;
    for (uint64_t e : boundary)
      foreign += !input_boundary.count(e) &&
                 !(input_rim.count(uint32_t(e >> 32)) && input_rim.count(uint32_t(e)));
    EXPECT_EQ(foreign, 0u) << "tau " << tau;
  }
  std::printf("[ merge ] bunny bricks: %d of %d cuts with exactly the input's boundary\n", exact,
              cuts);
  EXPECT_GE(exact, 1);
}

}  // namespace
