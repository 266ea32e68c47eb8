// Impostors against run-time meshes on llvmpipe: a field of N instances of one primitive type
// (pipes, cones, spheres, elbows, boxes of plant-like sizes on a grid, seen from above at an
// angle so every one is on screen) drawn by ParametricRenderer at 1280x720, glFinish'ed, in
// `impostor` and `tessellated` mode. items/s counts instances drawn; tessellated meshes are built
// in a warm-up frame (the cache), so the timed frames measure drawing only.
//
// BM_Flicker measures how steady thin pipes are far away: a field of 2 m pipes and elbows 10 cm
// thick (under a pixel at 80 m) seen from 80 m while the camera slides a quarter pixel per frame
// for 48 frames. flicker_share = pixels whose object id changes between consecutive frames /
// pixels covered in either frame. Configurations: impostor (thin things drawn at least half a
// pixel thick, the default), impostor at true size (thin_radius_px 0), the same primitives
// tessellated at a fixed 1 mm and drawn as triangles (the reference a mesh renderer would give),
// and tessellated mode as it runs by default on llvmpipe (a resolution per instance at tau 1 px,
// thin tubes as ribbons, below 0.4 px left out).
#include <benchmark/benchmark.h>

#include <GL/gl.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <map>
#include <memory>
#include <numbers>
#include <string>

#include "camera.h"
#include "egl_context.h"
#include "gl_renderer.h"
#include "package_view.h"
#include "parametrics/parametric_renderer.h"
#include "preprocess_driver.h"
#include "tws_writer.h"

namespace tw {
namespace {

constexpr int kWidth = 1280;
constexpr int kHeight = 720;
constexpr int kSide = 40;  // kSide x kSide instances per type
constexpr double kSpacingM = 1.5;

Primitive primitiveOfType(int type) {
  switch (type) {
    case 0: return Cylinder{0.15f, 1.2f, true};
    case 1: return Cone{0.3f, 0.12f, 0.6f, true};
    case 2: return Sphere{0.4f};
    case 3: return TorusSegment{0.45f, 0.15f, float(std::numbers::pi / 2)};
    default: return Box{glm::vec3(0.5f, 0.3f, 0.2f)};
  }
}
const char* kTypeNames[] = {"cylinder", "cone", "sphere", "torus", "box"};

// Builds (once per type) the package of the field.
std::filesystem::path fieldPackage(int type) {
  static std::map<int, std::filesystem::path> built;
  if (auto it = built.find(type); it != built.end()) return it->second;
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("tw_bench_parametrics_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  const std::filesystem::path scene = dir / (std::string(kTypeNames[type]) + ".tws");
  {
    TwsWriter writer(scene);
    writer.onLayer(0, {"field", 0xff4080c0u});
    uint32_t id = 0;
    for (int i = 0; i < kSide; ++i)
      for (int j = 0; j < kSide; ++j) {
        SceneObject object;
        object.info.id = id;
        object.info.name = "part " + std::to_string(id);
        object.info.color_rgba = 0xff000000u | (0x40u + (id * 37u) % 0xa0u) << 8 | 0x80u;
        object.info.transform.origin = glm::dvec3(i * kSpacingM, j * kSpacingM, 0.0);
        const float a = 0.37f * float(id);  // various orientations
        object.info.transform.linear =
            glm::mat3(std::cos(a), std::sin(a), 0, -std::sin(a), std::cos(a), 0, 0, 0, 1) *
            glm::mat3(1, 0, 0, 0, std::cos(0.8f), std::sin(0.8f), 0, -std::sin(0.8f), std::cos(0.8f));
        object.geometry = primitiveOfType(type);
        writer.onObject(object);
        ++id;
      }
    writer.finish();
  }
  PreprocessOptions options;
  options.inputs = {scene};
  options.output = dir / (std::string(kTypeNames[type]) + ".twk");
  runPreprocess(options);
  built[type] = options.output;
  return options.output;
}

void BM_ParametricField(benchmark::State& state) {
  const int type = int(state.range(0));
  const ParametricMode mode = state.range(1) ? ParametricMode::Tessellated : ParametricMode::Impostor;
  static EglContext egl;
  const std::filesystem::path package = fieldPackage(type);
  PackageView view = PackageView::open(package, PackageView::Verify::Headers);
  RendererOptions renderer_options;
  renderer_options.width = kWidth;
  renderer_options.height = kHeight;
  GlRenderer renderer(renderer_options);
  std::vector<uint32_t> colors;
  for (const pkg::ObjectRecord& o : view.objects()) colors.push_back(o.color_rgba);
  renderer.setObjectColors(colors);
  ParametricRenderer parametric(view, renderer);
  std::vector<uint32_t> clusters;
  uint64_t instances = 0;
  for (uint32_t c = 0; c < view.clusters().size(); ++c)
    if (view.clusters()[c].kind == static_cast<uint8_t>(pkg::ClusterKind::Parametric)) {
      clusters.push_back(c);
      instances += view.clusters()[c].instance_count;
    }
  const double extent = (kSide - 1) * kSpacingM;
  Camera camera;
  camera.position = view.origin() + glm::dvec3(0.5 * extent, -0.35 * extent, 0.75 * extent);
  camera.lookAt(view.origin() + glm::dvec3(0.5 * extent, 0.45 * extent, 0.0));
  camera.near_m = 0.05;
  camera.far_m = 1000.0;
  ParametricView pv;
  pv.eye = camera.position - view.origin();
  pv.forward = camera.forward();
  pv.near_m = camera.near_m;
  pv.pixel_scale = camera.pixelScale(kHeight);
  pv.min_feature_px = 1.0;
  const glm::mat4 rotation(camera.viewRotation());
  const glm::mat4 projection(camera.projection(double(kWidth) / kHeight));
  uint64_t frame = 0;
  ParametricDrawStats stats;
  auto drawFrame = [&] {
    renderer.beginFrame(rotation, projection);
    stats = parametric.draw(clusters, pv, mode, frame++);
    renderer.endFrame();
    glFinish();
  };
  drawFrame();  // warm-up: programs, tessellated meshes
  for (auto _ : state) drawFrame();
  state.SetItemsProcessed(int64_t(state.iterations() * instances));
  state.counters["instances"] = double(instances);
  state.counters["mesh_triangles"] = double(stats.mesh_triangles);
  state.SetLabel(std::string(kTypeNames[type]) + " " + parametricModeName(mode));
}

std::filesystem::path thinPipesPackage() {
  static std::filesystem::path built;
  if (!built.empty()) return built;
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("tw_bench_parametrics_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  const std::filesystem::path scene = dir / "thin.tws";
  {
    TwsWriter writer(scene);
    writer.onLayer(0, {"pipes", 0xff3070d0u});
    uint32_t id = 0;
    for (int i = 0; i < 30; ++i)
      for (int j = 0; j < 30; ++j) {
        SceneObject object;
        object.info.id = id;
        object.info.name = "pipe " + std::to_string(id);
        object.info.color_rgba = 0xff000000u | (0x40u + (id * 53u) % 0xa0u) << 8 | 0x60u;
        object.info.transform.origin = glm::dvec3(i * 2.0, j * 2.0, 0.0);
        const float a = 0.61f * float(id);
        object.info.transform.linear =
            glm::mat3(std::cos(a), std::sin(a), 0, -std::sin(a), std::cos(a), 0, 0, 0, 1) *
            glm::mat3(1, 0, 0, 0, 0, 1, 0, -1, 0);  // axis horizontal
        if (id % 3 == 2)
          object.geometry = Primitive(TorusSegment{0.4f, 0.05f, float(std::numbers::pi / 2)});
        else
          object.geometry = Primitive(Cylinder{0.05f, 1.6f, true});
        writer.onObject(object);
        ++id;
      }
    writer.finish();
  }
  PreprocessOptions options;
  options.inputs = {scene};
  options.output = dir / "thin.twk";
  runPreprocess(options);
  built = options.output;
  return built;
}

void BM_Flicker(benchmark::State& state) {
  // 0 impostor, 1 impostor true size, 2 fine mesh, 3 tessellated per instance
  const int config = int(state.range(0));
  static EglContext egl;
  PackageView view = PackageView::open(thinPipesPackage(), PackageView::Verify::Headers);
  RendererOptions renderer_options;
  renderer_options.width = kWidth;
  renderer_options.height = kHeight;
  GlRenderer renderer(renderer_options);
  ParametricMeshOptions mesh_options;
  if (config == 2) mesh_options.fixed_tolerance_m = 0.001;
  ParametricRenderer parametric(view, renderer, mesh_options);
  std::vector<uint32_t> clusters;
  for (uint32_t c = 0; c < view.clusters().size(); ++c)
    if (view.clusters()[c].kind == static_cast<uint8_t>(pkg::ClusterKind::Parametric))
      clusters.push_back(c);
  Camera camera;
  camera.position = view.origin() + glm::dvec3(29.0, -50.0, 62.0);
  camera.lookAt(view.origin() + glm::dvec3(29.0, 29.0, 0.0));
  camera.near_m = 0.05;
  camera.far_m = 1000.0;
  const double px_m = glm::length(camera.position - (view.origin() + glm::dvec3(29, 29, 0))) /
                      camera.pixelScale(kHeight);
  const ParametricMode mode = config >= 2 ? ParametricMode::Tessellated : ParametricMode::Impostor;
  std::vector<uint32_t> previous, ids;
  uint64_t changed = 0, covered = 0, frames = 0;
  for (auto _ : state) {
    previous.clear();
    for (int f = 0; f < 48; ++f) {
      Camera c = camera;
      c.position += camera.right() * (0.25 * px_m * f);
      ParametricView pv;
      pv.eye = c.position - view.origin();
      pv.forward = c.forward();
      pv.near_m = c.near_m;
      pv.pixel_scale = c.pixelScale(kHeight);
      pv.min_feature_px = 1.0;
      pv.thin_radius_px = config == 1 ? 0.0 : 0.5;
      pv.tolerance_px = 1.0;
      renderer.beginFrame(glm::mat4(c.viewRotation()),
                          glm::mat4(c.projection(double(kWidth) / kHeight)));
      parametric.draw(clusters, pv, mode, uint64_t(f));
      renderer.endFrame();
      renderer.readObjectIds(ids, false);
      if (!previous.empty()) {
        for (size_t i = 0; i < ids.size(); ++i) {
          if (ids[i] == 0 && previous[i] == 0) continue;
          ++covered;
          changed += ids[i] != previous[i];
        }
        ++frames;
      }
      previous.swap(ids);
    }
  }
  state.counters["flicker_share"] = covered ? double(changed) / double(covered) : 0.0;
  state.counters["covered_px_per_frame"] = frames ? double(covered) / double(frames) : 0.0;
  state.SetItemsProcessed(int64_t(frames));  // frames compared per second
  const char* names[] = {"impostor", "impostor_true_size", "mesh_1mm", "tessellated_per_instance"};
  state.SetLabel(names[config]);
}

BENCHMARK(BM_Flicker)->DenseRange(0, 3)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);

BENCHMARK(BM_ParametricField)
    ->ArgsProduct({{0, 1, 2, 3, 4}, {0, 1}})
    ->ArgNames({"type", "tessellated"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()  // llvmpipe renders on its own threads: wall time is the cost
    ->MinTime(0.5);

}  // namespace
}  // namespace tw

BENCHMARK_MAIN();
