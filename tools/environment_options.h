// The options that put a model in its setting, shared by the verbs that draw it (render, view,
// bench): --ocean, --sky, the waterline, the sun, the wind and its waves.
#pragma once

#include <optional>

#include <CLI/CLI.hpp>
#include <glm/glm.hpp>

#include "environment/environment_pass.h"

namespace tw {

struct EnvironmentArgs {
  bool ocean = false;
  bool sky = false;
  double waterline_m = 0.0;
  double sun_elevation_deg = SkyOptions{}.sun_elevation_deg;
  double sun_azimuth_deg = SkyOptions{}.sun_azimuth_deg;
  double wind_mps = 8.0;
  double wind_direction_deg = 30.0;
  int waves = 8;
  double steepness = OceanWaves{}.steepness;
  double ocean_size_m = OceanGridOptions{}.size_m;
};

void addEnvironmentOptions(CLI::App& cmd, EnvironmentArgs& args);

// The setting the options ask for, its ocean centred on `model_centre` (world); nullopt when
// neither --ocean nor --sky is given. Throws std::runtime_error naming the option for a value
// that cannot be drawn.
std::optional<EnvironmentOptions> environmentOptions(const EnvironmentArgs& args,
                                                     const glm::dvec3& model_centre);

}  // namespace tw
