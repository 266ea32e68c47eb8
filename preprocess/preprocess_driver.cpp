// The preprocessing run: stage order, the resume store, timing and the report.
#include "preprocess_driver.h"
#include "preprocess_steps.h"

#include <sys/resource.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include <algorithm>
#include <fstream>
#include <cmath>
#include <chrono>
#include <limits>
#include <memory>
#include <optional>
#include <stdexcept>

#include <tbb/global_control.h>

#include "brick_cache.h"
#include "brick_seams.h"
#include "cluster_dag.h"
#include "dag_merge.h"
#include "dag_serialization.h"
#include "memory_need.h"
#include "near_group_vertices.h"
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
constexpr uint32_t kPreprocessorRevision = 5;  // 5: rims almost meeting in a group joined

uint64_t peakRssBytes() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<uint64_t>(usage.ru_maxrss) * 1024;  // Linux reports KiB
}

// The resident high-water mark since the last resetPeakRss (Linux: VmHWM); 0 when unknown.
uint64_t peakRssSinceReset() {
  std::ifstream status("/proc/self/status");
  std::string word;
  while (status >> word)
    if (word == "VmHWM:") {
      uint64_t kib = 0;
      status >> kib;
      return kib * 1024;
    }
  return 0;
}

// Lets one process report each brick job's own peak (a rank builds several).
void resetPeakRss() {
  std::ofstream clear("/proc/self/clear_refs");
  clear << "5";
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
SnapPiece brickSnapPiece(const ClusterDag& dag, BrickRecord& brick,
                         std::function<bool(const glm::vec3&)> near_other_brick) {
  if (dag.clusters.size() != brick.cluster_count)
    throw std::runtime_error("preprocess: a brick changed in the resume store during the run");
  brick.exported.assign(brick.cluster_count, 0);
  for (uint32_t id : brick.root_ids) brick.exported[id] = 1;
  return {dag.clusters, brick.exported, SharedPositions::SeamsAndRoots,
          std::move(near_other_brick)};
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

// Adds the groups of `groups` to the per-method counts (index: GroupMethod).
void addGroupMethods(GroupMethodCounts& counts, const std::vector<DagGroup>& groups) {
  for (const DagGroup& g : groups) ++counts[size_t(g.method)];
}

// Builds the visibility section of the package at `path` and stores it there.
VisibilitySummary addVisibility(const std::filesystem::path& path,
                                const PreprocessOptions& options) {
  VisibilityBuildOptions build;
  build.cells.cell_size_m = options.view_cell_size_m;
  build.sampling.rays_per_cell = options.visibility_rays;
  build.parametric_candidates = options.parametric_occluders;
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
  summary.parametric_clusters = built.parametric_clusters;
  summary.parametric_candidates = built.parametric_candidates;
  summary.parametric_triangles = built.parametric_triangles;
  summary.parametric_instances = built.parametric_instances;
  summary.parametric_instances_total = built.parametric_instances_total;
  summary.parametric_min_width_m = built.parametric_min_width_m;
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

// One run of the preprocessor: the state its stages hand on to each other, and the stages in
// the order they run (runPreprocess below).
class PreprocessRun {
 public:
  explicit PreprocessRun(const PreprocessOptions& options)
      : options_(options),
        progress_(options.progress),
        run_start_(Clock::now()),
        clock_(report_),
        snapper_(storage_.position_step_m),
        cache_(openCache()) {}

  // The steps of a split run (preprocess_steps.h) read what the plan left and never redo it.
  void requirePlan(uint64_t plan_run_hash);
  void brickInputs();
  void findSeams();
  float inputNoiseTolerance() const;
  uint32_t brickStopLevel() const;
  void buildBricks();
  void requireBuiltBricks() const;
  BrickJobReport buildBrickJob(uint32_t b);
  const BrickedScene& scene() const { return scene_; }
  const PreprocessReport& report() const { return report_; }
  uint64_t runHash() const { return cache_.runHash(); }
  void mergeUpperLevels();
  void pack();
  void write();
  void buildVisibility();
  PreprocessReport finish();

 private:
  BrickCache openCache();
  void packObjects();
  void snapToFixpoint();
  std::string databasePathFrom(const std::filesystem::path& package) const;
  void packMeshClusters();
  void packParametricClusters();
  DagOptions optionsForBrick(uint32_t b) const;
  void prepareBrickOptions();
  ClusterDag buildBrickDag(uint32_t b);
  SnapPiece upperSnapPiece() const { return {upper_.clusters, {}, SharedPositions::All, {}}; }

  const PreprocessOptions& options_;
  Progress* progress_;
  Clock::time_point run_start_;
  PreprocessReport report_;
  StageClock clock_;
  std::unique_ptr<tbb::global_control> thread_limit_;
  BrickingOptions bricking_;
  DagOptions dag_options_;
  DagOptions brick_options_;
  PackageStorage storage_;
  QuantizationSnapper snapper_;
  BrickCache cache_;
  bool plan_must_exist_ = false;
  BrickedScene scene_;
  BrickSeams seams_;
  std::vector<BrickRecord> bricks_;
  std::vector<std::unique_ptr<ClusterDag>> resident_;  // bricks kept in memory after their build
  std::vector<DagCluster> roots_;                      // every brick's roots, for the merge
  ClusterDag upper_;                                   // the merged levels above the bricks
  uint32_t upper_piece_ = 0;                           // the merged levels' snapping piece
  uint64_t total_clusters_ = 0, total_groups_ = 0;    // in the bricks
  std::vector<uint32_t> object_layers_;  // for the covered-face search: 4 bytes an object
  std::filesystem::path written_path_;
  double snap_in_build_ = 0.0, snap_in_pack_ = 0.0;  // reported as a stage of its own
};

// The package's path, checked before anything is read: a run of hours must not fail at its final
// rename, nor write over one of its own inputs.
void validateOutput(const PreprocessOptions& options) {
  namespace fs = std::filesystem;
  const fs::path& out = options.output;
  if (out.empty()) throw std::invalid_argument("preprocess: the output path (-o) is empty");
  std::error_code ec;
  if (fs::is_directory(out, ec))
    throw std::invalid_argument(out.string() + ": is a directory; -o names the package file to write");
  for (const fs::path& input : options.inputs)
    if (fs::exists(out, ec) && fs::equivalent(out, input, ec))
      throw std::invalid_argument(out.string() + ": is also an input; writing the package there would destroy it");
  const fs::path folder = out.has_parent_path() ? out.parent_path() : fs::path(".");
  if (!fs::is_directory(folder, ec))
    throw std::invalid_argument(out.string() + ": the folder " + folder.string() + " does not exist");
  if (::access(folder.c_str(), W_OK | X_OK) != 0)
    throw std::invalid_argument(out.string() + ": the folder " + folder.string() +
                                " is not writable: " + std::strerror(errno));
}

// What a plan needs (no package path yet).
void validateBuildOptions(const PreprocessOptions& options) {
  if (options.inputs.empty()) throw std::invalid_argument("no input files");
  if (options.parametric_cluster_size < 1 || options.parametric_cluster_size > 65536)
    throw std::invalid_argument("preprocess: parametric cluster size must be 1..65536");
  if (options.cluster_size < 64 || options.cluster_size > 4096)
    throw std::invalid_argument("cluster size must be between 64 and 4096 triangles");
  requireMemoryBudget(options.memory_budget_bytes, memoryNeed(0, 0, 0));
}

void validateOptions(const PreprocessOptions& options) {
  validateBuildOptions(options);
  validateOutput(options);
}

// The options of every stage, and the resume store keyed by the inputs and those options (a
// fresh run empties it first).
BrickCache PreprocessRun::openCache() {
  if (options_.threads > 0)
    thread_limit_ = std::make_unique<tbb::global_control>(
        tbb::global_control::max_allowed_parallelism, options_.threads);
  bricking_.work_dir = options_.work_dir.empty() ? workDirFor(options_.output) : options_.work_dir;
  bricking_.memory_budget_bytes = options_.memory_budget_bytes;
  bricking_.max_brick_triangles = options_.max_brick_triangles;
  bricking_.position_step_m = pkg::kDefaultPositionStepM;
  bricking_.progress = progress_;
  bricking_.exclude_layers = options_.exclude_layers;
  bricking_.up = options_.up;
  bricking_.cad = options_.cad;
  dag_options_.cluster_size = options_.cluster_size;

  RunHash hash;
  hash.addValue(kPreprocessorRevision);
  for (const auto& input : options_.inputs) hash.addFile(std::filesystem::absolute(input));
  hash.addBrickingOptions(bricking_);
  hash.addValue(options_.cluster_size);
  hash.addValue(options_.parametric_cluster_size);
  if (!options_.resume) removeWorkDir(bricking_.work_dir);
  return BrickCache(bricking_.work_dir, hash.digest());
}

// 1. Bricks on disk (or the finished bricking of a killed run): a survey of the inputs' bounds
// and sizes, then their triangles binned into bricks.
void PreprocessRun::brickInputs() {
  if (options_.resume) {
    if (auto stored = loadBrickedScene(cache_, bricking_.work_dir)) {
      scene_ = std::move(*stored);
      report_.bricking_reused = true;
    }
  }
  if (!report_.bricking_reused && plan_must_exist_)
    throw std::runtime_error(bricking_.work_dir.string() +
                             ": the plan's bricking is missing or damaged; run `terawalk preprocess "
                             "plan` again");
  if (!report_.bricking_reused) {
    clock_.start("survey");
    SceneSurvey survey = surveyScene(options_.inputs, bricking_.nurbs_tolerance, progress_,
                                     bricking_.exclude_layers, bricking_.up,
                                     bricking_.cad,
                                     readerVertexBytes(bricking_.memory_budget_bytes),
                                     bricking_.work_dir);
    throwIfCancelled(progress_);
    // The budget must hold the smallest brick this run can build (bricks sized from the budget
    // shrink with it down to kMinBrickTriangles) and the per-object and per-instance tables: if
    // it cannot, stop now rather than exceed it.
    const uint64_t smallest_brick =
        bricking_.max_brick_triangles ? bricking_.max_brick_triangles : kMinBrickTriangles;
    try {
      requireMemoryBudget(options_.memory_budget_bytes,
                          memoryNeed(std::min(smallest_brick, survey.triangles()),
                                     survey.objects, survey.primitives));
    } catch (...) {
      // The survey's vertex spill may have made the work folder; it holds nothing (the spill
      // file is unlinked) and a refused run leaves nothing behind.
      std::error_code ignored;
      std::filesystem::remove(bricking_.work_dir, ignored);
      throw;
    }
    clock_.start("brick");
    scene_ = brickScene(options_.inputs, survey, bricking_);
    storeBrickedScene(cache_, scene_);
  }
  throwIfCancelled(progress_);
  report_.input_triangles = scene_.triangle_count + scene_.triangles_repeated;
  report_.primitives = scene_.parametric_count;
  report_.objects = scene_.object_count;
  report_.triangles_turned = scene_.triangles_turned;
  report_.triangles_repeated = scene_.triangles_repeated;
  report_.bricks = static_cast<uint32_t>(scene_.bricks.size());
}

// How far apart two copies of one vertex may be and still be one, across bricks
// (cross_brick_weld.h) and inside one (grid_weld.h): the base step (bricking's grid) plus two
// float steps of the largest coordinate the readers stored, since a CAD export's noise is an ulp
// of the coordinates it wrote (at 290 m, 3e-5 m: two base steps), neither of the package's
// origin-relative ones nor of a placement's far origin (BrickedScene::stored_coordinate_extent).
float PreprocessRun::inputNoiseTolerance() const {
  const float stored = float(scene_.stored_coordinate_extent);
  const double ulp = double(std::nextafter(stored, INFINITY)) - double(stored);
  return float(storage_.position_step_m + 2.0 * ulp);
}

// 2a. The seams between bricks, locked in every brick's build so neighbouring bricks never
// crack. Only the true seams are locked: the model's own open edges (uncapped pipes, sheets) stay
// free to simplify and drop, as in a one-brick build, which needs no locking at all.
void PreprocessRun::findSeams() {
  brick_options_ = dag_options_;
  if (scene_.bricks.size() <= 1) return;
  clock_.start("seams");
  // Found once per bricking: a resumed run and every brick job read them back.
  std::optional<std::vector<uint8_t>> stored;
  if (report_.bricking_reused) stored = cache_.load(kBrickSeamsKey);
  if (stored) {
    seams_ = BrickSeams::deserialize(*stored, cache_.blobPath(kBrickSeamsKey).string());
  } else if (plan_must_exist_) {
    throw std::runtime_error(cache_.blobPath(kBrickSeamsKey).string() +
                             ": the plan's seams are missing or damaged; run `terawalk preprocess "
                             "plan` again");
  } else {
    seams_ = BrickSeams::find(scene_, inputNoiseTolerance(), progress_);
    cache_.store(kBrickSeamsKey, seams_.serialize());
  }
  report_.seam_edges = seams_.size();
  report_.welded_across_bricks = seams_.weldedPositions();
  brick_options_.lock_open_boundaries = true;
  brick_options_.is_seam_edge = [this](const glm::vec3& a, const glm::vec3& b) {
    return seams_.contains(a, b);
  };
  report_.brick_stop_level = brickStopLevel();
  brick_options_.max_levels = report_.brick_stop_level + 1;
}

// 2b. The level every brick's DAG stops at, where the merge takes over: the first at which the
// bricks' fronts, halving from their triangle counts, fit half a brick together.
//
// Why a common level: bricks left to run until their locked seams stop them end at different
// levels (on the 10M plant mesh, 6 to 9), and a brick that stops early keeps its root unchanged
// in every front up to the merge, so those fronts hardly shrink (0.84 to 1.0 of the front
// below). Stopping them all at one level hands the merge one front of equal depth, which it
// simplifies without seams, halving as a one-brick build does. Half a brick bounds the front
// held for the merge (and the merge's own build) by what one brick build already takes, however
// large the model. A brick whose seams stop it below that level still leaves a step there.
uint32_t PreprocessRun::brickStopLevel() const {
  uint64_t triangles = 0;
  for (const BrickInfo& brick : scene_.bricks) triangles += brick.triangle_count;
  const uint64_t front_limit = std::max<uint64_t>(scene_.max_brick_triangles / 2, 1);
  uint32_t level = 0;
  while (triangles > front_limit && level + 2 < dag_options_.max_levels) {
    triangles /= 2;
    ++level;
  }
  return level;
}

// The DAG options of brick b: the run's, plus (with several bricks) the test for rims lying
// within another brick's bounds, padded by twice the package's grid error at the coarsest grid
// a cluster of the model could use.
DagOptions PreprocessRun::optionsForBrick(uint32_t b) const {
  DagOptions options = brick_options_;
  if (scene_.bricks.size() <= 1) return options;
  glm::vec3 lo(INFINITY), hi(-INFINITY);
  for (const BrickInfo& brick : scene_.bricks) {
    lo = glm::min(lo, brick.bounds_min);
    hi = glm::max(hi, brick.bounds_max);
  }
  const float pad = packageGridTolerance(hi - lo, storage_.position_step_m);
  options.is_near_other_brick = [this, b, pad](const glm::vec3& p) {
    for (uint32_t other = 0; other < scene_.bricks.size(); ++other) {
      if (other == b) continue;
      const BrickInfo& box = scene_.bricks[other];
      if (glm::all(glm::lessThanEqual(box.bounds_min - pad, p)) &&
          glm::all(glm::lessThanEqual(p, box.bounds_max + pad)))
        return true;
    }
    return false;
  };
  return options;
}

// 2c. One LOD DAG per brick, up to the common stop level. A finished brick goes to the resume store; memory keeps its roots
// (for the merge) and its quantization shifts (snapping pass 1, solved now while it is in
// memory). The last brick's DAG stays too when it is within budget / 8, so a one-brick model is
// never read back.
void PreprocessRun::buildBricks() {
  clock_.start("build bricks");
  beginStage(progress_, "build bricks", scene_.bricks.size());
  prepareBrickOptions();
  const uint64_t resident_limit = options_.memory_budget_bytes / 8;
  bricks_.resize(scene_.bricks.size());
  resident_.resize(scene_.bricks.size());
  for (uint32_t b = 0; b < scene_.bricks.size(); ++b) {
    throwIfCancelled(progress_);
    std::optional<std::vector<uint8_t>> blob;
    if (options_.resume) blob = cache_.load(b);
    ClusterDag dag;
    if (blob) {
      dag = deserializeClusterDag(*blob, cache_.blobPath(b).string());
      ++report_.bricks_reused;
    } else if (plan_must_exist_) {
      throw std::runtime_error("preprocess: brick " + std::to_string(b) + " is not built (" +
                               cache_.blobPath(b).string() + ")");
    } else {
      dag = buildBrickDag(b);
      blob = serializeClusterDag(dag);
      cache_.store(b, *blob);
    }
    const uint64_t dag_bytes = blob->size();
    blob.reset();
    BrickRecord& brick = bricks_[b];
    brick.first_cluster = uint32_t(total_clusters_);
    brick.first_group = uint32_t(total_groups_);
    brick.cluster_count = uint32_t(dag.clusters.size());
    brick.group_count = uint32_t(dag.groups.size());
    total_clusters_ += dag.clusters.size();
    total_groups_ += dag.groups.size();
    if (total_clusters_ >= pkg::kNone || total_groups_ >= pkg::kNone)
      throw std::runtime_error("preprocess: too many clusters or groups for the package format");
    for (uint32_t c = 0; c < dag.clusters.size(); ++c)
      if (dag.clusters[c].parent_group == kNoGroup) {
        brick.root_ids.push_back(c);
        roots_.push_back(dag.clusters[c]);
        report_.merge_front_triangles += dag.clusters[c].triangleCount();
      }
    addLevels(report_.triangles_per_level, dag);
    addGroupMethods(report_.groups_by_method, dag.groups);
    // Only the last brick may stay: earlier ones would sit beside every later brick build, which
    // is where the peak is. A one-brick model is then never read back (nor welded twice).
    const bool keep = b + 1 == scene_.bricks.size() && dag_bytes <= resident_limit;
    const auto snap_start = Clock::now();
    snapper_.solve(b, brickSnapPiece(dag, brick, optionsForBrick(b).is_near_other_brick), keep);
    snap_in_build_ += secondsSince(snap_start);
    if (keep) resident_[b] = std::make_unique<ClusterDag>(std::move(dag));
    updateProgress(progress_, b + 1);
  }
  endStage(progress_);
  throwIfCancelled(progress_);
}

void PreprocessRun::prepareBrickOptions() {
  brick_options_.position_step_m = storage_.position_step_m;
  brick_options_.noise_tolerance_m = inputNoiseTolerance();
}

// One brick's DAG from its triangles, welded to its neighbours' rims.
ClusterDag PreprocessRun::buildBrickDag(uint32_t b) {
  BrickMesh mesh = loadBrick(scene_, b);
  seams_.weldAcrossBricks(mesh.positions);
  return buildClusterDag(DagInput{mesh.positions, mesh.indices, mesh.triangle_object_ids},
                         optionsForBrick(b));
}

// A step's work directory must hold the plan's bricking for the same inputs and options.
void PreprocessRun::requirePlan(uint64_t plan_run_hash) {
  plan_must_exist_ = true;
  if (cache_.runHash() != plan_run_hash)
    throw std::runtime_error(
        bricking_.work_dir.string() +
        ": the inputs (their sizes or modification times) or this terawalk changed since the "
        "plan was made; run `terawalk preprocess plan` again");
}

// The merge's precondition, with every missing brick named at once.
void PreprocessRun::requireBuiltBricks() const {
  std::string missing;
  uint32_t count = 0;
  for (uint32_t b = 0; b < scene_.bricks.size(); ++b)
    if (!std::filesystem::exists(cache_.blobPath(b))) {
      if (count++ < 20) missing += (missing.empty() ? "" : " ") + std::to_string(b);
    }
  if (count == 0) return;
  throw std::runtime_error(
      bricking_.work_dir.string() + ": " + std::to_string(count) + " of " +
      std::to_string(scene_.bricks.size()) + " bricks are not built (" + missing +
      (count > 20 ? " ..." : "") + "); run `terawalk preprocess brick --work " +
      bricking_.work_dir.string() + " --index N` for each");
}

// A brick job: the brick's DAG into the resume store, unless it is there already.
BrickJobReport PreprocessRun::buildBrickJob(uint32_t b) {
  if (b >= scene_.bricks.size())
    throw std::invalid_argument("preprocess brick: index " + std::to_string(b) +
                                " is not in the plan (" + std::to_string(scene_.bricks.size()) +
                                " bricks, 0.." + std::to_string(scene_.bricks.size() - 1) + ")");
  BrickJobReport job;
  job.index = b;
  job.triangles = scene_.bricks[b].triangle_count;
  if (cache_.has(b)) {
    job.already_built = true;
    return job;
  }
  resetPeakRss();
  const auto start = Clock::now();
  prepareBrickOptions();
  const ClusterDag dag = buildBrickDag(b);
  cache_.store(b, serializeClusterDag(dag));
  job.clusters = dag.clusters.size();
  job.seconds = secondsSince(start);
  job.peak_rss_bytes = peakRssSinceReset();
  return job;
}

// 3. Upper levels from all the bricks' roots, renumbered after the bricks' clusters and groups;
// the roots' new parents are noted for when their bricks are packed.
void PreprocessRun::mergeUpperLevels() {
  clock_.start("merge");
  beginStage(progress_, "merge bricks", 0);
  {
    // The merged levels hold near-touching rims of different groups too (near_group_vertices.h):
    // they need the package's grid step for it, which the merge uses for nothing else.
    DagOptions merge_options = dag_options_;
    merge_options.position_step_m = storage_.position_step_m;
    MergedRoots merged = mergeBrickRoots(std::move(roots_), merge_options);
    roots_ = {};
    report_.root_triangles = merged.dag.root_triangles;
    std::vector<uint32_t> root_global;  // merged front index -> DAG cluster
    for (BrickRecord& brick : bricks_) {
      for (uint32_t id : brick.root_ids) root_global.push_back(brick.first_cluster + id);
      brick.root_parents.resize(brick.root_ids.size());
    }
    auto group_id = [&](uint32_t g) {
      return g == kNoGroup ? kNoGroup : uint32_t(total_groups_) + g;
    };
    uint32_t f = 0;
    for (BrickRecord& brick : bricks_)
      for (RootParent& parent : brick.root_parents) {
        const DagCluster& root = merged.dag.clusters[f++];
        parent = {group_id(root.parent_group), root.parent_error, root.parent_lod_center,
                  root.parent_lod_radius};
      }
    appendMergedLevels(merged, root_global, uint32_t(total_clusters_), uint32_t(total_groups_),
                       upper_.clusters, upper_.groups);
    addLevels(report_.triangles_per_level, upper_);
    addGroupMethods(report_.groups_by_method, upper_.groups);
  }
  if (total_clusters_ + upper_.clusters.size() >= pkg::kNone ||
      total_groups_ + upper_.groups.size() >= pkg::kNone)
    throw std::runtime_error("preprocess: too many clusters or groups for the package format");
  upper_piece_ = uint32_t(bricks_.size());
  snapper_.solve(upper_piece_, upperSnapPiece(), true);
  endStage(progress_);
  report_.clusters = total_clusters_ + upper_.clusters.size();
}

// 4. Package records: layers, objects, mesh clusters, parametric clusters. Pages and tables
// stream to files in the work dir as they are filled: what stays in memory while packing is one
// brick's DAG, the open page and a short tail of each table, whatever the model's size.
void PreprocessRun::pack() {
  clock_.start("pack");
  beginStage(progress_, "pack", bricks_.size() + 1);
  snapToFixpoint();
  storage_.origin = scene_.origin;
  storage_.input_hash = cache_.runHash();
  std::filesystem::create_directories(bricking_.work_dir);
  storage_.spillPagesTo(bricking_.work_dir / "pages.spill");
  // Each table keeps about budget / 1024 in memory (2 MiB at the default 2G).
  storage_.spillTablesTo(bricking_.work_dir / "tables",
                         std::clamp<uint64_t>(options_.memory_budget_bytes / 1024, 1024, 4u << 20));
  if (!options_.database.empty()) storage_.setDatabasePath(databasePathFrom(options_.output));
  packObjects();
  packMeshClusters();
  packParametricClusters();
  endStage(progress_);
}

// The database as the package names it: relative to the package's folder when it can be, so
// a folder holding both can be moved or copied whole.
std::string PreprocessRun::databasePathFrom(const std::filesystem::path& package) const {
  const std::filesystem::path db = std::filesystem::absolute(options_.database).lexically_normal();
  const std::filesystem::path folder =
      std::filesystem::absolute(package).lexically_normal().parent_path();
  if (db.root_name() != folder.root_name()) return db.string();
  const std::filesystem::path relative = db.lexically_relative(folder);
  return relative.empty() ? db.string() : relative.string();
}

// Snapping pass 1 to its fixpoint: a piece whose shared vertices another piece coarsened is
// solved again (rare; a re-read brick at most).
void PreprocessRun::snapToFixpoint() {
  const auto fixpoint_start = Clock::now();
  for (std::vector<uint32_t> stale = snapper_.stalePieces(); !stale.empty();
       stale = snapper_.stalePieces()) {
    for (uint32_t p : stale) {
      if (p == upper_piece_) {
        snapper_.solve(p, upperSnapPiece(), true);
        continue;
      }
      std::unique_ptr<ClusterDag> loaded;
      const ClusterDag& dag = resident_[p] ? *resident_[p] : *(loaded = loadBrickDag(cache_, p));
      snapper_.solve(p, brickSnapPiece(dag, bricks_[p], optionsForBrick(p).is_near_other_brick),
                      resident_[p] != nullptr);
      ++report_.bricks_resolved;
    }
  }
  snap_in_pack_ += secondsSince(fixpoint_start);
}

void PreprocessRun::packObjects() {
  for (const Layer& layer : scene_.layers) storage_.addLayer(layer);
  forEachObject(scene_, [&](const BrickedObject& object) {
    object_layers_.push_back(object.layer);
    ObjectInfo info;
    info.id = object.source_id;
    info.name = object.name;
    info.layer = object.layer;
    info.db_key = object.db_key;
    info.color_rgba = object.color_rgba;
    storage_.addObject(info, object.bounds_min, object.bounds_max,
                       object.closed_surface ? pkg::kObjectClosedSurface : 0u);
  });
}

// Mesh clusters brick by brick, then the merged levels, so each group's produced clusters stay
// contiguous.
void PreprocessRun::packMeshClusters() {
  report_.shared_positions = snapper_.sharedPositions();
  DagPlacement placement = beginDagPlacement(storage_);
  placement.max_shift = snapper_.maxShift();
  placement.coarsened_vertices = snapper_.coarsenedVertices();
  // Snapping moves a vertex by up to half a cell of the coarsest grid: every lod sphere grows by
  // that much (package_assembly.h).
  placement.lod_slack =
      static_cast<float>(quantizationErrorM(storage_.position_step_m, placement.max_shift));
  std::vector<uint32_t> shifts;
  for (uint32_t b = 0; b < bricks_.size(); ++b) {
    throwIfCancelled(progress_);
    std::unique_ptr<ClusterDag> dag =
        resident_[b] ? std::move(resident_[b]) : loadBrickDag(cache_, b);
    BrickRecord& brick = bricks_[b];
    const auto snap_start = Clock::now();
    const auto snapped =
        snapper_.snap(b, brickSnapPiece(*dag, brick, optionsForBrick(b).is_near_other_brick), shifts);
    snap_in_pack_ += secondsSince(snap_start);
    renumberBrick(*dag, brick);
    addDagPieceToPackage(*dag, brick.first_cluster, brick.first_group, snapped, shifts, placement,
                         storage_);
    updateProgress(progress_, b + 1);
  }
  const auto snapped = snapper_.snap(upper_piece_, upperSnapPiece(), shifts);
  addDagPieceToPackage(upper_, uint32_t(total_clusters_), uint32_t(total_groups_), snapped, shifts,
                       placement, storage_);
  upper_ = ClusterDag{};
}

// Parametric clusters out of core: sorted runs within budget / 8, merged into the storage, with
// the sealed pipe runs and covered box faces searched once here rather than at every start of
// the runtime.
void PreprocessRun::packParametricClusters() {
  ParametricSortOptions sort_options;
  sort_options.work_dir = bricking_.work_dir / "parametric-runs";
  sort_options.memory_budget_bytes = std::max<uint64_t>(options_.memory_budget_bytes / 8, 1u << 20);
  sort_options.max_per_cluster = options_.parametric_cluster_size;
  const ParametricStream parametrics =
      [&](const std::function<void(std::span<const ParametricItem>)>& sink) {
        std::vector<ParametricItem> items;
        forEachParametricBatch(scene_, 4096, [&](std::span<const ParametricRecord> batch) {
          items.clear();
          for (const ParametricRecord& r : batch)
            items.push_back({r.object, r.primitive, r.transform});
          sink(items);
        });
      };
  const InstanceFlagMarking marked =
      markInstanceFlags(parametrics, storage_.origin, object_layers_);
  object_layers_ = {};
  sort_options.instance_role_flags = marked.role_flags;
  storage_.sealed_runs_marked = true;
  storage_.covered_faces_marked = true;
  report_.sealed_run_members = marked.sealed.sealed_members;
  report_.sealed_run_closers = marked.sealed.closers;
  report_.covered_box_faces = marked.covered.covered_faces;
  const ParametricSortStats sorted =
      addParametricClustersOutOfCore(parametrics, sort_options, storage_);
  report_.parametric_clusters = sorted.clusters;
  report_.parametric_sort_runs = sorted.runs;
}

// 5. One file, written atomically; with visibility, first inside the work directory, so the
// final name only ever holds a finished package.
void PreprocessRun::write() {
  clock_.start("write");
  beginStage(progress_, "write package", 0);
  written_path_ = options_.visibility ? bricking_.work_dir / "package.twk" : options_.output;
  PackageWriteStats written = writePackage(storage_, written_path_);
  storage_ = PackageStorage{};
  endStage(progress_);
  report_.package_bytes = written.file_bytes;
  throwIfCancelled(progress_);
}

// 6. Visibility, from the written package; its section replaces the empty one.
void PreprocessRun::buildVisibility() {
  if (!options_.visibility) return;
  clock_.start("visibility");
  report_.visibility = addVisibility(written_path_, options_);
  std::filesystem::rename(written_path_, options_.output);
  report_.package_bytes = std::filesystem::file_size(options_.output);
}

// Snapping ran inside "build bricks" and "pack": shown apart, the stages still sum to the run.
PreprocessReport PreprocessRun::finish() {
  clock_.stop();
  for (StageTime& stage : report_.stages) {
    if (stage.name == "build bricks") stage.seconds -= snap_in_build_;
    if (stage.name == "pack") stage.seconds -= snap_in_pack_;
  }
  for (size_t i = 0; i < report_.stages.size(); ++i)
    if (report_.stages[i].name == "pack") {
      report_.stages.insert(report_.stages.begin() + i, {"snap", snap_in_build_ + snap_in_pack_});
      break;
    }
  if (!options_.keep_work_dir) removeWorkDir(bricking_.work_dir);
  report_.peak_rss_bytes = peakRssBytes();
  report_.seconds = secondsSince(run_start_);
  return std::move(report_);
}

// From the bricks (built here, or found in the work directory) to the package: the stages a
// one-process run and a merge share.
PreprocessReport buildPackageFromBricks(PreprocessRun& run) {
  run.buildBricks();
  run.mergeUpperLevels();
  run.pack();
  run.write();
  run.buildVisibility();
  return run.finish();
}

}  // namespace

PreprocessReport runPreprocess(const PreprocessOptions& options) {
  validateOptions(options);
  try {
    PreprocessRun run(options);
    run.brickInputs();
    run.findSeams();
    return buildPackageFromBricks(run);
  } catch (...) {
    // A failed run leaves nothing behind: its work folder (up to several times the package)
    // would keep a full disk full. A cancelled run keeps its finished bricks for --resume, and
    // so does any run with --keep-work. (A killed run cannot clean up: --resume reuses it.)
    const bool cancelled = options.progress && options.progress->cancelled();
    if (!cancelled && !options.keep_work_dir)
      removeWorkDir(options.work_dir.empty() ? workDirFor(options.output) : options.work_dir);
    throw;
  }
}

namespace {

// The options a step runs with: the plan's, with the step's own threads, progress and output,
// over the plan's work directory, never clearing it.
PreprocessOptions stepOptions(const PreprocessPlan& plan, const StepOptions& step) {
  PreprocessOptions options = plan.options;
  options.threads = step.threads;
  options.progress = step.progress;
  options.output = step.output;
  options.keep_work_dir = step.keep_work_dir;
  options.resume = true;
  return options;
}

}  // namespace

PreprocessPlan planPreprocess(const PreprocessOptions& given) {
  PreprocessOptions options = given;
  validateBuildOptions(options);
  if (options.work_dir.empty()) {
    if (options.output.empty())
      throw std::invalid_argument("preprocess plan: --work names the work directory");
    options.work_dir = workDirFor(options.output);
  }
  // Every step may run elsewhere in the shared folder: the plan names its inputs absolutely.
  for (auto& input : options.inputs) input = std::filesystem::absolute(input);
  if (!options.database.empty())
    options.database = std::filesystem::absolute(options.database).lexically_normal();
  options.resume = true;  // a finished bricking of the same inputs and options is kept
  PreprocessRun run(options);
  run.brickInputs();
  run.findSeams();

  PreprocessPlan plan;
  plan.options = options;
  plan.options.output.clear();
  plan.run_hash = run.runHash();
  plan.input_triangles = run.report().input_triangles;
  plan.primitives = run.report().primitives;
  plan.objects = run.report().objects;
  for (const BrickInfo& brick : run.scene().bricks)
    plan.jobs.push_back({brick.index, brick.triangle_count});
  std::stable_sort(plan.jobs.begin(), plan.jobs.end(),
                   [](const BrickJob& a, const BrickJob& b) { return a.triangles > b.triangles; });
  writePreprocessPlan(plan, options.work_dir);
  return plan;
}

struct PlannedBricks::State {
  PreprocessOptions options;
  std::unique_ptr<PreprocessRun> run;
};

PlannedBricks::PlannedBricks(const PreprocessPlan& plan, const StepOptions& step)
    : state_(std::make_unique<State>()) {
  state_->options = stepOptions(plan, step);
  state_->run = std::make_unique<PreprocessRun>(state_->options);
  state_->run->requirePlan(plan.run_hash);
  state_->run->brickInputs();
  state_->run->findSeams();
}

PlannedBricks::~PlannedBricks() = default;

uint32_t PlannedBricks::count() const { return uint32_t(state_->run->scene().bricks.size()); }

BrickJobReport PlannedBricks::build(uint32_t index) { return state_->run->buildBrickJob(index); }

PreprocessReport mergePreprocess(const PreprocessPlan& plan, const StepOptions& step) {
  const PreprocessOptions options = stepOptions(plan, step);
  validateOptions(options);
  PreprocessRun run(options);
  run.requirePlan(plan.run_hash);
  run.brickInputs();
  run.requireBuiltBricks();
  run.findSeams();
  return buildPackageFromBricks(run);
}

}  // namespace tw
