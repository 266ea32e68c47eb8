// The sky (sky.h).
#include "sky.h"

#include <cmath>
#include <stdexcept>

namespace tw {

void validateSky(const SkyOptions& sky) {
  if (!std::isfinite(sky.sun_elevation_deg) || !std::isfinite(sky.sun_azimuth_deg))
    throw std::invalid_argument("the sun's elevation and azimuth must be numbers");
  if (sky.sun_elevation_deg < -90.0 || sky.sun_elevation_deg > 90.0)
    throw std::invalid_argument("the sun's elevation must be -90 to 90 degrees");
}

glm::dvec3 sunDirection(const SkyOptions& sky) {
  const double e = glm::radians(sky.sun_elevation_deg), a = glm::radians(sky.sun_azimuth_deg);
  return {std::cos(e) * std::cos(a), std::cos(e) * std::sin(a), std::sin(e)};
}

std::string skyGlsl() {
  return std::string("layout(location = ") + std::to_string(kSunDirLocation) + R"() uniform vec3 sun_dir;

// Daylight fades out as the sun sinks below the horizon; low suns warm the horizon.
float daylight() { return smoothstep(-0.12, 0.10, sun_dir.z); }
vec3 sunColor() { return mix(vec3(1.00, 0.45, 0.20), vec3(1.00, 0.96, 0.88), smoothstep(0.0, 0.45, sun_dir.z)); }

vec3 skyRadiance(vec3 dir) {
  float day = daylight();
  float up = max(dir.z, 0.0);
  float low_sun = 1.0 - smoothstep(0.0, 0.5, sun_dir.z);
  vec3 zenith = mix(vec3(0.02, 0.03, 0.07), vec3(0.16, 0.36, 0.72), day);
  vec3 horizon = mix(vec3(0.05, 0.06, 0.10), vec3(0.72, 0.81, 0.90), day);
  // The horizon warms towards the sun when it is low.
  float toward_sun = max(dot(normalize(vec3(dir.xy, 0.0) + 1e-6), normalize(vec3(sun_dir.xy, 0.0) + 1e-6)), 0.0);
  horizon = mix(horizon, vec3(0.95, 0.58, 0.35) * day, low_sun * pow(toward_sun, 3.0) * 0.8);
  vec3 color = mix(horizon, zenith, pow(up, 0.45));
  // Below the horizon (no ocean drawn there, or beyond its edge): a hazy sea-level tone.
  if (dir.z < 0.0) color = mix(horizon, horizon * vec3(0.45, 0.55, 0.65), smoothstep(0.0, -0.15, dir.z));
  // The sun's glow (its disc is the sky pass's, per fragment).
  float cos_sun = dot(dir, sun_dir);
  color += sunColor() * pow(max(cos_sun, 0.0), 120.0) * 0.35 * smoothstep(-0.02, 0.02, sun_dir.z);
  return min(color, vec3(1.0));
}
)";
}

}  // namespace tw
