// The GL 4.5 core mesh renderer: offscreen targets, the mesh programs, one multi-draw per
// culling state and program, and GPU timing. The contract is in gl_renderer.h; the shaders and
// the per-draw struct they share with this file are in gl_shaders.h.
#include "gl_renderer.h"

#define GL_GLEXT_PROTOTYPES 1
#include <GL/glcorearb.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>

#include "gl_program.h"
#include "gl_shaders.h"

namespace tw {
namespace {

// Timer queries in flight: a frame's result is normally available within two frames, so four
// slots mean endFrame never has to wait.
constexpr int kQueryRing = 4;

// Compiles and links one vertex + fragment program (gl_program.h: nothing is left behind when a
// step throws; ~Impl releases the programs already built).
GLuint buildProgram(const std::string& vertex_source, const std::string& fragment_source,
                    const char* name) {
  return buildGlProgram({{GL_VERTEX_SHADER, vertex_source}, {GL_FRAGMENT_SHADER, fragment_source}},
                        std::string("GlRenderer: ") + name);
}

[[noreturn]] void throwOutOfPool(size_t item, const char* what) {
  throw std::out_of_range("GlRenderer::draw: item " + std::to_string(item) + ": " + what +
                          " outside the geometry pool");
}

}  // namespace

struct GlRenderer::Impl {
  RendererOptions options;
  GLuint fbo = 0, color = 0, ids = 0, depth = 0;
  GLuint program = 0;               // objects flat from the vertices (vertex_object_tags.h)
  GLuint per_triangle_program = 0;  // clusters with GpuCluster::object_per_triangle
  GLuint depth_program = 0;  // occluder pass: depth only, vertices pushed away from the eye
  GLuint outline_program = 0;  // selection outline over the finished frame
  GLuint empty_vertex_array = 0;  // for the outline's screen triangle (no attributes)
  GLuint pass_buffer = 0;  // uniform buffer: the SurfacePass being drawn and the sections
  SurfacePass surface_pass = SurfacePass::Opaque;
  uint32_t section_count = 0;
  GLuint indirect_buffer = 0, draw_data_buffer = 0, color_buffer = 0;
  GLuint state_buffer = 0;  // GpuObjectState per object, as many as colours
  uint32_t object_color_count = 0;
  glm::mat4 view_projection{1.0f};

  // Scratch reused every draw, so steady frames do not allocate.
  std::vector<gl::DrawElementsIndirectCommand> commands;
  std::vector<gl::GpuDrawData> draw_data;
  // draw() scratch: items split by culling and by program.
  std::array<std::vector<DrawItem>, 4> batches;

  // Frame statistics and timer queries.
  RenderStats frame;
  GLuint queries[kQueryRing] = {};
  uint64_t query_frame[kQueryRing] = {};  // frame number whose time the slot measures
  // When the slot's beginFrame ran: a GPU time longer than the wall time since then is bogus.
  std::chrono::steady_clock::time_point query_begin[kQueryRing] = {};
  bool query_pending[kQueryRing] = {};
  int active_query = -1;                  // slot between beginFrame and endFrame
  int last_ended_query = -1;
  uint64_t frames_begun = 0;
  uint64_t newest_collected_frame = 0;    // 0 = none
  double last_gpu_ms = 0.0;

  // Makes new targets and only then replaces the old ones, so a failed resize leaves the
  // renderer as it was.
  void createTargets(int width, int height) {
    if (width <= 0 || height <= 0) {
      throw std::invalid_argument("GlRenderer: size " + std::to_string(width) + "x" +
                                  std::to_string(height) + " is not positive");
    }
    while (glGetError() != GL_NO_ERROR) {
    }  // only our own errors count below
    GLuint t_color = 0, t_ids = 0, t_depth = 0, t_fbo = 0;
    glCreateTextures(GL_TEXTURE_2D, 1, &t_color);
    glTextureStorage2D(t_color, 1, GL_RGBA8, width, height);
    glCreateTextures(GL_TEXTURE_2D, 1, &t_ids);
    glTextureStorage2D(t_ids, 1, GL_R32UI, width, height);
    glCreateTextures(GL_TEXTURE_2D, 1, &t_depth);
    glTextureStorage2D(t_depth, 1, GL_DEPTH_COMPONENT32F, width, height);
    for (GLuint texture : {t_color, t_ids, t_depth}) {
      glTextureParameteri(texture, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
      glTextureParameteri(texture, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    }
    glCreateFramebuffers(1, &t_fbo);
    glNamedFramebufferTexture(t_fbo, GL_COLOR_ATTACHMENT0, t_color, 0);
    glNamedFramebufferTexture(t_fbo, GL_COLOR_ATTACHMENT1, t_ids, 0);
    glNamedFramebufferTexture(t_fbo, GL_DEPTH_ATTACHMENT, t_depth, 0);
    const GLenum buffers[2] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1};
    glNamedFramebufferDrawBuffers(t_fbo, 2, buffers);
    const GLenum status = glCheckNamedFramebufferStatus(t_fbo, GL_FRAMEBUFFER);
    const GLenum error = glGetError();
    if (status != GL_FRAMEBUFFER_COMPLETE || error != GL_NO_ERROR) {
      glDeleteFramebuffers(1, &t_fbo);
      glDeleteTextures(1, &t_color);
      glDeleteTextures(1, &t_ids);
      glDeleteTextures(1, &t_depth);
      char message[160];
      std::snprintf(message, sizeof message,
                    "GlRenderer: cannot create %dx%d render targets (status 0x%04x, error 0x%04x)",
                    width, height, status, error);
      throw std::runtime_error(message);
    }
    deleteTargets();
    fbo = t_fbo, color = t_color, ids = t_ids, depth = t_depth;
    options.width = width;
    options.height = height;
  }

  void deleteTargets() {
    glDeleteFramebuffers(1, &fbo);
    glDeleteTextures(1, &color);
    glDeleteTextures(1, &ids);
    glDeleteTextures(1, &depth);
    fbo = color = ids = depth = 0;
  }

  // State the mesh pass needs; set on every call because other passes share the context.
  void bindTargetState() const {
    glBindFramebuffer(GL_FRAMEBUFFER, fbo);
    glViewport(0, 0, options.width, options.height);
    glDisable(GL_SCISSOR_TEST);
    glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    glDepthMask(GL_TRUE);
    // Reversed Z (camera.h): depth 1 at the near plane, 0 at the far plane and in the clear.
    glClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE);
  }

  void collect(int slot, bool wait) {
    if (!query_pending[slot]) return;
    if (!wait) {
      GLuint available = GL_FALSE;
      glGetQueryObjectuiv(queries[slot], GL_QUERY_RESULT_AVAILABLE, &available);
      if (!available) return;
    }
    GLuint64 ns = 0;
    glGetQueryObjectui64v(queries[slot], GL_QUERY_RESULT, &ns);
    query_pending[slot] = false;
    // llvmpipe reports nonsense (about the system uptime) for a query whose frame it had no
    // rasterizer work to time; such a result cannot be longer than the wall time it spans.
    const auto wall = std::chrono::steady_clock::now() - query_begin[slot];
    if (ns > static_cast<GLuint64>(std::chrono::nanoseconds(wall).count())) {
      return;
    }
    if (query_frame[slot] > newest_collected_frame) {
      newest_collected_frame = query_frame[slot];
      last_gpu_ms = static_cast<double>(ns) * 1e-6;
    }
  }

  // Releases every GL name (0 and never-created names are ignored by GL), also when the
  // constructor threw half-way.
  ~Impl() {
    endQuery();
    glDeleteQueries(kQueryRing, queries);
    glDeleteBuffers(1, &indirect_buffer);
    glDeleteBuffers(1, &draw_data_buffer);
    glDeleteBuffers(1, &color_buffer);
    glDeleteBuffers(1, &state_buffer);
    glDeleteBuffers(1, &pass_buffer);
    glDeleteVertexArrays(1, &empty_vertex_array);
    glDeleteProgram(outline_program);
    glDeleteProgram(program);
    glDeleteProgram(per_triangle_program);
    glDeleteProgram(depth_program);
    deleteTargets();
  }

  void endQuery() {
    if (active_query < 0) return;
    glEndQuery(GL_TIME_ELAPSED);
    query_pending[active_query] = true;
    last_ended_query = active_query;
    active_query = -1;
  }
};

GlRenderer::GlRenderer(const RendererOptions& options) : impl_(std::make_unique<Impl>()) {
  Impl& s = *impl_;
  s.options = options;
  while (glGetError() != GL_NO_ERROR) {
  }  // errors left by others must not be blamed on us
  s.createTargets(options.width, options.height);
  s.program = buildProgram(gl::meshVertexShader(), gl::meshFragmentShader(false), "mesh");
  s.per_triangle_program = buildProgram(gl::meshVertexShader(), gl::meshFragmentShader(true),
                                        "mesh, objects per triangle");
  s.depth_program =
      buildProgram(gl::occluderVertexShader(), gl::occluderFragmentShader(), "occluder");
  s.outline_program =
      buildProgram(gl::outlineVertexShader(), gl::outlineFragmentShader(), "selection outline");
  glCreateVertexArrays(1, &s.empty_vertex_array);
  glCreateBuffers(1, &s.pass_buffer);
  const gl::SurfacePassBlock opaque_pass{uint32_t(SurfacePass::Opaque), 0, {}, {}};
  glNamedBufferData(s.pass_buffer, sizeof opaque_pass, &opaque_pass, GL_DYNAMIC_DRAW);
  glCreateBuffers(1, &s.indirect_buffer);
  glCreateBuffers(1, &s.draw_data_buffer);
  glCreateBuffers(1, &s.color_buffer);
  // Never bind an empty store: keep one (unused) entry until colours are set.
  const uint32_t none = 0;
  glNamedBufferData(s.color_buffer, sizeof none, &none, GL_STATIC_DRAW);
  glCreateBuffers(1, &s.state_buffer);
  const GpuObjectState no_state;
  glNamedBufferData(s.state_buffer, sizeof no_state, &no_state, GL_DYNAMIC_DRAW);
  for (GLuint program : {s.program, s.per_triangle_program, s.outline_program})
    glProgramUniform1ui(program, gl::kObjectColorCountLocation, 0u);
  glCreateQueries(GL_TIME_ELAPSED, kQueryRing, s.queries);
  if (GLenum error = glGetError(); error != GL_NO_ERROR) {
    char message[96];
    std::snprintf(message, sizeof message, "GlRenderer: set-up failed (GL error 0x%04x)", error);
    throw std::runtime_error(message);
  }
}

GlRenderer::~GlRenderer() = default;

int GlRenderer::width() const { return impl_->options.width; }
int GlRenderer::height() const { return impl_->options.height; }
unsigned GlRenderer::framebuffer() const { return impl_->fbo; }
unsigned GlRenderer::depthTexture() const { return impl_->depth; }
unsigned GlRenderer::objectColorBuffer() const { return impl_->color_buffer; }
unsigned GlRenderer::objectStateBuffer() const { return impl_->state_buffer; }
uint32_t GlRenderer::objectColorCount() const { return impl_->object_color_count; }
const glm::mat4& GlRenderer::viewProjection() const { return impl_->view_projection; }

void GlRenderer::resize(int width, int height) {
  if (width == impl_->options.width && height == impl_->options.height && impl_->fbo != 0) return;
  impl_->createTargets(width, height);
}

void GlRenderer::setCullBackfaces(bool cull) { impl_->options.cull_backfaces = cull; }

void GlRenderer::setObjectColors(std::span<const uint32_t> rgba) {
  Impl& s = *impl_;
  if (rgba.empty()) {
    s.object_color_count = 0;
  } else {
    glNamedBufferData(s.color_buffer, static_cast<GLsizeiptr>(rgba.size_bytes()), rgba.data(),
                      GL_STATIC_DRAW);
    s.object_color_count = static_cast<uint32_t>(
        std::min<size_t>(rgba.size(), std::numeric_limits<uint32_t>::max()));
    // The states cover the same objects (shaders read both below object_color_count): none set.
    const std::vector<GpuObjectState> none(s.object_color_count);
    glNamedBufferData(s.state_buffer, static_cast<GLsizeiptr>(none.size() * sizeof(GpuObjectState)),
                      none.data(), GL_DYNAMIC_DRAW);
  }
  for (GLuint program : {s.program, s.per_triangle_program, s.outline_program})
    glProgramUniform1ui(program, gl::kObjectColorCountLocation, s.object_color_count);
}

void GlRenderer::setObjectStates(std::span<const GpuObjectState> states) {
  Impl& s = *impl_;
  const size_t n = std::min<size_t>(states.size(), s.object_color_count);
  if (n > 0)
    glNamedBufferSubData(s.state_buffer, 0, static_cast<GLsizeiptr>(n * sizeof(GpuObjectState)),
                         states.data());
}

void GlRenderer::setSurfacePass(SurfacePass pass) {
  Impl& s = *impl_;
  if (pass == s.surface_pass) return;
  s.surface_pass = pass;
  const uint32_t value = uint32_t(pass);
  glNamedBufferSubData(s.pass_buffer, 0, sizeof value, &value);
  if (pass == SurfacePass::Opaque) {
    glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    glDepthMask(GL_TRUE);
    glDisable(GL_BLEND);
  }
}

SurfacePass GlRenderer::surfacePass() const { return impl_->surface_pass; }

void GlRenderer::setSections(std::span<const SectionPlane> planes, const glm::dvec3& eye) {
  Impl& s = *impl_;
  if (planes.size() > gl::kMaxSectionPlanes)
    throw std::invalid_argument("GlRenderer::setSections: " + std::to_string(planes.size()) +
                                " planes, at most " + std::to_string(gl::kMaxSectionPlanes));
  // Eye-relative, in double until the end: n . (p_eye + eye - point) > 0 removes p_eye.
  gl::SurfacePassBlock block{};
  block.section_count = uint32_t(planes.size());
  for (size_t i = 0; i < planes.size(); ++i)
    block.planes[i] = glm::vec4(glm::vec3(planes[i].normal),
                                float(glm::dot(planes[i].normal, eye - planes[i].point)));
  if (block.section_count == 0 && s.section_count == 0) return;
  s.section_count = block.section_count;
  glNamedBufferSubData(s.pass_buffer, offsetof(gl::SurfacePassBlock, section_count),
                       sizeof block - offsetof(gl::SurfacePassBlock, section_count), &block.section_count);
}

bool GlRenderer::sectionsActive() const { return impl_->section_count > 0; }

void GlRenderer::bindSurfaceState() const { bindSurfaceState(impl_->fbo); }

void GlRenderer::bindSurfaceState(unsigned framebuffer) const {
  const Impl& s = *impl_;
  glBindFramebuffer(GL_FRAMEBUFFER, framebuffer);
  glViewport(0, 0, s.options.width, s.options.height);
  glDisable(GL_SCISSOR_TEST);
  glClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE);  // reversed Z (camera.h)
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_GREATER);
  if (s.surface_pass == SurfacePass::Opaque) {
    glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    glDepthMask(GL_TRUE);
    glDisable(GL_BLEND);
  } else {
    // Ghosts: over the opaque frame, behind what is in front of them, leaving depth and ids to
    // the opaque objects (what is seen through a ghost is what a click picks).
    glColorMaski(0, GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    glColorMaski(1, GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
    glDepthMask(GL_FALSE);
    glEnablei(GL_BLEND, 0);
    glBlendColor(0.0f, 0.0f, 0.0f, kXrayAlpha);
    glBlendFunc(GL_CONSTANT_ALPHA, GL_ONE_MINUS_CONSTANT_ALPHA);
  }
  glBindBufferBase(GL_UNIFORM_BUFFER, gl::kSurfacePassBinding, s.pass_buffer);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, gl::kObjectColorBinding, s.color_buffer);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, gl::kObjectStateBinding, s.state_buffer);
}

void GlRenderer::drawSelectionOutlines() {
  const Impl& s = *impl_;
  glBindFramebuffer(GL_FRAMEBUFFER, s.fbo);
  glViewport(0, 0, s.options.width, s.options.height);
  glDisable(GL_SCISSOR_TEST);
  glDisable(GL_DEPTH_TEST);
  glDisable(GL_BLEND);
  glDisable(GL_CULL_FACE);
  // The ids are read, so they must not be written: colour only.
  glColorMaski(0, GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
  glColorMaski(1, GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
  glDepthMask(GL_FALSE);
  glUseProgram(s.outline_program);
  glBindTextureUnit(0, s.ids);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, gl::kObjectStateBinding, s.state_buffer);
  glBindVertexArray(s.empty_vertex_array);
  glDrawArrays(GL_TRIANGLES, 0, 3);
  glBindVertexArray(0);
  glBindTextureUnit(0, 0);
  glUseProgram(0);
  glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
  glDepthMask(GL_TRUE);
  glEnable(GL_DEPTH_TEST);
}

void GlRenderer::beginFrame(const glm::mat4& view_rotation, const glm::mat4& projection) {
  Impl& s = *impl_;
  s.endQuery();  // a frame begun twice: the first one ends here
  s.frame = RenderStats{};
  ++s.frames_begun;
  int slot = static_cast<int>(s.frames_begun % kQueryRing);
  s.collect(slot, true);  // four frames old: available in practice, and needed to reuse the slot
  s.query_frame[slot] = s.frames_begun;
  s.query_begin[slot] = std::chrono::steady_clock::now();
  glBeginQuery(GL_TIME_ELAPSED, s.queries[slot]);
  s.active_query = slot;

  s.bindTargetState();
  const glm::vec4 background(s.options.background, 1.0f);
  glClearNamedFramebufferfv(s.fbo, GL_COLOR, 0, &background[0]);
  const GLuint no_object[4] = {0, 0, 0, 0};
  glClearNamedFramebufferuiv(s.fbo, GL_COLOR, 1, no_object);
  const GLfloat far_depth = 0.0f;
  glClearNamedFramebufferfv(s.fbo, GL_DEPTH, 0, &far_depth);

  const glm::mat4 view_projection = projection * view_rotation;
  s.view_projection = view_projection;
  for (GLuint program : {s.program, s.per_triangle_program})
    glProgramUniformMatrix4fv(program, gl::kViewProjectionLocation, 1, GL_FALSE,
                              &view_projection[0][0]);
  glProgramUniformMatrix4fv(s.depth_program, gl::kViewProjectionLocation, 1, GL_FALSE,
                            &view_projection[0][0]);
}

// Builds the indirect commands and per-draw records of `items` into the scratch vectors and
// uploads them; returns the triangles. Checks every range first, so a bad item throws before
// anything reaches the GPU.
uint64_t GlRenderer::prepareDraws(const GeometryPool& pool, std::span<const DrawItem> items) {
  Impl& s = *impl_;
  const PoolLayout& layout = pool.layout();
  s.commands.clear();
  s.draw_data.clear();
  uint64_t triangles = 0;
  for (size_t i = 0; i < items.size(); ++i) {
    const GpuCluster& c = items[i].placement;
    if (c.triangle_count == 0) continue;
    // Checked here because an index past the pool makes the GPU read outside the buffers.
    const uint64_t index_count = 3ull * c.triangle_count;
    if (c.first_index > layout.indices || index_count > layout.indices - c.first_index ||
        c.first_index + index_count > std::numeric_limits<uint32_t>::max()) {
      throwOutOfPool(i, "indices");
    }
    if (c.first_vertex > layout.vertices || c.vertex_count > layout.vertices - c.first_vertex ||
        c.first_vertex > static_cast<uint64_t>(std::numeric_limits<int32_t>::max())) {
      throwOutOfPool(i, "vertices");
    }
    if (c.first_triangle > layout.triangles ||
        c.triangle_count > layout.triangles - c.first_triangle ||
        c.first_triangle + c.triangle_count > std::numeric_limits<uint32_t>::max()) {
      throwOutOfPool(i, "triangles");
    }
    s.commands.push_back({static_cast<uint32_t>(index_count), 1u,
                          static_cast<uint32_t>(c.first_index),
                          static_cast<int32_t>(c.first_vertex), static_cast<uint32_t>(i)});
    gl::GpuDrawData d{};
    d.offset_eye = items[i].offset_eye;
    d.cell_m = static_cast<float>(c.cell_m);
    d.first_triangle = static_cast<uint32_t>(c.first_triangle);
    d.push_m = std::max(items[i].push_m, 0.0f);
    s.draw_data.push_back(d);
    triangles += c.triangle_count;
  }
  if (s.commands.empty()) return 0;
  // Re-specified (orphaned) on every call, so a call never waits for the previous one's reads.
  glNamedBufferData(s.indirect_buffer,
                    static_cast<GLsizeiptr>(s.commands.size() * sizeof(s.commands[0])),
                    s.commands.data(), GL_STREAM_DRAW);
  glNamedBufferData(s.draw_data_buffer,
                    static_cast<GLsizeiptr>(s.draw_data.size() * sizeof(s.draw_data[0])),
                    s.draw_data.data(), GL_STREAM_DRAW);
  return triangles;
}

void GlRenderer::draw(const GeometryPool& pool, std::span<const DrawItem> items) {
  Impl& s = *impl_;
  // Culling and the program are GL state, so each combination gets a multi-draw of its own.
  for (auto& batch : s.batches) batch.clear();
  for (const DrawItem& item : items) {
    // A section shows the inside of what it cuts: nothing is culled while one is active.
    const bool cull = (item.cull_back || s.options.cull_backfaces) && s.section_count == 0;
    s.batches[(cull ? 0 : 1) + (item.placement.object_per_triangle ? 2 : 0)].push_back(item);
  }
  for (size_t b = 0; b < s.batches.size(); ++b) drawBatch(pool, s.batches[b], b % 2 == 0, b >= 2);
}

void GlRenderer::drawBatch(const GeometryPool& pool, std::span<const DrawItem> items,
                           bool cull_back, bool object_per_triangle) {
  Impl& s = *impl_;
  const uint64_t triangles = prepareDraws(pool, items);  // counted only once all were checked
  if (s.commands.empty()) return;
  s.frame.draws += static_cast<uint32_t>(s.commands.size());
  s.frame.triangles += triangles;
  if (!cull_back) s.frame.two_sided_triangles += triangles;

  bindSurfaceState();
  if (cull_back) {
    glEnable(GL_CULL_FACE);
    glCullFace(GL_BACK);
    glFrontFace(GL_CCW);
  } else {
    glDisable(GL_CULL_FACE);
  }
  glUseProgram(object_per_triangle ? s.per_triangle_program : s.program);
  glBindVertexArray(pool.vertexArray());
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, gl::kDrawDataBinding, s.draw_data_buffer);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, gl::kTriangleObjectBinding,
                   pool.triangleObjectBuffer());
  glBindBuffer(GL_DRAW_INDIRECT_BUFFER, s.indirect_buffer);
  glMultiDrawElementsIndirect(GL_TRIANGLES, GL_UNSIGNED_SHORT, nullptr,
                              static_cast<GLsizei>(s.commands.size()), 0);
  glBindBuffer(GL_DRAW_INDIRECT_BUFFER, 0);
  glBindVertexArray(0);
  glUseProgram(0);
}

uint64_t GlRenderer::drawDepth(const GeometryPool& pool, std::span<const DrawItem> items,
                               unsigned framebuffer) {
  Impl& s = *impl_;
  const uint64_t triangles = prepareDraws(pool, items);
  if (s.commands.empty()) return 0;
  glBindFramebuffer(GL_FRAMEBUFFER, framebuffer);
  glViewport(0, 0, s.options.width, s.options.height);
  glDisable(GL_SCISSOR_TEST);
  glColorMask(GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
  glDepthMask(GL_TRUE);
  glClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_GREATER);
  glDisable(GL_BLEND);
  glDisable(GL_CULL_FACE);  // an occluder hides from both sides
  glUseProgram(s.depth_program);
  glBindVertexArray(pool.vertexArray());
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, gl::kDrawDataBinding, s.draw_data_buffer);
  glBindBuffer(GL_DRAW_INDIRECT_BUFFER, s.indirect_buffer);
  glMultiDrawElementsIndirect(GL_TRIANGLES, GL_UNSIGNED_SHORT, nullptr,
                              static_cast<GLsizei>(s.commands.size()), 0);
  glBindBuffer(GL_DRAW_INDIRECT_BUFFER, 0);
  glBindVertexArray(0);
  glUseProgram(0);
  glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
  return triangles;
}

RenderStats GlRenderer::endFrame() {
  Impl& s = *impl_;
  s.endQuery();
  // Oldest first, so last_gpu_ms ends as the newest finished frame.
  for (int k = 1; k <= kQueryRing; ++k) {
    s.collect(static_cast<int>((s.frames_begun + k) % kQueryRing), false);
  }
  s.frame.gpu_ms = s.last_gpu_ms;
  return s.frame;
}

double GlRenderer::waitForGpuMs() {
  Impl& s = *impl_;
  if (s.last_ended_query < 0) return 0.0;
  s.collect(s.last_ended_query, true);
  return s.last_gpu_ms;
}

namespace {

template <typename T>
void flipRows(std::vector<T>& pixels, size_t row_elements, int height) {
  for (int y = 0; y < height / 2; ++y) {
    T* top = pixels.data() + static_cast<size_t>(y) * row_elements;
    T* bottom = pixels.data() + static_cast<size_t>(height - 1 - y) * row_elements;
    std::swap_ranges(top, top + row_elements, bottom);
  }
}

void prepareRead(GLuint fbo, GLenum attachment) {
  glBindBuffer(GL_PIXEL_PACK_BUFFER, 0);
  glPixelStorei(GL_PACK_ALIGNMENT, 4);
  glPixelStorei(GL_PACK_ROW_LENGTH, 0);
  glNamedFramebufferReadBuffer(fbo, attachment);
  glBindFramebuffer(GL_READ_FRAMEBUFFER, fbo);
}

}  // namespace

void GlRenderer::readColor(std::vector<uint8_t>& rgba, bool flip_y) const {
  const Impl& s = *impl_;
  const int w = s.options.width, h = s.options.height;
  rgba.resize(static_cast<size_t>(w) * h * 4);
  prepareRead(s.fbo, GL_COLOR_ATTACHMENT0);
  glReadPixels(0, 0, w, h, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
  if (flip_y) flipRows(rgba, static_cast<size_t>(w) * 4, h);
}

void GlRenderer::readObjectIds(std::vector<uint32_t>& ids, bool flip_y) const {
  const Impl& s = *impl_;
  const int w = s.options.width, h = s.options.height;
  ids.resize(static_cast<size_t>(w) * h);
  prepareRead(s.fbo, GL_COLOR_ATTACHMENT1);
  glReadPixels(0, 0, w, h, GL_RED_INTEGER, GL_UNSIGNED_INT, ids.data());
  if (flip_y) flipRows(ids, static_cast<size_t>(w), h);
}

void GlRenderer::readDepth(std::vector<float>& depth, bool flip_y) const {
  const Impl& s = *impl_;
  const int w = s.options.width, h = s.options.height;
  depth.resize(static_cast<size_t>(w) * h);
  prepareRead(s.fbo, GL_COLOR_ATTACHMENT0);  // depth reads ignore the read buffer
  glReadPixels(0, 0, w, h, GL_DEPTH_COMPONENT, GL_FLOAT, depth.data());
  if (flip_y) flipRows(depth, static_cast<size_t>(w), h);
}

void GlRenderer::blitToScreen(int screen_width, int screen_height) const {
  const Impl& s = *impl_;
  glNamedFramebufferReadBuffer(s.fbo, GL_COLOR_ATTACHMENT0);
  const bool same_size = screen_width == s.options.width && screen_height == s.options.height;
  glBlitNamedFramebuffer(s.fbo, 0, 0, 0, s.options.width, s.options.height, 0, 0, screen_width,
                         screen_height, GL_COLOR_BUFFER_BIT, same_size ? GL_NEAREST : GL_LINEAR);
  // Overlays (the viewer's panel) draw next, and must land on the screen, not in the frame.
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  glViewport(0, 0, screen_width, screen_height);
}

}  // namespace tw
