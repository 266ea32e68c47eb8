// Evaluation of rational B-spline patches (positions and normals) and validation of their data.
#pragma once

#include <string>

#include <glm/glm.hpp>

#include "scene.h"

namespace tw {

// Returns an empty string when `patch` is well formed (degrees >= 1, counts > degrees, knot
// vectors of the right length, non-decreasing, with a non-empty domain, positive weights, finite
// values), otherwise the reason it is not. Readers use it to reject bad files.
std::string validateNurbsPatch(const NurbsPatch& patch);

// Parameter domain [u0, u1] x [v0, v1] of a valid patch.
struct NurbsDomain {
  float u0, u1, v0, v1;
};
NurbsDomain nurbsDomain(const NurbsPatch& patch);

// Point on a valid patch at (u, v) inside its domain; `normal`, when not null, receives the unit
// surface normal (or +Z where the surface is degenerate).
glm::vec3 evaluateNurbs(const NurbsPatch& patch, float u, float v, glm::vec3* normal = nullptr);

}  // namespace tw
