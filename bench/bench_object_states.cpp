// What toggling a layer costs on the render thread: the CPU state change with its hidden-object
// count, and the one upload of every object's state to the GPU (GlRenderer::setObjectStates,
// timed to glFinish). Sized like the 10M plant: 120,173 objects, a layer of every eighth.
// Figures: docs/benchmarks.md, "Review".
#include <benchmark/benchmark.h>

#include <memory>
#include <vector>

#include <GL/gl.h>

#include "egl_context.h"
#include "gl_renderer.h"
#include "object_states.h"

namespace tw {
namespace {

constexpr uint32_t kObjects = 120'173;

std::vector<uint32_t> layerObjects() {
  std::vector<uint32_t> layer;
  for (uint32_t o = 0; o < kObjects; o += 8) layer.push_back(o);
  return layer;
}

// Hides the layer, or shows it again.
void toggle(ObjectStates& states, const std::vector<uint32_t>& layer, bool& hidden) {
  hidden = !hidden;
  for (uint32_t o : layer) states.set(o, kObjectHidden, hidden);
}

// Hide (and show again) one layer, then the first cut query that recounts.
void BM_ToggleLayerOnTheCpu(benchmark::State& state) {
  ObjectStates states(kObjects);
  const std::vector<uint32_t> layer = layerObjects();
  bool hidden = false;
  for (auto _ : state) {
    toggle(states, layer, hidden);
    benchmark::DoNotOptimize(states.anyOpaque(0, 7));
  }
  state.SetItemsProcessed(int64_t(state.iterations()) * int64_t(layer.size()));
}
BENCHMARK(BM_ToggleLayerOnTheCpu)->Unit(benchmark::kMillisecond);

// The whole state table in one upload, waited for.
void BM_UploadAllStates(benchmark::State& state) {
  EglContext context;
  RendererOptions options;
  options.width = 64;
  options.height = 64;
  GlRenderer renderer(options);
  renderer.setObjectColors(std::vector<uint32_t>(kObjects, 0xff808080u));
  ObjectStates states(kObjects);
  const std::vector<uint32_t> layer = layerObjects();
  bool hidden = false;
  for (auto _ : state) {
    toggle(states, layer, hidden);
    renderer.setObjectStates(states.gpuStates());
    glFinish();
  }
  state.SetBytesProcessed(int64_t(state.iterations()) * int64_t(kObjects * sizeof(GpuObjectState)));
}
BENCHMARK(BM_UploadAllStates)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace tw

BENCHMARK_MAIN();
