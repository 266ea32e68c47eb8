// Draws the parametric clusters of a cut (tessellated mode: parametric_instance_meshes.h, one
// level of detail per instance): cylinders, cones/frustums, spheres and torus segments
// as ray-cast impostors, boxes as rasterized boxes, extrusions and revolutions as run-time
// meshes (docs/parametrics.md).
//
// The package's instance table is resident: it is uploaded once, on the first impostor draw, into an SSBO of
// gpu::GpuInstance (parametric_gpu.h, the layout C++ and GLSL share), each instance's origin made
// relative to its cluster's anchor (bounding-sphere centre) in double. Per frame, each drawn
// cluster gets one GpuParametricDraw (anchor - eye, in double, then rounded) and one indirect
// command (a 14-vertex box strip, 36-vertex list for boxes, x its instances, base instance = its
// first instance); the clusters
// of one type are one glMultiDrawArraysIndirect (two for the ray-cast types: eye outside the proxy,
// with early depth rejection, and eye inside), so a frame makes at most nine impostor calls.
// Output goes into the GlRenderer's targets with its conventions: reversed-Z depth (exact per
// pixel through gl_FragDepth), object index + 1 in the id target, the same object colours (its
// colour SSBO) and lighting (gl_shaders.h shadingGlsl()). Draw after GlRenderer::beginFrame.
// Needs a current GL 4.5 context for the object's whole life.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string_view>

#include <glm/glm.hpp>

#include "gl_renderer.h"
#include "object_states.h"
#include "package_view.h"
#include "parametric_instance_meshes.h"
#include "parametric_meshes.h"

namespace tw {

// Auto, the default, is resolved once a GL context is current: tessellated on Mesa's software
// rasterizers (llvmpipe, softpipe), whose fragment throughput is poor and where the meshes were
// measured faster (docs/parametrics.md: 36.0 against 47.0 ms median on the 1M plant's decks
// path), impostor on GPUs, the design's choice (not measured here: no GPU in CI).
enum class ParametricMode { Impostor, Tessellated, Off, Auto };
// "impostor", "tessellated", "off", "auto"; parseParametricMode throws std::invalid_argument
// naming the value otherwise.
const char* parametricModeName(ParametricMode mode);
ParametricMode parseParametricMode(std::string_view name);
// Auto -> Tessellated or Impostor by the current context's GL_RENDERER; other modes unchanged.
ParametricMode resolveParametricMode(ParametricMode mode);

// The camera as the parametric passes need it; positions in the package frame.
struct ParametricView {
  glm::dvec3 eye{0.0};
  glm::dvec3 forward{1.0, 0.0, 0.0};  // unit view direction (Camera::forward)
  double near_m = 0.05;
  double pixel_scale = 1.0;  // Camera::pixelScale(viewport height)
  double min_feature_px = 1.0;  // impostors whose bounding sphere projects below are culled
  // Tubes and spheres thinner than this radius on screen are drawn this thick (a line of about
  // one pixel rather than broken dots); 0 draws them at their true size.
  double thin_radius_px = 0.5;
  // Tessellated mode: chordal error allowed on screen for cylinders, cones, spheres, torus
  // segments (each instance at its own distance; the frame loop passes tau).
  double tolerance_px = 1.0;
  // Tessellated mode in hzb: which pass of the frame this draw is (parametric_instance_meshes.h,
  // "Occlusion"), and the test of an eye-relative box against this frame's pyramid.
  InstancePass pass = InstancePass::All;
  std::function<bool(const glm::vec3& lo, const glm::vec3& hi)> box_hidden;
  // Tessellated mode: instances of objects this surface pass skips are not expanded
  // (object_states.h): the hidden ones, and in the opaque pass the ghosted ones.
  const ObjectStates* objects = nullptr;
  SurfacePass surface = SurfacePass::Opaque;  // the renderer's pass this draw belongs to
};

struct ParametricDrawStats {
  uint32_t clusters_drawn = 0;
  // Impostors: submitted (before per-instance small-feature culling in the shader); tessellated
  // mode: drawn (after per-instance frustum and small-feature culling).
  uint64_t instances_drawn = 0;
  uint32_t impostor_calls = 0;       // multi-draws issued
  uint64_t mesh_triangles = 0;       // tessellated clusters (extrusion, revolution, or all)
  uint64_t two_sided_triangles = 0;  // of mesh_triangles: drawn without back-face culling
  uint64_t thin_instances = 0;       // tessellated mode: of instances_drawn, ribbons and points
  uint64_t instances_occluded = 0;   // tessellated mode, second pass: hidden one by one
  uint64_t instances_tested = 0;     // tessellated mode: tested one by one (InstanceLodStats)
  uint32_t meshes_built = 0;
  double cpu_ms = 0.0;  // CPU time of the call and of its prepare() (llvmpipe rasterizes later)
};

class ParametricRenderer {
 public:
  // Throws std::runtime_error when GL set-up fails. `view` and `renderer` must outlive this
  // object.
  ParametricRenderer(const PackageView& view, GlRenderer& renderer,
                     const ParametricMeshOptions& mesh_options = {});
  ~ParametricRenderer();
  ParametricRenderer(const ParametricRenderer&) = delete;
  ParametricRenderer& operator=(const ParametricRenderer&) = delete;

  // Makes what `mode` draws with now rather than on its first draw: for Impostor, the programs
  // and the instance table (start-up, not a frame, pays for them). Throws as the constructor.
  void prepareMode(ParametricMode mode);

  // Draws `clusters` (parametric cluster indices; others are ignored) into the renderer's targets
  // with the camera of its last beginFrame. Off draws nothing; Auto is resolved first. `frame`
  // orders the mesh cache.
  ParametricDrawStats draw(std::span<const uint32_t> clusters, const ParametricView& view,
                           ParametricMode mode, uint64_t frame);
  // Same, into `framebuffer` (same size as the renderer's targets, with colour 0, ids 1, depth).
  ParametricDrawStats drawInto(unsigned framebuffer, std::span<const uint32_t> clusters,
                               const ParametricView& view, ParametricMode mode, uint64_t frame);

  // Tessellated mode: the CPU half of the next draw() of the same clusters and pass (choosing
  // and expanding each instance, ParametricInstanceMeshes::prepare), which makes no GL call and so
  // may run on another thread while the GL thread submits other draws. That draw() then only
  // submits; a draw() of other clusters or another pass drops it. Other modes, Auto included
  // (resolving it needs GL): nothing. Not beside any other call on this object.
  void prepare(std::span<const uint32_t> clusters, const ParametricView& view, ParametricMode mode);

  // Tessellated mode in hzb, after the frame's final-depth pyramid: which of the instances drawn
  // this frame are hidden, so the next frame's first pass leaves them to its second.
  void recordInstanceVisibility(const std::function<bool(const glm::vec3&, const glm::vec3&)>& box_hidden);

  ParametricMeshes& meshes();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace tw
