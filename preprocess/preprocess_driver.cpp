// The preprocessing run: stage order, the resume store, timing and the report.
#include "preprocess_driver.h"

#include <sys/resource.h>

#include <chrono>
#include <limits>
#include <memory>
#include <stdexcept>

#include <tbb/global_control.h>

#include "brick_cache.h"
#include "brick_seams.h"
#include "cluster_dag.h"
#include "dag_merge.h"
#include "dag_serialization.h"
#include "parametrics/instance_flag_marking.h"
#include "package_assembly.h"
#include "package_rewrite.h"
#include "package_view.h"
#include "package_writer.h"
#include "parametrics/parametric_clusters.h"
#include "parametrics/parametric_external_sort.h"
#include "quantization_snap.h"
#include "scene_bricking.h"
#include "visibility_build.h"

namespace tw {
namespace {

using Clock = std::chrono::steady_clock;

// Bumped whenever the preprocessor's output changes for the same inputs and options, so that a
// resume never mixes bricks built by two versions.
constexpr uint32_t kPreprocessorRevision = 3;

uint64_t peakRssBytes() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<uint64_t>(usage.ru_maxrss) * 1024;  // Linux reports KiB
}

class StageClock {
 public:
  explicit StageClock(PreprocessReport& report) : report_(report) {}
  void start(const char* name) {
    stop();
    name_ = name;
    start_ = Clock::now();
  }
  void stop() {
    if (name_.empty()) return;
    report_.stages.push_back(
        {name_, std::chrono::duration<double>(Clock::now() - start_).count()});
    name_.clear();
  }

 private:
  PreprocessReport& report_;
  std::string name_;
  Clock::time_point start_;
};

double secondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

void throwIfCancelled(Progress* progress) {
  if (progress && progress->cancelled()) throw std::runtime_error("cancelled");
}

// The new parent of a brick root, from the merge (group in the whole DAG's numbering).
struct RootParent {
  uint32_t group = kNoGroup;
  float error = std::numeric_limits<float>::infinity();
  glm::vec3 lod_center{0.0f};
  float lod_radius = 0.0f;
};

// What stays in memory of a finished brick while its DAG waits in the resume store.
struct BrickRecord {
  uint32_t first_cluster = 0;  // its clusters' and groups' first indices in the whole DAG
  uint32_t first_group = 0;
  uint32_t cluster_count = 0;
  uint32_t group_count = 0;
  std::vector<uint32_t> root_ids;  // brick-local, ascending
  std::vector<RootParent> root_parents;  // one per root, after the merge
  std::vector<uint8_t> exported;   // one per cluster: is a root (built on demand)
};

// A brick's snapping input: its seams and roots are shared with other pieces.
SnapPiece brickSnapPiece(const ClusterDag& dag, BrickRecord& brick) {
  if (dag.clusters.size() != brick.cluster_count)
    throw std::runtime_error("preprocess: a brick changed in the resume store during the run");
  brick.exported.assign(brick.cluster_count, 0);
  for (uint32_t id : brick.root_ids) brick.exported[id] = 1;
  return {dag.clusters, brick.exported, SharedPositions::SeamsAndRoots};
}

std::unique_ptr<ClusterDag> loadBrickDag(const BrickCache& cache, uint32_t b) {
  std::optional<std::vector<uint8_t>> blob = cache.load(b);
  if (!blob)
    throw std::runtime_error("preprocess: brick " + std::to_string(b) +
                             " vanished from the resume store " + cache.blobPath(b).string());
  return std::make_unique<ClusterDag>(deserializeClusterDag(*blob, cache.blobPath(b).string()));
}

// Into the whole DAG's numbering, with the roots' parents from the merge.
void renumberBrick(ClusterDag& dag, const BrickRecord& brick) {
  auto rebase = [](uint32_t index, uint32_t base) {
    return index == kNoGroup ? kNoGroup : index + base;
  };
  for (DagCluster& c : dag.clusters) {
    c.group = rebase(c.group, brick.first_group);
    c.parent_group = rebase(c.parent_group, brick.first_group);
  }
  for (DagGroup& g : dag.groups) {
    for (uint32_t& child : g.children) child += brick.first_cluster;
    for (uint32_t& made : g.clusters) made += brick.first_cluster;
  }
  for (size_t r = 0; r < brick.root_ids.size(); ++r) {
    DagCluster& c = dag.clusters[brick.root_ids[r]];
    const RootParent& parent = brick.root_parents[r];
    c.parent_group = parent.group;
    c.parent_error = parent.error;
    c.parent_lod_center = parent.lod_center;
    c.parent_lod_radius = parent.lod_radius;
  }
}

void addLevels(std::vector<uint64_t>& triangles_per_level, const ClusterDag& dag) {
  for (const DagCluster& c : dag.clusters) {
    if (triangles_per_level.size() <= c.level) triangles_per_level.resize(c.level + 1, 0);
    triangles_per_level[c.level] += c.triangleCount();
  }
}

// Builds the visibility section of the package at `path` and stores it there.
VisibilitySummary addVisibility(const std::filesystem::path& path,
                                const PreprocessOptions& options) {
  VisibilityBuildOptions build;
  build.cells.cell_size_m = options.view_cell_size_m;
  build.sampling.rays_per_cell = options.visibility_rays;
  build.progress = options.progress;
  VisibilityBuildReport built;
  std::vector<uint8_t> bytes;
  {
    const PackageView view = PackageView::open(path);
    bytes = buildVisibilitySection(view, build, &built);
  }
  VisibilitySummary summary;
  summary.ran = true;
  summary.candidate_level = built.candidate_level;
  summary.candidate_triangles = built.candidate_triangles;
  summary.cell_size_m = built.cell_size_m;
  summary.free_cells = built.free_cells;
  summary.solid_cells = built.solid_cells;
  summary.rays = built.rays;
  summary.average_occluders = built.average_occluders;
  summary.average_visible = built.average_visible;
  summary.section_bytes = bytes.size();
  summary.rays_per_second = built.sampling_s > 0 ? double(built.rays) / built.sampling_s : 0.0;
  summary.decode_s = built.decode_s;
  summary.voxelize_s = built.voxelize_s;
  summary.embree_build_s = built.embree_build_s;
  summary.sampling_s = built.sampling_s;
  if (!bytes.empty()) replacePackageSection(path, pkg::SectionType::Visibility, bytes);
  return summary;
}

}  // namespace

PreprocessReport runPreprocess(const PreprocessOptions& options) {
  if (options.inputs.empty()) throw std::invalid_argument("no input files");
  if (options.parametric_cluster_size < 1 || options.parametric_cluster_size > 65536)
    throw std::invalid_argument("preprocess: parametric cluster size must be 1..65536");
  if (options.cluster_size < 64 || options.cluster_size > 4096)
    throw std::invalid_argument("cluster size must be between 64 and 4096 triangles");
  auto run_start = Clock::now();
  PreprocessReport report;
  StageClock clock(report);
  Progress* progress = options.progress;
  std::unique_ptr<tbb::global_control> thread_limit;
  if (options.threads > 0)
    thread_limit = std::make_unique<tbb::global_control>(
        tbb::global_control::max_allowed_parallelism, options.threads);

  BrickingOptions bricking;
  bricking.work_dir = workDirFor(options.output);
  bricking.memory_budget_bytes = options.memory_budget_bytes;
  bricking.max_brick_triangles = options.max_brick_triangles;
  bricking.position_step_m = pkg::kDefaultPositionStepM;
  bricking.progress = progress;
  DagOptions dag_options;
  dag_options.cluster_size = options.cluster_size;

  RunHash hash;
  hash.addValue(kPreprocessorRevision);
  for (const auto& input : options.inputs) hash.addFile(std::filesystem::absolute(input));
  hash.addBrickingOptions(bricking);
  hash.addValue(options.cluster_size);
  hash.addValue(options.parametric_cluster_size);
  if (!options.resume) removeWorkDir(bricking.work_dir);
  BrickCache cache(bricking.work_dir, hash.digest());

  // 1. Bricks on disk (or the finished bricking of a killed run).
  BrickedScene scene;
  if (options.resume) {
    if (auto stored = loadBrickedScene(cache, bricking.work_dir)) {
      scene = std::move(*stored);
      report.bricking_reused = true;
    }
  }
  if (!report.bricking_reused) {
    clock.start("survey");
    SceneSurvey survey = surveyScene(options.inputs, bricking.nurbs_tolerance, progress);
    throwIfCancelled(progress);
    clock.start("brick");
    scene = brickScene(options.inputs, survey, bricking);
    storeBrickedScene(cache, scene);
  }
  throwIfCancelled(progress);
  report.input_triangles = scene.triangle_count;
  report.primitives = scene.parametric_count;
  report.objects = scene.object_count;
  report.triangles_turned = scene.triangles_turned;
  report.bricks = static_cast<uint32_t>(scene.bricks.size());

  // 2. One LOD DAG per brick, seams locked so neighbouring bricks never crack. A finished brick
  // goes to the resume store; memory keeps its roots (for the merge) and its quantization shifts
  // (snapping pass 1, solved now while it is in memory). The last brick's DAG stays too when it
  // is within budget / 8, so a one-brick model is never read back.
  // Only the true seams are locked: the model's own open edges (uncapped pipes, sheets) stay free
  // to simplify and drop, as in a one-brick build, which needs no locking at all.
  DagOptions brick_options = dag_options;
  BrickSeams seams;
  if (scene.bricks.size() > 1) {
    clock.start("seams");
    seams = BrickSeams::find(scene, progress);
    report.seam_edges = seams.size();
    brick_options.lock_open_boundaries = true;
    brick_options.is_seam_edge = [&seams](const glm::vec3& a, const glm::vec3& b) {
      return seams.contains(a, b);
    };
  }
  clock.start("build bricks");
  beginStage(progress, "build bricks", scene.bricks.size());
  PackageStorage storage;
  brick_options.position_step_m = storage.position_step_m;
  QuantizationSnapper snapper(storage.position_step_m);
  const uint64_t resident_limit = options.memory_budget_bytes / 8;
  std::vector<BrickRecord> bricks(scene.bricks.size());
  std::vector<std::unique_ptr<ClusterDag>> resident(scene.bricks.size());
  std::vector<DagCluster> roots;
  uint64_t total_clusters = 0, total_groups = 0;
  double snap_in_build = 0.0, snap_in_pack = 0.0;  // reported as a stage of its own
  for (uint32_t b = 0; b < scene.bricks.size(); ++b) {
    throwIfCancelled(progress);
    std::optional<std::vector<uint8_t>> blob;
    if (options.resume) blob = cache.load(b);
    ClusterDag dag;
    if (blob) {
      dag = deserializeClusterDag(*blob, cache.blobPath(b).string());
      ++report.bricks_reused;
    } else {
      BrickMesh mesh = loadBrick(scene, b);
      dag = buildClusterDag(
          DagInput{mesh.positions, mesh.indices, mesh.triangle_object_ids}, brick_options);
      mesh = BrickMesh{};
      blob = serializeClusterDag(dag);
      cache.store(b, *blob);
    }
    const uint64_t dag_bytes = blob->size();
    blob.reset();
    BrickRecord& brick = bricks[b];
    brick.first_cluster = uint32_t(total_clusters);
    brick.first_group = uint32_t(total_groups);
    brick.cluster_count = uint32_t(dag.clusters.size());
    brick.group_count = uint32_t(dag.groups.size());
    total_clusters += dag.clusters.size();
    total_groups += dag.groups.size();
    if (total_clusters >= pkg::kNone || total_groups >= pkg::kNone)
      throw std::runtime_error("preprocess: too many clusters or groups for the package format");
    for (uint32_t c = 0; c < dag.clusters.size(); ++c)
      if (dag.clusters[c].parent_group == kNoGroup) {
        brick.root_ids.push_back(c);
        roots.push_back(dag.clusters[c]);
        report.merge_front_triangles += dag.clusters[c].triangleCount();
      }
    addLevels(report.triangles_per_level, dag);
    // Only the last brick may stay: earlier ones would sit beside every later brick build, which
    // is where the peak is. A one-brick model is then never read back (nor welded twice).
    const bool keep = b + 1 == scene.bricks.size() && dag_bytes <= resident_limit;
    const auto snap_start = Clock::now();
    snapper.solve(b, brickSnapPiece(dag, brick), keep);
    snap_in_build += secondsSince(snap_start);
    if (keep) resident[b] = std::make_unique<ClusterDag>(std::move(dag));
    updateProgress(progress, b + 1);
  }
  endStage(progress);
  throwIfCancelled(progress);

  // 3. Upper levels from all the bricks' roots, renumbered after the bricks' clusters and groups;
  // the roots' new parents are noted for when their bricks are packed.
  clock.start("merge");
  beginStage(progress, "merge bricks", 0);
  ClusterDag upper;
  {
    MergedRoots merged = mergeBrickRoots(std::move(roots), dag_options);
    roots = {};
    report.root_triangles = merged.dag.root_triangles;
    std::vector<uint32_t> root_global;  // merged front index -> DAG cluster
    for (BrickRecord& brick : bricks) {
      for (uint32_t id : brick.root_ids) root_global.push_back(brick.first_cluster + id);
      brick.root_parents.resize(brick.root_ids.size());
    }
    auto group_id = [&](uint32_t g) {
      return g == kNoGroup ? kNoGroup : uint32_t(total_groups) + g;
    };
    uint32_t f = 0;
    for (BrickRecord& brick : bricks)
      for (RootParent& parent : brick.root_parents) {
        const DagCluster& root = merged.dag.clusters[f++];
        parent = {group_id(root.parent_group), root.parent_error, root.parent_lod_center,
                  root.parent_lod_radius};
      }
    appendMergedLevels(merged, root_global, uint32_t(total_clusters), uint32_t(total_groups),
                       upper.clusters, upper.groups);
    addLevels(report.triangles_per_level, upper);
  }
  if (total_clusters + upper.clusters.size() >= pkg::kNone ||
      total_groups + upper.groups.size() >= pkg::kNone)
    throw std::runtime_error("preprocess: too many clusters or groups for the package format");
  const uint32_t upper_piece = uint32_t(bricks.size());
  const SnapPiece upper_snap{upper.clusters, {}, SharedPositions::All};
  snapper.solve(upper_piece, upper_snap, true);
  endStage(progress);
  report.clusters = total_clusters + upper.clusters.size();

  // 4. Package records: layers, objects, mesh clusters, parametric clusters. Mesh clusters go
  // brick by brick, then the merged levels (so each group's produced clusters stay contiguous);
  // finished pages stream to a spill file in the work dir.
  clock.start("pack");
  beginStage(progress, "pack", bricks.size() + 1);
  // Snapping pass 1 to its fixpoint: a piece whose shared vertices another piece coarsened is
  // solved again (rare; a re-read brick at most).
  const auto fixpoint_start = Clock::now();
  for (std::vector<uint32_t> stale = snapper.stalePieces(); !stale.empty();
       stale = snapper.stalePieces()) {
    for (uint32_t p : stale) {
      if (p == upper_piece) {
        snapper.solve(p, upper_snap, true);
        continue;
      }
      std::unique_ptr<ClusterDag> loaded;
      const ClusterDag& dag = resident[p] ? *resident[p] : *(loaded = loadBrickDag(cache, p));
      snapper.solve(p, brickSnapPiece(dag, bricks[p]), resident[p] != nullptr);
      ++report.bricks_resolved;
    }
  }
  snap_in_pack += secondsSince(fixpoint_start);
  storage.origin = scene.origin;
  storage.input_hash = cache.runHash();
  std::filesystem::create_directories(bricking.work_dir);
  // Pages and tables stream to files as they are filled: what stays in memory while packing is
  // one brick's DAG, the open page and a short tail of each table, whatever the model's size.
  storage.spillPagesTo(bricking.work_dir / "pages.spill");
  // Each table keeps about budget / 1024 in memory (2 MiB at the default 2G).
  storage.spillTablesTo(bricking.work_dir / "tables",
                        std::clamp<uint64_t>(options.memory_budget_bytes / 1024, 1024, 4u << 20));
  for (const Layer& layer : scene.layers) storage.addLayer(layer);
  std::vector<uint32_t> object_layers;  // for the covered-face search: 4 bytes an object
  forEachObject(scene, [&](const BrickedObject& object) {
    object_layers.push_back(object.layer);
    ObjectInfo info;
    info.id = object.source_id;
    info.name = object.name;
    info.layer = object.layer;
    info.db_key = object.db_key;
    info.color_rgba = object.color_rgba;
    storage.addObject(info, object.bounds_min, object.bounds_max,
                      object.closed_surface ? pkg::kObjectClosedSurface : 0u);
  });
  report.shared_positions = snapper.sharedPositions();
  DagPlacement placement = beginDagPlacement(storage);
  placement.max_shift = snapper.maxShift();
  placement.coarsened_vertices = snapper.coarsenedVertices();
  // Snapping moves a vertex by up to half a cell of the coarsest grid: every lod sphere grows by
  // that much (package_assembly.h).
  placement.lod_slack =
      static_cast<float>(quantizationErrorM(storage.position_step_m, placement.max_shift));
  std::vector<uint32_t> shifts;
  for (uint32_t b = 0; b < bricks.size(); ++b) {
    throwIfCancelled(progress);
    std::unique_ptr<ClusterDag> dag = resident[b] ? std::move(resident[b]) : loadBrickDag(cache, b);
    BrickRecord& brick = bricks[b];
    const auto snap_start = Clock::now();
    const auto snapped = snapper.snap(b, brickSnapPiece(*dag, brick), shifts);
    snap_in_pack += secondsSince(snap_start);
    renumberBrick(*dag, brick);
    addDagPieceToPackage(*dag, brick.first_cluster, brick.first_group, snapped, shifts, placement,
                         storage);
    updateProgress(progress, b + 1);
  }
  {
    const auto snapped = snapper.snap(upper_piece, upper_snap, shifts);
    addDagPieceToPackage(upper, uint32_t(total_clusters), uint32_t(total_groups), snapped, shifts,
                         placement, storage);
    upper = ClusterDag{};
  }
  // Parametric clusters out of core: sorted runs within budget / 8, merged into the storage.
  ParametricSortOptions sort_options;
  sort_options.work_dir = bricking.work_dir / "parametric-runs";
  sort_options.memory_budget_bytes = std::max<uint64_t>(options.memory_budget_bytes / 8, 1u << 20);
  sort_options.max_per_cluster = options.parametric_cluster_size;
  const ParametricStream parametrics =
      [&](const std::function<void(std::span<const ParametricItem>)>& sink) {
        std::vector<ParametricItem> items;
        forEachParametricBatch(scene, 4096, [&](std::span<const ParametricRecord> batch) {
          items.clear();
          for (const ParametricRecord& r : batch)
            items.push_back({r.object, r.primitive, r.transform});
          sink(items);
        });
      };
  // Sealed pipe runs and covered box faces, searched once here rather than at every start of
  // the runtime.
  const InstanceFlagMarking marked = markInstanceFlags(parametrics, storage.origin, object_layers);
  object_layers = {};
  sort_options.instance_role_flags = marked.role_flags;
  storage.sealed_runs_marked = true;
  storage.covered_faces_marked = true;
  report.sealed_run_members = marked.sealed.sealed_members;
  report.sealed_run_closers = marked.sealed.closers;
  report.covered_box_faces = marked.covered.covered_faces;
  const ParametricSortStats sorted = addParametricClustersOutOfCore(parametrics, sort_options, storage);
  report.parametric_clusters = sorted.clusters;
  report.parametric_sort_runs = sorted.runs;
  endStage(progress);

  // 5. One file, written atomically; with visibility, first inside the work directory, so the
  // final name only ever holds a finished package.
  clock.start("write");
  beginStage(progress, "write package", 0);
  const std::filesystem::path written_path =
      options.visibility ? bricking.work_dir / "package.twk" : options.output;
  PackageWriteStats written = writePackage(storage, written_path);
  storage = PackageStorage{};
  endStage(progress);
  report.package_bytes = written.file_bytes;
  throwIfCancelled(progress);

  // 6. Visibility, from the written package; its section replaces the empty one.
  if (options.visibility) {
    clock.start("visibility");
    report.visibility = addVisibility(written_path, options);
    std::filesystem::rename(written_path, options.output);
    report.package_bytes = std::filesystem::file_size(options.output);
  }
  clock.stop();
  // Snapping ran inside "build bricks" and "pack": shown apart, the stages still sum to the run.
  for (StageTime& stage : report.stages) {
    if (stage.name == "build bricks") stage.seconds -= snap_in_build;
    if (stage.name == "pack") stage.seconds -= snap_in_pack;
  }
  for (size_t i = 0; i < report.stages.size(); ++i)
    if (report.stages[i].name == "pack") {
      report.stages.insert(report.stages.begin() + i, {"snap", snap_in_build + snap_in_pack});
      break;
    }
  if (!options.keep_work_dir) removeWorkDir(bricking.work_dir);
  report.peak_rss_bytes = peakRssBytes();
  report.seconds = std::chrono::duration<double>(Clock::now() - run_start).count();
  return report;
}

}  // namespace tw
