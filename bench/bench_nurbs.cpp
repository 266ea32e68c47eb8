// Tessellation rate of NURBS patch sets: the conforming shared-border algorithm
// (formats/nurbs_conforming.h) against today's per-patch tessellateNurbs (formats/), on the
// generator's hull and on a 2 x 2 layout, plus the OpenMesh check of the result.
//
// The hull comes from a generated scene named by the environment variable TW_HULL_TWS (for
// example `terawalk gen plant --triangles 200K -o plant.tws`; its first NURBS object is used);
// without it the hull benchmarks are skipped. Figures: items_per_second is patches/s,
// triangles_per_second the output rate.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <optional>
#include <string>

#include "nurbs_conforming.h"
#include "patch_mesh_check.h"
#include "scene_io.h"
#include "scene_sink.h"
#include "tessellate.h"

namespace tw {
namespace {

class FirstNurbsSink : public SceneSink {
 public:
  void onLayer(uint32_t, const Layer&) override {}
  void onObject(const SceneObject& o) override {
    if (const auto* n = std::get_if<NurbsPatchSet>(&o.geometry); n && !set) set = *n;
  }
  std::optional<NurbsPatchSet> set;
};

const NurbsPatchSet* hull() {
  static const std::optional<NurbsPatchSet> loaded = []() -> std::optional<NurbsPatchSet> {
    const char* path = std::getenv("TW_HULL_TWS");
    if (!path || !*path) return std::nullopt;
    FirstNurbsSink sink;
    readScene(path, sink);
    return sink.set;
  }();
  return loaded ? &*loaded : nullptr;
}

// Four bicubic patches over [0,2]^2 on one wavy height field; the second is reversed in both
// directions so the layout is not trivially aligned.
const NurbsPatchSet& gridOfFour() {
  static const NurbsPatchSet set = [] {
    NurbsPatchSet s;
    for (int pj = 0; pj < 2; ++pj)
      for (int pi = 0; pi < 2; ++pi) {
        NurbsPatch p;
        p.knots_u = p.knots_v = {0, 0, 0, 0, 1, 1, 1, 1};
        for (int j = 0; j < 4; ++j)
          for (int i = 0; i < 4; ++i) {
            const float x = static_cast<float>(pi) + static_cast<float>(i) / 3.0f;
            const float y = static_cast<float>(pj) + static_cast<float>(j) / 3.0f;
            const float z = 0.25f * std::sin(2.1f * x + 0.3f) * std::cos(1.7f * y - 0.2f) + 0.1f * x * y;
            p.control_points.push_back({x, y, z, 1.0f});
          }
        s.patches.push_back(std::move(p));
      }
    std::reverse(s.patches[1].control_points.begin(), s.patches[1].control_points.end());
    return s;
  }();
  return set;
}

const NurbsPatchSet* layout(int which) { return which == 0 ? hull() : &gridOfFour(); }

void report(benchmark::State& state, size_t patches, uint64_t triangles) {
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations() * patches));
  state.counters["triangles_per_second"] =
      benchmark::Counter(static_cast<double>(triangles * state.iterations()), benchmark::Counter::kIsRate);
  state.counters["triangles"] = static_cast<double>(triangles);
}

// Argument: 0 = generated hull, 1 = 2 x 2 layout. Tolerance 2 mm (hull, metres) or 0.5 mm.
float toleranceFor(int which) { return which == 0 ? kDefaultChordalTolerance : 0.0005f; }

void BM_Conforming(benchmark::State& state) {
  const NurbsPatchSet* set = layout(static_cast<int>(state.range(0)));
  if (!set) return state.SkipWithError("set TW_HULL_TWS to a generated .tws for the hull");
  uint64_t triangles = 0;
  for (auto _ : state) {
    TriangleMesh mesh;
    tessellateNurbsConforming(*set, toleranceFor(static_cast<int>(state.range(0))), mesh);
    triangles = mesh.triangleCount();
    benchmark::DoNotOptimize(mesh.indices.data());
  }
  report(state, set->patches.size(), triangles);
}

void BM_PerPatch(benchmark::State& state) {
  const NurbsPatchSet* set = layout(static_cast<int>(state.range(0)));
  if (!set) return state.SkipWithError("set TW_HULL_TWS to a generated .tws for the hull");
  uint64_t triangles = 0;
  for (auto _ : state) {
    TriangleMesh mesh;
    tessellateNurbs(*set, toleranceFor(static_cast<int>(state.range(0))), mesh);
    triangles = mesh.triangleCount();
    benchmark::DoNotOptimize(mesh.indices.data());
  }
  report(state, set->patches.size(), triangles);
}

void BM_CheckPatchMesh(benchmark::State& state) {
  const NurbsPatchSet* set = layout(static_cast<int>(state.range(0)));
  if (!set) return state.SkipWithError("set TW_HULL_TWS to a generated .tws for the hull");
  TriangleMesh mesh;
  tessellateNurbsConforming(*set, toleranceFor(static_cast<int>(state.range(0))), mesh);
  for (auto _ : state) {
    const PatchMeshReport r = checkPatchMesh(mesh, *set);
    if (!r.ok()) state.SkipWithError(r.first_problem.c_str());
    benchmark::DoNotOptimize(r.faces);
  }
  report(state, set->patches.size(), mesh.triangleCount());
}

BENCHMARK(BM_Conforming)->ArgName("hull0_grid1")->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_PerPatch)->ArgName("hull0_grid1")->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_CheckPatchMesh)->ArgName("hull0_grid1")->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace tw

BENCHMARK_MAIN();
