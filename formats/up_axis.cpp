// Y-up files turned Z up as they are read. See up_axis.h.
#include "up_axis.h"

#include <stdexcept>
#include <string>

namespace tw {

UpAxis parseUpAxis(std::string_view name) {
  if (name == "auto") return UpAxis::Auto;
  if (name == "y") return UpAxis::Y;
  if (name == "z") return UpAxis::Z;
  throw std::invalid_argument("unknown up axis '" + std::string(name) +
                              "' (expected auto, y or z)");
}

const char* upAxisName(UpAxis up) {
  switch (up) {
    case UpAxis::Auto: return "auto";
    case UpAxis::Y: return "y";
    case UpAxis::Z: return "z";
  }
  return "auto";
}

glm::dmat3 yUpToZUp() {
  // Columns: where X, Y and Z go. X stays, Y becomes Z, Z becomes -Y.
  return glm::dmat3(glm::dvec3(1, 0, 0), glm::dvec3(0, 0, 1), glm::dvec3(0, -1, 0));
}

void UpAxisSink::onObject(const SceneObject& object) {
  turned_.info = object.info;
  turned_.geometry = object.geometry;
  const glm::dmat3 turn = yUpToZUp();
  turned_.info.transform.origin = turn * object.info.transform.origin;
  turned_.info.transform.linear = glm::mat3(turn * glm::dmat3(object.info.transform.linear));
  next_.onObject(turned_);
}

}  // namespace tw
