// The setting's options (environment_options.h).
#include "environment_options.h"

#include <stdexcept>
#include <string>

namespace tw {

void addEnvironmentOptions(CLI::App& cmd, EnvironmentArgs& args) {
  cmd.add_flag("--ocean", args.ocean, "Draw an ocean of Gerstner waves around the model (docs/environment.md)");
  cmd.add_flag("--sky", args.sky, "Draw a sky with a sun behind the model");
  cmd.add_option("--waterline", args.waterline_m, "Height of still water, world metres (the generated plant: -10)")
      ->capture_default_str();
  cmd.add_option("--sun-elevation", args.sun_elevation_deg, "Sun above the horizon, degrees")->capture_default_str();
  cmd.add_option("--sun-azimuth", args.sun_azimuth_deg, "Sun's direction, degrees counter-clockwise from +X")
      ->capture_default_str();
  cmd.add_option("--wind", args.wind_mps, "Wind speed, m/s: sets the waves' lengths and heights")->capture_default_str();
  cmd.add_option("--wind-direction", args.wind_direction_deg, "Where the wind blows to, degrees from +X")
      ->capture_default_str();
  cmd.add_option("--waves", args.waves, "Number of Gerstner waves (1 to 16)")->capture_default_str();
  cmd.add_option("--wave-steepness", args.steepness, "0 (rising and falling only) to 1 (sharpest crests)")
      ->capture_default_str();
  cmd.add_option("--ocean-size", args.ocean_size_m, "Side of the ocean's square, metres")->capture_default_str();
}

std::optional<EnvironmentOptions> environmentOptions(const EnvironmentArgs& args,
                                                     const glm::dvec3& model_centre) {
  if (!args.ocean && !args.sky) return std::nullopt;
  EnvironmentOptions options;
  options.ocean = args.ocean;
  options.sky = args.sky;
  options.grid.center = glm::dvec2(model_centre);
  options.grid.waterline_m = args.waterline_m;
  options.grid.size_m = args.ocean_size_m;
  options.sun.sun_elevation_deg = args.sun_elevation_deg;
  options.sun.sun_azimuth_deg = args.sun_azimuth_deg;
  try {
    options.waves = wavesForWind(args.wind_mps, args.wind_direction_deg, args.waves);
    options.waves.steepness = args.steepness;
    validateEnvironment(options);
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(std::string("--ocean/--sky options: ") + e.what());
  }
  return options;
}

}  // namespace tw
