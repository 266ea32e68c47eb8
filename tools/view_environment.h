// The viewer's "Ocean and sky" panel: switches the ocean and the sky on and off, moves the
// waterline and the sun, and edits the waves, from a wind (speed, direction, number of waves) or
// one by one (amplitude, wavelength, direction), and their steepness. Every change goes to the
// walkthrough at once (Walkthrough::setEnvironment); the waves move with the viewer's clock.
#pragma once

#include <optional>
#include <string>

#include <glm/glm.hpp>

#include "environment/environment_pass.h"
#include "frame_loop.h"

namespace tw {

class ViewEnvironment {
 public:
  // `initial`: what the command line asked for (nullopt: both off, the ocean centred on
  // `model_centre` at the waterline 0 when switched on).
  ViewEnvironment(Walkthrough& walk, const std::optional<EnvironmentOptions>& initial,
                  const glm::dvec3& model_centre);

  void setOcean(bool on);
  void setSky(bool on);
  void drawPanel();

 private:
  void apply();

  Walkthrough& walk_;
  EnvironmentOptions options_;
  std::string error_;  // the last change that could not be drawn, shown in the panel
};

}  // namespace tw
