// Objects checked against the scene's documented range. See scene_range.h.
#include "scene_range.h"

#include <cmath>
#include <cstdio>
#include <variant>

#include "bounds.h"
#include "format_error.h"

namespace tw {
namespace {

bool finite(const glm::dvec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }
bool finite(const glm::vec3& v) { return finite(glm::dvec3(v)); }

std::string number(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", v);
  return text;
}

// Why `object` is out of range, or "" when it is not.
std::string outOfRange(const SceneObject& object) {
  const Transform& t = object.info.transform;
  if (!finite(t.origin)) return "its placement's origin is not finite";
  for (int c = 0; c < 3; ++c)
    if (!finite(t.linear[c])) return "its placement's rotation or scale is not finite";
  // The local box, checked finite on the way (one pass over a mesh's positions: this runs on
  // every part a reader delivers); its placed corners bound the object, a little generously
  // for a turned one, which the limits' margins allow.
  LocalBox box;
  if (const auto* mesh = std::get_if<TriangleMesh>(&object.geometry)) {
    for (const glm::vec3& p : mesh->positions) {
      if (!finite(p)) return "a vertex position is not finite";
      box.min = glm::min(box.min, p);
      box.max = glm::max(box.max, p);
    }
  } else if (const auto* patches = std::get_if<NurbsPatchSet>(&object.geometry)) {
    for (const NurbsPatch& patch : patches->patches)
      for (const glm::vec4& c : patch.control_points)
        if (!finite(glm::vec3(c)) || !std::isfinite(c.w)) return "a control point is not finite";
    box = localBounds(object.geometry);
  } else {
    box = localBounds(object.geometry);
    if (!finite(box.min) || !finite(box.max)) return "a primitive dimension is not finite";
  }
  const Aabb world = placedBox(box, t);
  if (world.empty()) return "";
  if (!finite(world.min) || !finite(world.max)) return "its bounds are not finite";
  const glm::dvec3 extent = world.extent();
  const double largest = std::max(extent.x, std::max(extent.y, extent.z));
  if (largest > kMaxObjectExtentM)
    return "it measures " + number(largest) + " m, beyond the " + number(kMaxObjectExtentM) +
           " m an object may measure";
  const glm::dvec3 far = glm::max(glm::abs(world.min), glm::abs(world.max));
  const double reach = std::max(far.x, std::max(far.y, far.z));
  if (reach > kMaxSceneCoordinateM)
    return "it reaches " + number(reach) + " m from the origin, beyond the " +
           number(kMaxSceneCoordinateM) + " m a scene may span";
  return "";
}

}  // namespace

void RangeCheckedSink::onObject(const SceneObject& object) {
  const std::string why = outOfRange(object);
  if (!why.empty()) {
    const std::string name = object.info.name.empty() ? "" : " '" + object.info.name + "'";
    throw FormatError(file_name_, "object " + std::to_string(object.info.id) + name + ": " + why);
  }
  inner_.onObject(object);
}

}  // namespace tw
