// A closed 2D profile with holes swept along a direction into a closed triangle mesh: what an
// IFC extrusion is when no primitive holds it (a slab with a stair opening in its profile, an
// oblique extrusion).
//
// The caps are the profile triangulated by ear clipping after each hole is bridged into the outer
// loop (the hole's rightmost vertex joined to the nearest outer vertex it can see to its right);
// the sides are one quad per loop edge. Loops may wind either way; the outer loop is made
// counter-clockwise and the holes clockwise, so every face points out of the solid.
#pragma once

#include <vector>

#include <glm/glm.hpp>

#include "scene.h"

namespace tw {

// Appends the prism to `out` (positions and indices; no normals): the profile in the XY plane at
// z = 0, its copy moved by `sweep` (any direction with a positive z). Loops need three points
// or more; degenerate ones are left out. Returns the triangles appended.
size_t appendProfilePrism(const std::vector<glm::dvec2>& outer,
                          const std::vector<std::vector<glm::dvec2>>& holes,
                          const glm::dvec3& sweep, TriangleMesh& out);

// Twice the signed area of a closed loop (its last point joins its first): positive when it
// winds counter-clockwise.
double loopArea2(const std::vector<glm::dvec2>& loop);

// The profile's triangles (also any one planar polygon's, projected): indices into the loops concatenated (outer first,
// then each hole), counter-clockwise. A loop ear clipping cannot finish (degenerate, or crossing
// itself) has its rest fanned, so no part of it is left open.
std::vector<uint32_t> triangulateProfile(const std::vector<glm::dvec2>& outer,
                                         const std::vector<std::vector<glm::dvec2>>& holes);

}  // namespace tw
