// The camera the rendering tests place: at `eye`, looking at `target`, with near 5 cm and far
// 1 km (package frame or world, as the caller's positions are). For tests linking tw_runtime.
#pragma once

#include <glm/glm.hpp>

#include "camera.h"

namespace tw::test {

inline Camera lookingAt(const glm::dvec3& eye, const glm::dvec3& target) {
  Camera camera;
  camera.position = eye;
  camera.lookAt(target);
  camera.near_m = 0.05;
  camera.far_m = 1000.0;
  return camera;
}

}  // namespace tw::test
