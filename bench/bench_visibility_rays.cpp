// Embree ray throughput as the visibility build casts rays (occlusion/embree_scene.h,
// occlusion/visibility_sampling.h). Scene: a generated plant of about 300K equivalent triangles
// (tools/plantgen, seed 1), every object tessellated at the default 2 mm, cut into 256-triangle
// candidate clusters with one Embree geometry per cluster (user id = cluster), as
// buildVisibilitySection does with its candidate front (up to 1M triangles by default). View cells
// from buildViewCells with about 1024 cells; the benchmark samples 64 of the free cells, evenly
// spread.
//
//   build-microbench/bench/bench_visibility_rays --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
//
// Rows:
//  - SampleVisibility: sampleVisibility itself (cells in parallel with TBB, each cell's rays one
//    by one through EmbreeScene::intersect, then the greedy occluder choice): the build's path.
//  - IntersectSingle: the same kind of rays (8 origins per cell, spherical Fibonacci directions)
//    one by one on one thread: the per-core rate behind the row above.
//  - IntersectBatch / OccludedBatch: EmbreeScene's batched calls over all cores, for comparison
//    (coherent hint off: these rays are incoherent).
// Rates: items_per_second = rays. Multi-threaded rows are timed in wall-clock time.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <vector>

#include <glm/glm.hpp>

#include "clusterize.h"
#include "embree_scene.h"
#include "plant_generator.h"
#include "scene_sink.h"
#include "tessellate.h"
#include "view_cells.h"
#include "visibility_sampling.h"

namespace tw {
namespace {

constexpr uint64_t kPlantTriangles = 300'000;
constexpr uint32_t kClusterTriangles = 256;
constexpr uint32_t kCells = 64;
constexpr uint32_t kRaysPerCell = 1024;  // VisibilitySamplingOptions' default

// Tessellates every object into one world-space mesh (the plant sits near the origin).
class TessellatingSink : public SceneSink {
 public:
  void onLayer(uint32_t, const Layer&) override {}
  void onObject(const SceneObject& object) override {
    TriangleMesh local;
    tessellate(object.geometry, kDefaultChordalTolerance, local);
    const auto base = static_cast<uint32_t>(positions.size());
    for (const glm::vec3& p : local.positions)
      positions.push_back(glm::vec3(object.info.transform.apply(p)));
    for (uint32_t i : local.indices) indices.push_back(base + i);
  }
  std::vector<glm::vec3> positions;
  std::vector<uint32_t> indices;
};

struct World {
  std::unique_ptr<EmbreeScene> scene;
  ViewCellGrid grid;  // free_cells cut down to kCells
  uint64_t triangles = 0;
  uint32_t candidates = 0;
  std::vector<Ray> rays;  // kRaysPerCell per sampled cell
};

const World& world() {
  static const World w = [] {
    World out;
    TessellatingSink sink;
    PlantOptions plant;
    plant.target_triangles = kPlantTriangles;
    generatePlant(plant, sink, nullptr, nullptr);
    out.triangles = sink.indices.size() / 3;

    glm::dvec3 lo(1e300), hi(-1e300);
    for (const glm::vec3& p : sink.positions) {
      lo = glm::min(lo, glm::dvec3(p));
      hi = glm::max(hi, glm::dvec3(p));
    }
    ViewCellOptions cells;
    cells.target_cells = 1024;
    out.grid = buildViewCells(sink.positions, sink.indices, lo, hi, cells);
    std::vector<uint32_t> chosen;
    const size_t free_count = out.grid.free_cells.size();
    const size_t take = std::min<size_t>(kCells, free_count);
    for (size_t i = 0; i < take; ++i) chosen.push_back(out.grid.free_cells[i * free_count / take]);
    out.grid.free_cells = chosen;

    out.scene = std::make_unique<EmbreeScene>(glm::dvec3(0.0));
    const TriangleClusters split =
        clusterizeTriangles(sink.positions, sink.indices, kClusterTriangles);
    std::vector<uint32_t> local(sink.positions.size(), ~0u);
    for (size_t k = 0; k < split.clusterCount(); ++k) {
      std::vector<glm::vec3> positions;
      std::vector<uint32_t> indices, used;
      for (uint32_t i = split.offsets[k]; i < split.offsets[k + 1]; ++i)
        for (int corner = 0; corner < 3; ++corner) {
          const uint32_t v = sink.indices[3 * size_t(split.triangles[i]) + corner];
          if (local[v] == ~0u) {
            local[v] = static_cast<uint32_t>(positions.size());
            positions.push_back(sink.positions[v]);
            used.push_back(v);
          }
          indices.push_back(local[v]);
        }
      for (uint32_t v : used) local[v] = ~0u;
      out.scene->addMesh(std::move(positions), std::move(indices), static_cast<uint32_t>(k));
    }
    out.candidates = static_cast<uint32_t>(split.clusterCount());
    out.scene->commit();

    // Rays like the sampler's: 8 origins per cell (one per octant, centred), 128 spherical
    // Fibonacci directions each.
    constexpr uint32_t kOrigins = 8, kDirections = kRaysPerCell / kOrigins;
    for (uint32_t cell : out.grid.free_cells) {
      const glm::dvec3 cell_min = out.grid.cellMin(cell);
      for (uint32_t s = 0; s < kOrigins; ++s) {
        const glm::dvec3 octant(s & 1, (s >> 1) & 1, (s >> 2) & 1);
        const glm::vec3 origin(cell_min + (octant + 0.5) * (0.5 * out.grid.cell_size_m));
        for (uint32_t i = 0; i < kDirections; ++i) {
          const double z = 1.0 - (2.0 * i + 1.0) / kDirections;
          const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
          const double phi = 2.399963229728653 * i + 0.7 * s;
          Ray ray;
          ray.origin = origin;
          ray.direction = glm::vec3(r * std::cos(phi), r * std::sin(phi), z);
          out.rays.push_back(ray);
        }
      }
    }
    return out;
  }();
  return w;
}

void setCounters(benchmark::State& state, const World& w, uint64_t rays_per_iteration) {
  state.SetItemsProcessed(int64_t(state.iterations()) * int64_t(rays_per_iteration));
  state.counters["triangles"] = double(w.triangles);
  state.counters["candidates"] = double(w.candidates);
}

void BM_SampleVisibility(benchmark::State& state) {
  const World& w = world();
  VisibilitySamplingOptions options;
  options.rays_per_cell = kRaysPerCell;
  uint64_t rays = 0;
  double occluders = 0.0;
  for (auto _ : state) {
    VisibilityData data = sampleVisibility(*w.scene, w.grid, options);
    rays = data.rays_cast;
    occluders = 0.0;
    for (const VisibilityCell& cell : data.cells) occluders += double(cell.occluders.size());
    if (!data.cells.empty()) occluders /= double(data.cells.size());
    benchmark::DoNotOptimize(data.cells.data());
  }
  setCounters(state, w, rays);
  state.counters["cells"] = double(w.grid.free_cells.size());
  state.counters["occluders_per_cell"] = occluders;
}

void BM_IntersectSingle(benchmark::State& state) {
  const World& w = world();
  uint64_t hits = 0;
  for (auto _ : state) {
    hits = 0;
    for (const Ray& ray : w.rays) hits += w.scene->intersect(ray).hit ? 1 : 0;
    benchmark::DoNotOptimize(hits);
  }
  setCounters(state, w, w.rays.size());
  state.counters["hit_fraction"] = double(hits) / double(w.rays.size());
}

void BM_IntersectBatch(benchmark::State& state) {
  const World& w = world();
  std::vector<EmbreeScene::Hit> hits(w.rays.size());
  for (auto _ : state) {
    w.scene->intersect(w.rays, hits, false);
    benchmark::DoNotOptimize(hits.data());
  }
  setCounters(state, w, w.rays.size());
}

void BM_OccludedBatch(benchmark::State& state) {
  const World& w = world();
  std::vector<uint8_t> blocked(w.rays.size());
  for (auto _ : state) {
    w.scene->occluded(w.rays, blocked, false);
    benchmark::DoNotOptimize(blocked.data());
  }
  setCounters(state, w, w.rays.size());
}

BENCHMARK(BM_SampleVisibility)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_IntersectSingle)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_IntersectBatch)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_OccludedBatch)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace tw

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  // Built before the first row so its cost (generation, voxelization, BVH) is never timed.
  const tw::World& w = tw::world();
  std::printf("scene: %llu triangles, %u candidate clusters, %zu cells sampled of %u free\n",
              static_cast<unsigned long long>(w.triangles), w.candidates,
              w.grid.free_cells.size(), w.grid.cellCount() - w.grid.solid_cells);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
