// Section planes: what a reviewer cuts the model open with.
//
// A plane removes what lies on the side its normal points to (BCF's ClippingPlane rule: the
// direction points to the hidden side). A section box is six planes facing out of it, so it
// removes what lies outside the box. Planes and a box combine: a point is removed when any plane
// removes it. The surface passes clip every draw path on the GPU (gl_shaders.h sectionClipped) and
// fill the cut with the section colour.
#pragma once

#include <array>
#include <string>
#include <vector>

#include <glm/glm.hpp>

namespace tw {

struct SectionPlane {
  glm::dvec3 point{0.0};            // world metres
  glm::dvec3 normal{0.0, 0.0, 1.0};  // unit, toward the removed side
};

// At most this many planes a reviewer places one by one, besides a section box; the renderer
// takes both at once.
inline constexpr size_t kMaxUserSectionPlanes = 6;
inline constexpr size_t kMaxSectionPlanes = kMaxUserSectionPlanes + 6;

// The six planes of the box [min, max], facing out.
std::array<SectionPlane, 6> sectionBoxPlanes(const glm::dvec3& min, const glm::dvec3& max);

// Whether `plane` removes the world point `p` (strictly on its normal's side).
inline bool sectionRemoves(const SectionPlane& plane, const glm::dvec3& p) {
  return glm::dot(plane.normal, p - plane.point) > 0.0;
}

// "X,Y,Z,NX,NY,NZ" (a point on the plane and its normal, toward the removed side; the normal is
// normalized). Throws std::invalid_argument naming what is wrong: not six finite numbers, or a
// zero normal.
SectionPlane parseSectionPlane(const std::string& text);

}  // namespace tw
