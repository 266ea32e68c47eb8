// The object and world point under a pixel; see object_pick.h.
#include "object_pick.h"

#include <stdexcept>
#include <string>
#include <vector>

namespace tw {

std::optional<Pick> pickPixel(const GlRenderer& renderer, const Camera& camera, int x, int y) {
  const int width = renderer.width(), height = renderer.height();
  if (x < 0 || y < 0 || x >= width || y >= height)
    throw std::out_of_range("pixel " + std::to_string(x) + "," + std::to_string(y) +
                            " is outside the " + std::to_string(width) + "x" +
                            std::to_string(height) + " image");
  std::vector<uint32_t> ids;
  std::vector<float> depth;
  renderer.readObjectIds(ids, true);
  renderer.readDepth(depth, true);
  const size_t at = size_t(y) * width + x;
  if (ids[at] == 0 || !(depth[at] > 0.0f)) return std::nullopt;
  // The pixel's centre in normalized device coordinates (y up), its reversed-Z depth as is
  // (glClipControl ZERO_TO_ONE), back through projection * rotation to an eye-relative point.
  const double aspect = double(width) / double(height);
  const glm::dvec4 ndc(2.0 * (x + 0.5) / width - 1.0, 1.0 - 2.0 * (y + 0.5) / height,
                       double(depth[at]), 1.0);
  const glm::dmat4 inverse = glm::inverse(camera.projection(aspect) * camera.viewRotation());
  const glm::dvec4 p = inverse * ndc;
  const glm::dvec3 offset = glm::dvec3(p) / p.w;
  Pick pick;
  pick.object = ids[at] - 1;
  pick.world = camera.position + offset;
  pick.distance_m = glm::length(offset);
  return pick;
}

}  // namespace tw
