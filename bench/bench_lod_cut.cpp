// Time of LodCut::select(): an orbit of 30 views at 1280x720, tau 1, every page resident (the
// full cut, the most work), and the worst case (tau 0, no culling: every group visited, level 0
// drawn). The package is TW_LOD_CUT_PACKAGE, or the Stanford bunny preprocessed on first use.
//
//   build-microbench/bench/bench_lod_cut --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
//
// Rates: items_per_second = cut selections (frames); clusters_tested_per_s = clusters whose
// bounds and error the traversal tested (its per-node cost).
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <numbers>

#include "camera.h"
#include "lod_cut.h"
#include "package_view.h"
#include "preprocess_driver.h"

namespace {

const tw::PackageView& package() {
  static const std::unique_ptr<tw::PackageView> view = [] {
    std::filesystem::path path;
    if (const char* given = std::getenv("TW_LOD_CUT_PACKAGE")) {
      path = given;
    } else {
      path = std::filesystem::temp_directory_path() / "terawalk-bench-bunny.twk";
      tw::PreprocessOptions options;
      options.inputs = {std::filesystem::path(TW_SHARED_DATA_DIR) / "stanford-bunny.obj"};
      options.output = path;
      tw::runPreprocess(options);
    }
    return std::make_unique<tw::PackageView>(tw::PackageView::open(path));
  }();
  return *view;
}

std::vector<tw::CutView> orbitViews(const tw::PackageView& view) {
  const auto& h = view.header();
  const glm::dvec3 lo(h.bounds_min[0], h.bounds_min[1], h.bounds_min[2]);
  const glm::dvec3 hi(h.bounds_max[0], h.bounds_max[1], h.bounds_max[2]);
  const glm::dvec3 center = view.origin() + 0.5 * (lo + hi);
  const double radius = glm::length(hi - lo) * 0.5;
  std::vector<tw::CutView> views;
  for (int i = 0; i < 30; ++i) {
    const double angle = 2 * std::numbers::pi * i / 30;
    tw::Camera camera;
    camera.position = center + radius * glm::dvec3(1.2 * std::cos(angle), 1.2 * std::sin(angle), 0.3);
    camera.near_m = std::max(1e-3, radius * 1e-4);
    camera.far_m = radius * 100;
    camera.lookAt(center);
    tw::CutView v;
    v.eye = camera.position - view.origin();
    v.frustum = tw::makeFrustum(camera, v.eye, 1280.0 / 720.0);
    v.pixel_scale = camera.pixelScale(720.0);
    v.near_m = camera.near_m;
    views.push_back(v);
  }
  return views;
}

void runSelect(benchmark::State& state, const tw::CutOptions& options) {
  const tw::PackageView& view = package();
  const tw::LodCut cut(view);
  const std::vector<tw::CutView> views = orbitViews(view);
  const auto all_resident = [](uint32_t) { return true; };
  tw::CutResult result;
  size_t i = 0;
  uint64_t tested = 0;
  for (auto _ : state) {
    cut.select(views[i++ % views.size()], options, all_resident, result);
    tested += result.stats.clusters_tested;
    benchmark::DoNotOptimize(result.clusters.data());
  }
  state.SetItemsProcessed(int64_t(state.iterations()));
  state.counters["clusters_tested_per_s"] =
      benchmark::Counter(double(tested), benchmark::Counter::kIsRate);
  state.counters["clusters"] = double(view.clusters().size());
  state.counters["drawn"] = double(result.clusters.size());
}

void BM_SelectOrbit(benchmark::State& state) { runSelect(state, tw::CutOptions{}); }

void BM_SelectWorstCase(benchmark::State& state) {
  tw::CutOptions options;
  options.tau_px = 0.0;
  options.min_feature_px = 0.0;
  options.frustum_cull = false;
  runSelect(state, options);
}

BENCHMARK(BM_SelectOrbit)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_SelectWorstCase)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
