// The model's setting, drawn after its opaque passes: the ocean (ocean_mesh.h, with the waves of
// gerstner_waves.h added in the vertex shader) and the sky (sky.h).
//
// Order and targets: the ocean first, depth-tested against the model and writing depth and the
// id 0 ("no object": it is never picked); water over the background is opaque, and over a part
// below the waterline it is blended by the water's thickness there (read from a copy of the
// model's depth), so a hull shows through only as a darker tone. Then the sky, where the depth is
// still empty (the background), writing colour alone. Neither is drawn before the occlusion
// passes, so neither ever hides the model in the hierarchical Z.
//
// Water shading: Fresnel (Schlick, water's 0.02) between the sky's reflection and a deep-water
// colour, the sun's highlight, and haze towards the horizon.
#pragma once

#include <cstdint>
#include <memory>

#include <glm/glm.hpp>

#include "environment/gerstner_waves.h"
#include "environment/ocean_mesh.h"
#include "environment/sky.h"
#include "gl_renderer.h"

namespace tw {

struct EnvironmentOptions {
  bool ocean = false;
  bool sky = false;
  OceanGridOptions grid;   // centre and waterline in world coordinates
  OceanWaves waves = wavesForWind(8.0, 30.0, 8);
  SkyOptions sun;
};

// Throws std::invalid_argument (from the parts' checks) for options that cannot be drawn.
void validateEnvironment(const EnvironmentOptions& options);

struct EnvironmentStats {
  uint64_t ocean_triangles = 0;
  uint32_t ocean_leaves = 0;
  double ocean_mesh_ms = 0.0;  // CPU: building and uploading the mesh
};

class EnvironmentPass {
 public:
  EnvironmentPass();  // needs a current GL 4.5 context; throws std::runtime_error if GL fails
  ~EnvironmentPass();
  EnvironmentPass(const EnvironmentPass&) = delete;
  EnvironmentPass& operator=(const EnvironmentPass&) = delete;

  void set(const EnvironmentOptions& options);  // validated by the caller
  const EnvironmentOptions& options() const { return options_; }
  bool active() const { return options_.ocean || options_.sky; }

  // Draws into the renderer's targets, after its opaque passes, with the camera of the frame:
  // `eye` its world position (the renderer's frame is relative to it), the rotation and
  // projection its beginFrame had; `time_s` drives the waves.
  EnvironmentStats draw(GlRenderer& renderer, const glm::dvec3& eye, const glm::mat4& view_rotation,
                        const glm::mat4& projection, double time_s);

 private:
  void drawOcean(GlRenderer& renderer, const glm::dvec3& eye, const glm::mat4& view_projection,
                 const glm::mat4& projection, double time_s, EnvironmentStats& stats);
  void drawSky(GlRenderer& renderer, const glm::mat4& view_projection);
  void copyDepth(GlRenderer& renderer);

  EnvironmentOptions options_;
  std::vector<WaveTerm> terms_;
  double wave_reach_m_ = 0.0;  // the leaves' boxes grow by it for frustum culling
  OceanMesh mesh_;                   // this frame's, its memory kept from frame to frame
  std::vector<glm::vec2> relative_;  // its positions relative to the eye, as uploaded
  unsigned ocean_program_ = 0, sky_program_ = 0;
  unsigned vao_ = 0, sky_vao_ = 0, sky_buffer_ = 0;
  int sky_vertices_ = 0;
  unsigned vertex_buffer_ = 0, index_buffer_ = 0;
  size_t vertex_capacity_ = 0, index_capacity_ = 0;  // bytes of the buffers' storage
  unsigned depth_copy_ = 0;
  int depth_width_ = 0, depth_height_ = 0;
};

}  // namespace tw
