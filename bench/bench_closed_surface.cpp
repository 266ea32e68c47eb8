// Cost of the closed-surface test (preprocess/closed_surface.h) the bricking pass runs on every
// mesh piece: the generator's pump and compressor meshes and a finely tessellated sphere.
// items_per_second is triangles/s; multiplied out by a scene's mesh triangles it gives what the
// test adds to the brick stage.
#include <benchmark/benchmark.h>

#include "closed_surface.h"
#include "plant_parts.h"
#include "tessellate.h"

namespace tw {
namespace {

void runCheck(benchmark::State& state, const TriangleMesh& mesh) {
  for (auto _ : state) benchmark::DoNotOptimize(checkClosedSurface(mesh).enclosesSolid());
  state.SetItemsProcessed(int64_t(state.iterations()) * int64_t(mesh.indices.size() / 3));
  state.counters["triangles"] = double(mesh.indices.size() / 3);
}

const plant::EquipmentTemplates& templates() {
  static const plant::EquipmentTemplates t;
  return t;
}

void BM_ClosedSurfacePump(benchmark::State& state) {
  runCheck(state, std::get<TriangleMesh>(templates().pump.geometry));
}
BENCHMARK(BM_ClosedSurfacePump);

void BM_ClosedSurfaceCompressor(benchmark::State& state) {
  runCheck(state, std::get<TriangleMesh>(templates().compressor.geometry));
}
BENCHMARK(BM_ClosedSurfaceCompressor);

void BM_ClosedSurfaceSphere(benchmark::State& state) {
  static const TriangleMesh sphere = [] {
    TriangleMesh m;
    tessellatePrimitive(Sphere{1.0f}, 0.00002f, m);
    return m;
  }();
  runCheck(state, sphere);
}
BENCHMARK(BM_ClosedSurfaceSphere);

}  // namespace
}  // namespace tw

BENCHMARK_MAIN();
