// The stereo options (stereo_options.h).
#include "stereo_options.h"

#include <stdexcept>

namespace tw {

void addStereoOptions(CLI::App& cmd, StereoArgs& args, const std::string& modes_help) {
  cmd.add_option("--stereo", args.mode, modes_help)->capture_default_str();
  cmd.add_option("--eye-separation", args.eye_separation_m, "Stereo: between the eyes, metres")
      ->capture_default_str();
  cmd.add_option("--zero-parallax", args.zero_parallax_m,
                 "Stereo: distance at which both eyes' images coincide, metres")
      ->capture_default_str();
}

StereoOptions stereoOptions(const StereoArgs& args) {
  StereoOptions stereo;
  try {
    stereo.mode = parseStereoMode(args.mode);
    stereo.eye_separation_m = args.eye_separation_m;
    stereo.zero_parallax_m = args.zero_parallax_m;
    validateStereo(stereo);
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(std::string("--stereo: ") + e.what());
  }
  return stereo;
}

}  // namespace tw
