// Reader throughput on one core: binary PLY, OBJ and .tws, each over the same mesh-heavy scene
// written once to /tmp (so the page cache, not the disk, is measured: the readers' own cost),
// plus .tws over a generated plant (parametric pipes, elbows, vessels, NURBS hulls: what .tws is
// for) and OBJ over a real CAD export.
//
//   build-microbench/bench/bench_readers --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
//
// Rates: bytes_per_second = bytes of file read; items_per_second = triangles delivered for the
// mesh scenes, objects delivered for the plant (its parametrics and NURBS stay parametric).
#include <benchmark/benchmark.h>

#include <cmath>
#include <filesystem>

#include "obj_writer.h"
#include "ply_reader.h"
#include "ply_writer.h"
#include "obj_reader.h"
#include "plant_generator.h"
#include "tessellate.h"
#include "tws_reader.h"
#include "tws_writer.h"

namespace tw {
namespace {

// A wavy 1000 x 1000 grid cut into 100 objects: about 2 M triangles, like a scanned or
// finely tessellated CAD part list.
void emitScene(SceneSink& sink) {
  sink.onLayer(0, {"default", 0xff808080u});
  constexpr int kObjects = 100, kRows = 10, kCols = 1000;
  for (int o = 0; o < kObjects; ++o) {
    SceneObject object;
    object.info.id = static_cast<uint32_t>(o);
    object.info.name = "part " + std::to_string(o);
    object.info.db_key = "K-" + std::to_string(o);
    object.info.transform.origin = {1000.0, 2000.0, 10.0 * o};
    TriangleMesh mesh;
    for (int r = 0; r <= kRows; ++r)
      for (int c = 0; c <= kCols; ++c)
        mesh.positions.push_back({c * 0.01f, r * 0.01f, 0.05f * std::sin(c * 0.1f + r * 0.3f)});
    for (int r = 0; r < kRows; ++r)
      for (int c = 0; c < kCols; ++c) {
        uint32_t a = static_cast<uint32_t>(r * (kCols + 1) + c), b = a + 1,
                 d = a + kCols + 1, e = d + 1;
        mesh.indices.insert(mesh.indices.end(), {a, b, e, a, e, d});
      }
    object.geometry = std::move(mesh);
    sink.onObject(object);
  }
}

std::filesystem::path fixture(const char* extension) {
  auto dir = std::filesystem::temp_directory_path() / "terawalk-bench";
  std::filesystem::create_directories(dir);
  auto path = dir / (std::string("readers") + extension);
  if (std::filesystem::exists(path)) return path;
  std::string ext = extension;
  if (ext == ".ply") {
    PlyWriter writer(path, kDefaultChordalTolerance);
    emitScene(writer);
    writer.finish();
  } else if (ext == ".obj") {
    ObjWriter writer(path, kDefaultChordalTolerance);
    emitScene(writer);
    writer.finish();
  } else {
    TwsWriter writer(path);
    emitScene(writer);
    writer.finish();
  }
  return path;
}

// Touches every part so that nothing is optimised away, and keeps nothing.
class CountingSink : public SceneSink {
 public:
  void onLayer(uint32_t, const Layer&) override {}
  void onObject(const SceneObject& object) override {
    ++objects;
    if (const auto* mesh = std::get_if<TriangleMesh>(&object.geometry))
      triangles += mesh->triangleCount();
  }
  uint64_t triangles = 0;
  uint64_t objects = 0;
};

template <void (*Read)(const std::filesystem::path&, SceneSink&, const ReadOptions&)>
void readerBenchmark(benchmark::State& state, const char* extension) {
  auto path = fixture(extension);
  uint64_t bytes = std::filesystem::file_size(path);
  uint64_t triangles = 0;
  for (auto _ : state) {
    CountingSink sink;
    Read(path, sink, ReadOptions{});
    triangles = sink.triangles;
    benchmark::DoNotOptimize(triangles);
  }
  state.SetBytesProcessed(static_cast<int64_t>(bytes * state.iterations()));
  state.SetItemsProcessed(static_cast<int64_t>(triangles * state.iterations()));
  state.counters["file_MB"] = static_cast<double>(bytes) / 1e6;
  state.counters["triangles"] = static_cast<double>(triangles);
}

// A generated plant of 500K equivalent triangles (seed 1) as .tws, written once per process
// (the generator is deterministic, so the file is the same every run).
std::filesystem::path plantFixture() {
  static const std::filesystem::path path = [] {
    auto dir = std::filesystem::temp_directory_path() / "terawalk-bench";
    std::filesystem::create_directories(dir);
    auto out = dir / "readers-plant.tws";
    TwsWriter writer(out);
    PlantOptions options;
    options.target_triangles = 500'000;
    generatePlant(options, writer, nullptr, nullptr);
    writer.finish();
    return out;
  }();
  return path;
}

void BM_ReadTwsPlant(benchmark::State& state) {
  const std::filesystem::path path = plantFixture();
  const uint64_t bytes = std::filesystem::file_size(path);
  uint64_t objects = 0, mesh_triangles = 0;
  for (auto _ : state) {
    CountingSink sink;
    readTws(path, sink, ReadOptions{});
    objects = sink.objects;
    mesh_triangles = sink.triangles;
    benchmark::DoNotOptimize(objects);
  }
  state.SetBytesProcessed(static_cast<int64_t>(bytes * state.iterations()));
  state.SetItemsProcessed(static_cast<int64_t>(objects * state.iterations()));
  state.counters["file_MB"] = static_cast<double>(bytes) / 1e6;
  state.counters["objects"] = static_cast<double>(objects);
  state.counters["mesh_triangles"] = static_cast<double>(mesh_triangles);
}

// A real CAD export (KiCad's D-sub connector, 648 objects, 3-decimal coordinates) when the
// shared models are present beside the repository.
void BM_ReadObjKicad(benchmark::State& state) {
  std::filesystem::path path = std::filesystem::path(TW_SHARED_DATA_DIR) / "kicad_dsub62.obj";
  if (!std::filesystem::exists(path)) {
    state.SkipWithError("shared data not present");
    return;
  }
  uint64_t bytes = std::filesystem::file_size(path);
  uint64_t triangles = 0;
  for (auto _ : state) {
    CountingSink sink;
    readObj(path, sink, ReadOptions{});
    triangles = sink.triangles;
    benchmark::DoNotOptimize(triangles);
  }
  state.SetBytesProcessed(static_cast<int64_t>(bytes * state.iterations()));
  state.SetItemsProcessed(static_cast<int64_t>(triangles * state.iterations()));
  state.counters["triangles"] = static_cast<double>(triangles);
}

void BM_ReadPlyBinary(benchmark::State& state) { readerBenchmark<readPly>(state, ".ply"); }
void BM_ReadObj(benchmark::State& state) { readerBenchmark<readObj>(state, ".obj"); }
void BM_ReadTws(benchmark::State& state) { readerBenchmark<readTws>(state, ".tws"); }

BENCHMARK(BM_ReadPlyBinary)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_ReadObj)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_ReadTws)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_ReadTwsPlant)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_ReadObjKicad)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace tw

BENCHMARK_MAIN();
