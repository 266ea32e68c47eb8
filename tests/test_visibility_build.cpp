// The visibility preprocess: ray sampling (determinism whatever the thread count, the greedy
// occluder ranking, visible sets that hold what rays see and not what is sealed away), the
// section built from a small package (ids on the candidate front), and `runPreprocess` with
// visibility on and off (only the visibility section differs; a run cancelled during visibility
// resumes to the same bytes; damaged packages give FormatError).
#include <gtest/gtest.h>

#include <tbb/global_control.h>

#include <algorithm>
#include <stdexcept>

#include "dag_front.h"
#include "embree_scene.h"
#include "package_view.h"
#include "preprocess_driver.h"
#include "pvs_mapping.h"
#include "test_support.h"
#include "tws_writer.h"
#include "visibility_build.h"
#include "visibility_sampling.h"
#include "visibility_section.h"

namespace tw {
namespace {

namespace fs = std::filesystem;

TriangleMesh box(const glm::vec3& lo, const glm::vec3& hi) {
  TriangleMesh soup;
  test::appendBox(soup, lo, hi);
  return soup;
}

// A grid of `dims` cells of `size` from `min`, every cell free.
ViewCellGrid openGrid(const glm::dvec3& min, double size, const glm::uvec3& dims) {
  ViewCellGrid grid;
  grid.min = min;
  grid.cell_size_m = size;
  grid.dims = dims;
  for (uint32_t i = 0; i < grid.cellCount(); ++i) grid.free_cells.push_back(i);
  return grid;
}

void expectSameData(const VisibilityData& a, const VisibilityData& b) {
  ASSERT_EQ(a.cells.size(), b.cells.size());
  EXPECT_EQ(a.rays_cast, b.rays_cast);
  for (size_t i = 0; i < a.cells.size(); ++i) {
    EXPECT_EQ(a.cells[i].grid_index, b.cells[i].grid_index);
    EXPECT_EQ(a.cells[i].occluders, b.cells[i].occluders) << "cell " << i;
    EXPECT_EQ(a.cells[i].visible, b.cells[i].visible) << "cell " << i;
    EXPECT_EQ(a.cells[i].occluder_coverage, b.cells[i].occluder_coverage) << "cell " << i;
    EXPECT_EQ(a.cells[i].hit_fraction, b.cells[i].hit_fraction) << "cell " << i;
  }
}

TEST(VisibilitySampling, SameSeedSameDataWhateverTheThreadCount) {
  EmbreeScene scene(glm::dvec3(0.0));
  for (uint32_t i = 0; i < 12; ++i) {
    const glm::vec3 lo(-9.0f + 1.5f * float(i), float(i % 3) * 3.0f - 4.0f, float(i % 4) - 1.0f);
    TriangleMesh s = box(lo, lo + glm::vec3(1.0f, 0.5f + 0.2f * float(i), 1.5f));
    scene.addMesh(std::move(s.positions), std::move(s.indices), 100 + i);
  }
  scene.commit();
  const ViewCellGrid grid = openGrid(glm::dvec3(-8.0, -8.0, -2.0), 2.0, glm::uvec3(8, 8, 2));
  VisibilitySamplingOptions options;
  options.rays_per_cell = 300;  // not a multiple of the samples
  VisibilityData one, two, again, other_seed;
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
    one = sampleVisibility(scene, grid, options);
  }
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
    two = sampleVisibility(scene, grid, options);
  }
  again = sampleVisibility(scene, grid, options);
  ASSERT_EQ(one.cells.size(), 128u);
  EXPECT_EQ(one.rays_cast, 128u * 300u);
  expectSameData(one, two);
  expectSameData(one, again);

  options.seed = 2;
  other_seed = sampleVisibility(scene, grid, options);
  ASSERT_EQ(other_seed.cells.size(), one.cells.size());
  size_t differing = 0;
  for (size_t i = 0; i < one.cells.size(); ++i)
    differing += one.cells[i].hit_fraction != other_seed.cells[i].hit_fraction;
  EXPECT_GT(differing, 0u) << "the seed has no effect";

  uint64_t hits = 0;
  for (const VisibilityCell& c : one.cells) {
    EXPECT_TRUE(std::is_sorted(c.visible.begin(), c.visible.end()));
    for (uint32_t id : c.occluders)
      EXPECT_TRUE(std::binary_search(c.visible.begin(), c.visible.end(), id));
    hits += !c.visible.empty();
  }
  EXPECT_GT(hits, 64u);
}

TEST(VisibilitySampling, BigWallRanksFirstWithHighCoverage) {
  // From the cell [0, 1]^3: a huge wall at x = 1.5 and a huge floor at z = -1 (one candidate,
  // id 7, three quarters of the sphere), and three small boxes elsewhere.
  EmbreeScene scene(glm::dvec3(0.0));
  TriangleMesh wall = box({1.5f, -500.0f, -500.0f}, {2.0f, 500.0f, 500.0f});
  test::appendBox(wall, {-500.0f, -500.0f, -1.5f}, {1.5f, 500.0f, -1.0f});
  scene.addMesh(std::move(wall.positions), std::move(wall.indices), 7);
  TriangleMesh a = box({-7.0f, -1.0f, 0.0f}, {-5.0f, 1.0f, 2.0f});
  TriangleMesh b = box({-1.0f, -7.0f, 0.0f}, {1.0f, -5.0f, 2.0f});
  TriangleMesh c = box({-1.0f, -1.0f, 5.0f}, {1.0f, 1.0f, 7.0f});
  scene.addMesh(std::move(a.positions), std::move(a.indices), 3);
  scene.addMesh(std::move(b.positions), std::move(b.indices), 4);
  scene.addMesh(std::move(c.positions), std::move(c.indices), 5);
  scene.commit();
  const ViewCellGrid grid = openGrid(glm::dvec3(0.0), 1.0, glm::uvec3(1));
  VisibilitySamplingOptions options;
  const VisibilityData data = sampleVisibility(scene, grid, options);
  ASSERT_EQ(data.cells.size(), 1u);
  const VisibilityCell& cell = data.cells[0];
  ASSERT_FALSE(cell.occluders.empty());
  EXPECT_EQ(cell.occluders[0], 7u);
  EXPECT_GT(cell.occluder_coverage, 0.6f);
  EXPECT_GE(cell.hit_fraction, cell.occluder_coverage);
  EXPECT_EQ(cell.visible, (std::vector<uint32_t>{3, 4, 5, 7}));

  // Asking for all the hits takes the small boxes too, most covering first.
  options.coverage_target = 1.0f;
  const VisibilityData all = sampleVisibility(scene, grid, options);
  EXPECT_EQ(all.cells[0].occluders.size(), 4u);
  EXPECT_EQ(all.cells[0].occluders[0], 7u);
  EXPECT_FLOAT_EQ(all.cells[0].occluder_coverage, all.cells[0].hit_fraction);
  options.max_occluders = 2;
  EXPECT_EQ(sampleVisibility(scene, grid, options).cells[0].occluders.size(), 2u);
}

TEST(VisibilitySampling, VisibleSetHasWhatRaysSeeNotWhatIsSealedAway) {
  EmbreeScene scene(glm::dvec3(0.0));
  TriangleMesh seen = box({4.0f, -1.0f, -1.0f}, {6.0f, 1.0f, 1.0f});
  TriangleMesh shell = box({-9.0f, -3.0f, -3.0f}, {-4.0f, 3.0f, 3.0f});  // closed
  TriangleMesh hidden = box({-7.0f, -1.0f, -1.0f}, {-5.0f, 1.0f, 1.0f});  // inside the shell
  scene.addMesh(std::move(seen.positions), std::move(seen.indices), 1);
  scene.addMesh(std::move(shell.positions), std::move(shell.indices), 2);
  scene.addMesh(std::move(hidden.positions), std::move(hidden.indices), 3);
  scene.commit();
  const ViewCellGrid grid = openGrid(glm::dvec3(0.0), 1.0, glm::uvec3(1));
  const VisibilityData data = sampleVisibility(scene, grid, VisibilitySamplingOptions{});
  ASSERT_EQ(data.cells.size(), 1u);
  // A direct ray from the cell sees box 1; the sampled set has it, and never box 3.
  Ray ray;
  ray.origin = glm::vec3(0.5f);
  ray.direction = glm::vec3(5.0f, 0.0f, 0.0f) - ray.origin;
  ASSERT_EQ(scene.intersect(ray).user_id, 1u);
  EXPECT_EQ(data.cells[0].visible, (std::vector<uint32_t>{1, 2}));

  VisibilitySamplingOptions no_sets;
  no_sets.visible_sets = false;
  const VisibilityData without = sampleVisibility(scene, grid, no_sets);
  EXPECT_TRUE(without.cells[0].visible.empty());
  EXPECT_FALSE(without.cells[0].occluders.empty());
  EXPECT_FALSE(without.visible_sets);
}

TEST(VisibilitySampling, RejectsUncommittedSceneAndZeroRays) {
  EmbreeScene scene(glm::dvec3(0.0));
  const ViewCellGrid grid = openGrid(glm::dvec3(0.0), 1.0, glm::uvec3(1));
  EXPECT_THROW(sampleVisibility(scene, grid, VisibilitySamplingOptions{}), std::invalid_argument);
  scene.commit();
  VisibilitySamplingOptions options;
  options.rays_per_cell = 0;
  EXPECT_THROW(sampleVisibility(scene, grid, options), std::invalid_argument);
}

// A deck (an 80 x 80 x 1 m slab), four 6 m blocks on it and a pipe (parametric), far from the
// datum.
fs::path writeScene(const fs::path& dir) {
  fs::path path = dir / "deck.tws";
  TwsWriter writer(path);
  writer.onLayer(0, {"structure", 0xff336699u});
  uint32_t id = 0;
  auto add = [&](const glm::dvec3& at, const glm::vec3& half, int n) {
    SceneObject object;
    object.info.id = id++;
    object.info.name = "block " + std::to_string(object.info.id);
    object.info.transform.origin = glm::dvec3(500000.0, 7000000.0, 0.0) + at;
    object.geometry = test::subdividedBox(half, n);
    writer.onObject(object);
  };
  add({0.0, 0.0, -0.5}, {40.0f, 40.0f, 0.5f}, 8);
  for (int i = 0; i < 4; ++i)
    add({(i & 1) ? 15.0 : -15.0, (i & 2) ? 15.0 : -15.0, 3.0}, glm::vec3(3.0f), 6);
  SceneObject pipe;
  pipe.info.id = id++;
  pipe.info.name = "pipe";
  pipe.info.transform.origin = {500000.0, 7000000.0, 8.0};
  pipe.geometry = Primitive{Cylinder{0.2f, 2.0f, false}};
  writer.onObject(pipe);
  writer.finish();
  return path;
}

PreprocessOptions optionsFor(const fs::path& input, const fs::path& output) {
  PreprocessOptions options;
  options.inputs = {input};
  options.output = output;
  options.cluster_size = 128;
  options.visibility = true;
  options.visibility_rays = 256;
  return options;
}

// The package, built once per test program (visibility off).
const fs::path& deckPackage() {
  static const fs::path path = [] {
    const fs::path dir = test::processScratchDir("visibility_build");
    PreprocessOptions options = optionsFor(writeScene(dir), dir / "deck.twk");
    options.visibility = false;
    runPreprocess(options);
    return dir / "deck.twk";
  }();
  return path;
}

std::string sectionBytes(const std::string& file, const pkg::SectionEntry& entry) {
  return file.substr(entry.offset, pkg::storedBytes(entry));
}

TEST(VisibilityBuild, SectionIdsAreFrontClusters) {
  const PackageView view = PackageView::open(deckPackage());
  EXPECT_TRUE(view.visibility().empty());
  VisibilityBuildOptions options;
  options.sampling.rays_per_cell = 256;
  options.cells.cell_size_m = 2.0;  // cells wholly inside the 6 m blocks, whatever the origin
  VisibilityBuildReport report;
  const std::vector<uint8_t> bytes = buildVisibilitySection(view, options, &report);
  ASSERT_FALSE(bytes.empty());
  EXPECT_EQ(report.section_bytes, bytes.size());
  EXPECT_GT(report.candidate_clusters, 0u);
  EXPECT_DOUBLE_EQ(report.cell_size_m, 2.0);
  EXPECT_EQ(report.free_cells + report.solid_cells, report.grid_cells);
  EXPECT_GT(report.solid_cells, 0u) << "the blocks' insides";
  EXPECT_EQ(report.rays, uint64_t(report.free_cells) * 256u);
  EXPECT_GT(report.average_occluders, 0.0);
  EXPECT_GE(report.average_visible, report.average_occluders);

  const VisibilityView vis =
      VisibilityView::parse(bytes, "deck", 0, view.clusters().size());
  ASSERT_FALSE(vis.empty());
  const pkg::VisibilityHeader& h = vis.header();
  EXPECT_EQ(h.cell_count, report.free_cells);
  EXPECT_EQ(h.solid_cells, report.solid_cells);
  EXPECT_EQ(h.rays_cast, report.rays);
  EXPECT_EQ(h.rays_per_cell, 256u);
  EXPECT_EQ(h.candidate_level, report.candidate_level);
  EXPECT_EQ(h.candidate_triangles, report.candidate_triangles);
  EXPECT_EQ(h.flags & pkg::kVisibleSetsPresent, pkg::kVisibleSetsPresent);
  EXPECT_NEAR(vis.averageOccluders(), report.average_occluders, 1e-9);

  EXPECT_EQ(h.flags & pkg::kParametricCandidates, pkg::kParametricCandidates);
  EXPECT_EQ(report.parametric_candidates, 1u) << "the pipe";
  EXPECT_GT(report.parametric_triangles, 0u);

  const DagFront front = dagFront(view, h.candidate_level);
  EXPECT_EQ(front.clusters.size(), report.candidate_clusters);
  auto candidate = [&](uint32_t id) {
    return std::binary_search(front.clusters.begin(), front.clusters.end(), id) ||
           view.clusters()[id].kind == uint8_t(pkg::ClusterKind::Parametric);
  };
  uint32_t with_occluders = 0;
  for (const pkg::VisibilityCellRecord& cell : vis.cells()) {
    for (uint32_t id : vis.occluders(cell)) EXPECT_TRUE(candidate(id)) << id;
    for (uint32_t id : vis.visible(cell)) EXPECT_TRUE(candidate(id)) << id;
    with_occluders += cell.occluder_count > 0;
    EXPECT_LE(cell.occluder_coverage, cell.hit_fraction + 1e-6f);
  }
  EXPECT_GT(with_occluders, vis.cells().size() / 2);

  // Classifying with a coarser front (the boxes simplify to boxes) drops the same cells.
  VisibilityBuildOptions coarse = options;
  coarse.max_classification_triangles = report.candidate_triangles / 3;
  VisibilityBuildReport coarse_report;
  buildVisibilitySection(view, coarse, &coarse_report);
  EXPECT_EQ(coarse_report.solid_cells, report.solid_cells);
  EXPECT_EQ(coarse_report.candidate_triangles, report.candidate_triangles);

  // A camera on the deck between the blocks has a cell; one inside a block has none.
  const glm::dvec3 datum(500000.0, 7000000.0, 0.0);
  const glm::dvec3 on_deck = datum + glm::dvec3(0.0, 0.0, 1.7) - view.origin();
  const glm::dvec3 in_block = datum + glm::dvec3(15.0, 15.0, 3.0) - view.origin();
  EXPECT_NE(vis.cellAt(on_deck), nullptr);
  EXPECT_EQ(vis.cellAt(in_block), nullptr);
}

TEST(VisibilityBuild, PreprocessWithAndWithoutVisibilityDifferOnlyInTheSection) {
  const fs::path dir = test::scratchDir();
  const fs::path input = writeScene(dir);
  PreprocessOptions on = optionsFor(input, dir / "on.twk");
  PreprocessOptions off = optionsFor(input, dir / "off.twk");
  off.visibility = false;
  const PreprocessReport with = runPreprocess(on);
  const PreprocessReport without = runPreprocess(off);
  EXPECT_TRUE(with.visibility.ran);
  EXPECT_FALSE(without.visibility.ran);
  EXPECT_GT(with.visibility.free_cells, 0u);
  EXPECT_GT(with.visibility.section_bytes, 0u);
  EXPECT_EQ(with.package_bytes, fs::file_size(on.output));
  EXPECT_FALSE(fs::exists(on.output.string() + ".work"));
  EXPECT_TRUE(std::any_of(with.stages.begin(), with.stages.end(),
                          [](const StageTime& s) { return s.name == "visibility"; }));

  const PackageView a = PackageView::open(on.output, PackageView::Verify::All);
  const PackageView b = PackageView::open(off.output, PackageView::Verify::All);
  EXPECT_EQ(a.header().input_hash, b.header().input_hash);
  EXPECT_EQ(a.section(pkg::SectionType::Visibility).bytes, with.visibility.section_bytes);
  EXPECT_TRUE(b.visibility().empty());
  const std::string file_a = test::readFile(on.output), file_b = test::readFile(off.output);
  for (uint32_t s = 0; s < pkg::kSectionCount; ++s) {
    if (s == uint32_t(pkg::SectionType::Visibility)) continue;
    const auto type = pkg::SectionType(s);
    EXPECT_EQ(sectionBytes(file_a, a.section(type)), sectionBytes(file_b, b.section(type)))
        << pkg::kSectionNames[s];
    EXPECT_EQ(a.section(type).checksum, b.section(type).checksum);
  }
  const VisibilityView vis = VisibilityView::parse(a.visibility(), a.fileName(),
                                                   a.section(pkg::SectionType::Visibility).offset,
                                                   a.clusters().size());
  EXPECT_EQ(vis.header().cell_count, with.visibility.free_cells);
  EXPECT_EQ(vis.header().rays_per_cell, 256u);
}

// Cancels as soon as ray sampling has reported progress.
class CancelInVisibility : public Progress {
 public:
  void beginStage(std::string_view name, uint64_t) override {
    in_rays_ = name == "visibility rays";
  }
  void update(uint64_t done) override {
    if (in_rays_ && done > 0) cancel_ = true;
  }
  void endStage() override {}
  bool cancelled() const override { return cancel_; }

 private:
  bool in_rays_ = false;
  bool cancel_ = false;
};

TEST(VisibilityBuild, CancelledDuringVisibilityResumesToTheSameBytes) {
  const fs::path dir = test::scratchDir();
  const fs::path input = writeScene(dir);
  const fs::path reference = dir / "reference.twk";
  runPreprocess(optionsFor(input, reference));

  const fs::path output = dir / "resumed.twk";
  CancelInVisibility cancel;
  PreprocessOptions first = optionsFor(input, output);
  first.progress = &cancel;
  EXPECT_THROW(runPreprocess(first), std::runtime_error);
  EXPECT_FALSE(fs::exists(output)) << "a package without its visibility under the final name";
  PreprocessOptions second = optionsFor(input, output);
  second.resume = true;
  second.threads = 1;  // and the thread count does not matter either
  const PreprocessReport resumed = runPreprocess(second);
  EXPECT_TRUE(resumed.bricking_reused);
  EXPECT_EQ(test::readFile(output), test::readFile(reference));
}

TEST(VisibilityBuild, DamagedPackageGivesFormatError) {
  const std::string original = test::readFile(deckPackage());
  VisibilityBuildOptions options;
  options.cells.target_cells = 8;
  options.sampling.rays_per_cell = 8;
  const int rejected = test::expectRobustToDamage(
      original, "damaged.twk",
      [&](const fs::path& path, SceneSink&) {
        const PackageView view = PackageView::open(path);
        buildVisibilitySection(view, options);
      },
      100);
  EXPECT_GT(rejected, 250);  // the truncations at least
}

// A mesh block behind a parametric wall (a box primitive 2 m thick): seen from the open side,
// the wall is the occluder and the block is not in the visible set; without parametric
// candidates the rays pass through the wall and the block is seen.
TEST(VisibilityBuild, ParametricWallOccludesWhatIsBehindIt) {
  const fs::path dir = test::scratchDir();
  const fs::path input = dir / "wall.tws";
  {
    TwsWriter writer(input);
    writer.onLayer(0, {"structure", 0xff336699u});
    SceneObject block;
    block.info.id = 0;
    block.info.name = "block";
    block.info.transform.origin = {-30.0, 0.0, 0.0};
    block.geometry = test::subdividedBox(glm::vec3(4.0f), 4);
    writer.onObject(block);
    SceneObject floor;  // in front of the wall: a second mesh object the open side sees
    floor.info.id = 1;
    floor.info.name = "floor";
    floor.info.transform.origin = {20.0, 0.0, -21.0};
    floor.geometry = test::subdividedBox(glm::vec3(19.0f, 20.0f, 1.0f), 4);
    writer.onObject(floor);
    SceneObject wall;
    wall.info.id = 2;
    wall.info.name = "wall";
    wall.info.transform.origin = {0.0, 0.0, 0.0};
    wall.geometry = Primitive{Box{glm::vec3(1.0f, 200.0f, 200.0f)}};
    writer.onObject(wall);
    SceneObject valve;  // a small box on the open side, in the wall's parametric cluster
    valve.info.id = 3;
    valve.info.name = "valve";
    valve.info.transform.origin = {10.0, 5.0, -10.0};
    valve.geometry = Primitive{Box{glm::vec3(0.05f)}};
    writer.onObject(valve);
    writer.finish();
  }
  PreprocessOptions options = optionsFor(input, dir / "wall.twk");
  options.visibility = false;
  runPreprocess(options);
  const PackageView view = PackageView::open(options.output);
  const auto clusters = view.clusters();
  uint32_t wall = UINT32_MAX;
  std::vector<uint32_t> block;
  for (uint32_t c = 0; c < clusters.size(); ++c) {
    if (clusters[c].kind == uint8_t(pkg::ClusterKind::Parametric)) wall = c;
    else if (clusters[c].level == 0 && view.objects()[clusters[c].object_min].id == 0)
      block.push_back(c);
  }
  ASSERT_NE(wall, UINT32_MAX);
  ASSERT_FALSE(block.empty());

  VisibilityBuildOptions with;
  with.sampling.rays_per_cell = 512;
  with.cells.cell_size_m = 8.0;
  with.max_candidate_triangles = 1u << 30;  // level 0: the block's own clusters
  VisibilityBuildOptions without = with;
  without.parametric_candidates = false;
  const std::vector<uint8_t> with_bytes = buildVisibilitySection(view, with);
  const std::vector<uint8_t> without_bytes = buildVisibilitySection(view, without);
  const VisibilityView a = VisibilityView::parse(with_bytes, "with", 0, clusters.size());
  const VisibilityView b = VisibilityView::parse(without_bytes, "without", 0, clusters.size());
  ASSERT_FALSE(a.empty());
  ASSERT_FALSE(b.empty());
  EXPECT_NE(a.header().flags & pkg::kParametricCandidates, 0u);
  EXPECT_EQ(b.header().flags & pkg::kParametricCandidates, 0u);

  // A camera on the open side, 20 m from the wall.
  const glm::dvec3 eye = glm::dvec3(20.0, 0.0, 0.0) - view.origin();
  const pkg::VisibilityCellRecord* ca = a.cellAt(eye);
  const pkg::VisibilityCellRecord* cb = b.cellAt(eye);
  ASSERT_NE(ca, nullptr);
  ASSERT_NE(cb, nullptr);
  auto contains = [](std::span<const uint32_t> ids, uint32_t id) {
    return std::find(ids.begin(), ids.end(), id) != ids.end();
  };
  auto seesBlock = [&](std::span<const uint32_t> ids) {
    return std::any_of(block.begin(), block.end(), [&](uint32_t c) { return contains(ids, c); });
  };
  EXPECT_TRUE(contains(a.occluders(*ca), wall));
  EXPECT_EQ(a.occluders(*ca)[0], wall) << "the wall covers half the sphere of directions";
  EXPECT_TRUE(contains(a.visible(*ca), wall));
  EXPECT_FALSE(seesBlock(a.visible(*ca)));
  EXPECT_TRUE(seesBlock(b.visible(*cb)));
  EXPECT_FALSE(contains(b.visible(*cb), wall));

  // The budget takes the widest instances first: none fit in 11 triangles (a box has 12), and
  // then the section does not claim parametric occluders; 12 take the wall but not the valve,
  // so the cluster is sampled but not listed (it stays always visible).
  VisibilityBuildOptions tight = with;
  tight.max_parametric_triangles = 11;
  VisibilityBuildReport tight_report;
  const std::vector<uint8_t> tight_bytes = buildVisibilitySection(view, tight, &tight_report);
  EXPECT_EQ(tight_report.parametric_instances, 0u);
  EXPECT_EQ(tight_report.parametric_instances_total, 2u);
  EXPECT_EQ(VisibilityView::parse(tight_bytes, "tight", 0, clusters.size()).header().flags &
                pkg::kParametricCandidates,
            0u);
  tight.max_parametric_triangles = 12;
  const std::vector<uint8_t> partial_bytes = buildVisibilitySection(view, tight, &tight_report);
  EXPECT_EQ(tight_report.parametric_instances, 1u);
  EXPECT_EQ(tight_report.parametric_triangles, 12u);
  EXPECT_EQ(tight_report.parametric_clusters, 1u);
  EXPECT_EQ(tight_report.parametric_candidates, 0u);
  EXPECT_FLOAT_EQ(tight_report.parametric_min_width_m, 400.0f) << "the wall's second edge";
  const VisibilityView partial =
      VisibilityView::parse(partial_bytes, "partial", 0, clusters.size());
  EXPECT_NE(partial.header().flags & pkg::kParametricCandidates, 0u);
  EXPECT_TRUE(partial.parametricCandidates().empty());
  EXPECT_TRUE(std::find(partial.occluders(*partial.cellAt(eye)).begin(),
                        partial.occluders(*partial.cellAt(eye)).end(),
                        wall) != partial.occluders(*partial.cellAt(eye)).end())
      << "the wall still stops rays";

  // The wall (its cluster's one instance sampled) is a listed candidate; the mapping keeps it
  // where the set names it and drops it where it does not, and keeps every parametric cluster
  // for a section without the list.
  const auto listed = a.parametricCandidates();
  ASSERT_EQ(listed.size(), 1u);
  EXPECT_EQ(listed[0], wall);
  PvsMapping mapping(view, a.header().candidate_level, listed);
  std::vector<uint8_t> flags;
  mapping.flags(a.visible(*ca), flags);
  EXPECT_EQ(flags[wall], 1);
  EXPECT_EQ(flags[block[0]], 0);
  mapping.flags({}, flags);
  EXPECT_EQ(flags[wall], 0);
  PvsMapping legacy(view, b.header().candidate_level, b.parametricCandidates());
  legacy.flags({}, flags);
  EXPECT_EQ(flags[wall], 1);
}

TEST(VisibilityBuild, PackageWithoutMeshClustersGivesNoSection) {
  const fs::path dir = test::scratchDir();
  const fs::path input = dir / "pipes.tws";
  {
    TwsWriter writer(input);
    writer.onLayer(0, {"piping", 0xff00aa00u});
    for (uint32_t i = 0; i < 3; ++i) {
      SceneObject pipe;
      pipe.info.id = i;
      pipe.info.name = "pipe " + std::to_string(i);
      pipe.info.transform.origin = {2.0 * i, 0.0, 0.0};
      pipe.geometry = Primitive{Cylinder{0.1f, 4.0f, false}};
      writer.onObject(pipe);
    }
    writer.finish();
  }
  PreprocessOptions options = optionsFor(input, dir / "pipes.twk");
  const PreprocessReport report = runPreprocess(options);
  EXPECT_EQ(report.visibility.section_bytes, 0u);
  const PackageView view = PackageView::open(options.output, PackageView::Verify::All);
  EXPECT_TRUE(view.visibility().empty());
  EXPECT_TRUE(buildVisibilitySection(view, VisibilityBuildOptions{}).empty());
}

}  // namespace
}  // namespace tw
