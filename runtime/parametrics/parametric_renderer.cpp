// The parametric impostor renderer: resident instance table, per-frame indirect commands by type,
// one multi-draw per type. The contract is in parametric_renderer.h, the shaders in
// parametric_shaders.h, the shared records in parametric_gpu.h.
#include "parametric_renderer.h"

#define GL_GLEXT_PROTOTYPES 1
#include <GL/glcorearb.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

#include "gl_program.h"
#include "parametric_gpu.h"
#include "parametric_instance_meshes.h"
#include "parametric_shaders.h"

namespace tw {

const char* parametricModeName(ParametricMode mode) {
  switch (mode) {
    case ParametricMode::Impostor: return "impostor";
    case ParametricMode::Tessellated: return "tessellated";
    case ParametricMode::Off: return "off";
    case ParametricMode::Auto: return "auto";
  }
  return "?";
}

ParametricMode resolveParametricMode(ParametricMode mode) {
  if (mode != ParametricMode::Auto) return mode;
  const GLubyte* renderer = glGetString(GL_RENDERER);
  const std::string name = renderer ? reinterpret_cast<const char*>(renderer) : "";
  const bool software = name.find("llvmpipe") != std::string::npos ||
                        name.find("softpipe") != std::string::npos;
  return software ? ParametricMode::Tessellated : ParametricMode::Impostor;
}

ParametricMode parseParametricMode(std::string_view name) {
  if (name == "impostor") return ParametricMode::Impostor;
  if (name == "tessellated") return ParametricMode::Tessellated;
  if (name == "off") return ParametricMode::Off;
  if (name == "auto") return ParametricMode::Auto;
  throw std::invalid_argument("unknown parametrics mode '" + std::string(name) +
                              "' (impostor, tessellated, off, auto)");
}

namespace {

using Clock = std::chrono::steady_clock;
constexpr uint32_t kImpostorTypes = 5;        // cylinder, cone, sphere, torus, box
constexpr uint32_t kBoxVertices = 36;    // a box as a triangle list (boxes: flat face normals)
constexpr uint32_t kStripVertices = 14;  // a box as one strip (the ray-cast proxies)

// GL's command for glMultiDrawArraysIndirect.
struct DrawArraysIndirectCommand {
  uint32_t count;
  uint32_t instance_count;
  uint32_t first;
  uint32_t base_instance;
};
static_assert(sizeof(DrawArraysIndirectCommand) == 16);

gpu::GpuInstance gpuInstance(const pkg::InstanceRecord& in, std::span<const glm::vec2> profile_points,
                             const glm::dvec3& anchor) {
  gpu::GpuInstance g{};
  g.origin_m = glm::vec3(glm::dvec3(in.origin[0], in.origin[1], in.origin[2]) - anchor);
  g.object = in.object;
  g.axis_x = glm::vec4(in.linear[0], in.linear[1], in.linear[2], in.params[0]);
  g.axis_y = glm::vec4(in.linear[3], in.linear[4], in.linear[5], in.params[1]);
  g.axis_z = glm::vec4(in.linear[6], in.linear[7], in.linear[8], in.params[2]);
  g.type = in.type;
  g.flags = in.flags & pkg::kInstanceCapped;
  glm::vec3 lo(0.0f), hi(0.0f);
  if (!instanceLocalBox(in, profile_points, lo, hi)) lo = hi = glm::vec3(0.0f);  // degenerate: draws nothing
  g.local_min = lo;
  g.local_max = hi;
  return g;
}

}  // namespace

struct ParametricRenderer::Impl {
  const PackageView* view = nullptr;
  GlRenderer* renderer = nullptr;
  std::unique_ptr<ParametricMeshes> meshes;
  std::unique_ptr<ParametricInstanceMeshes> instance_meshes;
  bool fixed_tolerance = false;  // references: every mesh at one tolerance, per cluster
  std::array<GLuint, kImpostorTypes> programs{};         // eye outside the proxy (box: all)
  std::array<GLuint, kImpostorTypes> inside_programs{};  // eye inside (ray-cast types only)
  GLuint instance_buffer = 0, draw_buffer = 0, indirect_buffer = 0, vertex_array = 0;
  // The impostor programs and the resident instance table are made by prepareMode(Impostor) or
  // on the first impostor draw: the tessellated mode (software rasterizers) never needs them, and
  // their cost grows with the model (a table entry per instance).
  bool impostors_ready = false;
  void prepareImpostors();
  void checkGl(const std::string& what) const;  // throws on a pending GL error
  // Per-frame scratch, kept to avoid allocation in steady frames.
  std::array<std::vector<uint32_t>, kImpostorTypes> by_type;
  std::vector<uint32_t> mesh_clusters;      // tessellated per cluster
  std::vector<uint32_t> instance_clusters;  // tessellated per instance
  std::vector<ParametricMeshInstance> profile_instances;  // their extrusions and revolutions
  std::vector<gpu::GpuParametricDraw> draws;
  std::vector<DrawArraysIndirectCommand> commands;
  // A prepare() not yet drawn: the clusters and pass it was for, its statistics and CPU time.
  bool prepared = false;
  std::vector<uint32_t> prepared_clusters;
  InstancePass prepared_pass = InstancePass::All;
  InstanceLodStats prepared_stats;
  double prepared_ms = 0.0;

  // Sorts `clusters` into the lists above by how `mode` draws them.
  void classify(std::span<const uint32_t> clusters, ParametricMode mode) {
    const auto records = view->clusters();
    for (auto& list : by_type) list.clear();
    mesh_clusters.clear();
    instance_clusters.clear();
    for (uint32_t c : clusters) {
      if (c >= records.size() || records[c].kind != static_cast<uint8_t>(pkg::ClusterKind::Parametric) ||
          records[c].instance_count == 0 || records[c].instance_first >= view->instances().size())
        continue;  // the view validated the ranges; never read past the table all the same
      const uint32_t type = view->instances()[records[c].instance_first].type;
      if (mode == ParametricMode::Impostor && type < kImpostorTypes)
        by_type[type].push_back(c);
      else if (mode == ParametricMode::Tessellated && !fixed_tolerance &&
               ParametricInstanceMeshes::handles(type))
        instance_clusters.push_back(c);
      else
        mesh_clusters.push_back(c);
    }
  }

  InstanceLodView lodView(const ParametricView& camera) const {
    InstanceLodView lod_view;
    lod_view.eye = camera.eye;
    lod_view.view_projection = renderer->viewProjection();
    lod_view.pixel_scale = camera.pixel_scale;
    lod_view.near_m = camera.near_m;
    lod_view.tolerance_px = camera.tolerance_px;
    lod_view.min_feature_px = camera.min_feature_px;
    lod_view.pass = camera.pass;
    lod_view.box_hidden = camera.box_hidden;
    lod_view.objects = camera.objects;
    lod_view.surface = camera.surface;
    lod_view.keep_back_faces = renderer->sectionsActive();
    return lod_view;
  }

  ~Impl() {
    for (GLuint program : programs) glDeleteProgram(program);
    for (GLuint program : inside_programs) glDeleteProgram(program);
    glDeleteBuffers(1, &instance_buffer);
    glDeleteBuffers(1, &draw_buffer);
    glDeleteBuffers(1, &indirect_buffer);
    glDeleteVertexArrays(1, &vertex_array);
  }
};

ParametricRenderer::ParametricRenderer(const PackageView& view, GlRenderer& renderer,
                                       const ParametricMeshOptions& mesh_options)
    : impl_(std::make_unique<Impl>()) {
  Impl& s = *impl_;
  s.view = &view;
  s.renderer = &renderer;
  while (glGetError() != GL_NO_ERROR) {
  }
  s.meshes = std::make_unique<ParametricMeshes>(view, mesh_options);
  s.fixed_tolerance = mesh_options.fixed_tolerance_m > 0.0;
  // A reference draws every instance from its cluster's mesh at the one tolerance: it never
  // chooses per instance, so it neither prepares the bounds nor searches for sealed runs.
  if (!s.fixed_tolerance)
    s.instance_meshes =
        std::make_unique<ParametricInstanceMeshes>(view, mesh_options);
  glCreateBuffers(1, &s.draw_buffer);
  glCreateBuffers(1, &s.indirect_buffer);
  glCreateVertexArrays(1, &s.vertex_array);  // the proxies come from gl_VertexID: no attributes
  s.checkGl("set-up");
}

void ParametricRenderer::prepareMode(ParametricMode mode) {
  if (resolveParametricMode(mode) == ParametricMode::Impostor) impl_->prepareImpostors();
}

void ParametricRenderer::Impl::prepareImpostors() {
  if (impostors_ready) return;
  for (uint32_t type = 0; type < kImpostorTypes; ++type) {
    const std::string name = "ParametricRenderer: type " + std::to_string(type);
    if (type == static_cast<uint32_t>(pkg::PrimitiveType::Box)) {
      programs[type] = buildGlProgram({{GL_VERTEX_SHADER, gl::impostorVertexShader(type)},
                                       {GL_FRAGMENT_SHADER, gl::boxFragmentShader()}},
                                      name);
      continue;
    }
    programs[type] = buildGlProgram({{GL_VERTEX_SHADER, gl::impostorVertexShader(type)},
                                     {GL_FRAGMENT_SHADER, gl::impostorFragmentShader(type, true)}},
                                    name);
    inside_programs[type] =
        buildGlProgram({{GL_VERTEX_SHADER, gl::impostorVertexShader(type)},
                        {GL_FRAGMENT_SHADER, gl::impostorFragmentShader(type, false)}},
                       name + " (eye inside)");
  }
  // The resident table: every instance of a parametric cluster, relative to its cluster's anchor.
  const auto instances = view->instances();
  std::vector<gpu::GpuInstance> table(std::max<size_t>(instances.size(), 1));
  for (const pkg::ClusterRecord& c : view->clusters()) {
    if (c.kind != static_cast<uint8_t>(pkg::ClusterKind::Parametric)) continue;
    if (c.instance_first > instances.size() || c.instance_count > instances.size() - c.instance_first)
      continue;  // the view rejects such packages; never read past the table
    const glm::dvec3 anchor = clusterAnchor(c);
    for (uint32_t i = c.instance_first; i < c.instance_first + c.instance_count; ++i)
      table[i] = gpuInstance(instances[i], view->profilePoints(), anchor);
  }
  const uint64_t bytes = table.size() * sizeof(gpu::GpuInstance);
  glCreateBuffers(1, &instance_buffer);
  glNamedBufferStorage(instance_buffer, GLsizeiptr(bytes), table.data(), 0);
  checkGl("impostor set-up (" + std::to_string(bytes) + " instance bytes)");
  impostors_ready = true;
}

void ParametricRenderer::Impl::checkGl(const std::string& what) const {
  if (GLenum error = glGetError(); error != GL_NO_ERROR) {
    char code[16];
    std::snprintf(code, sizeof code, "0x%04x", error);
    throw std::runtime_error("ParametricRenderer: " + what + " failed (GL error " + code + ")");
  }
}

ParametricRenderer::~ParametricRenderer() = default;

ParametricMeshes& ParametricRenderer::meshes() { return *impl_->meshes; }

void ParametricRenderer::recordInstanceVisibility(
    const std::function<bool(const glm::vec3&, const glm::vec3&)>& box_hidden) {
  if (impl_->instance_meshes) impl_->instance_meshes->recordVisible(box_hidden);
}

ParametricDrawStats ParametricRenderer::draw(std::span<const uint32_t> clusters,
                                             const ParametricView& view, ParametricMode mode,
                                             uint64_t frame) {
  return drawInto(impl_->renderer->framebuffer(), clusters, view, mode, frame);
}

ParametricDrawStats ParametricRenderer::drawInto(unsigned framebuffer,
                                                 std::span<const uint32_t> clusters,
                                                 const ParametricView& view, ParametricMode mode,
                                                 uint64_t frame) {
  Impl& s = *impl_;
  ParametricDrawStats stats;
  mode = resolveParametricMode(mode);
  // A prepare() for exactly this draw is used; any other is dropped.
  const bool use_prepared = s.prepared && mode == ParametricMode::Tessellated &&
                            s.prepared_pass == view.pass &&
                            std::equal(clusters.begin(), clusters.end(), s.prepared_clusters.begin(),
                                       s.prepared_clusters.end());
  s.prepared = false;
  if (mode == ParametricMode::Off || (clusters.empty() && view.pass != InstancePass::Second))
    return stats;
  const auto start = Clock::now();
  const auto records = s.view->clusters();
  if (!use_prepared) s.classify(clusters, mode);  // a prepare() sorted these very clusters already

  GlRenderer& r = *s.renderer;
  const glm::mat4& view_projection = r.viewProjection();
  r.bindSurfaceState(framebuffer);

  // Impostors: commands and per-cluster records of every type in one upload each.
  s.draws.clear();
  s.commands.clear();
  std::array<uint32_t, kImpostorTypes + 1> type_begin{};
  for (uint32_t type = 0; type < kImpostorTypes; ++type) {
    type_begin[type] = static_cast<uint32_t>(s.commands.size());
    for (uint32_t c : s.by_type[type]) {
      const pkg::ClusterRecord& record = records[c];
      const bool box = type == static_cast<uint32_t>(pkg::PrimitiveType::Box);
      s.commands.push_back({box ? kBoxVertices : kStripVertices, record.instance_count, 0u,
                            record.instance_first});
      gpu::GpuParametricDraw d{};
      d.anchor_eye = glm::vec3(clusterAnchor(record) - view.eye);
      d.cluster = c;
      s.draws.push_back(d);
      ++stats.clusters_drawn;
      stats.instances_drawn += record.instance_count;
    }
  }
  type_begin[kImpostorTypes] = static_cast<uint32_t>(s.commands.size());
  if (!s.commands.empty()) {
    s.prepareImpostors();
    glNamedBufferData(s.indirect_buffer, GLsizeiptr(s.commands.size() * sizeof(s.commands[0])),
                      s.commands.data(), GL_STREAM_DRAW);
    glNamedBufferData(s.draw_buffer, GLsizeiptr(s.draws.size() * sizeof(s.draws[0])),
                      s.draws.data(), GL_STREAM_DRAW);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, gpu::kInstanceBinding, s.instance_buffer);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, gpu::kParametricDrawBinding, s.draw_buffer);
    glBindBuffer(GL_DRAW_INDIRECT_BUFFER, s.indirect_buffer);
    glBindVertexArray(s.vertex_array);
    const glm::vec4 forward_near(glm::vec3(view.forward), static_cast<float>(view.near_m));
    const float metres_per_px = static_cast<float>(1.0 / std::max(view.pixel_scale, 1e-9));
    for (uint32_t type = 0; type < kImpostorTypes; ++type) {
      const uint32_t first = type_begin[type], count = type_begin[type + 1] - first;
      if (count == 0) continue;
      const bool box = type == static_cast<uint32_t>(pkg::PrimitiveType::Box);
      // Boxes are drawn whole (seen from inside too); the ray-cast proxies cull back faces (the
      // vertex shader reverses the winding when the eye is inside a proxy), and go in two calls
      // over the same commands: eye outside (early depth rejection kept), eye inside.
      if (box) {
        glDisable(GL_CULL_FACE);
      } else {
        glEnable(GL_CULL_FACE);
        glCullFace(GL_BACK);
        glFrontFace(GL_CCW);
      }
      for (int pass = 0; pass < (box ? 1 : 2); ++pass) {
        const GLuint program = pass == 0 ? s.programs[type] : s.inside_programs[type];
        glUseProgram(program);
        glProgramUniformMatrix4fv(program, gl::kViewProjectionLocation, 1, GL_FALSE,
                                  &view_projection[0][0]);
        glProgramUniform1ui(program, gl::kObjectColorCountLocation, r.objectColorCount());
        glProgramUniform4fv(program, gl::kParamViewForwardNearLocation, 1, &forward_near[0]);
        glProgramUniform1f(program, gl::kParamMetresPerPxLocation, metres_per_px);
        glProgramUniform1f(program, gl::kParamMinFeaturePxLocation,
                           static_cast<float>(std::max(view.min_feature_px, 0.0)));
        glProgramUniform1ui(program, gl::kParamDrawBaseLocation, first);
        glProgramUniform1f(program, gl::kParamThinRadiusPxLocation,
                           static_cast<float>(std::max(view.thin_radius_px, 0.0)));
        glProgramUniform1i(program, gl::kParamProxyPassLocation,
                           box ? gl::kProxyPassAll
                               : (pass == 0 ? gl::kProxyPassOutside : gl::kProxyPassInside));
        glMultiDrawArraysIndirect(
            box ? GL_TRIANGLES : GL_TRIANGLE_STRIP,
            reinterpret_cast<const void*>(uintptr_t(first) * sizeof(DrawArraysIndirectCommand)),
            GLsizei(count), 0);
        ++stats.impostor_calls;
      }
    }
    glDisable(GL_CULL_FACE);
    glBindBuffer(GL_DRAW_INDIRECT_BUFFER, 0);
    glBindVertexArray(0);
    glUseProgram(0);
  }

  if (s.instance_meshes && (!s.instance_clusters.empty() ||
                            (mode == ParametricMode::Tessellated && view.pass == InstancePass::Second))) {
    InstanceLodStats lod_stats =
        use_prepared ? s.prepared_stats
                     : s.instance_meshes->prepare(s.instance_clusters, s.lodView(view), s.profile_instances);
    s.instance_meshes->submit(view_projection, r.objectColorCount(), lod_stats);
    stats.clusters_drawn += static_cast<uint32_t>(s.instance_clusters.size());
    stats.instances_drawn += lod_stats.instances_drawn;
    stats.instances_occluded += lod_stats.instances_occluded;
    stats.instances_tested += lod_stats.instances_tested;
    stats.mesh_triangles += lod_stats.triangles_drawn;
    stats.two_sided_triangles += lod_stats.two_sided_triangles;
    stats.thin_instances += lod_stats.thin_instances;
    const ParametricMeshStats profile_stats = s.meshes->drawInstances(
        s.profile_instances, view.eye, view_projection, view.pixel_scale, view.tolerance_px,
        r.objectColorCount(), frame);
    stats.instances_drawn += profile_stats.instances_drawn;
    stats.mesh_triangles += profile_stats.triangles_drawn;
    stats.two_sided_triangles += profile_stats.two_sided_triangles;
    stats.meshes_built += profile_stats.meshes_built;
  }
  if (!s.mesh_clusters.empty()) {
    glDisable(GL_CULL_FACE);
    const ParametricMeshStats mesh_stats =
        s.meshes->draw(s.mesh_clusters, view.eye, view_projection, view.pixel_scale, view.near_m,
                       r.objectColorCount(), frame);
    stats.clusters_drawn += mesh_stats.clusters_drawn;
    stats.instances_drawn += mesh_stats.instances_drawn;
    stats.mesh_triangles += mesh_stats.triangles_drawn;
    stats.two_sided_triangles += mesh_stats.triangles_drawn;
    stats.meshes_built += mesh_stats.meshes_built;
  }
  stats.cpu_ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count() +
                 (use_prepared ? s.prepared_ms : 0.0);
  return stats;
}

void ParametricRenderer::prepare(std::span<const uint32_t> clusters, const ParametricView& view,
                                 ParametricMode mode) {
  Impl& s = *impl_;
  s.prepared = false;
  if (mode != ParametricMode::Tessellated || !s.instance_meshes) return;  // Auto: resolving it asks GL
  const auto start = Clock::now();
  s.classify(clusters, ParametricMode::Tessellated);
  s.prepared_stats = s.instance_meshes->prepare(s.instance_clusters, s.lodView(view), s.profile_instances);
  s.prepared_clusters.assign(clusters.begin(), clusters.end());
  s.prepared_pass = view.pass;
  s.prepared_ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
  s.prepared = true;
}

}  // namespace tw
