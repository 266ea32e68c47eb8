// Cost of the hierarchical-Z pyramid at 1280x720: the CPU build (HzbPyramid::fromDepth), the GPU
// compute build and its read-back on whatever EGL gives (llvmpipe in CI; skipped with a message
// when no context can be made), the depth read-back plus CPU build as the alternative, and the
// throughput of the box test (projectBox + occluded).
// The depth image is a deck-like scene: screen-aligned slabs at random distances over a far
// background, the same every run (fixed seed).
//
//   build-microbench/bench/bench_hzb --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
//
// Rates: items_per_second = depth pixels for the builds (1280x720 a build), boxes for the tests.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#define GL_GLEXT_PROTOTYPES 1
#include <GL/glcorearb.h>

#include "camera.h"
#include "egl_context.h"
#include "hzb_builder.h"
#include "hzb_pyramid.h"

namespace tw {
namespace {

constexpr int kWidth = 1280;
constexpr int kHeight = 720;

Camera benchCamera() {
  Camera camera;
  camera.near_m = 0.05;
  camera.far_m = 5000.0;
  return camera;
}

glm::mat4 viewProjection() {
  const Camera camera = benchCamera();
  return glm::mat4(camera.projection(double(kWidth) / kHeight) * camera.viewRotation());
}

const std::vector<float>& depthImage() {
  static const std::vector<float> image = [] {
    const Camera camera = benchCamera();
    const double n = camera.near_m, f = camera.far_m;
    std::vector<float> depth(size_t(kWidth) * kHeight, 0.0f);
    std::mt19937 rng(2024);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (int i = 0; i < 60; ++i) {
      const int x0 = int(u(rng) * kWidth), y0 = int(u(rng) * kHeight);
      const int x1 = std::min(kWidth - 1, x0 + int(u(rng) * kWidth * 0.5));
      const int y1 = std::min(kHeight - 1, y0 + int(u(rng) * kHeight * 0.5));
      const double distance = 2.0 + u(rng) * 60.0;
      const float d = float(-n / (f - n) + n * f / (f - n) / distance);
      for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x)
          depth[size_t(y) * kWidth + x] = std::max(depth[size_t(y) * kWidth + x], d);
    }
    return depth;
  }();
  return image;
}

void BM_HzbBuildCpu(benchmark::State& state) {
  const std::vector<float>& depth = depthImage();
  for (auto _ : state) {
    HzbPyramid pyramid = HzbPyramid::fromDepth(depth, kWidth, kHeight);
    benchmark::DoNotOptimize(pyramid.level(pyramid.levelCount() - 1).data());
  }
  state.SetItemsProcessed(int64_t(state.iterations()) * kWidth * kHeight);
}

// As the frame loop builds it: into the same pyramid frame after frame, level 0 filled in place.
void BM_HzbRebuildCpu(benchmark::State& state) {
  const std::vector<float>& depth = depthImage();
  HzbPyramid pyramid;
  for (auto _ : state) {
    const std::span<float> base = pyramid.beginBuild(kWidth, kHeight);
    std::copy(depth.begin(), depth.end(), base.begin());  // stands in for the read-back
    pyramid.finishBuild();
    benchmark::DoNotOptimize(pyramid.level(pyramid.levelCount() - 1).data());
  }
  state.SetItemsProcessed(int64_t(state.iterations()) * kWidth * kHeight);
}

// One context and one uploaded depth texture for the whole program; null when EGL fails.
struct GpuState {
  std::unique_ptr<EglContext> egl;
  std::unique_ptr<HzbBuilder> builder;
  GLuint depth = 0;
  std::string error;
};

GpuState& gpu() {
  static GpuState state = [] {
    GpuState s;
    try {
      s.egl = std::make_unique<EglContext>();
      s.builder = std::make_unique<HzbBuilder>();
      glCreateTextures(GL_TEXTURE_2D, 1, &s.depth);
      glTextureStorage2D(s.depth, 1, GL_DEPTH_COMPONENT32F, kWidth, kHeight);
      glTextureSubImage2D(s.depth, 0, 0, 0, kWidth, kHeight, GL_DEPTH_COMPONENT, GL_FLOAT,
                          depthImage().data());
      glFinish();
    } catch (const std::exception& e) {
      s.builder.reset();
      s.egl.reset();
      s.error = std::string("no GL context: ") + e.what();
    }
    return s;
  }();
  return state;
}

// Build only: glFinish makes the wall time the GPU's (llvmpipe runs on its own threads, so the
// benchmark is registered with UseRealTime).
void BM_HzbBuildGpu(benchmark::State& state) {
  GpuState& g = gpu();
  if (!g.builder) {
    state.SkipWithError(g.error.c_str());
    return;
  }
  for (auto _ : state) {
    g.builder->build(g.depth, kWidth, kHeight);
    glFinish();
  }
  state.SetItemsProcessed(int64_t(state.iterations()) * kWidth * kHeight);
  state.SetLabel(g.egl->renderer());
}

// Build and read back levels [first_level, end): what a CPU test of the GPU pyramid costs per
// frame. Level 0 is 3.5 MB; level 3 (160x90) 56 KB.
void BM_HzbBuildGpuReadBack(benchmark::State& state) {
  GpuState& g = gpu();
  if (!g.builder) {
    state.SkipWithError(g.error.c_str());
    return;
  }
  const int first_level = int(state.range(0));
  HzbPyramid pyramid;
  for (auto _ : state) {
    g.builder->build(g.depth, kWidth, kHeight);
    g.builder->readBack(pyramid, first_level);
    benchmark::DoNotOptimize(pyramid.level(pyramid.levelCount() - 1).data());
  }
  state.SetItemsProcessed(int64_t(state.iterations()) * kWidth * kHeight);
  state.SetLabel(g.egl->renderer());
}

// The alternative on a software rasterizer: read the depth back and build on the CPU.
void BM_HzbDepthReadBackCpuBuild(benchmark::State& state) {
  GpuState& g = gpu();
  if (!g.builder) {
    state.SkipWithError(g.error.c_str());
    return;
  }
  std::vector<float> depth(size_t(kWidth) * kHeight);
  for (auto _ : state) {
    glGetTextureImage(g.depth, 0, GL_DEPTH_COMPONENT, GL_FLOAT, GLsizei(depth.size() * 4),
                      depth.data());
    HzbPyramid pyramid = HzbPyramid::fromDepth(depth, kWidth, kHeight);
    benchmark::DoNotOptimize(pyramid.level(pyramid.levelCount() - 1).data());
  }
  state.SetItemsProcessed(int64_t(state.iterations()) * kWidth * kHeight);
  state.SetLabel(g.egl->renderer());
}

// Random boxes of 1 cm to 5 m at 1 to 80 m, spread over the view: the mix a walkthrough's node
// bounds give. Projection and test together, as the frame loop calls them.
struct Boxes {
  std::vector<glm::vec3> lo, hi;
};

const Boxes& boxes() {
  static const Boxes b = [] {
    Boxes out;
    std::mt19937 rng(77);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    for (int i = 0; i < 4096; ++i) {
      const float distance = 1.0f + 79.0f * u(rng);
      // Camera looks along +X; image right is -Y, image up is +Z.
      const glm::vec3 centre(distance, (u(rng) - 0.5f) * distance * 1.8f,
                             (u(rng) - 0.5f) * distance * 1.1f);
      const float size = 0.01f * std::pow(500.0f, u(rng));
      out.lo.push_back(centre - 0.5f * size);
      out.hi.push_back(centre + 0.5f * size);
    }
    return out;
  }();
  return b;
}

void BM_HzbProjectAndTest(benchmark::State& state) {
  const HzbPyramid pyramid = HzbPyramid::fromDepth(depthImage(), kWidth, kHeight);
  const glm::mat4 vp = viewProjection();
  const Boxes& b = boxes();
  size_t i = 0, hidden = 0;
  for (auto _ : state) {
    const ScreenFootprint fp = projectBox(b.lo[i], b.hi[i], vp, kWidth, kHeight);
    hidden += pyramid.occluded(fp) ? 1 : 0;
    i = (i + 1) % b.lo.size();
  }
  benchmark::DoNotOptimize(hidden);
  state.SetItemsProcessed(int64_t(state.iterations()));
  state.counters["occluded_fraction"] =
      state.iterations() ? double(hidden) / double(state.iterations()) : 0.0;
}

// The test alone, on footprints projected beforehand.
void BM_HzbOccludedOnly(benchmark::State& state) {
  const HzbPyramid pyramid = HzbPyramid::fromDepth(depthImage(), kWidth, kHeight);
  const glm::mat4 vp = viewProjection();
  const Boxes& b = boxes();
  std::vector<ScreenFootprint> footprints;
  for (size_t k = 0; k < b.lo.size(); ++k)
    footprints.push_back(projectBox(b.lo[k], b.hi[k], vp, kWidth, kHeight));
  size_t i = 0, hidden = 0;
  for (auto _ : state) {
    hidden += pyramid.occluded(footprints[i]) ? 1 : 0;
    i = (i + 1) % footprints.size();
  }
  benchmark::DoNotOptimize(hidden);
  state.SetItemsProcessed(int64_t(state.iterations()));
}

BENCHMARK(BM_HzbBuildCpu)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_HzbRebuildCpu)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_HzbBuildGpu)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_HzbBuildGpuReadBack)->Arg(0)->Arg(3)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_HzbDepthReadBackCpuBuild)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_HzbProjectAndTest);
BENCHMARK(BM_HzbOccludedOnly);

}  // namespace
}  // namespace tw

BENCHMARK_MAIN();
