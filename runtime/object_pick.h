// Picking: which object a pixel of the last frame shows, and where, from the renderer's id and
// depth buffers. The viewer's click and `terawalk pick` use it.
//
// The object is the id buffer's (object index + 1; 0 is nothing), so a pick is exact at every
// level of detail: coarse clusters and far proxies keep each triangle's object. The point comes
// from the pixel's reversed-Z depth, unprojected through the camera in double precision and added
// to the eye's world position: exact to the depth buffer's precision (a float at that depth).
#pragma once

#include <cstdint>
#include <optional>

#include <glm/glm.hpp>

#include "camera.h"
#include "gl_renderer.h"

namespace tw {

struct Pick {
  uint32_t object = 0;     // object index in the package
  glm::dvec3 world{0.0};   // world metres of the picked point
  double distance_m = 0.0; // from the eye
};

// `x`, `y`: pixel in image coordinates (top-left origin), inside the renderer's size. The last
// frame must have been drawn with `camera`. Nothing under the pixel: nullopt. Throws
// std::out_of_range for a pixel outside the image.
std::optional<Pick> pickPixel(const GlRenderer& renderer, const Camera& camera, int x, int y);

}  // namespace tw
