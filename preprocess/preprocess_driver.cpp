// The preprocessing run: stage order, the resume store, timing and the report.
#include "preprocess_driver.h"

#include <sys/resource.h>

#include <chrono>
#include <stdexcept>

#include <tbb/global_control.h>

#include "brick_cache.h"
#include "cluster_dag.h"
#include "dag_merge.h"
#include "dag_serialization.h"
#include "package_assembly.h"
#include "package_writer.h"
#include "parametric_clusters.h"
#include "scene_bricking.h"

namespace tw {
namespace {

using Clock = std::chrono::steady_clock;

// Bumped whenever the preprocessor's output changes for the same inputs and options, so that a
// resume never mixes bricks built by two versions.
constexpr uint32_t kPreprocessorRevision = 1;

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

void throwIfCancelled(Progress* progress) {
  if (progress && progress->cancelled()) throw std::runtime_error("cancelled");
}

}  // namespace

PreprocessReport runPreprocess(const PreprocessOptions& options) {
  if (options.inputs.empty()) throw std::invalid_argument("no input files");
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
  bricking.progress = progress;
  DagOptions dag_options;
  dag_options.cluster_size = options.cluster_size;

  RunHash hash;
  hash.addValue(kPreprocessorRevision);
  for (const auto& input : options.inputs) hash.addFile(std::filesystem::absolute(input));
  hash.addBrickingOptions(bricking);
  hash.addValue(options.cluster_size);
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
  report.bricks = static_cast<uint32_t>(scene.bricks.size());

  // 2. One LOD DAG per brick, seams locked so neighbouring bricks never crack.
  clock.start("build bricks");
  beginStage(progress, "build bricks", scene.bricks.size());
  DagOptions brick_options = dag_options;
  brick_options.lock_open_boundaries = true;
  std::vector<ClusterDag> dags;
  dags.reserve(scene.bricks.size());
  for (uint32_t b = 0; b < scene.bricks.size(); ++b) {
    throwIfCancelled(progress);
    std::optional<std::vector<uint8_t>> blob;
    if (options.resume) blob = cache.load(b);
    if (blob) {
      dags.push_back(deserializeClusterDag(*blob, cache.blobPath(b).string()));
      ++report.bricks_reused;
    } else {
      BrickMesh mesh = loadBrick(scene, b);
      ClusterDag dag = buildClusterDag(
          DagInput{mesh.positions, mesh.indices, mesh.triangle_object_ids}, brick_options);
      cache.store(b, serializeClusterDag(dag));
      dags.push_back(std::move(dag));
    }
    updateProgress(progress, b + 1);
  }
  endStage(progress);
  throwIfCancelled(progress);

  // 3. Upper levels from all the bricks' roots.
  clock.start("merge");
  beginStage(progress, "merge bricks", 0);
  ClusterDag dag = mergeBrickDags(std::move(dags), dag_options);
  endStage(progress);
  report.triangles_per_level = dag.triangles_per_level;
  report.root_triangles = dag.root_triangles;
  report.clusters = dag.clusters.size();

  // 4. Package records: layers, objects, mesh clusters, parametric clusters.
  clock.start("pack");
  beginStage(progress, "pack", dag.clusters.size());
  PackageStorage storage;
  storage.origin = scene.origin;
  storage.input_hash = cache.runHash();
  for (const Layer& layer : scene.layers) storage.addLayer(layer);
  forEachObject(scene, [&](const BrickedObject& object) {
    ObjectInfo info;
    info.id = object.source_id;
    info.name = object.name;
    info.layer = object.layer;
    info.db_key = object.db_key;
    info.color_rgba = object.color_rgba;
    storage.addObject(info, object.bounds_min, object.bounds_max);
  });
  addDagToPackage(dag, storage);
  dag = ClusterDag{};  // encoded now; release the geometry before the parametrics
  std::vector<ParametricItem> items;
  items.reserve(scene.parametric_count);
  forEachParametricBatch(scene, 4096, [&](std::span<const ParametricRecord> batch) {
    for (const ParametricRecord& r : batch) items.push_back({r.object, r.primitive, r.transform});
  });
  ParametricClustering clustering = clusterPrimitives(items, storage.origin);
  report.parametric_clusters = addParametricClusters(items, clustering, storage).size();
  endStage(progress);

  // 5. One file, written atomically.
  clock.start("write");
  beginStage(progress, "write package", 0);
  PackageWriteStats written = writePackage(storage, options.output);
  endStage(progress);
  clock.stop();
  report.package_bytes = written.file_bytes;
  if (!options.keep_work_dir) removeWorkDir(bricking.work_dir);
  report.peak_rss_bytes = peakRssBytes();
  report.seconds = std::chrono::duration<double>(Clock::now() - run_start).count();
  return report;
}

}  // namespace tw
