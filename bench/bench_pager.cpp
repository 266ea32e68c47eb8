// Pager queue operations and the loader hand-off (runtime/pager.h), without GL: takeUploads
// returns host data, so the whole page life cycle runs on the CPU.
//
// Two packages, written through PackageStorage into the temp directory at start-up (deleted at
// exit), both of bumpy grid patches with two objects each:
//  - "queue": 4096 pages of one 32-triangle cluster each, for the render thread's queue work;
//  - "stream": 64 pages of the default 128 KiB target (256-triangle clusters, about 2M
//    triangles), zstd as the writer does by default, for the load -> decode -> upload hand-off.
//
//   build-microbench/bench/bench_pager --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
//
// Rows (items_per_second = the operation named):
//  - RequestFrame/moving:1: one frame of a moving camera: beginFrame, then a request for every one
//    of the 4096 pages with a priority that changes each frame (each re-queues its page under the
//    queue lock). moving:0 is a still camera: the same priorities again, which the pager renews
//    without taking the lock. Nothing loads: loader_threads = 0 and a 1-byte host budget, so after
//    the first page the queue only grows and reorders.
//  - Touch: touch() of 4096 pages (the LRU mark the cut sets on every drawn page each frame).
//  - Stream/loaders:N: a camera sweeping the stream package: a window of 8 pages advancing 2
//    pages a step, each step running frames (request window by distance, touch, beginFrame,
//    takeUploads) until the whole window is resident, with a GPU budget of a quarter of the
//    package so eviction runs too. loaders:0 loads on the render thread inside beginFrame;
//    loaders:2 on two loader threads (this machine has 2 cores). items = pages uploaded, bytes =
//    upload bytes (what would go to the GPU), wall-clock time.
#include <benchmark/benchmark.h>

#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <glm/glm.hpp>

#include "package_view.h"
#include "package_writer.h"
#include "pager.h"

namespace tw {
namespace {

namespace fs = std::filesystem;

constexpr uint32_t kQueuePages = 4096;
constexpr uint32_t kStreamPages = 64;
constexpr uint32_t kWindowPages = 8;
constexpr uint32_t kWindowStep = 2;

fs::path scratchDir() {
  static const fs::path dir = [] {
    fs::path d = fs::temp_directory_path() / ("terawalk-bench-pager-" + std::to_string(::getpid()));
    fs::create_directories(d);
    return d;
  }();
  return dir;
}

// One bumpy grid patch of cols x rows quads at x offset `at`, two objects.
void addPatch(PackageStorage& storage, float at, int cols, int rows, uint32_t object) {
  std::vector<glm::vec3> positions;
  std::vector<uint32_t> indices, objects;
  for (int i = 0; i <= cols; ++i)
    for (int j = 0; j <= rows; ++j)
      positions.emplace_back(at + 1.5f * i / cols, 1.5f * j / rows,
                             0.1f * std::sin(0.7f * i + 1.3f * j + at));
  for (int i = 0; i < cols; ++i)
    for (int j = 0; j < rows; ++j) {
      const uint32_t a = i * (rows + 1) + j, b = a + 1, d = a + (rows + 1), e = d + 1;
      indices.insert(indices.end(), {a, d, e, a, e, b});
    }
  const uint32_t triangles = static_cast<uint32_t>(indices.size() / 3);
  for (uint32_t t = 0; t < triangles; ++t)
    objects.push_back(t < triangles / 2 ? object : object + 1);
  ClusterGeometryInput input;
  input.positions = positions;
  input.indices = indices;
  input.triangle_objects = objects;
  storage.addMeshCluster(input, ClusterLod{});
}

// About `pages` pages of clusters of cols x rows quads: one cluster a page when
// target_page_bytes is 0, else pages of that target size (the last page may be a small one).
std::unique_ptr<PackageView> makePackage(const char* name, uint32_t pages, int cols, int rows,
                                         uint32_t target_page_bytes) {
  constexpr uint32_t kObjects = 8;
  PackageStorage storage;
  storage.target_page_bytes = target_page_bytes == 0 ? 1 : target_page_bytes;
  storage.addLayer({"grid", 0xff808080u});
  for (uint32_t o = 0; o < kObjects; ++o) {
    ObjectInfo info;
    info.id = o;
    info.name = "patch " + std::to_string(o);
    storage.addObject(info, glm::vec3(0.0f, 0.0f, -1.0f), glm::vec3(2.0f * pages, 2.0f, 1.0f));
  }
  for (uint32_t cluster = 0; storage.pageCount() < pages + (target_page_bytes == 0 ? 0 : 1);
       ++cluster)
    addPatch(storage, 2.0f * cluster, cols, rows, cluster % (kObjects - 1));
  const fs::path path = scratchDir() / (std::string(name) + ".twk");
  writePackage(storage, path);
  return std::make_unique<PackageView>(PackageView::open(path));
}

const PackageView& queuePackage() {
  static const std::unique_ptr<PackageView> view = makePackage("queue", kQueuePages, 4, 4, 0);
  return *view;
}

const PackageView& streamPackage() {
  static const std::unique_ptr<PackageView> view =
      makePackage("stream", kStreamPages, 16, 8, pkg::kDefaultTargetPageBytes);
  return *view;
}

void BM_PagerRequestFrame(benchmark::State& state) {
  const PackageView& view = queuePackage();
  const bool moving = state.range(0) != 0;
  PagerOptions options;
  options.loader_threads = 0;
  options.host_budget_bytes = 1;
  Pager pager(view, makePackagePageSource(view), options);
  const auto pages = static_cast<uint32_t>(view.pages().size());
  uint64_t frame = 0;
  for (auto _ : state) {
    pager.beginFrame(++frame);
    const uint64_t shift = moving ? frame * 104729u : 0;
    for (uint32_t p = 0; p < pages; ++p)
      pager.request(p, static_cast<float>((p * 7919u + shift) % 1000u));
  }
  state.SetItemsProcessed(int64_t(state.iterations()) * pages);
  state.counters["pages"] = pages;
  state.counters["queued"] = pager.stats().pages_requested;
}

void BM_PagerTouch(benchmark::State& state) {
  const PackageView& view = queuePackage();
  PagerOptions options;
  options.loader_threads = 0;
  Pager pager(view, makePackagePageSource(view), options);
  const auto pages = static_cast<uint32_t>(view.pages().size());
  uint64_t frame = 0;
  for (auto _ : state) {
    pager.beginFrame(++frame);
    for (uint32_t p = 0; p < pages; ++p) pager.touch(p);
  }
  state.SetItemsProcessed(int64_t(state.iterations()) * pages);
}

void BM_PagerStream(benchmark::State& state) {
  const PackageView& view = streamPackage();
  const auto pages = static_cast<uint32_t>(view.pages().size());
  uint64_t raw_bytes = 0;
  for (const pkg::PageRecord& p : view.pages()) raw_bytes += p.raw_bytes;
  PagerOptions options;
  options.loader_threads = static_cast<uint32_t>(state.range(0));
  options.evict_after_frames = 2;
  // A quarter of the package's decoded size (16 bytes a triangle: poolLayoutFor's split).
  uint64_t triangles = 0;
  for (const pkg::ClusterRecord& c : view.clusters()) triangles += c.triangle_count;
  options.gpu_budget_bytes = triangles * 16 / 4;
  Pager pager(view, makePackagePageSource(view), options);
  uint64_t frame = 0, uploaded_pages = 0, uploaded_bytes = 0, evicted = 0, frames = 0;
  for (auto _ : state) {
    for (uint32_t first = 0; first + kWindowPages <= pages; first += kWindowStep) {
      for (uint32_t spins = 0;; ++spins) {
        if (spins > 1'000'000) {
          state.SkipWithError("the window never became resident");
          return;
        }
        bool all = true;
        for (uint32_t p = first; p < first + kWindowPages; ++p) {
          if (pager.resident(p)) {
            pager.touch(p);
          } else {
            all = false;
            pager.request(p, float(kWindowPages - (p - first)));
          }
        }
        if (all) break;
        pager.beginFrame(++frame);
        ++frames;
        std::vector<PageUpload> uploads = pager.takeUploads();
        const PagerStats stats = pager.stats();
        evicted += stats.pages_evicted;
        uploaded_pages += uploads.size();
        uploaded_bytes += stats.bytes_uploaded;
        if (uploads.empty() && options.loader_threads > 0) std::this_thread::yield();
      }
    }
  }
  state.SetItemsProcessed(int64_t(uploaded_pages));
  state.SetBytesProcessed(int64_t(uploaded_bytes));
  state.counters["pages"] = pages;
  state.counters["page_raw_KiB"] = double(raw_bytes) / pages / 1024.0;
  state.counters["evicted_per_sweep"] =
      state.iterations() ? double(evicted) / double(state.iterations()) : 0.0;
  state.counters["frames_per_sweep"] =
      state.iterations() ? double(frames) / double(state.iterations()) : 0.0;
}

BENCHMARK(BM_PagerRequestFrame)->ArgName("moving")->Arg(1)->Arg(0)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_PagerTouch)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_PagerStream)->ArgName("loaders")->Arg(0)->Arg(2)->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
}  // namespace tw

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  int status = 0;
  try {
    std::printf("packages: queue %zu pages, stream %zu pages\n", tw::queuePackage().pages().size(),
                tw::streamPackage().pages().size());
    benchmark::RunSpecifiedBenchmarks();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_pager: %s\n", e.what());
    status = 1;
  }
  benchmark::Shutdown();
  std::error_code ignored;
  std::filesystem::remove_all(tw::scratchDir(), ignored);
  return status;
}
