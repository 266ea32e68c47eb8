// The sky: a gradient from the horizon's haze to the zenith's blue, warmer as the sun goes down,
// with the sun's glow (its disc is drawn by the sky pass). Written once as GLSL (skyGlsl) for the
// sky pass and the water's reflection; the sun's direction is computed here, on the CPU, for both.
#pragma once

#include <string>

#include <glm/glm.hpp>

namespace tw {

struct SkyOptions {
  double sun_elevation_deg = 35.0;  // above the horizon; below 0 is night (a dark sky)
  double sun_azimuth_deg = 220.0;   // counter-clockwise from +X (east), where the sun stands
};

// Throws std::invalid_argument when the elevation is outside -90..90 or either angle is not a
// number.
void validateSky(const SkyOptions& sky);

// Unit vector towards the sun, world (Z up).
glm::dvec3 sunDirection(const SkyOptions& sky);

// GLSL: `vec3 skyRadiance(vec3 dir)` (dir unit, world axes) with `uniform vec3 sun_dir` at
// location kSunDirLocation; linear colour 0..1.
inline constexpr int kSunDirLocation = 20;
std::string skyGlsl();

}  // namespace tw
