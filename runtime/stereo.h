// Stereo: two eyes a separation apart, each with an off-axis (sheared) projection so that what
// lies at the zero-parallax distance appears at the same place in both images, and the two images
// put together side by side, one above the other, or as a red-cyan anaglyph.
//
// Why off-axis rather than toed-in eyes: turning each eye towards the convergence point gives
// vertical parallax at the image corners, which hurts; parallel eyes with a shifted frustum do
// not. The walkthrough draws both eyes from one cut (Walkthrough::renderStereoFrame), selected
// for a camera just behind the centre eye whose frustum holds both eyes' frusta.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "camera.h"

namespace tw {

// QuadBuffered: each eye to its own back buffer of a stereo GL context (the viewer's window, where
// the display offers one); not a composed frame.
enum class StereoMode { Off, SideBySide, TopBottom, Anaglyph, QuadBuffered };

struct StereoOptions {
  StereoMode mode = StereoMode::Off;
  double eye_separation_m = 0.065;
  double zero_parallax_m = 10.0;  // distance at which the two images coincide
};

// "off", "side-by-side", "top-bottom", "anaglyph", "quad-buffered"; throws std::invalid_argument
// otherwise.
StereoMode parseStereoMode(const std::string& name);
const char* stereoModeName(StereoMode mode);
// Throws std::invalid_argument for a separation outside 0..10 m or a zero-parallax distance not
// above 0 (or not finite).
void validateStereo(const StereoOptions& stereo);

// The size of each eye's image inside a `width` x `height` frame: half the width side by side,
// half the height one above the other, the whole frame otherwise.
void stereoEyeSize(StereoMode mode, int width, int height, int& eye_width, int& eye_height);

// One eye: the centre camera moved sideways by half the separation (left: -1, right: +1), and
// its projection sheared so the zero-parallax plane is shared (reversed Z, as Camera's).
struct StereoEye {
  Camera camera;
  glm::dmat4 projection{1.0};
};
StereoEye stereoEye(const Camera& centre, double aspect, const StereoOptions& stereo, int side);

// A camera behind the centre eye whose frustum holds both eyes' frusta (for the shared cut).
Camera stereoCutCamera(const Camera& centre, double aspect, const StereoOptions& stereo);

// The frame from the two eyes' images (RGBA, rows top-down, eye_width x eye_height each); throws
// std::invalid_argument for QuadBuffered, which has no single frame.
void composeStereo(StereoMode mode, int eye_width, int eye_height, std::span<const uint8_t> left,
                   std::span<const uint8_t> right, std::vector<uint8_t>& frame);

}  // namespace tw
