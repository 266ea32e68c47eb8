// The visibility stage: candidates decoded from the package, view cells, Embree, sampling, the
// encoded section. See visibility_build.h.
#include "visibility_build.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numeric>

#include <tbb/parallel_for.h>

#include "dag_front.h"
#include "embree_scene.h"
#include "instance_primitive.h"
#include "tessellate.h"
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

bool isParametric(const pkg::ClusterRecord& r) {
  return r.kind == static_cast<uint8_t>(pkg::ClusterKind::Parametric);
}

// An instance's width: the second largest edge of its canonical box as placed (each edge scaled
// by its axis's length in the linear part). A pipe's is its diameter, a deck's or a wall's its
// smaller side; 0 for parameters that draw nothing.
float instanceWidth(const pkg::InstanceRecord& in, std::span<const glm::vec2> profile_points) {
  glm::vec3 lo, hi;
  if (!instanceLocalBox(in, profile_points, lo, hi)) return 0.0f;
  const glm::mat3 linear = instanceLinear(in);
  float edges[3];
  for (int a = 0; a < 3; ++a) edges[a] = (hi[a] - lo[a]) * glm::length(linear[a]);
  std::sort(edges, edges + 3);
  return std::isfinite(edges[1]) ? edges[1] : 0.0f;
}

// Which instances become candidates (a flag per instance): the widest first, ties by index,
// while their triangles at `tolerance` (counted, not built) stay within the budget. The smaller
// ones let rays through, which can only add to the sets.
std::vector<uint8_t> chooseParametricOccluders(const PackageView& view, float tolerance,
                                               uint64_t budget, VisibilityBuildReport& rep) {
  const auto instances = view.instances();
  std::vector<float> width(instances.size());
  std::vector<uint32_t> triangles(instances.size());
  tbb::parallel_for(size_t(0), instances.size(), [&](size_t i) {
    const Primitive primitive = primitiveOf(instances[i], view.profilePoints());
    width[i] = instanceWidth(instances[i], view.profilePoints());
    triangles[i] = uint32_t(std::min<uint64_t>(primitiveTriangleCount(primitive, tolerance),
                                               UINT32_MAX));
  });
  std::vector<uint32_t> order(instances.size());
  std::iota(order.begin(), order.end(), 0u);
  std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
    return width[a] != width[b] ? width[a] > width[b] : a < b;
  });
  std::vector<uint8_t> taken(instances.size(), 0);
  uint64_t total = 0;
  for (uint32_t i : order) {
    if (width[i] <= 0.0f || total + triangles[i] > budget) break;
    total += triangles[i];
    taken[i] = 1;
    ++rep.parametric_instances;
    rep.parametric_min_width_m = width[i];
  }
  return taken;
}

// The taken instances of parametric cluster `cluster`, tessellated at `tolerance` and placed in the
// package frame (the frame of decoded mesh clusters).
CandidateMesh tessellateParametricCluster(const PackageView& view, uint32_t cluster,
                                          float tolerance, const std::vector<uint8_t>& taken) {
  const pkg::ClusterRecord& c = view.clusters()[cluster];
  CandidateMesh out;
  TriangleMesh local;
  for (uint32_t i = c.instance_first; i < c.instance_first + c.instance_count; ++i) {
    if (!taken[i]) continue;
    const pkg::InstanceRecord& in = view.instances()[i];
    local.positions.clear();
    local.normals.clear();
    local.indices.clear();
    tessellatePrimitive(primitiveOf(in, view.profilePoints()), tolerance, local);
    const glm::mat3 linear = instanceLinear(in);
    const glm::vec3 origin(in.origin[0], in.origin[1], in.origin[2]);
    const auto base = uint32_t(out.positions.size());
    for (const glm::vec3& p : local.positions) out.positions.push_back(origin + linear * p);
    for (uint32_t index : local.indices) out.indices.push_back(base + index);
  }
  return out;
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
  if (front.clusters.empty()) return {};  // no mesh: no DAG front for the cells to name

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
  std::vector<uint32_t> parametric_candidates;  // ascending
  if (options.parametric_candidates) {
    std::vector<uint32_t> parametric;
    for (uint32_t c = 0; c < view.clusters().size(); ++c)
      if (isParametric(view.clusters()[c])) parametric.push_back(c);
    if (!parametric.empty()) {
      const float tolerance = options.parametric_tolerance_m;
      const std::vector<uint8_t> taken = chooseParametricOccluders(
          view, tolerance, options.max_parametric_triangles, rep);
      std::vector<CandidateMesh> tessellated(parametric.size());
      tbb::parallel_for(size_t(0), parametric.size(), [&](size_t i) {
        tessellated[i] = tessellateParametricCluster(view, parametric[i], tolerance, taken);
      });
      for (size_t i = 0; i < parametric.size(); ++i) {
        if (tessellated[i].indices.empty()) continue;
        rep.parametric_triangles += tessellated[i].indices.size() / 3;
        scene.addMesh(std::move(tessellated[i].positions), std::move(tessellated[i].indices),
                      parametric[i]);
        ++rep.parametric_clusters;
        // A cluster is a candidate (a visible set is complete for it) only when every one of
        // its instances was sampled; the others stay always visible.
        const pkg::ClusterRecord& c = view.clusters()[parametric[i]];
        if (std::all_of(taken.begin() + c.instance_first,
                        taken.begin() + c.instance_first + c.instance_count,
                        [](uint8_t t) { return t != 0; }))
          parametric_candidates.push_back(parametric[i]);
      }
      rep.parametric_instances_total = view.instances().size();
      rep.parametric_candidates = parametric_candidates.size();
    }
  }
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
  data.parametric_occluders = rep.parametric_clusters > 0;
  data.parametric_candidates = std::move(parametric_candidates);

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
