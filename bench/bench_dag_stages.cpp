// The LOD DAG's stages one by one, through the public functions of preprocess/: clustering
// (clusterize.h), grouping (cluster_grouping.h, METIS), group simplification (each group of
// neighbouring clusters gathered into a compact vertex buffer and simplified to half with
// meshopt_simplify + meshopt_SimplifyLockBorder, as cluster_dag.cpp does before any fallback),
// the whole DAG build (cluster_dag.h), and far-proxy remeshing (far_proxy.h, OpenVDB) of an
// aggregate of many small CAD parts.
//
// Mesh input: the Stanford bunny (TW_SHARED_DATA_DIR; skipped with a message when missing).
// Far-proxy input: 1000 small parts (bolts, valves, fittings: cylinders, spheres, boxes, elbows,
// tessellated at 3 mm) scattered in a 2 x 2 x 1 m block, fixed seed.
//
//   build-microbench/bench/bench_dag_stages --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
//
// Rates: items_per_second = input triangles of the stage (clusters for grouping). The DAG build
// and the far proxy use TBB / OpenVDB threads, so they are timed in wall-clock time; the other
// stages are single-threaded.
#include <benchmark/benchmark.h>

#include <meshoptimizer.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <random>
#include <string>
#include <unordered_map>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include "cluster_dag.h"
#include "cluster_grouping.h"
#include "clusterize.h"
#include "far_proxy.h"
#include "obj_reader.h"
#include "scene_sink.h"
#include "tessellate.h"
#include "world_mesh_sink.h"

namespace tw {
namespace {

constexpr uint32_t kClusterTriangles = 256;  // DagOptions' and the preprocessor's default
constexpr uint32_t kGroupSize = 8;           // DagOptions' default

// The bunny, welded by exact position (the DAG's first step, so clusters share vertices).
struct Bunny {
  std::string error;
  std::vector<glm::vec3> positions;
  std::vector<uint32_t> indices;
  std::vector<uint32_t> objects;  // one per triangle, all 0
  TriangleClusters clusters;
  std::vector<std::vector<uint32_t>> cluster_tris;  // per cluster, vertex indices
  std::vector<glm::vec3> centers;
  std::vector<std::vector<uint32_t>> groups;
};

const Bunny& bunny() {
  static const Bunny b = [] {
    Bunny out;
    const std::filesystem::path path =
        std::filesystem::path(TW_SHARED_DATA_DIR) / "stanford-bunny.obj";
    if (!std::filesystem::exists(path)) {
      out.error = "shared data not present: " + path.string();
      return out;
    }
    WorldMeshSink sink;
    ReadOptions options;
    options.max_part_triangles = 1u << 24;
    readObj(path, sink, options);
    std::vector<uint32_t> remap(sink.positions.size());
    const size_t unique = meshopt_generateVertexRemap(remap.data(), sink.indices.data(),
                                                      sink.indices.size(), sink.positions.data(),
                                                      sink.positions.size(), sizeof(glm::vec3));
    out.positions.resize(unique);
    meshopt_remapVertexBuffer(out.positions.data(), sink.positions.data(), sink.positions.size(),
                              sizeof(glm::vec3), remap.data());
    out.indices.resize(sink.indices.size());
    meshopt_remapIndexBuffer(out.indices.data(), sink.indices.data(), sink.indices.size(),
                             remap.data());
    out.objects.assign(out.indices.size() / 3, 0u);
    out.clusters = clusterizeTriangles(out.positions, out.indices, kClusterTriangles);
    for (size_t k = 0; k < out.clusters.clusterCount(); ++k) {
      std::vector<uint32_t> tris;
      glm::vec3 lo(1e30f), hi(-1e30f);
      for (uint32_t i = out.clusters.offsets[k]; i < out.clusters.offsets[k + 1]; ++i)
        for (int corner = 0; corner < 3; ++corner) {
          const uint32_t v = out.indices[3 * size_t(out.clusters.triangles[i]) + corner];
          tris.push_back(v);
          lo = glm::min(lo, out.positions[v]);
          hi = glm::max(hi, out.positions[v]);
        }
      out.cluster_tris.push_back(std::move(tris));
      out.centers.push_back(0.5f * (lo + hi));
    }
    std::vector<std::span<const uint32_t>> spans(out.cluster_tris.begin(), out.cluster_tris.end());
    out.groups = groupClusters(spans, out.centers, kGroupSize, out.positions.size());
    return out;
  }();
  return b;
}

// clusterizeTriangles over the bunny; range(0) = max triangles per cluster.
void BM_Clusterize(benchmark::State& state) {
  const Bunny& b = bunny();
  if (!b.error.empty()) {
    state.SkipWithError(b.error.c_str());
    return;
  }
  const auto max_triangles = static_cast<uint32_t>(state.range(0));
  size_t clusters = 0;
  for (auto _ : state) {
    TriangleClusters split = clusterizeTriangles(b.positions, b.indices, max_triangles);
    clusters = split.clusterCount();
    benchmark::DoNotOptimize(split.triangles.data());
  }
  state.SetItemsProcessed(int64_t(state.iterations()) * int64_t(b.indices.size() / 3));
  state.counters["clusters"] = double(clusters);
}

// groupClusters (METIS k-way on the cluster adjacency) over the bunny's level-0 clusters.
void BM_GroupClusters(benchmark::State& state) {
  const Bunny& b = bunny();
  if (!b.error.empty()) {
    state.SkipWithError(b.error.c_str());
    return;
  }
  const std::vector<std::span<const uint32_t>> spans(b.cluster_tris.begin(), b.cluster_tris.end());
  size_t groups = 0;
  for (auto _ : state) {
    auto result = groupClusters(spans, b.centers, kGroupSize, b.positions.size());
    groups = result.size();
    benchmark::DoNotOptimize(result.data());
  }
  state.SetItemsProcessed(int64_t(state.iterations()) * int64_t(b.cluster_tris.size()));
  state.counters["clusters"] = double(b.cluster_tris.size());
  state.counters["groups"] = double(groups);
}

// Every level-0 group of the bunny, one after the other: gather into a compact local vertex
// buffer (meshopt's cost and error scale depend on the whole buffer it is given), then simplify
// to half the triangles with the group's outer border locked, target error 1.0 relative (the
// DagOptions defaults). The border check and the sloppy / proxy fallbacks are not included.
void BM_SimplifyGroupsLocked(benchmark::State& state) {
  const Bunny& b = bunny();
  if (!b.error.empty()) {
    state.SkipWithError(b.error.c_str());
    return;
  }
  uint64_t input = 0;
  for (const auto& group : b.groups)
    for (uint32_t c : group) input += b.cluster_tris[c].size() / 3;
  std::unordered_map<uint32_t, uint32_t> to_local;
  std::vector<uint32_t> gtris, ltris, out;
  std::vector<glm::vec3> lpos;
  uint64_t output = 0;
  double max_error = 0.0;
  for (auto _ : state) {
    output = 0;
    for (const auto& group : b.groups) {
      gtris.clear();
      for (uint32_t c : group)
        gtris.insert(gtris.end(), b.cluster_tris[c].begin(), b.cluster_tris[c].end());
      to_local.clear();
      lpos.clear();
      ltris.resize(gtris.size());
      for (size_t i = 0; i < gtris.size(); ++i) {
        auto [it, inserted] = to_local.try_emplace(gtris[i], uint32_t(lpos.size()));
        if (inserted) lpos.push_back(b.positions[gtris[i]]);
        ltris[i] = it->second;
      }
      const float scale = meshopt_simplifyScale(&lpos[0].x, lpos.size(), sizeof(glm::vec3));
      out.resize(ltris.size());
      float error = 0.0f;
      const size_t target = (ltris.size() / 6) * 3;
      const size_t count =
          meshopt_simplify(out.data(), ltris.data(), ltris.size(), &lpos[0].x, lpos.size(),
                           sizeof(glm::vec3), target, 1.0f, meshopt_SimplifyLockBorder, &error);
      output += count / 3;
      max_error = std::max(max_error, double(error * scale));
      benchmark::DoNotOptimize(out.data());
    }
  }
  state.SetItemsProcessed(int64_t(state.iterations()) * int64_t(input));
  state.counters["groups"] = double(b.groups.size());
  state.counters["output_ratio"] = input ? double(output) / double(input) : 0.0;
  state.counters["max_error"] = max_error;
}

// buildClusterDag over the bunny: every level up to the root, with the defaults.
void BM_BuildClusterDag(benchmark::State& state) {
  const Bunny& b = bunny();
  if (!b.error.empty()) {
    state.SkipWithError(b.error.c_str());
    return;
  }
  DagInput input{b.positions, b.indices, b.objects};
  uint32_t levels = 0;
  size_t clusters = 0;
  for (auto _ : state) {
    ClusterDag dag = buildClusterDag(input);
    levels = dag.levelCount();
    clusters = dag.clusters.size();
    benchmark::DoNotOptimize(dag.clusters.data());
  }
  state.SetItemsProcessed(int64_t(state.iterations()) * int64_t(b.indices.size() / 3));
  state.counters["levels"] = double(levels);
  state.counters["clusters"] = double(clusters);
}

// Many small disconnected parts: what stalls edge collapse and gets a far proxy.
struct Aggregate {
  std::vector<glm::vec3> positions;
  std::vector<uint32_t> indices;
  std::vector<uint32_t> objects;
};

const Aggregate& aggregate() {
  static const Aggregate a = [] {
    Aggregate out;
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    constexpr int kParts = 1000;
    constexpr float kToleranceM = 0.003f;
    for (int k = 0; k < kParts; ++k) {
      Primitive primitive;
      const float size = 0.03f + 0.12f * u(rng);
      switch (k % 4) {
        case 0: primitive = Cylinder{0.3f * size, 2.0f * size, true}; break;
        case 1: primitive = Sphere{0.5f * size}; break;
        case 2: primitive = Box{glm::vec3(0.5f * size, 0.3f * size, 0.2f * size)}; break;
        default: primitive = TorusSegment{size, 0.25f * size, 1.5707964f}; break;
      }
      TriangleMesh part;
      tessellatePrimitive(primitive, kToleranceM, part);
      const glm::vec3 axis = glm::normalize(glm::vec3(u(rng) - 0.5f, u(rng) - 0.5f, u(rng) + 0.1f));
      const glm::mat3 rotation(glm::rotate(glm::mat4(1.0f), 6.2831853f * u(rng), axis));
      const glm::vec3 at(2.0f * u(rng), 2.0f * u(rng), 1.0f * u(rng));
      const auto base = static_cast<uint32_t>(out.positions.size());
      for (const glm::vec3& p : part.positions) out.positions.push_back(at + rotation * p);
      for (uint32_t i : part.indices) out.indices.push_back(base + i);
      out.objects.insert(out.objects.end(), part.indices.size() / 3, static_cast<uint32_t>(k));
    }
    return out;
  }();
  return a;
}

// buildFarProxy of the aggregate; range(0) = target triangles.
void BM_FarProxy(benchmark::State& state) {
  const Aggregate& a = aggregate();
  FarProxyOptions options;
  options.target_triangles = static_cast<uint32_t>(state.range(0));
  FarProxyInput input{a.positions, a.indices, a.objects};
  uint32_t triangles = 0;
  float error = 0.0f, voxel = 0.0f;
  for (auto _ : state) {
    FarProxy proxy = buildFarProxy(input, options);
    triangles = proxy.triangleCount();
    error = proxy.part_error;
    voxel = proxy.voxel_size;
    benchmark::DoNotOptimize(proxy.indices.data());
  }
  state.SetItemsProcessed(int64_t(state.iterations()) * int64_t(a.indices.size() / 3));
  state.counters["source_triangles"] = double(a.indices.size() / 3);
  state.counters["proxy_triangles"] = triangles;
  state.counters["part_error_m"] = error;
  state.counters["voxel_m"] = voxel;
}

BENCHMARK(BM_Clusterize)->ArgName("max_tris")->Arg(128)->Arg(256)->Arg(1024)
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_GroupClusters)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_SimplifyGroupsLocked)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_BuildClusterDag)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_FarProxy)->ArgName("target")->Arg(1024)->Arg(4096)->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
}  // namespace tw

BENCHMARK_MAIN();
