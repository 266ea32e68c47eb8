// The preprocessor end to end on small inputs: several bricks, a package the reader accepts,
// shrinking levels, kept objects and layers, and resume after a cancelled run giving the same
// bytes as an uninterrupted one.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "brick_cache.h"
#include "cluster_dag.h"
#include "dag_levels.h"
#include "dag_merge.h"
#include "dag_serialization.h"
#include "parametrics/instance_flag_marking.h"
#include "package_assembly.h"
#include "package_check.h"
#include "package_view.h"
#include "package_writer.h"
#include "parametrics/parametric_clusters.h"
#include "preprocess_driver.h"
#include "test_support.h"
#include "tws_writer.h"

namespace tw {
namespace {

namespace fs = std::filesystem;

// A closed, bumpy grid of boxes spread over a wide area, so bricking splits it, plus a few
// parametric objects on their own layer.
fs::path writeScene(const fs::path& dir) {
  fs::path path = dir / "scene.tws";
  TwsWriter writer(path);
  writer.onLayer(0, {"structure", 0xff336699u});
  writer.onLayer(1, {"piping", 0xff00aa00u});
  uint32_t id = 0;
  for (int gx = 0; gx < 12; ++gx)
    for (int gy = 0; gy < 12; ++gy) {
      SceneObject object;
      object.info.id = id++;
      object.info.name = "block " + std::to_string(gx) + "," + std::to_string(gy);
      object.info.db_key = "B-" + std::to_string(object.info.id);
      object.info.transform.origin = {gx * 30.0 + 500000.0, gy * 30.0 + 7000000.0, 0.0};
      object.geometry = test::subdividedBox(glm::vec3(5.0f), 8);
      writer.onObject(object);
    }
  for (int i = 0; i < 20; ++i) {
    SceneObject pipe;
    pipe.info.id = id++;
    pipe.info.layer = 1;
    pipe.info.name = "pipe " + std::to_string(i);
    pipe.info.db_key = "6\"-HC-" + std::to_string(1000 + i);
    pipe.info.transform.origin = {500000.0 + i * 10.0, 7000000.0, 12.0};
    pipe.geometry = Primitive{Cylinder{0.1f, 8.0f, false}};
    writer.onObject(pipe);
  }
  for (int i = 0; i < 4; ++i) {  // a deck of four plates side by side: three shared sides
    SceneObject plate;
    plate.info.id = id++;
    plate.info.name = "deck plate " + std::to_string(i);
    plate.info.db_key = "DK-1";
    plate.info.transform.origin = {500004.0 + i * 8.0, 7000003.5, 20.0};
    plate.geometry = Primitive{Box{glm::vec3(4.0f, 3.5f, 0.075f)}};
    writer.onObject(plate);
  }
  writer.finish();
  return path;
}

// Cancels after `bricks` completed brick builds, as a kill between bricks would.
class CancelAfterBricks : public Progress {
 public:
  explicit CancelAfterBricks(uint64_t bricks) : bricks_(bricks) {}
  void beginStage(std::string_view name, uint64_t) override { in_bricks_ = name == "build bricks"; }
  void update(uint64_t done) override {
    if (in_bricks_ && done >= bricks_) cancel_ = true;
  }
  void endStage() override {}
  bool cancelled() const override { return cancel_; }

 private:
  uint64_t bricks_;
  bool in_bricks_ = false;
  bool cancel_ = false;
};

PreprocessOptions optionsFor(const fs::path& input, const fs::path& output) {
  PreprocessOptions options;
  options.inputs = {input};
  options.output = output;
  options.max_brick_triangles = 20000;  // 144 blocks x 768 triangles: several bricks
  options.cluster_size = 128;
  return options;
}

TEST(Preprocess, BuildsAValidPackageFromSeveralBricks) {
  fs::path dir = test::scratchDir();
  fs::path input = writeScene(dir);
  fs::path output = dir / "scene.twk";
  PreprocessReport report = runPreprocess(optionsFor(input, output));
  EXPECT_GT(report.bricks, 3u);
  EXPECT_EQ(report.input_triangles, 144u * 768u);
  EXPECT_EQ(report.primitives, 24u);
  EXPECT_EQ(report.objects, 168u);
  EXPECT_EQ(report.covered_box_faces, 6u);  // each shared side, from both plates
  ASSERT_GE(report.triangles_per_level.size(), 3u);
  for (size_t level = 1; level < report.triangles_per_level.size(); ++level)
    EXPECT_LE(report.triangles_per_level[level], report.triangles_per_level[level - 1])
        << "level " << level;
  EXPECT_LE(report.root_triangles, 65536u);
  EXPECT_EQ(report.package_bytes, fs::file_size(output));
  EXPECT_FALSE(fs::exists(output.string() + ".work")) << "work directory left behind";

  PackageView view = PackageView::open(output, PackageView::Verify::All);
  EXPECT_EQ(view.objects().size(), 168u);
  EXPECT_EQ(view.layers().size(), 2u);
  EXPECT_EQ(view.instances().size(), 24u);
  EXPECT_TRUE(view.header().flags & pkg::kHeaderCoveredFacesMarked);
  const CheckReport checked = checkPackage(view);
  EXPECT_TRUE(checked.ok());
}

TEST(Preprocess, ResumeAfterCancelGivesTheSameBytes) {
  fs::path dir = test::scratchDir();
  fs::path input = writeScene(dir);
  fs::path reference = dir / "reference.twk";
  PreprocessReport full = runPreprocess(optionsFor(input, reference));
  ASSERT_GT(full.bricks, 3u);

  fs::path output = dir / "resumed.twk";
  CancelAfterBricks cancel(2);
  PreprocessOptions first = optionsFor(input, output);
  first.progress = &cancel;
  EXPECT_THROW(runPreprocess(first), std::runtime_error);
  EXPECT_FALSE(fs::exists(output));
  EXPECT_TRUE(fs::exists(output.string() + ".work"));

  PreprocessOptions second = optionsFor(input, output);
  second.resume = true;
  PreprocessReport resumed = runPreprocess(second);
  EXPECT_TRUE(resumed.bricking_reused);
  EXPECT_EQ(resumed.bricks_reused, 2u);
  EXPECT_EQ(test::readFile(output), test::readFile(reference));
}

TEST(Preprocess, ResumeWithOtherOptionsStartsOver) {
  fs::path dir = test::scratchDir();
  fs::path input = writeScene(dir);
  fs::path output = dir / "scene.twk";
  CancelAfterBricks cancel(2);
  PreprocessOptions first = optionsFor(input, output);
  first.progress = &cancel;
  EXPECT_THROW(runPreprocess(first), std::runtime_error);
  PreprocessOptions second = optionsFor(input, output);
  second.resume = true;
  second.cluster_size = 256;  // different output: nothing may be reused
  PreprocessReport report = runPreprocess(second);
  EXPECT_EQ(report.bricks_reused, 0u);
  EXPECT_FALSE(report.bricking_reused && report.bricks_reused > 0);
}

// The streamed assembly (brick DAGs re-read from the resume store one at a time, snapping solved
// piece by piece, pages spilled to disk) gives the bytes the whole-DAG, in-memory assembly gives
// from the same bricks: every brick merged with mergeBrickDags, packed with addDagToPackage, the
// package written from memory.
TEST(Preprocess, StreamedPackageEqualsTheInMemoryAssembly) {
  fs::path dir = test::scratchDir();
  fs::path input = writeScene(dir);
  fs::path output = dir / "streamed.twk";
  PreprocessOptions options = optionsFor(input, output);
  // The smallest budget this input allows (its 20,000-triangle bricks need 7.6 MiB to build):
  // no brick DAG stays resident, all are re-read.
  options.memory_budget_bytes = 9u << 20;
  options.keep_work_dir = true;
  PreprocessReport report = runPreprocess(options);
  ASSERT_GT(report.bricks, 3u);
  const fs::path work = output.string() + ".work";
  ASSERT_TRUE(fs::exists(work / "pages.spill"));

  const PackageView view = PackageView::open(output, PackageView::Verify::All);
  BrickCache cache(work, view.header().input_hash);
  std::optional<BrickedScene> scene = loadBrickedScene(cache, work);
  ASSERT_TRUE(scene.has_value());
  std::vector<ClusterDag> bricks;
  for (uint32_t b = 0; b < scene->bricks.size(); ++b) {
    std::optional<std::vector<uint8_t>> blob = cache.load(b);
    ASSERT_TRUE(blob.has_value()) << "brick " << b;
    bricks.push_back(deserializeClusterDag(*blob));
  }
  DagOptions dag_options;
  dag_options.cluster_size = options.cluster_size;
  ClusterDag dag = mergeBrickDags(std::move(bricks), dag_options);
  EXPECT_EQ(dag.clusters.size(), report.clusters);
  EXPECT_EQ(dag.triangles_per_level, report.triangles_per_level);
  EXPECT_EQ(dag.root_triangles, report.root_triangles);
  EXPECT_GT(report.merge_front_triangles, 0u);
  EXPECT_GT(report.shared_positions, 0u) << "bricks meet at seams";

  PackageStorage storage;
  storage.origin = scene->origin;
  storage.input_hash = view.header().input_hash;
  for (const Layer& layer : scene->layers) storage.addLayer(layer);
  forEachObject(*scene, [&](const BrickedObject& object) {
    ObjectInfo info;
    info.id = object.source_id;
    info.name = object.name;
    info.layer = object.layer;
    info.db_key = object.db_key;
    info.color_rgba = object.color_rgba;
    storage.addObject(info, object.bounds_min, object.bounds_max,
                      object.closed_surface ? pkg::kObjectClosedSurface : 0u);
  });
  addDagToPackage(dag, storage);
  std::vector<uint32_t> object_layers;
  for (const pkg::ObjectRecord& o : storage.objects) object_layers.push_back(o.layer);
  std::vector<ParametricItem> items;
  forEachParametricBatch(*scene, 4096, [&](std::span<const ParametricRecord> batch) {
    for (const ParametricRecord& r : batch) items.push_back({r.object, r.primitive, r.transform});
  });
  const InstanceFlagMarking marked = markInstanceFlags(
      [&](const std::function<void(std::span<const ParametricItem>)>& sink) { sink(items); },
      storage.origin, object_layers);
  storage.sealed_runs_marked = true;
  storage.covered_faces_marked = true;
  addParametricClusters(items,
                        clusterPrimitives(items, storage.origin, options.parametric_cluster_size),
                        storage, marked.role_flags);
  const fs::path in_memory = dir / "in_memory.twk";
  writePackage(storage, in_memory);
  EXPECT_GT(storage.pages.size(), 1u);
  EXPECT_EQ(test::readFile(output), test::readFile(in_memory));
  removeWorkDir(work);
}

// Whether brick DAGs stay resident (large budget) or are re-read from the resume store (tiny
// budget) changes nothing in the package; two runs give the same bytes; the work directory and
// its page spill file are gone after success.
TEST(Preprocess, ResidencyAndRepeatedRunsGiveTheSameBytes) {
  fs::path dir = test::scratchDir();
  fs::path input = writeScene(dir);
  std::string reference;
  for (uint64_t budget : {uint64_t(9) << 20, uint64_t(4) << 30, uint64_t(9) << 20}) {
    fs::path output = dir / ("budget-" + std::to_string(budget) + ".twk");
    PreprocessOptions options = optionsFor(input, output);
    options.memory_budget_bytes = budget;
    runPreprocess(options);
    EXPECT_FALSE(fs::exists(output.string() + ".work")) << "work directory left behind";
    EXPECT_FALSE(fs::exists(fs::path(output.string() + ".work") / "pages.spill"));
    std::string bytes = test::readFile(output);
    if (reference.empty()) reference = bytes;
    EXPECT_EQ(bytes, reference) << "budget " << budget;
  }
}

// The resume store's DAG blobs: exact round trip, and damage is an error, never a crash.
TEST(Preprocess, DagSerializationRoundTripsAndRejectsDamage) {
  std::vector<glm::vec3> positions;
  std::vector<uint32_t> indices, ids;
  constexpr uint32_t n = 40;
  for (uint32_t y = 0; y <= n; ++y)
    for (uint32_t x = 0; x <= n; ++x)
      positions.push_back({float(x), float(y), 0.3f * std::sin(0.4f * float(x + y))});
  for (uint32_t y = 0; y < n; ++y)
    for (uint32_t x = 0; x < n; ++x) {
      uint32_t a = y * (n + 1) + x, b = a + 1, c = a + n + 1, d = c + 1;
      indices.insert(indices.end(), {a, b, d, a, d, c});
      ids.insert(ids.end(), {x / 10, x / 10});
    }
  ClusterDag dag = buildClusterDag(DagInput{positions, indices, ids}, DagOptions{});
  ASSERT_GT(dag.groups.size(), 0u);
  std::vector<uint8_t> bytes = serializeClusterDag(dag);
  ClusterDag back = deserializeClusterDag(bytes);
  EXPECT_EQ(serializeClusterDag(back), bytes);
  ASSERT_EQ(back.clusters.size(), dag.clusters.size());
  EXPECT_EQ(back.clusters.back().positions, dag.clusters.back().positions);
  EXPECT_EQ(back.triangles_per_level, dag.triangles_per_level);

  int rejected = 0, attempts = 0;
  for (size_t cut = 0; cut < bytes.size(); cut += 1 + bytes.size() / 400) {
    ++attempts;
    try {
      deserializeClusterDag(std::span<const uint8_t>(bytes.data(), cut), "dag.bin");
    } catch (const FormatError& e) {
      ++rejected;
      EXPECT_NE(std::string(e.what()).find("dag.bin"), std::string::npos);
    }
  }
  EXPECT_EQ(rejected, attempts) << "every truncation must be rejected";
  std::vector<uint8_t> bad = bytes;
  bad[0] ^= 0xff;
  EXPECT_THROW(deserializeClusterDag(bad), FormatError);
}

TEST(Preprocess, RejectsBadArguments) {
  fs::path dir = test::scratchDir();
  PreprocessOptions none;
  none.output = dir / "x.twk";
  EXPECT_THROW(runPreprocess(none), std::invalid_argument);
  PreprocessOptions bad = optionsFor(writeScene(dir), dir / "x.twk");
  bad.cluster_size = 3;
  EXPECT_THROW(runPreprocess(bad), std::invalid_argument);
  PreprocessOptions missing = optionsFor(dir / "absent.obj", dir / "x.twk");
  EXPECT_THROW(runPreprocess(missing), FormatError);
}

}  // namespace
}  // namespace tw

namespace tw {
namespace {

// Two triangles per quad between consecutive rings of an open tube: rings + 1 rings of `sides`
// vertices each, ring after ring.
void appendTubeQuads(std::vector<uint32_t>& indices, int rings, int sides) {
  for (int r = 0; r < rings; ++r)
    for (int s = 0; s < sides; ++s) {
      const uint32_t a = r * sides + s, b = r * sides + (s + 1) % sides;
      const uint32_t c = a + sides, d = b + sides;
      indices.insert(indices.end(), {a, b, d, a, d, c});
    }
}

// Uncapped pipes (open at both ends, as CAD exports them) spread over several bricks. Only the
// brick seams may be locked: if the pipes' own open ends were locked too, no pipe could ever be
// simplified or dropped and the levels would stall. The package must still be crack-free.
// 100 pipes 40 m long along X, so every split of the model cuts through them, and 2,500 short
// open stubs: 252,000 triangles of open CAD parts.
void writePipesAndStubs(const fs::path& input) {
  constexpr int kSides = 12, kRings = 80;
  TwsWriter writer(input);
  writer.onLayer(0, {"piping", 0xff00aa00u});
  uint32_t id = 0;
  for (int gy = 0; gy < 10; ++gy)
    for (int gz = 0; gz < 10; ++gz) {
      SceneObject pipe;
      pipe.info.id = id++;
      pipe.info.name = "pipe " + std::to_string(pipe.info.id);
      pipe.info.transform.origin = {0.0, gy * 2.0, gz * 2.0};
      TriangleMesh mesh;
      for (int r = 0; r <= kRings; ++r)
        for (int s = 0; s < kSides; ++s) {
          const float a = 6.2831853f * s / kSides;
          mesh.positions.push_back({0.5f * r, 0.2f * std::cos(a), 0.2f * std::sin(a)});
        }
      appendTubeQuads(mesh.indices, kRings, kSides);
      pipe.geometry = std::move(mesh);
      writer.onObject(pipe);
    }
  // And 2,500 short stubs (one ring of quads): every vertex on an open end, so a build that
  // locked the model's own open edges could never touch them.
  for (int gx = 0; gx < 50; ++gx)
    for (int gy = 0; gy < 50; ++gy) {
      SceneObject stub;
      stub.info.id = id++;
      stub.info.name = "stub " + std::to_string(stub.info.id);
      stub.info.transform.origin = {gx * 0.8, gy * 0.4, -3.0};
      TriangleMesh mesh;
      for (int r = 0; r <= 1; ++r)
        for (int s = 0; s < kSides; ++s) {
          const float a = 6.2831853f * s / kSides;
          mesh.positions.push_back({0.05f * std::cos(a), 0.05f * std::sin(a), 0.1f * r});
        }
      appendTubeQuads(mesh.indices, 1, kSides);
      stub.geometry = std::move(mesh);
      writer.onObject(stub);
    }
  writer.finish();
}

TEST(Preprocess, OpenCadPartsAcrossBricksStillShrinkEveryLevel) {
  fs::path dir = test::scratchDir();
  fs::path input = dir / "pipes.tws";
  writePipesAndStubs(input);
  PreprocessOptions options;
  options.inputs = {input};
  options.output = dir / "pipes.twk";
  options.max_brick_triangles = 40000;  // 252,000 triangles: several bricks
  options.cluster_size = 128;
  const PreprocessReport report = runPreprocess(options);
  ASSERT_GT(report.bricks, 2u);
  EXPECT_GT(report.seam_edges, 0u);
  const auto& levels = report.triangles_per_level;
  // What the bricks could not simplify goes to the merge. With every open edge locked, all the
  // stubs would (81,582 of 252,000 triangles when this test was written); with the seams alone,
  // 11,438.
  EXPECT_LE(report.merge_front_triangles, report.input_triangles / 8);
  ASSERT_GT(levels.size(), 3u);
  EXPECT_LE(report.root_triangles, 65536u);
  for (size_t l = 1; l < levels.size() && levels[l - 1] > 65536; ++l)
    EXPECT_LE(levels[l], 0.6 * levels[l - 1]) << "level " << l << " did not shrink";
  // The first levels, which are all above the root limit here, must really shrink.
  EXPECT_LE(levels[2], 0.4 * levels[0]);
  const PackageView view = PackageView::open(options.output, PackageView::Verify::All);
  const CheckReport check = checkPackage(view);
  EXPECT_TRUE(check.ok()) << (check.failure ? check.failure->check + ": " + check.failure->what
                                            : std::string("cancelled"));
}

// Every brick's DAG stops at one level, the first at which the bricks' fronts fit half a brick,
// and the merge simplifies from there without seams. So the merge's front is the bricks' whole
// front at that level (no brick root left behind at a lower one), and each front halves across
// the join as a one-brick build does.
TEST(Preprocess, BricksStopAtOneLevelAndTheFrontsHalveAcrossTheMerge) {
  fs::path dir = test::scratchDir();
  fs::path input = dir / "pipes.tws";
  writePipesAndStubs(input);
  PreprocessOptions options;
  options.inputs = {input};
  options.output = dir / "pipes.twk";
  options.max_brick_triangles = 40000;
  options.cluster_size = 128;
  const PreprocessReport report = runPreprocess(options);
  ASSERT_GT(report.bricks, 2u);
  // 252,000 triangles halve to within 20,000 (half a brick) after four levels.
  EXPECT_EQ(report.brick_stop_level, 4u);
  const PackageView view = PackageView::open(options.output, PackageView::Verify::All);
  const DagLevels levels = dagLevels(view);
  ASSERT_GT(levels.levels.size(), report.brick_stop_level + 2);
  EXPECT_EQ(levels.levels[report.brick_stop_level].triangles, report.merge_front_triangles)
      << "every brick reached the stop level";
  EXPECT_TRUE(levels.halves);
  for (size_t l = 1; l < levels.levels.size(); ++l) {
    if (levels.levels[l - 1].triangles > DagLevels::kHalvingFloor) {
      EXPECT_LE(levels.levels[l].ratio, DagLevels::kHalvingMax) << "level " << l;
    }
  }
  EXPECT_EQ(levels.root_clusters, 1u);
  EXPECT_TRUE(levels.errors_monotone);
}

// 64 pipe runs of 6 separate parts each (16 sides, 24 rings, 2.1 m long), each part's far end
// `gap` short of the next part's start; each run a 64th of the base step further along, so that
// its joints meet the grid at another phase.
void writePipeRuns(const fs::path& input, float gap) {
  constexpr int kSides = 16, kRings = 24, kParts = 6;
  constexpr float kPartLength = 2.1f;
  TwsWriter writer(input);
  writer.onLayer(0, {"piping", 0xff00aa00u});
  uint32_t id = 0;
  for (int gy = 0; gy < 8; ++gy)
    for (int gz = 0; gz < 8; ++gz)
      for (int part = 0; part < kParts; ++part) {
        SceneObject object;
        object.info.id = id++;
        object.info.name = "part " + std::to_string(object.info.id);
        const double phase = (gy * 8 + gz) * pkg::kDefaultPositionStepM / 64;
        object.info.transform.origin = {part * double(kPartLength) + phase, gy * 1.3, gz * 1.3};
        TriangleMesh mesh;
        for (int r = 0; r <= kRings; ++r)
          for (int s = 0; s < kSides; ++s) {
            const float a = 6.2831853f * float(s) / kSides;
            const float x = r == kRings ? kPartLength - gap : kPartLength * float(r) / kRings;
            mesh.positions.push_back({x, 0.3f * std::cos(a), 0.3f * std::sin(a)});
          }
        appendTubeQuads(mesh.indices, kRings, kSides);
        object.geometry = std::move(mesh);
        writer.onObject(object);
      }
  writer.finish();
}

// CAD exports cut pipe runs into parts (pipe, elbow, pipe...) whose touching ends differ by
// float noise. The package's position grid stores such ends as one vertex; the DAG must see them
// as one too, or simplifying one part opens an edge the other still draws (verify: crack). Each
// run here is 6 separate parts whose shared ends are 1 um apart, well below the 15 um step, or
// 9 um: then the two rings often round to neighbouring points of the base grid, which only the
// weld across bricks joins where a joint falls between two bricks.
TEST(Preprocess, PartsTouchingWithinFloatNoiseAreWeldedAndCrackFree) {
  fs::path dir = test::scratchDir();
  fs::path input = dir / "runs.tws";
  for (float gap : {1e-6f, 9e-6f}) {
    SCOPED_TRACE("gap " + std::to_string(gap));
    writePipeRuns(input, gap);
    for (uint64_t brick_triangles : {uint64_t(0), uint64_t(300000)}) {
      SCOPED_TRACE(brick_triangles == 0 ? "several bricks" : "one brick");
      PreprocessOptions options;
      options.inputs = {input};
      options.output = dir / "runs.twk";
      options.max_brick_triangles = brick_triangles == 0 ? 25000 : brick_triangles;
      options.cluster_size = 128;
      const PreprocessReport report = runPreprocess(options);
      EXPECT_EQ(report.bricks > 1, brick_triangles == 0);
      // Where a joint falls between two bricks, its two rings are welded into one seam before
      // the bricks are built (cross_brick_weld.h); inside one brick the grid weld joins them.
      if (report.bricks == 1) {
        EXPECT_EQ(report.welded_across_bricks, 0u);
      } else if (gap > 5e-6f) {
        EXPECT_GT(report.welded_across_bricks, 0u);
      }
      const PackageView view = PackageView::open(options.output, PackageView::Verify::All);
      const CheckReport check = checkPackage(view);
      EXPECT_TRUE(check.ok()) << (check.failure ? check.failure->check + ": " + check.failure->what
                                                : std::string("cancelled"));
      EXPECT_GT(check.counts.border_edges, 0u);
    }
  }
}

// Joints a little open (0.4 mm, far above float noise and the 15 um base step, so nothing welds
// them at full resolution) close on the coarse levels' grids, where the package decodes both
// rings as one and `verify` joins them: the group holding a joint must not move one ring and
// not the other (it joins them first), or the coarse level shows a gap the fine one did not.
TEST(Preprocess, JointsOpenBelowACoarseGridStayClosedOnCoarseLevels) {
  fs::path dir = test::scratchDir();
  fs::path input = dir / "runs.tws";
  writePipeRuns(input, 4e-4f);
  for (uint64_t brick_triangles : {uint64_t(25000), uint64_t(300000)}) {
    SCOPED_TRACE(brick_triangles);
    PreprocessOptions options;
    options.inputs = {input};
    options.output = dir / "runs.twk";
    options.max_brick_triangles = brick_triangles;
    options.cluster_size = 128;
    runPreprocess(options);
    const PackageView view = PackageView::open(options.output, PackageView::Verify::All);
    const CheckReport check = checkPackage(view);
    EXPECT_TRUE(check.ok()) << (check.failure ? check.failure->check + ": " + check.failure->what
                                              : std::string("cancelled"));
  }
}

}  // namespace
}  // namespace tw
