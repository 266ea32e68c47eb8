// Page encode and decode (formats/page_codec.h) on one core: the preprocessor's pack stage and the
// runtime loaders' work per page. Input: the Stanford bunny (TW_SHARED_DATA_DIR; the benchmarks
// skip with a message when it is missing) cut into 256-triangle clusters (clusterize.h, the
// preprocessor's default size), with an object id per 512 input triangles so clusters hold a few
// object runs like CAD clusters do. Clusters are packed into 128 KiB pages, 16-byte aligned, as
// PackageStorage does.
//
//   build-microbench/bench/bench_page_codec --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
//
// Rates: items_per_second = triangles; bytes_per_second = raw page bytes (encoded clusters before
// zstd), whichever side of the operation they are on, so every row compares directly. The
// counters say what each stream costs per triangle and what zstd saves.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "clusterize.h"
#include "obj_reader.h"
#include "package_format.h"
#include "page_codec.h"
#include "scene_sink.h"
#include "world_mesh_sink.h"

namespace tw {
namespace {

constexpr uint32_t kClusterTriangles = 256;
constexpr uint32_t kTrianglesPerObject = 512;
constexpr double kStepM = pkg::kDefaultPositionStepM;

struct Cluster {
  std::vector<glm::vec3> positions;  // compact
  std::vector<uint32_t> indices;
  std::vector<uint32_t> objects;
};

struct Page {
  std::vector<uint8_t> raw;                             // encoded clusters, 16-aligned
  std::vector<std::pair<uint32_t, uint32_t>> clusters;  // offset, encoded bytes
  uint64_t triangles = 0;
};

struct Corpus {
  std::string error;  // non-empty: no input
  std::vector<Cluster> clusters;
  uint64_t triangles = 0;
  uint32_t object_limit = 0;
  std::vector<std::vector<uint8_t>> encoded;  // per cluster, optimised
  uint64_t encoded_bytes = 0;
  std::vector<Page> pages;
  uint64_t page_raw_bytes = 0;
};

const Corpus& corpus() {
  static const Corpus c = [] {
    Corpus out;
    const std::filesystem::path path =
        std::filesystem::path(TW_SHARED_DATA_DIR) / "stanford-bunny.obj";
    if (!std::filesystem::exists(path)) {
      out.error = "shared data not present: " + path.string();
      return out;
    }
    WorldMeshSink sink;
    ReadOptions options;
    options.max_part_triangles = 1u << 24;
    readObj(path, sink, options);
    const TriangleClusters split =
        clusterizeTriangles(sink.positions, sink.indices, kClusterTriangles);
    std::vector<uint32_t> local(sink.positions.size(), ~0u);
    for (size_t k = 0; k < split.clusterCount(); ++k) {
      Cluster cluster;
      std::vector<uint32_t> used;
      for (uint32_t i = split.offsets[k]; i < split.offsets[k + 1]; ++i) {
        const uint32_t t = split.triangles[i];
        for (int corner = 0; corner < 3; ++corner) {
          const uint32_t v = sink.indices[3 * size_t(t) + corner];
          if (local[v] == ~0u) {
            local[v] = static_cast<uint32_t>(cluster.positions.size());
            cluster.positions.push_back(sink.positions[v]);
            used.push_back(v);
          }
          cluster.indices.push_back(local[v]);
        }
        cluster.objects.push_back(t / kTrianglesPerObject);
        out.object_limit = std::max(out.object_limit, t / kTrianglesPerObject + 1);
      }
      for (uint32_t v : used) local[v] = ~0u;
      out.triangles += cluster.objects.size();
      out.clusters.push_back(std::move(cluster));
    }
    // Encoded once for the decoders, then packed into pages like PackageStorage does.
    ClusterEncodeOptions encode;
    encode.position_step_m = kStepM;
    for (const Cluster& cluster : out.clusters) {
      std::vector<uint8_t> bytes;
      encodeCluster({cluster.positions, {}, cluster.indices, cluster.objects}, encode, bytes);
      out.encoded_bytes += bytes.size();
      out.encoded.push_back(std::move(bytes));
    }
    for (size_t k = 0; k < out.encoded.size(); ++k) {
      const std::vector<uint8_t>& bytes = out.encoded[k];
      uint64_t offset = out.pages.empty() ? 0 : pkg::alignUp(out.pages.back().raw.size(),
                                                             pkg::kClusterAlignment);
      if (out.pages.empty() || offset + bytes.size() > pkg::kDefaultTargetPageBytes) {
        out.pages.emplace_back();
        offset = 0;
      }
      Page& page = out.pages.back();
      page.raw.resize(offset, 0);
      page.raw.insert(page.raw.end(), bytes.begin(), bytes.end());
      page.clusters.emplace_back(static_cast<uint32_t>(offset),
                                 static_cast<uint32_t>(bytes.size()));
      page.triangles += out.clusters[k].objects.size();
    }
    for (const Page& page : out.pages) out.page_raw_bytes += page.raw.size();
    return out;
  }();
  return c;
}

// Sets the shared rates for work over the whole corpus, once per iteration.
void setRates(benchmark::State& state, const Corpus& c) {
  state.SetItemsProcessed(int64_t(state.iterations()) * int64_t(c.triangles));
  state.SetBytesProcessed(int64_t(state.iterations()) * int64_t(c.page_raw_bytes));
  state.counters["triangles"] = double(c.triangles);
  state.counters["clusters"] = double(c.clusters.size());
}

// encodeCluster on every cluster; range(0) = optimize (vertex-cache and vertex-fetch order).
void BM_EncodeClusters(benchmark::State& state) {
  const Corpus& c = corpus();
  if (!c.error.empty()) {
    state.SkipWithError(c.error.c_str());
    return;
  }
  ClusterEncodeOptions options;
  options.position_step_m = kStepM;
  options.optimize = state.range(0) != 0;
  std::vector<uint8_t> out;
  out.reserve(c.encoded_bytes * 2);
  for (auto _ : state) {
    out.clear();
    for (const Cluster& cluster : c.clusters)
      encodeCluster({cluster.positions, {}, cluster.indices, cluster.objects}, options, out);
    benchmark::DoNotOptimize(out.data());
  }
  setRates(state, c);
  state.counters["encoded_B_per_tri"] = double(out.size()) / double(c.triangles);
}

// decodeCluster on every cluster (the bounds-checked decoder the runtime loaders call).
void BM_DecodeClusters(benchmark::State& state) {
  const Corpus& c = corpus();
  if (!c.error.empty()) {
    state.SkipWithError(c.error.c_str());
    return;
  }
  DecodedCluster decoded;
  for (auto _ : state) {
    for (const std::vector<uint8_t>& bytes : c.encoded) {
      const DecodeStatus status = decodeCluster(bytes, kStepM, c.object_limit, decoded);
      if (!status.ok()) {
        state.SkipWithError(status.error);
        return;
      }
      benchmark::DoNotOptimize(decoded.indices.data());
    }
  }
  setRates(state, c);
  state.counters["encoded_B_per_tri"] = double(c.encoded_bytes) / double(c.triangles);
}

// zstd over whole pages; range(0) = level (the package writer's default is 9).
void BM_CompressPages(benchmark::State& state) {
  const Corpus& c = corpus();
  if (!c.error.empty()) {
    state.SkipWithError(c.error.c_str());
    return;
  }
  const int level = static_cast<int>(state.range(0));
  std::vector<uint8_t> out;
  uint64_t stored = 0;
  for (auto _ : state) {
    out.clear();
    for (const Page& page : c.pages) compressPage(page.raw, level, out);
    stored = out.size();
    benchmark::DoNotOptimize(out.data());
  }
  setRates(state, c);
  state.counters["pages"] = double(c.pages.size());
  state.counters["zstd_ratio"] = stored ? double(c.page_raw_bytes) / double(stored) : 0.0;
}

// Pages compressed at `level`, one buffer each.
std::vector<std::vector<uint8_t>> compressedPages(const Corpus& c, int level) {
  std::vector<std::vector<uint8_t>> stored;
  for (const Page& page : c.pages) {
    stored.emplace_back();
    compressPage(page.raw, level, stored.back());
  }
  return stored;
}

void BM_DecompressPages(benchmark::State& state) {
  const Corpus& c = corpus();
  if (!c.error.empty()) {
    state.SkipWithError(c.error.c_str());
    return;
  }
  const std::vector<std::vector<uint8_t>> stored = compressedPages(c, 9);
  std::vector<uint8_t> raw;
  for (auto _ : state) {
    for (size_t p = 0; p < c.pages.size(); ++p) {
      if (const char* error =
              decompressPage(stored[p], static_cast<uint32_t>(c.pages[p].raw.size()), raw)) {
        state.SkipWithError(error);
        return;
      }
      benchmark::DoNotOptimize(raw.data());
    }
  }
  setRates(state, c);
}

// What a loader does per page: decompress (range(0) = 1: zstd level 9 pages; 0: raw pages) and
// decode each of its clusters.
void BM_LoadPages(benchmark::State& state) {
  const Corpus& c = corpus();
  if (!c.error.empty()) {
    state.SkipWithError(c.error.c_str());
    return;
  }
  const bool zstd = state.range(0) != 0;
  const std::vector<std::vector<uint8_t>> stored = zstd ? compressedPages(c, 9)
                                                        : std::vector<std::vector<uint8_t>>{};
  std::vector<uint8_t> scratch;
  DecodedCluster decoded;
  for (auto _ : state) {
    for (size_t p = 0; p < c.pages.size(); ++p) {
      std::span<const uint8_t> raw = c.pages[p].raw;
      if (zstd) {
        if (const char* error =
                decompressPage(stored[p], static_cast<uint32_t>(c.pages[p].raw.size()), scratch)) {
          state.SkipWithError(error);
          return;
        }
        raw = scratch;
      }
      for (const auto& [offset, bytes] : c.pages[p].clusters) {
        const DecodeStatus status =
            decodeCluster(raw.subspan(offset, bytes), kStepM, c.object_limit, decoded);
        if (!status.ok()) {
          state.SkipWithError(status.error);
          return;
        }
        benchmark::DoNotOptimize(decoded.indices.data());
      }
    }
  }
  setRates(state, c);
}

BENCHMARK(BM_EncodeClusters)->ArgName("optimize")->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_DecodeClusters)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_CompressPages)->ArgName("level")->Arg(1)->Arg(3)->Arg(9)
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_DecompressPages)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_LoadPages)->ArgName("zstd")->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace tw

BENCHMARK_MAIN();
