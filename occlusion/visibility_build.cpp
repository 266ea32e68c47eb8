// The visibility stage: candidates decoded from the package, view cells, Embree, sampling, the
// encoded section. See visibility_build.h.
#include "visibility_build.h"

#include <algorithm>
#include <chrono>

#include <tbb/parallel_for.h>

#include "dag_front.h"
#include "embree_scene.h"
#include "visibility_section.h"

namespace tw {
namespace {

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

struct CandidateMesh {
  std::vector<glm::vec3> positions;  // package frame
  std::vector<uint32_t> indices;
};

// Decodes the front's clusters, page by page (each page loaded once), pages in parallel. The
// result is indexed like front.clusters, so it does not depend on the thread count.
std::vector<CandidateMesh> decodeCandidates(const PackageView& view, const DagFront& front) {
  const auto records = view.clusters();
  // Runs of candidates sharing a page (clusters are stored page by page, so ascending ids keep
  // a page's clusters together; a page appearing twice is merely loaded twice).
  std::vector<std::pair<size_t, size_t>> runs;
  for (size_t i = 0; i < front.clusters.size();) {
    size_t j = i + 1;
    while (j < front.clusters.size() &&
           records[front.clusters[j]].page == records[front.clusters[i]].page)
      ++j;
    runs.push_back({i, j});
    i = j;
  }
  std::vector<CandidateMesh> meshes(front.clusters.size());
  tbb::parallel_for(size_t(0), runs.size(), [&](size_t r) {
    std::vector<uint8_t> scratch;
    DecodedCluster decoded;
    const auto [first, last] = runs[r];
    const std::span<const uint8_t> raw =
        view.loadPage(records[front.clusters[first]].page, scratch);
    for (size_t i = first; i < last; ++i) {
      view.decodeCluster(front.clusters[i], raw, decoded);
      meshes[i].positions = std::move(decoded.positions);
      meshes[i].indices = std::move(decoded.indices);
    }
  });
  return meshes;
}

}  // namespace

std::vector<uint8_t> buildVisibilitySection(const PackageView& view,
                                            const VisibilityBuildOptions& options,
                                            VisibilityBuildReport* report) {
  VisibilityBuildReport local;
  VisibilityBuildReport& rep = report ? *report : local;
  rep = VisibilityBuildReport{};
  Progress* progress = options.progress;

  const DagFront front = finestFrontWithin(view, options.max_candidate_triangles);
  rep.candidate_level = front.level;
  rep.candidate_clusters = front.clusters.size();
  rep.candidate_triangles = front.triangles;
  if (front.clusters.empty()) return {};

  // 1. Candidates, decoded (positions are already relative to the package origin).
  beginStage(progress, "visibility cells", 3);
  auto start = Clock::now();
  std::vector<CandidateMesh> meshes = decodeCandidates(view, front);
  rep.decode_s = secondsSince(start);
  updateProgress(progress, 1);

  // 2. View cells over the package bounds (parametric instances included), solid cells dropped
  // by the voxelized surface of a coarser front (or the candidates themselves).
  start = Clock::now();
  ViewCellGrid grid;
  {
    DagFront coarse;
    std::vector<CandidateMesh> coarse_meshes;
    const bool own_front = options.max_classification_triangles > 0 &&
                           options.max_classification_triangles < front.triangles;
    if (own_front) {
      coarse = finestFrontWithin(view, options.max_classification_triangles);
      coarse_meshes = decodeCandidates(view, coarse);
    }
    const std::vector<CandidateMesh>& surface = own_front ? coarse_meshes : meshes;
    std::vector<glm::vec3> positions;
    std::vector<uint32_t> indices;
    size_t vertex_total = 0, index_total = 0;
    for (const CandidateMesh& m : surface) {
      vertex_total += m.positions.size();
      index_total += m.indices.size();
    }
    positions.reserve(vertex_total);
    indices.reserve(index_total);
    for (const CandidateMesh& m : surface) {
      const auto base = uint32_t(positions.size());
      positions.insert(positions.end(), m.positions.begin(), m.positions.end());
      for (uint32_t i : m.indices) indices.push_back(base + i);
    }
    const pkg::PackageHeader& h = view.header();
    const glm::dvec3 lo(h.bounds_min[0], h.bounds_min[1], h.bounds_min[2]);
    const glm::dvec3 hi(h.bounds_max[0], h.bounds_max[1], h.bounds_max[2]);
    grid = buildViewCells(positions, indices, lo, hi, options.cells);
  }
  rep.voxelize_s = secondsSince(start);
  rep.grid_cells = grid.cellCount();
  rep.free_cells = uint32_t(grid.free_cells.size());
  rep.solid_cells = grid.solid_cells;
  rep.cell_size_m = grid.cell_size_m;
  updateProgress(progress, 2);

  // 3. One Embree geometry per candidate, user id = cluster id, so a hit names its cluster. The
  // vectors move into Embree, which reads them in place.
  start = Clock::now();
  EmbreeScene scene(view.origin());
  for (size_t i = 0; i < meshes.size(); ++i)
    scene.addMesh(std::move(meshes[i].positions), std::move(meshes[i].indices), front.clusters[i]);
  meshes = {};
  scene.commit();
  rep.embree_build_s = secondsSince(start);
  updateProgress(progress, 3);
  endStage(progress);

  // 4. Rays, occluder and visible sets.
  start = Clock::now();
  VisibilitySamplingOptions sampling = options.sampling;
  if (!sampling.progress) sampling.progress = progress;
  VisibilityData data = sampleVisibility(scene, grid, sampling);
  rep.sampling_s = secondsSince(start);
  data.candidate_level = front.level;
  data.candidate_triangles = front.triangles;

  rep.rays = data.rays_cast;
  uint64_t occluders = 0, visible = 0;
  for (const VisibilityCell& cell : data.cells) {
    occluders += cell.occluders.size();
    visible += cell.visible.size();
  }
  if (!data.cells.empty()) {
    rep.average_occluders = double(occluders) / double(data.cells.size());
    rep.average_visible = double(visible) / double(data.cells.size());
  }
  std::vector<uint8_t> bytes = encodeVisibility(data);
  rep.section_bytes = bytes.size();
  return bytes;
}

}  // namespace tw
