// What a package's parametric instance record stands for in the scene model: its primitive, its
// canonical-frame box and its placement. The runtime's impostors and tessellations and the
// preprocessor's visibility stage (parametric occluders) read instance records the same way.
#pragma once

#include <span>

#include <glm/glm.hpp>

#include "package_format.h"
#include "scene.h"

namespace tw {

// The scene.h primitive an instance record stands for (parameters as in package_format.h).
// Unknown types give a zero sphere, which tessellates to nothing.
Primitive primitiveOf(const pkg::InstanceRecord& instance, std::span<const glm::vec2> profile_points);

// The box an instance's primitive fills in its canonical frame: tight for cylinders, cones,
// spheres, torus segments (their sweep) and boxes, the profile's box swept for extrusions and a
// full turn's for revolutions; false for unknown types and for parameters that draw nothing
// (non-positive or non-finite sizes, a torus whose tube reaches its axis, a profile outside the
// table).
bool instanceLocalBox(const pkg::InstanceRecord& instance, std::span<const glm::vec2> profile_points,
                      glm::vec3& lo, glm::vec3& hi);

// The instance's linear part (canonical frame to package frame, columns), as stored.
inline glm::mat3 instanceLinear(const pkg::InstanceRecord& in) {
  return glm::mat3(in.linear[0], in.linear[1], in.linear[2], in.linear[3], in.linear[4],
                   in.linear[5], in.linear[6], in.linear[7], in.linear[8]);
}

}  // namespace tw
