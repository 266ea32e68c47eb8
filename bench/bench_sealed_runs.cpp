// Time of findSealedRuns() (formats/sealed_pipe_runs.h), which the preprocessor runs once (and the
// runtime at start-up for packages that do not carry its result): on the instance table of
// TW_SEALED_RUNS_PACKAGE (a preprocessed plant), and on 20,000 synthetic flanged L-shaped runs
// (100,000 instances) when none is given.
//
//   TW_SEALED_RUNS_PACKAGE=plant-10M.twk build/bench/bench_sealed_runs --benchmark_repetitions=5
//
// items_per_second = instances examined.
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdlib>
#include <memory>
#include <numbers>
#include <vector>

#include <glm/glm.hpp>

#include "package_view.h"
#include "sealed_pipe_runs.h"

namespace {

tw::pkg::InstanceRecord instance(tw::pkg::PrimitiveType type, const glm::vec3& origin,
                                 const glm::mat3& linear, std::initializer_list<float> params,
                                 bool capped) {
  tw::pkg::InstanceRecord r{};
  for (int k = 0; k < 3; ++k) r.origin[k] = origin[k];
  for (int c = 0; c < 3; ++c)
    for (int k = 0; k < 3; ++k) r.linear[c * 3 + k] = linear[c][k];
  int k = 0;
  for (float p : params) r.params[k++] = p;
  r.type = static_cast<uint32_t>(type);
  r.flags = capped ? tw::pkg::kInstanceCapped : 0u;
  return r;
}

// Runs on a 2 m grid: flange, 1.2 m spool along +x, elbow, 1.2 m spool along +y, flange.
std::vector<tw::pkg::InstanceRecord> syntheticRuns(int count) {
  using tw::pkg::PrimitiveType;
  const glm::mat3 along_x(glm::vec3(0, 1, 0), glm::vec3(0, 0, 1), glm::vec3(1, 0, 0));
  const glm::mat3 along_y(glm::vec3(0, 0, 1), glm::vec3(1, 0, 0), glm::vec3(0, 1, 0));
  const glm::mat3 elbow(glm::vec3(0, -1, 0), glm::vec3(1, 0, 0), glm::vec3(0, 0, 1));
  const float r = 0.05f, bend = 0.2f, spool = 1.2f;
  std::vector<tw::pkg::InstanceRecord> out;
  const int side = int(std::ceil(std::sqrt(double(count))));
  for (int i = 0; i < count; ++i) {
    const glm::vec3 o(2.0f * float(i % side), 2.0f * float(i / side), 3.0f);
    out.push_back(instance(PrimitiveType::Cylinder, o - glm::vec3(0.02f, 0, 0), along_x,
                           {1.5f * r, 0.04f}, true));
    out.push_back(instance(PrimitiveType::Cylinder, o, along_x, {r, spool}, false));
    out.push_back(instance(PrimitiveType::TorusSegment, o + glm::vec3(spool, bend, 0), elbow,
                           {bend, r, 0.5f * std::numbers::pi_v<float>}, false));
    out.push_back(instance(PrimitiveType::Cylinder, o + glm::vec3(spool + bend, bend, 0), along_y,
                           {r, spool}, false));
    out.push_back(instance(PrimitiveType::Cylinder, o + glm::vec3(spool + bend, bend + spool - 0.02f, 0),
                           along_y, {1.5f * r, 0.04f}, true));
  }
  return out;
}

void run(benchmark::State& state, std::span<const tw::pkg::InstanceRecord> instances) {
  tw::SealedRunStats stats;
  for (auto _ : state) benchmark::DoNotOptimize(tw::findSealedRuns(instances, &stats));
  state.SetItemsProcessed(int64_t(state.iterations()) * int64_t(instances.size()));
  state.counters["instances"] = double(instances.size());
  state.counters["sealed_members"] = double(stats.sealed_members);
}

void BM_SealedRunsSynthetic(benchmark::State& state) {
  static const std::vector<tw::pkg::InstanceRecord> runs = syntheticRuns(20000);
  run(state, runs);
}
BENCHMARK(BM_SealedRunsSynthetic)->Unit(benchmark::kMillisecond);

void BM_SealedRunsPackage(benchmark::State& state) {
  const char* path = std::getenv("TW_SEALED_RUNS_PACKAGE");
  if (!path) {
    state.SkipWithError("TW_SEALED_RUNS_PACKAGE not set");
    return;
  }
  static const auto view = std::make_unique<tw::PackageView>(tw::PackageView::open(path));
  run(state, view->instances());
}
BENCHMARK(BM_SealedRunsPackage)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
