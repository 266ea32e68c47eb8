// Ray sampling from view cells and the greedy occluder ranking. See visibility_sampling.h.
//
// Parallelism: cells run in parallel (TBB), each cell's rays one after another on its thread.
// A cell's rays depend only on the seed and its grid index, and its result only on its rays, so
// the output is the same whatever the thread count or the order cells finish in.
#include "visibility_sampling.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace tw {
namespace {

// Cells per progress step: the calling thread reports and polls cancellation between chunks,
// each of which runs in parallel.
constexpr uint32_t kCellsPerChunk = 256;

// SplitMix64: tiny, good enough for jitter, and specified (std distributions are not).
struct SplitMix64 {
  uint64_t state;
  uint64_t next() {
    uint64_t z = (state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
  }
  double uniform() { return double(next() >> 11) * 0x1.0p-53; }  // [0, 1)
};

uint64_t mixSeed(uint64_t seed, uint64_t a, uint64_t b) {
  SplitMix64 rng{seed ^ (a * 0xd1b54a32d192ed03ull) ^ (b * 0x8cb92ba72f3d8dd7ull)};
  rng.next();
  return rng.next();
}

// A uniformly random rotation (Shoemake's unit quaternion from three uniforms).
glm::dmat3 randomRotation(SplitMix64& rng) {
  const double u1 = rng.uniform(), u2 = rng.uniform(), u3 = rng.uniform();
  const double a = std::sqrt(1.0 - u1), b = std::sqrt(u1);
  const double t1 = 2.0 * std::numbers::pi * u2, t2 = 2.0 * std::numbers::pi * u3;
  const double x = a * std::sin(t1), y = a * std::cos(t1);
  const double z = b * std::sin(t2), w = b * std::cos(t2);
  return glm::dmat3(1 - 2 * (y * y + z * z), 2 * (x * y + w * z), 2 * (x * z - w * y),
                    2 * (x * y - w * z), 1 - 2 * (x * x + z * z), 2 * (y * z + w * x),
                    2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y));
}

// Direction i of a spherical Fibonacci set of n: equal-area bands in z, golden-angle azimuths.
glm::dvec3 fibonacciDirection(uint32_t i, uint32_t n) {
  constexpr double kGoldenAngle = 2.399963229728653;  // pi * (3 - sqrt(5))
  const double z = 1.0 - (2.0 * i + 1.0) / n;
  const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
  const double phi = kGoldenAngle * i;
  return {r * std::cos(phi), r * std::sin(phi), z};
}

struct CellResult {
  std::vector<uint32_t> occluders;
  std::vector<uint32_t> visible;
  float occluder_coverage = 0.0f;
  float hit_fraction = 0.0f;
};

// Origins on a k x k x k lattice of strata (k = ceil(cbrt(samples))), strata taken in a seeded
// shuffle when there are more than samples, each origin jittered inside its stratum. With the
// default 8 samples, one origin per octant.
void sampleCell(const EmbreeScene& scene, const ViewCellGrid& grid, uint32_t grid_index,
                const VisibilitySamplingOptions& options, uint32_t samples,
                std::vector<uint32_t>& first_hits, CellResult& out) {
  const glm::dvec3 cell_min = grid.cellMin(grid_index);
  const double size = grid.cell_size_m;
  uint32_t k = 1;
  while (k * k * k < samples) ++k;
  std::vector<uint32_t> strata(k * k * k);
  for (uint32_t i = 0; i < strata.size(); ++i) strata[i] = i;
  SplitMix64 cell_rng{mixSeed(options.seed, grid_index, 0xffffffffull)};
  if (strata.size() > samples)  // Fisher-Yates with our generator
    for (uint32_t i = uint32_t(strata.size()) - 1; i > 0; --i)
      std::swap(strata[i], strata[uint32_t(cell_rng.next() % (i + 1))]);

  first_hits.clear();
  uint32_t hits = 0;
  const uint32_t rays = options.rays_per_cell;
  for (uint32_t s = 0; s < samples; ++s) {
    SplitMix64 rng{mixSeed(options.seed, grid_index, s)};
    const uint32_t st = strata[s];
    const glm::dvec3 stratum(st % k, (st / k) % k, st / (k * k));
    const glm::dvec3 jitter(rng.uniform(), rng.uniform(), rng.uniform());
    const glm::dvec3 origin = cell_min + (stratum + jitter) * (size / k);
    const glm::dmat3 rotation = randomRotation(rng);
    const uint32_t count = rays / samples + (s < rays % samples ? 1 : 0);
    Ray ray;
    ray.origin = glm::vec3(origin);  // the grid is in the package frame, as is the scene
    for (uint32_t i = 0; i < count; ++i) {
      ray.direction = glm::vec3(rotation * fibonacciDirection(i, count));
      const EmbreeScene::Hit hit = scene.intersect(ray);
      if (!hit.hit) continue;
      ++hits;
      first_hits.push_back(hit.user_id);
    }
  }

  // Count first hits per candidate: sort the ids, then runs.
  std::sort(first_hits.begin(), first_hits.end());
  std::vector<std::pair<uint32_t, uint32_t>> counts;  // (first hits, candidate)
  for (size_t i = 0; i < first_hits.size();) {
    size_t j = i;
    while (j < first_hits.size() && first_hits[j] == first_hits[i]) ++j;
    counts.push_back({uint32_t(j - i), first_hits[i]});
    if (options.visible_sets) out.visible.push_back(first_hits[i]);
    i = j;
  }
  // Greedy cover: every ray has one first hit, so the candidate covering most uncovered rays is
  // always the one with most first hits left; ties go to the lower id.
  std::sort(counts.begin(), counts.end(), [](const auto& a, const auto& b) {
    return a.first != b.first ? a.first > b.first : a.second < b.second;
  });
  const double target = double(options.coverage_target) * hits;
  uint32_t covered = 0;
  for (const auto& [count, id] : counts) {
    if (out.occluders.size() >= options.max_occluders || double(covered) >= target) break;
    out.occluders.push_back(id);
    covered += count;
  }
  out.occluder_coverage = rays ? float(double(covered) / rays) : 0.0f;
  out.hit_fraction = rays ? float(double(hits) / rays) : 0.0f;
}

}  // namespace

VisibilityData sampleVisibility(const EmbreeScene& scene, const ViewCellGrid& grid,
                                const VisibilitySamplingOptions& options) {
  if (!scene.committed()) throw std::invalid_argument("sampleVisibility: scene not committed");
  if (options.rays_per_cell == 0)
    throw std::invalid_argument("sampleVisibility: zero rays per cell");
  const uint32_t samples = std::clamp<uint32_t>(options.samples_per_cell, 1, options.rays_per_cell);

  VisibilityData data;
  data.grid_dims = grid.dims;
  data.grid_min = grid.min;
  data.cell_size_m = grid.cell_size_m;
  data.rays_per_cell = options.rays_per_cell;
  data.solid_cells = grid.solid_cells;
  data.visible_sets = options.visible_sets;
  const auto cell_count = uint32_t(grid.free_cells.size());
  data.rays_cast = uint64_t(cell_count) * options.rays_per_cell;
  data.cells.resize(cell_count);

  Progress* progress = options.progress;
  beginStage(progress, "visibility rays", cell_count);
  for (uint32_t chunk = 0; chunk < cell_count; chunk += kCellsPerChunk) {
    if (progress && progress->cancelled()) {
      endStage(progress);
      throw std::runtime_error("cancelled");
    }
    const uint32_t end = std::min(cell_count, chunk + kCellsPerChunk);
    tbb::parallel_for(tbb::blocked_range<uint32_t>(chunk, end, 4), [&](const auto& range) {
      std::vector<uint32_t> first_hits;
      first_hits.reserve(options.rays_per_cell);
      for (uint32_t c = range.begin(); c != range.end(); ++c) {
        CellResult result;
        sampleCell(scene, grid, grid.free_cells[c], options, samples, first_hits, result);
        VisibilityCell& cell = data.cells[c];
        cell.grid_index = grid.free_cells[c];
        cell.occluders = std::move(result.occluders);
        cell.visible = std::move(result.visible);
        cell.occluder_coverage = result.occluder_coverage;
        cell.hit_fraction = result.hit_fraction;
      }
    });
    updateProgress(progress, end);
  }
  endStage(progress);
  return data;
}

}  // namespace tw
