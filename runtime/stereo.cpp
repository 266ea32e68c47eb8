// Stereo eyes and frames (stereo.h).
#include "stereo.h"

#include <cmath>
#include <cstring>
#include <stdexcept>

namespace tw {

StereoMode parseStereoMode(const std::string& name) {
  if (name == "off") return StereoMode::Off;
  if (name == "side-by-side") return StereoMode::SideBySide;
  if (name == "top-bottom") return StereoMode::TopBottom;
  if (name == "anaglyph") return StereoMode::Anaglyph;
  if (name == "quad-buffered") return StereoMode::QuadBuffered;
  throw std::invalid_argument("stereo mode '" + name +
                              "': give off, side-by-side, top-bottom, anaglyph or quad-buffered");
}

const char* stereoModeName(StereoMode mode) {
  switch (mode) {
    case StereoMode::Off: return "off";
    case StereoMode::SideBySide: return "side-by-side";
    case StereoMode::TopBottom: return "top-bottom";
    case StereoMode::Anaglyph: return "anaglyph";
    case StereoMode::QuadBuffered: return "quad-buffered";
  }
  return "off";
}

void validateStereo(const StereoOptions& stereo) {
  if (!(stereo.eye_separation_m >= 0.0 && stereo.eye_separation_m <= 10.0))
    throw std::invalid_argument("the eye separation must be 0 to 10 m");
  if (!(std::isfinite(stereo.zero_parallax_m) && stereo.zero_parallax_m > 0.0))
    throw std::invalid_argument("the zero-parallax distance must be above 0 m");
}

void stereoEyeSize(StereoMode mode, int width, int height, int& eye_width, int& eye_height) {
  eye_width = mode == StereoMode::SideBySide ? width / 2 : width;
  eye_height = mode == StereoMode::TopBottom ? height / 2 : height;
}

StereoEye stereoEye(const Camera& centre, double aspect, const StereoOptions& stereo, int side) {
  const double offset = 0.5 * stereo.eye_separation_m * side;
  StereoEye eye;
  eye.camera = centre;
  eye.camera.position += centre.right() * offset;
  eye.projection = centre.projection(aspect);
  // Seen from the eye, a point at distance D straight ahead of the centre lies `offset` to the
  // other side: x_ndc = -P00 offset / D. clip.x gains P00 offset / D per unit of -z (the
  // distance), so that point lands at the image centre of both eyes.
  eye.projection[2][0] = -eye.projection[0][0] * offset / stereo.zero_parallax_m;
  return eye;
}

Camera stereoCutCamera(const Camera& centre, double aspect, const StereoOptions& stereo) {
  // Each eye's frustum leans inwards from a point half the separation aside; a frustum of the
  // same angle from b = (separation / 2) / tan(half horizontal angle) behind holds both.
  const double tan_half_x = std::tan(0.5 * centre.fov_y_rad) * aspect;
  Camera cut = centre;
  cut.position -= centre.forward() * (0.5 * stereo.eye_separation_m / tan_half_x);
  return cut;
}

void composeStereo(StereoMode mode, int eye_width, int eye_height, std::span<const uint8_t> left,
                   std::span<const uint8_t> right, std::vector<uint8_t>& frame) {
  const size_t eye_bytes = size_t(eye_width) * size_t(eye_height) * 4;
  if (left.size() != eye_bytes || right.size() != eye_bytes)
    throw std::invalid_argument("composeStereo: an eye's image has the wrong size");
  const size_t row = size_t(eye_width) * 4;
  switch (mode) {
    case StereoMode::QuadBuffered:
      throw std::invalid_argument("composeStereo: quad-buffered stereo has no single frame");
    case StereoMode::Off:
      frame.assign(left.begin(), left.end());
      return;
    case StereoMode::SideBySide:
      frame.resize(2 * eye_bytes);
      for (int y = 0; y < eye_height; ++y) {
        std::memcpy(&frame[2 * row * y], &left[row * y], row);
        std::memcpy(&frame[2 * row * y + row], &right[row * y], row);
      }
      return;
    case StereoMode::TopBottom:
      frame.resize(2 * eye_bytes);
      std::memcpy(frame.data(), left.data(), eye_bytes);
      std::memcpy(frame.data() + eye_bytes, right.data(), eye_bytes);
      return;
    case StereoMode::Anaglyph:
      // Half-colour red-cyan: the left eye's luminance in red (less rivalry than its red
      // alone), the right eye's green and blue.
      frame.resize(eye_bytes);
      for (size_t p = 0; p < eye_bytes; p += 4) {
        frame[p] = uint8_t(0.299 * left[p] + 0.587 * left[p + 1] + 0.114 * left[p + 2] + 0.5);
        frame[p + 1] = right[p + 1];
        frame[p + 2] = right[p + 2];
        frame[p + 3] = 255;
      }
      return;
  }
}

}  // namespace tw
