// The LOD cut on real packages (the Stanford bunny, and a small plant-like scene of bricked boxes,
// scattered small parts, open sheets and parametric pipes at plant coordinates), both built once
// per program with runPreprocess: the cut equals the per-cluster rule when everything is
// resident, is monotone in tau, crack-free (no boundary edge level 0 lacks), falls back to
// resident ancestors and asks for exactly the missing pages, and culls by frustum and size.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <map>
#include <memory>
#include <numbers>
#include <set>
#include <unordered_map>
#include <unordered_set>

#include <unistd.h>

#include "bounds.h"
#include "camera.h"
#include "lod_cut.h"
#include "package_view.h"
#include "package_rewrite_support.h"
#include "preprocess_driver.h"
#include "test_support.h"
#include "tws_writer.h"

namespace tw {
namespace {

namespace fs = std::filesystem;
constexpr uint32_t kNone = pkg::kNone;
constexpr double kPi = std::numbers::pi;
constexpr double kWidth = 1280, kHeight = 720;

// Packages built once per process (test::processScratchDir: ctest runs every test as its own
// process, maybe several at once).
fs::path modelDir() { return test::processScratchDir("LodCutModels"); }

// ---- Test scenes ----

// A plant in miniature: an 8 x 8 grid of subdivided closed boxes (several bricks), hundreds of
// tiny disconnected boxes (the CAD case that needs sloppy simplification and dropping), open
// subdivided sheets (boundary edges the cut must keep), and parametric cylinders and spheres.
fs::path writePlantScene(const fs::path& dir) {
  fs::path path = dir / "plant.tws";
  TwsWriter writer(path);
  writer.onLayer(0, {"structure", 0xff336699u});
  writer.onLayer(1, {"piping", 0xff00aa00u});
  uint32_t id = 0;
  auto addBox = [&](glm::dvec3 origin, glm::vec3 half, int n) {
    SceneObject object;
    object.info.id = id;
    object.info.name = "box " + std::to_string(id++);
    object.info.transform.origin = origin;
    TriangleMesh mesh = test::subdividedBox(half, n);
    // Face grids repeat their shared edges' positions exactly; the DAG builder welds them.
    object.geometry = std::move(mesh);
    writer.onObject(object);
  };
  const glm::dvec3 site(500000.0, 7000000.0, 0.0);
  for (int gx = 0; gx < 8; ++gx)
    for (int gy = 0; gy < 8; ++gy) {
      glm::vec3 half(3.0f + gx % 3, 2.0f + gy % 4, 1.5f + (gx + gy) % 5);
      addBox(site + glm::dvec3(gx * 20.0, gy * 20.0, half.z), half, 6);
    }
  uint32_t seed = 1;
  auto next = [&]() {
    seed = seed * 1664525u + 1013904223u;
    return (seed >> 8) / 16777216.0;
  };
  for (int i = 0; i < 600; ++i) {
    glm::vec3 half(0.03f + 0.15f * static_cast<float>(next()));
    addBox(site + glm::dvec3(next() * 150.0, next() * 150.0, next() * 12.0), half, 1);
  }
  for (int i = 0; i < 40; ++i) {  // open sheets: one subdivided face each
    SceneObject sheet;
    sheet.info.id = id++;
    sheet.info.name = "sheet " + std::to_string(i);
    sheet.info.transform.origin = site + glm::dvec3(next() * 150.0, next() * 150.0, 8.0);
    TriangleMesh mesh;
    constexpr int n = 4;
    for (int a = 0; a <= n; ++a)
      for (int b = 0; b <= n; ++b)
        mesh.positions.push_back({a * 0.5f, b * 0.5f, 0.05f * static_cast<float>((a * b) % 3)});
    for (int a = 0; a < n; ++a)
      for (int b = 0; b < n; ++b) {
        uint32_t v = a * (n + 1) + b;
        mesh.indices.insert(mesh.indices.end(), {v, v + n + 1, v + n + 2, v, v + n + 2, v + 1});
      }
    sheet.geometry = std::move(mesh);
    writer.onObject(sheet);
  }
  for (int i = 0; i < 60; ++i) {
    SceneObject pipe;
    pipe.info.id = id++;
    pipe.info.layer = 1;
    pipe.info.name = "pipe " + std::to_string(i);
    pipe.info.transform.origin = site + glm::dvec3(5.0 + i * 2.3, 75.0 + (i % 7), 1.0);
    if (i % 4 == 3) pipe.geometry = Primitive{Sphere{0.4f}};
    else pipe.geometry = Primitive{Cylinder{0.15f, 6.0f, true}};
    writer.onObject(pipe);
  }
  writer.finish();
  return path;
}

// ---- A package with its decoded, welded geometry ----

struct Model {
  std::unique_ptr<PackageView> view;
  std::unique_ptr<LodCut> cut;
  std::vector<std::vector<uint32_t>> triangles;  // per mesh cluster: welded vertex ids, 3 a tri
  std::unordered_set<uint64_t> level0_boundary;  // edges used by one level-0 triangle
  std::unordered_set<uint32_t> level0_rim;  // vertices of level-0 edges not used exactly twice
  glm::dvec3 center_world{0.0};                  // of the package bounds
  double radius_m = 0.0;
  uint32_t bricks = 0;  // from the preprocessor's report (0: not built here)
};

uint64_t edgeKey(uint32_t a, uint32_t b) {
  if (a > b) std::swap(a, b);
  return (uint64_t{a} << 32) | b;
}

std::unordered_map<uint64_t, uint32_t> edgeCounts(const Model& model,
                                                  const std::vector<uint32_t>& clusters) {
  std::unordered_map<uint64_t, uint32_t> counts;
  for (uint32_t c : clusters) {
    const auto& t = model.triangles[c];
    for (size_t i = 0; i < t.size(); i += 3) {
      if (t[i] == t[i + 1] || t[i + 1] == t[i + 2] || t[i] == t[i + 2]) continue;
      ++counts[edgeKey(t[i], t[i + 1])];
      ++counts[edgeKey(t[i + 1], t[i + 2])];
      ++counts[edgeKey(t[i + 2], t[i])];
    }
  }
  return counts;
}

std::vector<uint64_t> boundaryEdges(const Model& model, const std::vector<uint32_t>& clusters) {
  std::vector<uint64_t> out;
  for (const auto& [edge, count] : edgeCounts(model, clusters))
    if (count == 1) out.push_back(edge);
  return out;
}

std::unique_ptr<Model> loadModel(const fs::path& package) {
  auto model = std::make_unique<Model>();
  model->view = std::make_unique<PackageView>(PackageView::open(package));
  model->cut = std::make_unique<LodCut>(*model->view);
  const PackageView& view = *model->view;
  auto clusters = view.clusters();
  model->triangles.resize(clusters.size());
  std::vector<std::vector<uint32_t>> by_page(view.pages().size());
  for (uint32_t c = 0; c < clusters.size(); ++c)
    if (clusters[c].kind == static_cast<uint8_t>(pkg::ClusterKind::Mesh))
      by_page[clusters[c].page].push_back(c);
  struct KeyHash {
    size_t operator()(const std::array<uint32_t, 3>& k) const {
      return (size_t{k[0]} * 0x9E3779B97F4A7C15ull) ^ (size_t{k[1]} * 0xC2B2AE3D27D4EB4Full) ^
             k[2];
    }
  };
  std::unordered_map<std::array<uint32_t, 3>, uint32_t, KeyHash> weld;
  std::vector<uint8_t> raw;
  DecodedCluster decoded;
  for (uint32_t p = 0; p < by_page.size(); ++p) {
    if (by_page[p].empty()) continue;
    view.readPage(p, raw);
    for (uint32_t c : by_page[p]) {
      view.decodeCluster(c, raw, decoded);
      std::vector<uint32_t> ids(decoded.positions.size());
      for (size_t v = 0; v < ids.size(); ++v) {
        std::array<uint32_t, 3> key;
        std::memcpy(key.data(), &decoded.positions[v], sizeof(key));
        ids[v] = weld.emplace(key, static_cast<uint32_t>(weld.size())).first->second;
      }
      for (uint32_t index : decoded.indices) model->triangles[c].push_back(ids[index]);
    }
  }
  for (const auto& [edge, count] : edgeCounts(*model, model->cut->levelZeroClusters())) {
    if (count == 1) model->level0_boundary.insert(edge);
    if (count != 2) model->level0_rim.insert({uint32_t(edge >> 32), uint32_t(edge)});
  }
  const auto& h = view.header();
  glm::dvec3 lo(h.bounds_min[0], h.bounds_min[1], h.bounds_min[2]);
  glm::dvec3 hi(h.bounds_max[0], h.bounds_max[1], h.bounds_max[2]);
  model->center_world = view.origin() + (lo + hi) * 0.5;
  model->radius_m = glm::length(hi - lo) * 0.5;
  return model;
}

const Model& bunny() {
  static std::unique_ptr<Model> model = [] {
    fs::path out = modelDir() / "bunny.twk";
    PreprocessOptions options;
    options.inputs = {test::sharedDataDir() / "stanford-bunny.obj"};
    options.output = out;
    runPreprocess(options);
    return loadModel(out);
  }();
  return *model;
}

// A real CAD part: the KiCad D-sub connector, 648 objects, many small disconnected pieces.
const Model& connector() {
  static std::unique_ptr<Model> model = [] {
    fs::path out = modelDir() / "kicad.twk";
    PreprocessOptions options;
    options.inputs = {test::sharedDataDir() / "kicad_dsub62.obj"};
    options.output = out;
    runPreprocess(options);
    return loadModel(out);
  }();
  return *model;
}

const Model& plant() {
  static std::unique_ptr<Model> model = [] {
    fs::path dir = modelDir();
    fs::path out = dir / "plant.twk";
    PreprocessOptions options;
    options.inputs = {writePlantScene(dir)};
    options.output = out;
    options.max_brick_triangles = 12000;  // several bricks, then merged levels
    options.cluster_size = 128;
    uint32_t bricks = runPreprocess(options).bricks;
    auto loaded = loadModel(out);
    loaded->bricks = bricks;
    return loaded;
  }();
  return *model;
}

const Model& bunnyPaged() {
  static std::unique_ptr<Model> model = [] {
    fs::path out = modelDir() / "bunny-paged.twk";
    test::rewritePackage(*bunny().view, out, false, true);
    return loadModel(out);
  }();
  return *model;
}

const Model& plantPaged() {
  static std::unique_ptr<Model> model = [] {
    fs::path out = modelDir() / "plant-paged.twk";
    test::rewritePackage(*plant().view, out, false, true);
    return loadModel(out);
  }();
  return *model;
}

// ---- Views and the independent reference rules ----

Camera cameraAt(const Model& model, glm::dvec3 offset_in_radii, double fov_deg = 60.0) {
  Camera camera;
  camera.position = model.center_world + offset_in_radii * model.radius_m;
  camera.fov_y_rad = fov_deg * kPi / 180.0;
  camera.near_m = std::max(1e-3, model.radius_m * 1e-3);
  camera.far_m = model.radius_m * 1000.0;
  camera.lookAt(model.center_world);
  return camera;
}

CutView cutViewOf(const Model& model, const Camera& camera) {
  CutView view;
  view.eye = camera.position - model.view->origin();
  view.frustum = makeFrustum(camera, view.eye, kWidth / kHeight);
  view.pixel_scale = camera.pixelScale(kHeight);
  view.near_m = camera.near_m;
  return view;
}

double projected(double error, const float center[3], double radius, const CutView& view) {
  double distance = glm::length(glm::dvec3(center[0], center[1], center[2]) - view.eye) - radius;
  return error * view.pixel_scale / std::max(distance, view.near_m);
}

// The flat rule of the format, cluster by cluster: error_px <= tau < parent_error_px.
std::vector<uint32_t> perClusterCut(const Model& model, const CutView& view, double tau) {
  std::vector<uint32_t> out;
  auto clusters = model.view->clusters();
  for (uint32_t i = 0; i < clusters.size(); ++i) {
    const pkg::ClusterRecord& c = clusters[i];
    if (c.kind != static_cast<uint8_t>(pkg::ClusterKind::Mesh)) continue;
    double e = projected(c.error, c.lod_center, c.lod_radius, view);
    double pe = std::isinf(c.parent_error)
                    ? std::numeric_limits<double>::infinity()
                    : projected(c.parent_error, c.parent_lod_center, c.parent_lod_radius, view);
    if (e <= tau && tau < pe) out.push_back(i);
  }
  return out;
}

std::vector<uint32_t> sorted(std::vector<uint32_t> v) {
  std::sort(v.begin(), v.end());
  return v;
}

CutOptions everything(double tau) {
  CutOptions options;
  options.tau_px = tau;
  options.frustum_cull = false;
  options.min_feature_px = 0.0;
  return options;
}

const auto kAllResident = [](uint32_t) { return true; };

// The groups above the drawn clusters (their parent groups, and upward). A valid cut is exactly
// the clusters whose parent group is in that set (or that are roots) and whose own group is not:
// anything else is an overlap (a drawn ancestor of a drawn cluster) or a hole.
std::vector<uint8_t> groupsAbove(const Model& model, const std::vector<uint32_t>& drawn) {
  auto clusters = model.view->clusters();
  auto groups = model.view->groups();
  std::vector<uint8_t> above(groups.size(), 0);
  std::vector<uint32_t> stack;
  for (uint32_t c : drawn)
    if (clusters[c].parent_group != kNone) stack.push_back(clusters[c].parent_group);
  while (!stack.empty()) {
    uint32_t g = stack.back();
    stack.pop_back();
    if (above[g]) continue;
    above[g] = 1;
    for (uint32_t c = groups[g].first_cluster; c < groups[g].first_cluster + groups[g].cluster_count;
         ++c)
      if (clusters[c].parent_group != kNone) stack.push_back(clusters[c].parent_group);
  }
  return above;
}

void expectValidCut(const Model& model, const std::vector<uint32_t>& drawn, const std::string& what) {
  auto clusters = model.view->clusters();
  std::vector<uint8_t> above = groupsAbove(model, drawn);
  std::vector<uint32_t> expected;
  for (uint32_t i = 0; i < clusters.size(); ++i) {
    const pkg::ClusterRecord& c = clusters[i];
    if (c.kind != static_cast<uint8_t>(pkg::ClusterKind::Mesh)) continue;
    if ((c.parent_group == kNone || above[c.parent_group]) && (c.group == kNone || !above[c.group]))
      expected.push_back(i);
  }
  EXPECT_EQ(sorted(drawn), expected) << what << ": not a cut of the DAG (overlap or hole)";
}

void expectNoNewBoundary(const Model& model, const std::vector<uint32_t>& drawn,
                         const std::string& what, bool exact) {
  std::vector<uint64_t> boundary = boundaryEdges(model, drawn);
  // A boundary edge is level 0's, or outlines one of its openings anew (both ends on its rims:
  // the rims of parts' own openings simplify, preprocess/cluster_dag.h); anything else is a crack.
  size_t cracks = 0;
  for (uint64_t edge : boundary)
    cracks += !model.level0_boundary.count(edge) &&
              !(model.level0_rim.count(uint32_t(edge >> 32)) && model.level0_rim.count(uint32_t(edge)));
  EXPECT_EQ(cracks, 0u) << what << ": boundary edges off level 0's rims";
  if (exact) {
    EXPECT_EQ(boundary.size(), model.level0_boundary.size()) << what;
  }
}

struct Eye {
  glm::dvec3 offset_in_radii;
  const char* name;
};
const Eye kEyes[] = {
    {{2.5, 0.4, 0.3}, "near side"},
    {{-0.3, -1.3, 0.6}, "close, above"},
    {{0.9, 0.0, 0.0}, "inside the bounds"},
    {{12.0, 7.0, 4.0}, "far"},
};
const double kTaus[] = {0.25, 1.0, 4.0, 16.0};

// ---- Index ----

TEST(LodCut, IndexesRootsRootPagesAndLevelZero) {
  for (const Model* model : {&bunny(), &plant()}) {
    const PackageView& view = *model->view;
    const LodCut& cut = *model->cut;
    auto clusters = view.clusters();
    std::set<uint32_t> root_pages;
    size_t roots = 0;
    for (uint32_t i = 0; i < clusters.size(); ++i)
      if (clusters[i].parent_group == kNone &&
          clusters[i].kind == static_cast<uint8_t>(pkg::ClusterKind::Mesh)) {
        ++roots;
        root_pages.insert(clusters[i].page);
        EXPECT_TRUE(std::count(cut.roots().begin(), cut.roots().end(), i));
      }
    EXPECT_EQ(cut.roots().size(), roots);
    EXPECT_EQ(std::vector<uint32_t>(root_pages.begin(), root_pages.end()), cut.rootPages());
    uint64_t level0_triangles = 0;
    for (uint32_t c : cut.levelZeroClusters()) {
      EXPECT_EQ(clusters[c].level, 0);
      level0_triangles += clusters[c].triangle_count;
    }
    EXPECT_EQ(level0_triangles, view.header().total_triangles);
    EXPECT_GT(view.groups().size(), 10u);  // a real DAG, not one level
  }
  EXPECT_EQ(bunny().view->header().total_triangles, 69451u);
  EXPECT_GT(plant().bricks, 1u);  // the plant's DAG joins several bricks' DAGs
}

// ---- Selection with everything resident ----

TEST(LodCut, AllResidentEqualsThePerClusterRule) {
  for (const Model* model : {&bunny(), &plant(), &connector()}) {
    CutResult result;
    std::set<size_t> distinct_sizes;
    for (const Eye& eye : kEyes)
      for (double tau : kTaus) {
        CutView view = cutViewOf(*model, cameraAt(*model, eye.offset_in_radii));
        model->cut->select(view, everything(tau), kAllResident, result);
        std::string what = std::string(eye.name) + " tau " + std::to_string(tau);
        EXPECT_EQ(sorted(result.clusters), perClusterCut(*model, view, tau)) << what;
        EXPECT_TRUE(result.wanted.empty()) << what;
        EXPECT_EQ(result.stats.groups_blocked, 0u);
        uint64_t triangles = 0;
        for (uint32_t c : result.clusters) triangles += model->view->clusters()[c].triangle_count;
        EXPECT_EQ(result.stats.triangles, triangles);
        distinct_sizes.insert(result.clusters.size());
      }
    EXPECT_GT(distinct_sizes.size(), 4u);  // the views exercise many different cuts
  }
}

TEST(LodCut, LoweringTauNeverLowersTheTriangleCount) {
  for (const Model* model : {&bunny(), &plant(), &connector()}) {
    CutResult result;
    for (const Eye& eye : kEyes) {
      CutView view = cutViewOf(*model, cameraAt(*model, eye.offset_in_radii));
      uint64_t previous = 0;
      for (double tau : {1e6, 256.0, 64.0, 16.0, 4.0, 2.0, 1.0, 0.5, 0.25, 0.05}) {
        model->cut->select(view, everything(tau), kAllResident, result);
        EXPECT_GE(result.stats.triangles, previous) << eye.name << " tau " << tau;
        previous = result.stats.triangles;
      }
      // Far enough down, the cut is the full-resolution model.
      model->cut->select(view, everything(0.0), kAllResident, result);
      EXPECT_EQ(sorted(result.clusters), model->cut->levelZeroClusters()) << eye.name;
    }
    // A huge tau from far away gives the roots.
    CutView far = cutViewOf(*model, cameraAt(*model, {20, 0, 0}));
    model->cut->select(far, everything(1e9), kAllResident, result);
    EXPECT_EQ(sorted(result.clusters), sorted(model->cut->roots()));
  }
}

TEST(LodCut, CutsAreCrackFreeAndWithoutOverlap) {
  const Model& model = bunny();
  CutResult result;
  size_t checked = 0;
  for (const Eye& eye : kEyes)
    for (double tau : kTaus) {
      CutView view = cutViewOf(model, cameraAt(model, eye.offset_in_radii));
      model.cut->select(view, everything(tau), kAllResident, result);
      std::string what = std::string("bunny ") + eye.name + " tau " + std::to_string(tau);
      expectValidCut(model, result.clusters, what);
      // The bunny's holes may be outlined anew by coarse clusters, never opened elsewhere.
      expectNoNewBoundary(model, result.clusters, what, false);
      checked += result.clusters.size();
    }
  EXPECT_GT(checked, 100u);
  ASSERT_GT(model.level0_boundary.size(), 0u);  // the bunny has holes: the check has teeth
}

TEST(LodCut, PlantAndCadCutsAreCrackFreeAndWithoutOverlap) {
  ASSERT_GT(plant().level0_boundary.size(), 0u);  // the open sheets
  for (const Model* m : {&plant(), &connector()}) {
  const Model& model = *m;
  CutResult result;
  for (const Eye& eye : kEyes)
    for (double tau : kTaus) {
      CutView view = cutViewOf(model, cameraAt(model, eye.offset_in_radii));
      model.cut->select(view, everything(tau), kAllResident, result);
      std::string what = std::string("plant ") + eye.name + " tau " + std::to_string(tau);
      expectValidCut(model, result.clusters, what);
      // Dropped parts take their sheets' borders with them: a subset, never a new edge.
      expectNoNewBoundary(model, result.clusters, what, false);
    }
  }
}

// ---- Ancestor fallback and page requests ----

// Pages resident: the root pages, and a pseudo-random share `keep_per_8` / 8 of the others.
std::function<bool(uint32_t)> partlyResident(const Model& model, uint32_t keep_per_8,
                                             uint32_t salt) {
  auto roots = std::make_shared<std::set<uint32_t>>(model.cut->rootPages().begin(),
                                                    model.cut->rootPages().end());
  return [roots, keep_per_8, salt](uint32_t page) {
    if (roots->count(page)) return true;
    return ((page + salt) * 2654435761u >> 13) % 8 < keep_per_8;
  };
}

// Checks a cut made with a partial residency against the rule, independently: the drawn set is
// a valid cut of resident clusters, and `wanted` is exactly the missing child pages of the
// groups on the cut's front whose error exceeds tau, each with that group's largest error.
void expectFallback(const Model& model, const CutView& view, double tau,
                    const std::function<bool(uint32_t)>& resident, const CutResult& result,
                    const std::string& what) {
  auto clusters = model.view->clusters();
  auto groups = model.view->groups();
  for (uint32_t c : result.clusters) EXPECT_TRUE(resident(clusters[c].page)) << what;
  expectValidCut(model, result.clusters, what);
  expectNoNewBoundary(model, result.clusters, what, false);

  std::vector<uint8_t> above = groupsAbove(model, result.clusters);
  std::map<uint32_t, double> expected;  // page -> priority
  uint32_t blocked = 0;
  for (uint32_t g = 0; g < groups.size(); ++g) {
    if (above[g]) continue;
    bool on_front = true;
    for (uint32_t c = groups[g].first_cluster; c < groups[g].first_cluster + groups[g].cluster_count;
         ++c)
      on_front &= clusters[c].parent_group == kNone || above[clusters[c].parent_group];
    if (!on_front) continue;
    double error_px = projected(groups[g].error, groups[g].lod_center, groups[g].lod_radius, view);
    if (!(error_px > tau)) continue;
    // It wants refinement but was not refined: some child page must be missing.
    bool missing = false;
    for (uint32_t c = 0; c < clusters.size(); ++c)
      if (clusters[c].parent_group == g && !resident(clusters[c].page)) {
        missing = true;
        double& priority = expected[clusters[c].page];
        priority = std::max(priority, error_px);
      }
    EXPECT_TRUE(missing) << what << ": group " << g << " should have been refined";
    ++blocked;
  }
  EXPECT_EQ(result.stats.groups_blocked, blocked) << what;
  std::set<uint32_t> seen;
  ASSERT_EQ(result.wanted.size(), expected.size()) << what;
  for (const PageWant& want : result.wanted) {
    EXPECT_TRUE(seen.insert(want.page).second) << what << ": page " << want.page << " twice";
    EXPECT_FALSE(resident(want.page)) << what;
    auto it = expected.find(want.page);
    ASSERT_NE(it, expected.end()) << what << ": page " << want.page << " not wanted";
    EXPECT_NEAR(want.priority, it->second, 1e-4 * it->second) << what;
  }
}

// With look-ahead (the default) the drawn cut is the same as without it, and `wanted` is exactly
// the missing child pages of every group the all-resident cut refines: the whole way down to the
// cut the view wants, asked for at once. The pages the fallback alone asks for keep their
// priorities (a group's projected error is at least its descendants').
void expectLookAhead(const Model& model, const CutView& view, double tau,
                     const std::function<bool(uint32_t)>& resident, const CutResult& without,
                     const CutResult& with, const std::string& what) {
  EXPECT_EQ(sorted(with.clusters), sorted(without.clusters)) << what;
  EXPECT_EQ(with.stats.groups_blocked, without.stats.groups_blocked) << what;
  CutResult full;
  model.cut->select(view, everything(tau), kAllResident, full);
  std::vector<uint8_t> refined = groupsAbove(model, full.clusters);
  std::set<uint32_t> expected;
  auto clusters = model.view->clusters();
  for (uint32_t c = 0; c < clusters.size(); ++c)
    if (clusters[c].parent_group != kNone && refined[clusters[c].parent_group] &&
        !resident(clusters[c].page))
      expected.insert(clusters[c].page);
  std::map<uint32_t, float> got;
  for (const PageWant& want : with.wanted) got[want.page] = want.priority;
  EXPECT_EQ(got.size(), with.wanted.size()) << what << ": a page asked for twice";
  std::set<uint32_t> got_pages;
  for (const auto& [page, priority] : got) got_pages.insert(page);
  EXPECT_EQ(got_pages, expected) << what;
  for (const PageWant& want : without.wanted) {
    auto it = got.find(want.page);
    ASSERT_NE(it, got.end()) << what << ": page " << want.page << " no longer asked for";
    EXPECT_NEAR(it->second, want.priority, 1e-4 * want.priority) << what;
  }
}

TEST(LodCut, MissingPagesFallBackToResidentAncestorsAndAreRequested) {
  for (const Model* model : {&bunnyPaged(), &plantPaged(), &bunny()}) {
    CutResult result, ahead;
    uint32_t total_blocked = 0;
    size_t extra_wanted = 0;
    for (uint32_t keep : {0u, 3u, 6u})
      for (const Eye& eye : kEyes)
        for (double tau : {0.5, 2.0}) {
          CutView view = cutViewOf(*model, cameraAt(*model, eye.offset_in_radii));
          auto resident = partlyResident(*model, keep, 17);
          CutOptions one_level = everything(tau);
          one_level.look_ahead = false;
          model->cut->select(view, one_level, resident, result);
          std::string what = std::string(eye.name) + " keep " + std::to_string(keep) + "/8 tau " +
                             std::to_string(tau);
          expectFallback(*model, view, tau, resident, result, what);
          total_blocked += result.stats.groups_blocked;
          model->cut->select(view, everything(tau), resident, ahead);
          expectLookAhead(*model, view, tau, resident, result, ahead, what + " look-ahead");
          extra_wanted += ahead.wanted.size() - result.wanted.size();
        }
    EXPECT_GT(total_blocked, 10u);
    EXPECT_GT(extra_wanted, 0u);  // looking ahead asked for more than the front's pages
  }
}

// Loading what is wanted, frame after frame, converges to the all-resident cut: in one round
// with look-ahead, within the DAG's depth (one level per round at worst) without it.
TEST(LodCut, LoadingWantedPagesConvergesToTheFullCut) {
  for (const Model* model : {&bunnyPaged(), &plantPaged()}) {
    for (bool look_ahead : {true, false}) {
      CutView view = cutViewOf(*model, cameraAt(*model, {0.9, 0.2, 0.3}));
      CutOptions options = everything(0.5);
      options.look_ahead = look_ahead;
      CutResult result;
      model->cut->select(view, options, kAllResident, result);
      std::vector<uint32_t> full = sorted(result.clusters);
      std::set<uint32_t> resident_pages(model->cut->rootPages().begin(),
                                        model->cut->rootPages().end());
      auto resident = [&](uint32_t page) { return resident_pages.count(page) > 0; };
      uint32_t frames = 0;
      for (; frames < 100; ++frames) {
        model->cut->select(view, options, resident, result);
        if (result.wanted.empty()) break;
        for (const PageWant& want : result.wanted) resident_pages.insert(want.page);
      }
      EXPECT_EQ(sorted(result.clusters), full);
      if (look_ahead) {
        EXPECT_EQ(frames, 1u);
      } else {
        EXPECT_LE(frames, model->view->header().level_count);
        EXPECT_GE(frames, 2u);
      }
      // Only pages the cut needed were loaded.
      EXPECT_LT(resident_pages.size(), model->view->pages().size());
      std::printf("[ lod ] %s, look-ahead %s: converged in %u rounds, %zu of %zu pages loaded\n",
                  model->view->fileName().c_str(), look_ahead ? "on" : "off", frames,
                  resident_pages.size(), model->view->pages().size());
    }
  }
}

// ---- Culling ----

TEST(LodCut, LookingAwayDrawsNothingAndWantsNothing) {
  for (const Model* model : {&bunnyPaged(), &plantPaged()}) {
    Camera camera = cameraAt(*model, {3, 0, 0});
    camera.lookAt(camera.position + (camera.position - model->center_world));  // turn around
    CutView view = cutViewOf(*model, camera);
    CutOptions options;
    options.tau_px = 1.0;
    CutResult result;
    auto only_roots = partlyResident(*model, 0, 0);
    model->cut->select(view, options, only_roots, result);
    EXPECT_TRUE(result.clusters.empty());
    EXPECT_TRUE(result.parametric_clusters.empty());
    EXPECT_TRUE(result.wanted.empty());  // nothing visible asks for pages
    EXPECT_GT(result.stats.culled_frustum, 0u);
    EXPECT_EQ(result.stats.groups_refined, 0u);
  }
}

// With frustum culling, the cut is the part of the unculled cut that intersects the frustum.
TEST(LodCut, FrustumCullingKeepsExactlyTheVisiblePartOfTheCut) {
  for (const Model* model : {&bunny(), &plant()}) {
    for (const Eye& eye : kEyes) {
      Camera camera = cameraAt(*model, eye.offset_in_radii, 35.0);
      camera.yaw_rad += 0.5;  // off centre: part of the model is outside
      CutView view = cutViewOf(*model, camera);
      CutOptions culled = everything(1.0);
      culled.frustum_cull = true;
      CutResult with, without;
      model->cut->select(view, culled, kAllResident, with);
      model->cut->select(view, everything(1.0), kAllResident, without);
      std::vector<uint32_t> visible;
      auto clusters = model->view->clusters();
      for (uint32_t c : without.clusters) {
        const auto& r = clusters[c];
        if (view.frustum.intersectsSphere({r.center[0], r.center[1], r.center[2]}, r.radius) &&
            view.frustum.intersectsBox({r.aabb_min[0], r.aabb_min[1], r.aabb_min[2]},
                                       {r.aabb_max[0], r.aabb_max[1], r.aabb_max[2]}))
          visible.push_back(c);
      }
      EXPECT_EQ(sorted(with.clusters), sorted(visible)) << eye.name;
      EXPECT_LE(with.stats.triangles, without.stats.triangles);
      if (std::string(eye.name) != "far") {
        EXPECT_LT(with.clusters.size(), without.clusters.size()) << eye.name;
        EXPECT_GT(with.stats.culled_frustum, 0u) << eye.name;
      }
    }
  }
}

TEST(LodCut, SmallFeaturesAreCulledFromFar) {
  // The bunny (0.15 m) from 2 km projects below a pixel: nothing is drawn.
  const Model& b = bunny();
  Camera camera = cameraAt(b, {1.0, 0, 0});
  camera.position = b.center_world + glm::dvec3(2000.0, 0, 0);
  camera.far_m = 1e5;
  camera.lookAt(b.center_world);
  CutOptions options;
  CutResult result;
  b.cut->select(cutViewOf(b, camera), options, kAllResident, result);
  EXPECT_TRUE(result.clusters.empty());
  EXPECT_GT(result.stats.culled_small, 0u);
  options.min_feature_px = 0.0;
  b.cut->select(cutViewOf(b, camera), options, kAllResident, result);
  EXPECT_FALSE(result.clusters.empty());

  // The plant: a threshold at the median projected cluster size culls exactly the clusters below
  // it, and culling by size never changes the LOD decisions (the kept set is a subset).
  const Model& p = plant();
  CutView view = cutViewOf(p, cameraAt(p, {1.5, 0.7, 0.5}));
  CutResult kept, all;
  p.cut->select(view, everything(1.0), kAllResident, all);
  auto clusters = p.view->clusters();
  auto diameterPx = [&](uint32_t c) {
    const auto& r = clusters[c];
    double distance = glm::length(glm::dvec3(r.center[0], r.center[1], r.center[2]) - view.eye);
    return 2.0 * r.radius * view.pixel_scale / std::max(distance - r.radius, view.near_m);
  };
  std::vector<double> sizes;
  for (uint32_t c : all.clusters) sizes.push_back(diameterPx(c));
  std::sort(sizes.begin(), sizes.end());
  ASSERT_GT(sizes.size(), 20u);
  double threshold = sizes[sizes.size() / 2];
  CutOptions small = everything(1.0);
  small.min_feature_px = threshold;
  p.cut->select(view, small, kAllResident, kept);
  EXPECT_GT(kept.stats.culled_small, 0u);
  EXPECT_LT(kept.clusters.size(), all.clusters.size());
  EXPECT_FALSE(kept.clusters.empty());
  std::set<uint32_t> kept_set(kept.clusters.begin(), kept.clusters.end());
  for (uint32_t c : all.clusters)
    EXPECT_EQ(kept_set.count(c) > 0, diameterPx(c) >= threshold) << "cluster " << c;
  EXPECT_EQ(kept.stats.culled_small + kept.clusters.size(), all.clusters.size());
}

TEST(LodCut, ParametricClustersAreCulledAndCounted) {
  const Model& model = plant();
  auto clusters = model.view->clusters();
  uint32_t parametric = 0;
  for (const auto& c : clusters) parametric += c.kind == static_cast<uint8_t>(pkg::ClusterKind::Parametric);
  ASSERT_GT(parametric, 0u);
  CutResult result;
  CutView view = cutViewOf(model, cameraAt(model, {1.5, 0.5, 0.4}));
  model.cut->select(view, everything(1.0), kAllResident, result);
  EXPECT_EQ(result.parametric_clusters.size(), parametric);
  uint32_t instances = 0;
  for (uint32_t c : result.parametric_clusters) {
    EXPECT_EQ(clusters[c].kind, static_cast<uint8_t>(pkg::ClusterKind::Parametric));
    instances += clusters[c].instance_count;
  }
  EXPECT_EQ(result.stats.parametric_instances, instances);
  EXPECT_EQ(instances, 60u);
  // Looking the other way culls them.
  Camera away = cameraAt(model, {3, 0, 0});
  away.lookAt(away.position + (away.position - model.center_world));
  CutOptions culled = everything(1.0);
  culled.frustum_cull = true;
  model.cut->select(cutViewOf(model, away), culled, kAllResident, result);
  EXPECT_TRUE(result.parametric_clusters.empty());
}

TEST(LodCut, PrefetchModeOnlyCollectsWantedPages) {
  const Model& model = bunnyPaged();
  CutView view = cutViewOf(model, cameraAt(model, {1.2, 0, 0}));
  auto resident = partlyResident(model, 2, 5);
  CutOptions options;
  CutResult full, prefetch;
  model.cut->select(view, options, resident, full);
  options.collect_draws = false;
  model.cut->select(view, options, resident, prefetch);
  EXPECT_TRUE(prefetch.clusters.empty());
  ASSERT_FALSE(full.wanted.empty());
  auto pages = [](const CutResult& r) {
    std::set<uint32_t> s;
    for (const PageWant& w : r.wanted) s.insert(w.page);
    return s;
  };
  EXPECT_EQ(pages(prefetch), pages(full));
}

TEST(LodCut, ReusesItsBuffersFromFrameToFrame) {
  const Model& model = bunnyPaged();
  CutView view = cutViewOf(model, cameraAt(model, {1.2, 0.3, 0}));
  CutOptions options;
  auto resident = partlyResident(model, 4, 1);
  CutResult result;
  model.cut->select(view, options, resident, result);
  const uint32_t* clusters = result.clusters.data();
  const PageWant* wanted = result.wanted.data();
  std::vector<uint32_t> first = result.clusters;
  for (int i = 0; i < 5; ++i) {
    model.cut->select(view, options, resident, result);
    EXPECT_EQ(result.clusters.data(), clusters);
    EXPECT_EQ(result.wanted.data(), wanted);
    EXPECT_EQ(result.clusters, first);  // and scratch state does not leak between calls
  }
}

// A residency predicate that throws mid-call leaves no stale state behind.
TEST(LodCut, RecoversFromAThrowingPredicate) {
  const Model& model = bunnyPaged();
  CutView view = cutViewOf(model, cameraAt(model, {1.2, 0.3, 0}));
  auto resident = partlyResident(model, 2, 3);
  CutResult before, after, scratch;
  int calls = 0;
  auto counting = [&](uint32_t page) {
    ++calls;
    return resident(page);
  };
  model.cut->select(view, CutOptions{}, counting, before);
  ASSERT_GE(before.wanted.size(), 2u);
  const int last = calls;  // throw at the last call: every page but the last one is wanted
  calls = 0;
  auto throwing = [&](uint32_t page) {
    if (++calls == last) throw std::runtime_error("pager gone");
    return resident(page);
  };
  EXPECT_THROW(model.cut->select(view, CutOptions{}, throwing, scratch), std::runtime_error);
  model.cut->select(view, CutOptions{}, resident, after);
  EXPECT_EQ(after.clusters, before.clusters);
  ASSERT_EQ(after.wanted.size(), before.wanted.size());
  for (size_t i = 0; i < after.wanted.size(); ++i) EXPECT_EQ(after.wanted[i].page, before.wanted[i].page);
}

// The format does not order groups; the cut must not depend on their indices. Rewrite the bunny
// package with its group table reversed (the worst case for an index-order walk) and compare.
TEST(LodCut, DoesNotDependOnGroupOrder) {
  const Model& model = bunnyPaged();
  fs::path file = test::scratchDir() / "reversed.twk";
  test::rewritePackage(*model.view, file, true, false);
  PackageView reversed = PackageView::open(file);
  // The preprocessor writes groups in build order (a group after the groups that produced its
  // children); the reversed copy breaks that everywhere, and the view still accepts it.
  auto producersBeforeParents = [](const PackageView& v) {
    size_t in_order = 0, edges = 0;
    for (const pkg::ClusterRecord& c : v.clusters())
      if (c.group != kNone && c.parent_group != kNone) {
        ++edges;
        in_order += c.group < c.parent_group;
      }
    return std::make_pair(in_order, edges);
  };
  auto [in_order, edges] = producersBeforeParents(*model.view);
  EXPECT_EQ(in_order, edges);
  EXPECT_GT(edges, 0u);
  EXPECT_EQ(producersBeforeParents(reversed).first, 0u);
  LodCut cut(reversed);
  CutResult a, b;
  for (const Eye& eye : kEyes)
    for (double tau : {0.5, 4.0}) {
      CutView cut_view = cutViewOf(model, cameraAt(model, eye.offset_in_radii));
      model.cut->select(cut_view, everything(tau), kAllResident, a);
      cut.select(cut_view, everything(tau), kAllResident, b);
      EXPECT_EQ(sorted(a.clusters), sorted(b.clusters)) << eye.name << " tau " << tau;
      auto resident = partlyResident(model, 3, 9);
      model.cut->select(cut_view, everything(tau), resident, a);
      cut.select(cut_view, everything(tau), resident, b);
      EXPECT_EQ(sorted(a.clusters), sorted(b.clusters)) << eye.name << " tau " << tau;
      EXPECT_EQ(a.wanted.size(), b.wanted.size());
    }
}

}  // namespace
}  // namespace tw
