// What the parametric rendering tests share: small packages of parametric parts (or their fine
// meshes) built through the preprocessor, a renderer run until its cut is steady, and per-pixel
// comparisons of object ids and depth. Included by test_parametric_renderer.cpp (impostors, modes,
// the generated plant) and test_parametric_tessellated.cpp (per-instance tessellation).
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "camera_test_support.h"
#include "egl_context.h"
#include "frame_loop.h"
#include "preprocess_driver.h"
#include "tessellate.h"
#include "test_support.h"
#include "tws_writer.h"

namespace tw::parametric_test {

namespace fs = std::filesystem;

constexpr int kWidth = 256, kHeight = 192;
constexpr float kFineToleranceM = 0.0001f;  // the reference meshes: 0.1 mm chordal error

struct Part {
  uint32_t id = 0;
  Primitive primitive;
  Transform transform;
  uint32_t color = 0xff3080c0u;
};

// Writes `parts` (each as a parametric primitive, or finely tessellated into a mesh when
// `tessellated`) plus optional mesh objects into a .tws, preprocesses it, returns the package.
inline fs::path buildPackage(const std::string& name, const std::vector<Part>& parts,
                             bool tessellated, const std::vector<SceneObject>& meshes = {},
                             uint32_t parametric_cluster_size = 64) {
  const fs::path dir = test::processScratchDir("parametric_renderer");
  const fs::path scene = dir / (name + ".tws");
  {
    TwsWriter writer(scene);
    writer.onLayer(0, {"parts", 0xff909090u});
    for (const Part& part : parts) {
      SceneObject object;
      object.info.id = part.id;
      object.info.name = "part " + std::to_string(part.id);
      object.info.color_rgba = part.color;
      object.info.transform = part.transform;
      if (tessellated) {
        TriangleMesh mesh;
        tessellatePrimitive(part.primitive, kFineToleranceM, mesh);
        mesh.normals.clear();
        object.geometry = std::move(mesh);
      } else {
        object.geometry = part.primitive;
      }
      writer.onObject(object);
    }
    for (const SceneObject& mesh : meshes) writer.onObject(mesh);
    writer.finish();
  }
  const fs::path out = dir / (name + ".twk");
  PreprocessOptions options;
  options.inputs = {scene};
  options.output = out;
  options.parametric_cluster_size = parametric_cluster_size;
  runPreprocess(options);
  return out;
}

using test::lookingAt;

struct Frame {
  std::vector<uint32_t> ids;
  std::vector<float> depth;
  std::vector<uint8_t> rgba;
  FrameStats stats;
};

// Renders until the cut is complete and steady. `reference`: every level-0 cluster (the fine
// meshes are compared at full resolution, not at a LOD whose error is a fraction of a pixel).
inline Frame render(const fs::path& package, const Camera& camera, ParametricMode mode,
                    OcclusionMode occlusion = OcclusionMode::Off, Walkthrough** keep = nullptr,
                    bool reference = false, double tau_px = 0.25, double fixed_tolerance_m = 0.0,
                    uint32_t clusters_per_run = 32, uint32_t primitives_per_flush = 8192,
                    bool scale_index = true, bool box_rows = true) {
  WalkthroughOptions options;
  options.reference = reference;
  options.parametric_meshes.fixed_tolerance_m = fixed_tolerance_m;
  options.parametric_meshes.clusters_per_run = clusters_per_run;
  options.parametric_meshes.primitives_per_flush = primitives_per_flush;
  options.parametric_meshes.scale_index = scale_index;
  options.parametric_meshes.box_rows = box_rows;
  options.width = kWidth;
  options.height = kHeight;
  options.occlusion = occlusion;
  options.prefetch = false;
  options.tau_px = tau_px;
  options.parametrics = mode;
  static std::unique_ptr<Walkthrough> kept;
  kept.reset();
  auto walk = std::make_unique<Walkthrough>(package, options);
  Frame frame;
  int complete = 0;
  for (int i = 0; i < 100 && complete < 3; ++i) {
    frame.stats = walk->renderFrame(camera, 0.0);
    complete = frame.stats.ancestor_fallbacks == 0 && frame.stats.pages_requested == 0
                   ? complete + 1
                   : 0;
  }
  walk->renderer().readObjectIds(frame.ids);
  walk->renderer().readDepth(frame.depth);
  walk->renderer().readColor(frame.rgba);
  if (keep) {
    kept = std::move(walk);
    *keep = kept.get();
  }
  return frame;
}

// Where a world point lands in the image (top-down rows), -1 when behind the eye.
inline glm::ivec2 pixelOf(const Camera& camera, const glm::dvec3& world) {
  const glm::dmat4 vp = camera.projection(double(kWidth) / kHeight) * camera.viewRotation();
  const glm::dvec4 clip = vp * glm::dvec4(world - camera.position, 1.0);
  if (clip.w <= 0.0) return {-1, -1};
  const double x = (clip.x / clip.w * 0.5 + 0.5) * kWidth;
  const double y = (1.0 - (clip.y / clip.w * 0.5 + 0.5)) * kHeight;
  return {int(std::floor(x)), int(std::floor(y))};
}

inline uint32_t idAt(const Frame& frame, glm::ivec2 p) {
  if (p.x < 0 || p.y < 0 || p.x >= kWidth || p.y >= kHeight) return ~0u;
  return frame.ids[size_t(p.y) * kWidth + p.x];
}
inline float depthAt(const Frame& frame, glm::ivec2 p) {
  return frame.depth[size_t(p.y) * kWidth + p.x];
}

struct Agreement {
  size_t covered = 0;        // pixels either frame covers
  size_t mismatched = 0;     // covered by one only, or by different objects
  size_t both = 0;           // covered by both with the same object
  size_t depth_close = 0;    // of `both`: relative depth difference within the tolerance
  std::vector<double> relative_depth;  // of `both`
  double mismatchShare() const { return covered ? double(mismatched) / covered : 1.0; }
  double depthShare() const { return both ? double(depth_close) / both : 0.0; }
  // Quantile q in [0, 1] of the relative depth differences.
  double depthQuantile(double q) {
    if (relative_depth.empty()) return 1.0;
    const size_t k = std::min(relative_depth.size() - 1, size_t(q * relative_depth.size()));
    std::nth_element(relative_depth.begin(), relative_depth.begin() + k, relative_depth.end());
    return relative_depth[k];
  }
};

// Reversed-Z depth is about near / distance, so a relative depth difference is a relative
// distance difference.
// Silhouettes: where the view ray grazes the surface, a chordal error of 0.5 mm moves the depth
// by centimetres, so depth is judged by quantiles, not by its worst pixel.
inline Agreement compare(const Frame& a, const Frame& b, double relative_depth_tolerance) {
  Agreement g;
  for (size_t i = 0; i < a.ids.size(); ++i) {
    if (a.ids[i] == 0 && b.ids[i] == 0) continue;
    ++g.covered;
    if (a.ids[i] != b.ids[i]) {
      ++g.mismatched;
      continue;
    }
    ++g.both;
    const double da = a.depth[i], db = b.depth[i];
    g.depth_close += std::abs(da - db) <= relative_depth_tolerance * std::max(da, db);
    g.relative_depth.push_back(std::abs(da - db) / std::max({da, db, 1e-30}));
  }
  return g;
}

inline Transform placed(const glm::dvec3& origin, const glm::vec3& axis_deg = glm::vec3(0.0f)) {
  Transform t;
  t.origin = origin;
  const glm::vec3 a = glm::radians(axis_deg);
  const glm::mat3 rx(1, 0, 0, 0, std::cos(a.x), std::sin(a.x), 0, -std::sin(a.x), std::cos(a.x));
  const glm::mat3 ry(std::cos(a.y), 0, -std::sin(a.y), 0, 1, 0, std::sin(a.y), 0, std::cos(a.y));
  const glm::mat3 rz(std::cos(a.z), std::sin(a.z), 0, -std::sin(a.z), std::cos(a.z), 0, 0, 0, 1);
  t.linear = rz * ry * rx;
  return t;
}

// An I-beam profile 0.3 m deep and 0.15 m wide, 10 mm flanges, 10 mm web, counter-clockwise.
inline std::vector<glm::vec2> smallIBeam() {
  return {{-0.075f, -0.15f}, {0.075f, -0.15f}, {0.075f, -0.14f}, {0.005f, -0.14f},
          {0.005f, 0.14f},   {0.075f, 0.14f},  {0.075f, 0.15f},  {-0.075f, 0.15f},
          {-0.075f, 0.14f},  {-0.005f, 0.14f}, {-0.005f, -0.14f}, {-0.075f, -0.14f}};
}

class ParametricRendering : public ::testing::Test {
 protected:
  EglContext context_;
};

// One primitive of each GPU-drawn type, placed at an angle: the cases every mode is checked on.
struct TypeCase {
  const char* name;
  Primitive primitive;
  Transform transform;
};

inline std::vector<TypeCase> typeCases() {
  return {
      {"cylinder", Cylinder{0.5f, 2.0f, true}, placed({0, 0, 0}, {20, 10, 0})},
      {"cone", Cone{0.7f, 0.25f, 1.5f, true}, placed({0, 0, 0}, {-15, 25, 0})},
      {"cone_apex", Cone{0.6f, 0.0f, 1.2f, false}, placed({0, 0, 0}, {0, 0, 0})},
      {"sphere", Sphere{0.8f}, placed({0, 0, 0.5})},
      {"torus", TorusSegment{1.0f, 0.25f, 2.3f}, placed({0, 0, 0.5}, {30, 0, 0})},
      {"box", Box{glm::vec3(0.9f, 0.5f, 0.3f)}, placed({0, 0, 0.5}, {10, 20, 30})},
  };
}

}  // namespace tw::parametric_test
