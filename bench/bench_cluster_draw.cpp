// What cluster size to draw on llvmpipe: the same ~1.2M triangles of CAD-like geometry (pipes,
// elbows, vessels, boxes tessellated at the default 2 mm tolerance) cut into clusters of 64 to
// 1024 triangles, drawn through GlRenderer with one multi-draw per frame at 1280x720, glFinish'ed.
// Also the cost of a draw on its own (1-triangle draws that clipping throws away) and of an
// empty frame (clears only), to separate per-draw overhead from per-triangle work.
//
// Clusters are contiguous runs of a spatially sorted index buffer (meshopt_spatialSortTriangles),
// each with its own vertices, vertex-cache optimised and quantized like the package
// (position_step * 2^shift cells, 16 bits), so vertex reuse inside a cluster is realistic.
#include <benchmark/benchmark.h>

#define GL_GLEXT_PROTOTYPES 1
#include <GL/glcorearb.h>
#include <meshoptimizer.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include "egl_context.h"
#include "geometry_pool.h"
#include "gl_renderer.h"
#include "package_format.h"
#include "scene.h"
#include "tessellate.h"

namespace tw {
namespace {

constexpr int kWidth = 1280;
constexpr int kHeight = 720;
constexpr uint64_t kTargetTriangles = 1'200'000;
constexpr double kStepM = pkg::kDefaultPositionStepM;

struct BenchContext {
  EglContext egl;
  GlRenderer renderer{[] {
    RendererOptions options;
    options.width = kWidth;
    options.height = kHeight;
    return options;
  }()};
};

BenchContext& context() {
  static BenchContext c;
  return c;
}

// A plant-like block: rows of pipes with elbows, spheres and boxes on a 3D grid, in metres.
struct Mesh {
  std::vector<glm::vec3> positions;
  std::vector<uint32_t> indices;
  std::vector<uint32_t> triangle_objects;
  glm::vec3 lo{1e30f}, hi{-1e30f};
};

const Mesh& sceneMesh() {
  static const Mesh mesh = [] {
    Mesh m;
      for (int k = 0; m.indices.size() / 3 < kTargetTriangles; ++k) {
      const int gx = k % 24, gy = (k / 24) % 24, gz = k / (24 * 24);
      Primitive primitive;
      switch (k % 4) {
        case 0: primitive = Cylinder{0.12f, 2.6f, false}; break;
        case 1: primitive = TorusSegment{0.5f, 0.12f, 1.5707964f}; break;
        case 2: primitive = Sphere{0.7f}; break;
        default: primitive = Box{glm::vec3(0.6f, 0.4f, 0.5f)}; break;
      }
      TriangleMesh part;
      tessellatePrimitive(primitive, kDefaultChordalTolerance, part);
      // A rotation per object so the pipes do not all line up.
      const float angle = 0.7f * static_cast<float>(k);
      const glm::mat3 rotation(glm::rotate(glm::mat4(1.0f), angle, glm::normalize(glm::vec3(
                                                                        1.0f, 0.5f, 0.3f))));
      const glm::vec3 at(gx * 3.0f, gy * 3.0f, gz * 3.0f);
      const auto base = static_cast<uint32_t>(m.positions.size());
      for (const glm::vec3& p : part.positions) {
        m.positions.push_back(at + rotation * p);
        m.lo = glm::min(m.lo, m.positions.back());
        m.hi = glm::max(m.hi, m.positions.back());
      }
      for (uint32_t index : part.indices) m.indices.push_back(base + index);
      // One object for all: the id pass costs the same whatever the ids are.
      m.triangle_objects.insert(m.triangle_objects.end(), part.indices.size() / 3, 0u);
    }
    // Spatial order, so a contiguous run of triangles is a compact cluster.
    std::vector<uint32_t> sorted(m.indices.size());
    meshopt_spatialSortTriangles(sorted.data(), m.indices.data(), m.indices.size(),
                                 &m.positions[0].x, m.positions.size(), sizeof(glm::vec3));
    m.indices = std::move(sorted);
    return m;
  }();
  return mesh;
}

struct ClusteredScene {
  std::unique_ptr<GeometryPool> pool;
  std::vector<GpuCluster> clusters;
  uint64_t triangles = 0;
  double mean_vertices = 0.0;
};

// Cuts the sorted mesh into clusters of `cluster_triangles` and uploads them into one pool.
ClusteredScene buildClusters(uint32_t cluster_triangles) {
  const Mesh& mesh = sceneMesh();
  ClusteredScene scene;
  PageUpload upload;
  std::vector<uint32_t> remap(mesh.positions.size(), ~0u);
  std::vector<uint32_t> used, local, optimized;
  const size_t triangle_total = mesh.indices.size() / 3;
  for (size_t first = 0; first < triangle_total; first += cluster_triangles) {
    const size_t count = std::min<size_t>(cluster_triangles, triangle_total - first);
    used.clear();
    local.clear();
    for (size_t i = 3 * first; i < 3 * (first + count); ++i) {
      uint32_t v = mesh.indices[i];
      if (remap[v] == ~0u) {
        remap[v] = static_cast<uint32_t>(used.size());
        used.push_back(v);
      }
      local.push_back(remap[v]);
    }
    for (uint32_t v : used) remap[v] = ~0u;
    // Vertex-cache order within the cluster, as the package encoder does.
    optimized.resize(local.size());
    meshopt_optimizeVertexCache(optimized.data(), local.data(), local.size(), used.size());

    glm::dvec3 lo(1e300), hi(-1e300);
    for (uint32_t v : used) {
      lo = glm::min(lo, glm::dvec3(mesh.positions[v]));
      hi = glm::max(hi, glm::dvec3(mesh.positions[v]));
    }
    GpuCluster c;
    const double extent = std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z});
    while (extent / (kStepM * std::ldexp(1.0, static_cast<int>(c.shift))) > 65535.0) ++c.shift;
    c.cell_m = kStepM * std::ldexp(1.0, static_cast<int>(c.shift));
    c.grid_origin = glm::ivec3(glm::floor(lo / c.cell_m));
    c.first_vertex = upload.vertices.size();
    c.first_index = upload.indices.size();
    c.first_triangle = upload.triangle_objects.size();
    c.vertex_count = static_cast<uint32_t>(used.size());
    c.triangle_count = static_cast<uint32_t>(count);
    for (uint32_t v : used) {
      glm::dvec3 q = glm::round(glm::dvec3(mesh.positions[v]) / c.cell_m -
                                glm::dvec3(c.grid_origin));
      q = glm::clamp(q, glm::dvec3(0.0), glm::dvec3(65535.0));
      pkg::EncodedVertex ev{};
      for (int a = 0; a < 3; ++a) ev.q[a] = static_cast<uint16_t>(q[a]);
      upload.vertices.push_back(ev);
    }
    for (uint32_t index : optimized) upload.indices.push_back(static_cast<uint16_t>(index));
    upload.triangle_objects.insert(upload.triangle_objects.end(),
                                   mesh.triangle_objects.begin() + first,
                                   mesh.triangle_objects.begin() + first + count);
    scene.clusters.push_back(c);
    scene.triangles += count;
  }
  scene.mean_vertices = double(upload.vertices.size()) / scene.clusters.size();
  PoolLayout layout{upload.vertices.size(), upload.indices.size(), upload.triangle_objects.size()};
  scene.pool = std::make_unique<GeometryPool>(layout);
  scene.pool->upload(upload);
  return scene;
}

// An oblique view from outside that frames the whole block.
struct View {
  glm::dvec3 eye;
  glm::mat4 rotation, projection;
};

View viewOf(const Mesh& mesh) {
  const glm::dvec3 lo(mesh.lo), hi(mesh.hi);
  const glm::dvec3 centre = 0.5 * (lo + hi);
  const double radius = 0.5 * glm::length(hi - lo);
  const double fov = 1.0471975511965976;
  const glm::dvec3 forward = glm::normalize(glm::dvec3(0.6, 0.7, -0.4));
  View view;
  view.eye = centre - forward * (radius / std::sin(fov / 2));
  view.rotation = glm::mat4(glm::lookAt(glm::dvec3(0.0), forward, glm::dvec3(0.0, 0.0, 1.0)));
  view.projection = glm::mat4(glm::perspectiveRH_ZO(fov, double(kWidth) / kHeight, 4.0 * radius,
                                                    0.05));
  return view;
}

std::vector<DrawItem> itemsFor(const std::vector<GpuCluster>& clusters, const glm::dvec3& eye) {
  std::vector<DrawItem> items;
  items.reserve(clusters.size());
  for (const GpuCluster& c : clusters) {
    DrawItem item;
    item.placement = c;
    item.offset_eye = glm::vec3(glm::dvec3(c.grid_origin) * c.cell_m - eye);
    items.push_back(item);
  }
  return items;
}

void BM_ClusterDraw(benchmark::State& state) {
  BenchContext& ctx = context();
  const auto cluster_triangles = static_cast<uint32_t>(state.range(0));
  static std::map<uint32_t, ClusteredScene> scenes;  // built once per size, outside the timing
  auto it = scenes.find(cluster_triangles);
  if (it == scenes.end()) it = scenes.emplace(cluster_triangles, buildClusters(cluster_triangles)).first;
  const ClusteredScene& scene = it->second;
  const View view = viewOf(sceneMesh());
  const std::vector<DrawItem> items = itemsFor(scene.clusters, view.eye);
  double gpu_ms = 0.0;
  uint64_t frames = 0;
  for (auto _ : state) {
    ctx.renderer.beginFrame(view.rotation, view.projection);
    ctx.renderer.draw(*scene.pool, items);
    ctx.renderer.endFrame();
    glFinish();
    gpu_ms += ctx.renderer.waitForGpuMs();
    ++frames;
  }
  state.counters["triangles"] = static_cast<double>(scene.triangles);
  state.counters["draws"] = static_cast<double>(scene.clusters.size());
  state.counters["verts_per_cluster"] = scene.mean_vertices;
  state.counters["tri_per_s"] = benchmark::Counter(static_cast<double>(scene.triangles),
                                                   benchmark::Counter::kIsIterationInvariantRate);
  state.counters["gpu_ms"] = frames ? gpu_ms / frames : 0.0;
}
BENCHMARK(BM_ClusterDraw)
    ->Arg(64)->Arg(128)->Arg(256)->Arg(512)->Arg(1024)
    ->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime()->UseRealTime();

// Per-draw cost on its own: `draws` one-triangle clusters behind the camera, which the
// rasterizer's clipping discards, so only the per-draw front end work remains.
void BM_DrawOverhead(benchmark::State& state) {
  BenchContext& ctx = context();
  const auto draws = static_cast<uint32_t>(state.range(0));
  PoolLayout layout{3, 3, 1};
  GeometryPool pool(layout);
  PageUpload upload;
  upload.vertices.resize(3);
  upload.vertices[1].q[0] = 1000;
  upload.vertices[2].q[1] = 1000;
  upload.indices = {0, 1, 2};
  upload.triangle_objects = {0};
  pool.upload(upload);
  GpuCluster c;
  c.vertex_count = 3;
  c.triangle_count = 1;
  c.cell_m = 1e-3;
  DrawItem item;
  item.placement = c;
  item.offset_eye = glm::vec3(0.0f, 0.0f, 5.0f);  // behind the camera, which looks along -Z
  const std::vector<DrawItem> items(draws, item);
  const glm::mat4 rotation(1.0f);
  const glm::mat4 projection(
      glm::perspectiveRH_ZO(1.0471975511965976, double(kWidth) / kHeight, 1000.0, 0.05));
  for (auto _ : state) {
    ctx.renderer.beginFrame(rotation, projection);
    ctx.renderer.draw(pool, items);
    ctx.renderer.endFrame();
    glFinish();
  }
  state.counters["draws"] = draws;
  state.counters["draws_per_s"] =
      benchmark::Counter(draws, benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_DrawOverhead)
    ->Arg(0)->Arg(1000)->Arg(10000)->Arg(100000)
    ->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime()->UseRealTime();

}  // namespace
}  // namespace tw

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  // Say what renders, so figures from a GPU and from llvmpipe are never mixed up.
  std::printf("GL_RENDERER: %s\n", tw::context().egl.renderer().c_str());
  const tw::Mesh& mesh = tw::sceneMesh();
  std::printf("scene: %zu triangles, %zu vertices, %dx%d\n", mesh.indices.size() / 3,
              mesh.positions.size(), tw::kWidth, tw::kHeight);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
