// The ocean and sky pass (environment_pass.h).
#include "environment/environment_pass.h"

#define GL_GLEXT_PROTOTYPES 1
#include <GL/glcorearb.h>

#include <chrono>
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <glm/gtc/constants.hpp>
#include <glm/gtc/type_ptr.hpp>

#include "gl_program.h"

namespace tw {
namespace {

// Uniform locations shared by the C++ side and the shaders below.
constexpr int kViewProjectionLocation = 0;
constexpr int kInverseProjectionLocation = 1;
constexpr int kWaterlineLocation = 2;     // float: still water's height relative to the eye
constexpr int kWaveCountLocation = 3;
constexpr int kCellModelLocation = 4;     // vec2: finest cell, 1 / (range factor * cells)
constexpr int kViewportLocation = 5;
constexpr int kSunLightLocation = 6;      // vec3: the glint's (ocean) or the disc's (sky) colour
constexpr int kWaveALocation = 32;        // vec4[16]: direction xy, wavenumber, phase at the eye
constexpr int kWaveBLocation = 48;        // vec4[16]: amplitude, Q, wavelength

// The ocean's vertex shader displaces the still-water vertex by the waves and shades it: the
// sky's reflection, Fresnel, the deep water and the haze all change slowly over the surface, so
// they are computed per vertex (a software rasterizer pays for every instruction of a fragment,
// and the water fills half the frame); the fragment shader adds the sun's glint and the depth
// under the water.
std::string oceanVertexShader() {
  return std::string(R"(#version 450 core
layout(location = 0) in vec2 position;  // still water, after geomorphing, relative to the eye
layout(location = 0) uniform mat4 view_projection;
layout(location = 2) uniform float waterline;
layout(location = 3) uniform int wave_count;
layout(location = 4) uniform vec2 cell_model;
layout(location = 32) uniform vec4 wave_a[16];
layout(location = 48) uniform vec4 wave_b[16];
out vec3 pos_eye;
out vec3 normal_world;
out vec3 water_color;
)") + skyGlsl() + R"(
void main() {
  // gerstner_waves.cpp's sums, term for term, with each wave faded by the mesh's cell size here.
  float cell = max(cell_model.x, length(vec3(position, waterline)) * cell_model.y);
  vec3 displacement = vec3(0.0), d_dx = vec3(0.0), d_dy = vec3(0.0);
  for (int i = 0; i < wave_count; ++i) {
    vec2 dir = wave_a[i].xy;
    float k = wave_a[i].z;
    float a = wave_b[i].x * smoothstep(2.0, 4.0, wave_b[i].z / cell);
    float q = wave_b[i].y;
    float theta = k * dot(dir, position) + wave_a[i].w;
    float s = sin(theta), c = cos(theta);
    displacement += vec3(-q * a * dir * s, a * c);
    float qka = q * k * a * c, ka = k * a * s;
    d_dx += vec3(-qka * dir.x * dir, -ka * dir.x);
    d_dy += vec3(-qka * dir.y * dir, -ka * dir.y);
  }
  pos_eye = vec3(position, waterline) + displacement;
  vec3 n = normalize(cross(vec3(1.0, 0.0, 0.0) + d_dx, vec3(0.0, 1.0, 0.0) + d_dy));
  normal_world = n;
  gl_Position = view_projection * vec4(pos_eye, 1.0);

  float dist = length(pos_eye);
  vec3 v = -pos_eye / max(dist, 1e-4);
  if (dot(n, v) < 0.0) n = -n;  // a back slope seen over a crest
  float facing = 1.0 - max(dot(n, v), 0.0);
  float fresnel = 0.02 + 0.98 * facing * facing * facing * facing * facing;
  vec3 r = reflect(-v, n);
  r.z = abs(r.z);
  float day = daylight();
  vec3 deep = vec3(0.012, 0.060, 0.095) * (0.25 + 0.75 * day)
            + vec3(0.0, 0.045, 0.050) * max(dot(n, sun_dir), 0.0) * day;
  vec3 color = mix(deep, skyRadiance(r), fresnel);
  vec3 haze = skyRadiance(normalize(vec3(-v.xy, 0.002)));
  water_color = mix(color, haze, 1.0 - exp(-dist / 12000.0));
}
)";
}

std::string oceanFragmentShader() {
  return R"(#version 450 core
in vec3 pos_eye;
in vec3 normal_world;
in vec3 water_color;
layout(location = 1) uniform mat4 inverse_projection;
layout(location = 5) uniform vec2 viewport;
layout(location = 6) uniform vec3 glint_color;  // the sun's colour times its height's fade
layout(location = 20) uniform vec3 sun_dir;
layout(binding = 0) uniform sampler2D scene_depth;
layout(location = 0) out vec4 out_color;
layout(location = 1) out uint out_id;
void main() {
  vec3 r = reflect(normalize(pos_eye), normalize(normal_world));
  float glint = exp2(500.0 * log2(max(dot(r, sun_dir), 1e-6)));
  vec3 color = water_color + glint_color * glint;
  // A part of the model under the water shows through it as a darker tone, less the deeper it is.
  float alpha = 1.0;
  float scene = texelFetch(scene_depth, ivec2(gl_FragCoord.xy), 0).r;
  if (scene > 0.0) {
    vec4 p = inverse_projection * vec4(gl_FragCoord.xy / viewport * 2.0 - 1.0, scene, 1.0);
    float thickness = max(length(p.xyz / p.w) - length(pos_eye), 0.0);
    alpha = mix(0.55, 1.0, 1.0 - exp(-thickness / 4.0));
  }
  out_color = vec4(min(color, vec3(1.0)), alpha);
  out_id = 0u;  // no object
}
)";
}

// The sky: a dome of directions around the eye, drawn at depth 0 (the background's), coloured
// per vertex; the fragments add only the sun's disc.
std::string skyVertexShader() {
  return std::string(R"(#version 450 core
layout(location = 0) in vec3 direction;
layout(location = 0) uniform mat4 view_projection;
out vec3 dir;
out vec3 sky_color;
)") + skyGlsl() + R"(
void main() {
  dir = direction;
  sky_color = skyRadiance(direction);
  vec4 clip = view_projection * vec4(direction, 0.0);
  gl_Position = vec4(clip.xy, 0.0, clip.w);
}
)";
}

std::string skyFragmentShader() {
  return R"(#version 450 core
in vec3 dir;
in vec3 sky_color;
layout(location = 6) uniform vec3 disc_color;  // the sun's colour, 0 below the horizon
layout(location = 20) uniform vec3 sun_dir;
layout(location = 0) out vec4 out_color;
void main() {
  float c = dot(normalize(dir), sun_dir);
  out_color = vec4(min(sky_color + disc_color * smoothstep(0.99955, 0.99975, c), vec3(1.0)), 1.0);
}
)";
}

// Directions of the sky dome: rings of latitude from the nadir to the zenith, as triangles.
std::vector<glm::vec3> skyDome() {
  constexpr int kAround = 64, kUp = 32;
  auto at = [](int a, int u) {
    const double azimuth = 2.0 * glm::pi<double>() * a / kAround;
    const double elevation = glm::pi<double>() * (double(u) / kUp - 0.5);
    return glm::vec3(float(std::cos(elevation) * std::cos(azimuth)), float(std::cos(elevation) * std::sin(azimuth)),
                     float(std::sin(elevation)));
  };
  std::vector<glm::vec3> triangles;
  for (int u = 0; u < kUp; ++u)
    for (int a = 0; a < kAround; ++a) {
      const glm::vec3 p00 = at(a, u), p10 = at(a + 1, u), p01 = at(a, u + 1), p11 = at(a + 1, u + 1);
      triangles.insert(triangles.end(), {p00, p10, p11, p00, p11, p01});
    }
  return triangles;
}

// The sun's colour as the shaders' sunColor() gives it, faded as the sun sets (for the glint and
// the disc, uploaded once a frame instead of computed per fragment).
glm::vec3 sunLight(const SkyOptions& sky) {
  const glm::dvec3 sun = sunDirection(sky);
  auto smooth = [](double e0, double e1, double x) {
    const double t = std::clamp((x - e0) / (e1 - e0), 0.0, 1.0);
    return t * t * (3.0 - 2.0 * t);
  };
  const glm::dvec3 color = glm::mix(glm::dvec3(1.00, 0.45, 0.20), glm::dvec3(1.00, 0.96, 0.88), smooth(0.0, 0.45, sun.z));
  return glm::vec3(color * smooth(-0.02, 0.05, sun.z));
}

// Writes `bytes` into `buffer`, growing its storage (by half again) only when they do not fit,
// so a frame's upload allocates nothing.
void upload(unsigned buffer, size_t& capacity, const void* data, size_t bytes) {
  if (bytes > capacity) {
    capacity = bytes + bytes / 2;
    glNamedBufferData(buffer, GLsizeiptr(capacity), nullptr, GL_DYNAMIC_DRAW);
  }
  if (bytes > 0) glNamedBufferSubData(buffer, 0, GLsizeiptr(bytes), data);
}

double msSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

void validateEnvironment(const EnvironmentOptions& options) {
  validateOceanGrid(options.grid);
  validateWaves(options.waves);
  validateSky(options.sun);
}

EnvironmentPass::EnvironmentPass() {
  ocean_program_ = buildGlProgram({{GL_VERTEX_SHADER, oceanVertexShader()},
                                   {GL_FRAGMENT_SHADER, oceanFragmentShader()}},
                                  "ocean");
  sky_program_ = buildGlProgram({{GL_VERTEX_SHADER, skyVertexShader()},
                                 {GL_FRAGMENT_SHADER, skyFragmentShader()}},
                                "sky");
  glCreateVertexArrays(1, &vao_);
  glEnableVertexArrayAttrib(vao_, 0);
  glVertexArrayAttribFormat(vao_, 0, 2, GL_FLOAT, GL_FALSE, 0);
  glVertexArrayAttribBinding(vao_, 0, 0);
  glCreateVertexArrays(1, &sky_vao_);
  const std::vector<glm::vec3> dome = skyDome();
  sky_vertices_ = GLsizei(dome.size());
  glCreateBuffers(1, &sky_buffer_);
  glNamedBufferStorage(sky_buffer_, GLsizeiptr(dome.size() * sizeof(glm::vec3)), dome.data(), 0);
  glEnableVertexArrayAttrib(sky_vao_, 0);
  glVertexArrayAttribFormat(sky_vao_, 0, 3, GL_FLOAT, GL_FALSE, 0);
  glVertexArrayAttribBinding(sky_vao_, 0, 0);
  glVertexArrayVertexBuffer(sky_vao_, 0, sky_buffer_, 0, sizeof(glm::vec3));
  glCreateBuffers(1, &vertex_buffer_);
  glCreateBuffers(1, &index_buffer_);
  glVertexArrayVertexBuffer(vao_, 0, vertex_buffer_, 0, sizeof(glm::vec2));
  glVertexArrayElementBuffer(vao_, index_buffer_);
}

EnvironmentPass::~EnvironmentPass() {
  glDeleteTextures(1, &depth_copy_);
  glDeleteBuffers(1, &vertex_buffer_);
  glDeleteBuffers(1, &index_buffer_);
  glDeleteVertexArrays(1, &vao_);
  glDeleteVertexArrays(1, &sky_vao_);
  glDeleteBuffers(1, &sky_buffer_);
  glDeleteProgram(ocean_program_);
  glDeleteProgram(sky_program_);
}

void EnvironmentPass::set(const EnvironmentOptions& options) {
  options_ = options;
  terms_ = waveTerms(options.waves);
  // How far the waves can move the water from its still place, up, down or sideways.
  wave_reach_m_ = 0.0;
  for (const WaveTerm& w : terms_) wave_reach_m_ += w.amplitude * (1.0 + w.q);
}

EnvironmentStats EnvironmentPass::draw(GlRenderer& renderer, const glm::dvec3& eye,
                                       const glm::mat4& view_rotation, const glm::mat4& projection,
                                       double time_s) {
  EnvironmentStats stats;
  if (!active()) return stats;
  const glm::mat4 view_projection = projection * view_rotation;
  // Both upload the sun; the sky's GLSL reads it in either program.
  if (options_.ocean) drawOcean(renderer, eye, view_projection, projection, time_s, stats);
  if (options_.sky) drawSky(renderer, view_projection);
  // Back to the state the surface passes expect.
  glDisablei(GL_BLEND, 0);
  glDepthFunc(GL_GREATER);
  glDepthMask(GL_TRUE);
  glColorMaski(1, GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
  glBindVertexArray(0);
  return stats;
}

void EnvironmentPass::copyDepth(GlRenderer& renderer) {
  const int w = renderer.width(), h = renderer.height();
  if (w != depth_width_ || h != depth_height_) {
    glDeleteTextures(1, &depth_copy_);
    glCreateTextures(GL_TEXTURE_2D, 1, &depth_copy_);
    glTextureStorage2D(depth_copy_, 1, GL_DEPTH_COMPONENT32F, w, h);
    glTextureParameteri(depth_copy_, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTextureParameteri(depth_copy_, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    depth_width_ = w;
    depth_height_ = h;
  }
  glCopyImageSubData(renderer.depthTexture(), GL_TEXTURE_2D, 0, 0, 0, 0, depth_copy_, GL_TEXTURE_2D, 0,
                     0, 0, 0, w, h, 1);
}

void EnvironmentPass::drawOcean(GlRenderer& renderer, const glm::dvec3& eye,
                                const glm::mat4& view_projection, const glm::mat4& projection,
                                double time_s, EnvironmentStats& stats) {
  const auto start = std::chrono::steady_clock::now();
  OceanFrustum frustum;
  frustum.view_projection = glm::dmat4(view_projection);
  frustum.wave_reach_m = wave_reach_m_;
  buildOceanMesh(options_.grid, eye, mesh_, &frustum);
  // Eye-relative, in double then float: plant coordinates are millions of metres.
  relative_.resize(mesh_.positions.size());
  for (size_t i = 0; i < relative_.size(); ++i) relative_[i] = glm::vec2(mesh_.positions[i] - glm::dvec2(eye));
  upload(vertex_buffer_, vertex_capacity_, relative_.data(), relative_.size() * sizeof(glm::vec2));
  upload(index_buffer_, index_capacity_, mesh_.indices.data(), mesh_.indices.size() * sizeof(uint32_t));
  stats.ocean_triangles = mesh_.indices.size() / 3;
  stats.ocean_leaves = mesh_.leaves;

  // Each wave's phase at the eye's XY, in double: k D.eye - w t + p, folded into one turn.
  const int count = int(std::min<size_t>(terms_.size(), kMaxOceanWaves));
  std::vector<glm::vec4> wave_a(count), wave_b(count);
  for (int i = 0; i < count; ++i) {
    const WaveTerm& w = terms_[size_t(i)];
    const double phase = std::fmod(w.k * glm::dot(w.direction, glm::dvec2(eye)) - w.omega * time_s + w.phase,
                                   2.0 * glm::pi<double>());
    wave_a[size_t(i)] = glm::vec4(glm::vec2(w.direction), float(w.k), float(phase));
    wave_b[size_t(i)] = glm::vec4(float(w.amplitude), float(w.q), float(w.wavelength), 0.0f);
  }
  stats.ocean_mesh_ms = msSince(start);

  copyDepth(renderer);
  renderer.bindSurfaceState();
  glDisable(GL_CULL_FACE);
  glEnablei(GL_BLEND, 0);
  glBlendFunci(0, GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
  glUseProgram(ocean_program_);
  glUniformMatrix4fv(kViewProjectionLocation, 1, GL_FALSE, glm::value_ptr(view_projection));
  const glm::mat4 inverse_projection = glm::inverse(projection);
  glUniformMatrix4fv(kInverseProjectionLocation, 1, GL_FALSE, glm::value_ptr(inverse_projection));
  glUniform1f(kWaterlineLocation, float(options_.grid.waterline_m - eye.z));
  glUniform1i(kWaveCountLocation, count);
  const double finest_cell = oceanCellSizeAt(options_.grid, 0.0);
  glUniform2f(kCellModelLocation, float(finest_cell),
              float(1.0 / (options_.grid.range_factor * options_.grid.cells_per_node)));
  glUniform2f(kViewportLocation, float(renderer.width()), float(renderer.height()));
  if (count > 0) {
    glUniform4fv(kWaveALocation, count, glm::value_ptr(wave_a[0]));
    glUniform4fv(kWaveBLocation, count, glm::value_ptr(wave_b[0]));
  }
  glUniform3fv(kSunDirLocation, 1, glm::value_ptr(glm::vec3(sunDirection(options_.sun))));
  glUniform3fv(kSunLightLocation, 1, glm::value_ptr(sunLight(options_.sun) * 1.5f));
  glBindTextureUnit(0, depth_copy_);
  glBindVertexArray(vao_);
  glDrawElements(GL_TRIANGLES, GLsizei(mesh_.indices.size()), GL_UNSIGNED_INT, nullptr);
  glBindTextureUnit(0, 0);
}

void EnvironmentPass::drawSky(GlRenderer& renderer, const glm::mat4& view_projection) {
  renderer.bindSurfaceState();
  glDisable(GL_CULL_FACE);
  glDepthFunc(GL_EQUAL);  // only where nothing was drawn
  glDepthMask(GL_FALSE);
  glColorMaski(1, GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);  // ids stay 0
  glUseProgram(sky_program_);
  glUniformMatrix4fv(kViewProjectionLocation, 1, GL_FALSE, glm::value_ptr(view_projection));
  glUniform3fv(kSunDirLocation, 1, glm::value_ptr(glm::vec3(sunDirection(options_.sun))));
  glUniform3fv(kSunLightLocation, 1, glm::value_ptr(sunLight(options_.sun) * 4.0f));
  glBindVertexArray(sky_vao_);
  glDrawArrays(GL_TRIANGLES, 0, sky_vertices_);
}

}  // namespace tw
