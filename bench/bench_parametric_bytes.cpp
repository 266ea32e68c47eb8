// Package bytes of the piping layers kept as parametric instances against the same primitives
// tessellated at the preprocessor's tolerance and finer (docs/parametrics.md). Not a timing: one
// iteration that writes two piping-only scenes from a generated plant, preprocesses both and
// reports their package sizes and the ratio as counters.
//
//   build/bench/bench_parametric_bytes            (generates a 1M plant)
//   TW_PLANT_TWS=plant.tws build/bench/bench_parametric_bytes
#include <benchmark/benchmark.h>

#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "plant_generator.h"
#include "preprocess_driver.h"
#include "scene_io.h"
#include "scene_sink.h"
#include "tessellate.h"
#include "tws_writer.h"

namespace tw {
namespace {

namespace fs = std::filesystem;

// Passes the objects of layers whose name starts with "piping" to two writers: one keeps them
// as they are, the other tessellates their primitives into meshes.
class PipingSplitter : public SceneSink {
 public:
  PipingSplitter(TwsWriter& instances, TwsWriter& tessellated, float tolerance)
      : instances_(instances), tessellated_(tessellated), tolerance_(tolerance) {}

  void onLayer(uint32_t index, const Layer& layer) override {
    if (piping_.size() <= index) piping_.resize(index + 1, false);
    piping_[index] = layer.name.rfind("piping", 0) == 0;
    instances_.onLayer(index, layer);
    tessellated_.onLayer(index, layer);
  }
  void onObject(const SceneObject& object) override {
    if (object.info.layer >= piping_.size() || !piping_[object.info.layer]) return;
    instances_.onObject(object);
    SceneObject mesh;
    mesh.info = object.info;
    TriangleMesh triangles;
    tessellate(object.geometry, tolerance_, triangles);
    mesh.geometry = std::move(triangles);
    tessellated_.onObject(mesh);
    ++objects;
    if (std::holds_alternative<Primitive>(object.geometry)) ++primitives;
  }
  uint64_t objects = 0, primitives = 0;

 private:
  TwsWriter& instances_;
  TwsWriter& tessellated_;
  float tolerance_;
  std::vector<bool> piping_;
};

void BM_PipingPackageBytes(benchmark::State& state) {
  const fs::path dir = fs::temp_directory_path() / "terawalk-bench-parametric-bytes";
  fs::create_directories(dir);
  fs::path plant;
  if (const char* given = std::getenv("TW_PLANT_TWS")) {
    plant = given;
  } else {
    plant = dir / "plant.tws";
    PlantOptions options;
    options.target_triangles = 1'000'000;
    options.seed = 1;
    TwsWriter writer(plant);
    generatePlant(options, writer, nullptr, nullptr);
    writer.finish();
  }
  const float tolerance = float(state.range(0)) * 1e-6f;  // micrometres
  uint64_t instance_bytes = 0, tessellated_bytes = 0, objects = 0, primitives = 0;
  for (auto _ : state) {
    {
      TwsWriter instances(dir / "piping-instances.tws");
      TwsWriter tessellated(dir / "piping-tessellated.tws");
      PipingSplitter splitter(instances, tessellated, tolerance);
      readScene(plant, splitter);
      instances.finish();
      tessellated.finish();
      objects = splitter.objects;
      primitives = splitter.primitives;
    }
    for (const char* name : {"piping-instances", "piping-tessellated"}) {
      PreprocessOptions options;
      options.inputs = {dir / (std::string(name) + ".tws")};
      options.output = dir / (std::string(name) + ".twk");
      runPreprocess(options);
      (name == std::string("piping-instances") ? instance_bytes : tessellated_bytes) =
          fs::file_size(options.output);
    }
  }
  state.counters["piping_objects"] = double(objects);
  state.counters["piping_primitives"] = double(primitives);
  state.counters["instance_package_bytes"] = double(instance_bytes);
  state.counters["tessellated_package_bytes"] = double(tessellated_bytes);
  state.counters["ratio"] = instance_bytes ? double(tessellated_bytes) / double(instance_bytes) : 0.0;
  state.SetBytesProcessed(int64_t(instance_bytes + tessellated_bytes));
  if (!std::getenv("TW_KEEP")) fs::remove_all(dir);
}

// Chordal tolerance in micrometres: the preprocessor's default (2 mm, kDefaultChordalTolerance),
// then finer.
BENCHMARK(BM_PipingPackageBytes)
    ->ArgName("tolerance_um")
    ->Arg(int(kDefaultChordalTolerance * 1e6f + 0.5f))
    ->Arg(1000)
    ->Arg(500)
    ->Iterations(1)
    ->Unit(benchmark::kSecond)
    ->UseRealTime();

}  // namespace
}  // namespace tw

BENCHMARK_MAIN();
