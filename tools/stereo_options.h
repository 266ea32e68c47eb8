// The stereo options shared by the verbs that draw a model (render, view): --stereo, the eye
// separation and the zero-parallax distance (stereo.h).
#pragma once

#include <string>

#include <CLI/CLI.hpp>

#include "stereo.h"

namespace tw {

struct StereoArgs {
  std::string mode = "off";
  double eye_separation_m = StereoOptions{}.eye_separation_m;
  double zero_parallax_m = StereoOptions{}.zero_parallax_m;
};

// `modes_help` describes --stereo's values for the verb.
void addStereoOptions(CLI::App& cmd, StereoArgs& args, const std::string& modes_help);

// The options as StereoOptions; throws std::runtime_error starting "--stereo: " for an unknown
// mode or a distance out of range.
StereoOptions stereoOptions(const StereoArgs& args);

}  // namespace tw
