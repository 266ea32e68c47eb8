// Closest points between the pieces a measurement is made of: segments, triangles and capped
// cylinders, in double precision. The minimum distance between two objects (object_distance.h)
// is the smallest of these over their triangle pairs and, where both are cylinders, the closed
// form.
#pragma once

#include <array>
#include <optional>

#include <glm/glm.hpp>

namespace tw {

using Triangle3d = std::array<glm::dvec3, 3>;

// A point on each side and the distance between them.
struct PointPair {
  glm::dvec3 a{0.0}, b{0.0};
  double distance = 0.0;
};

// The closest points of segments p0-p1 and q0-q1 (either may be a point); s and t are their
// parameters along each, in [0, 1].
struct SegmentClosest {
  PointPair points;
  double s = 0.0, t = 0.0;
};
SegmentClosest closestOnSegments(const glm::dvec3& p0, const glm::dvec3& p1, const glm::dvec3& q0,
                                 const glm::dvec3& q1);

// The point of triangle abc (its inside included) closest to p.
glm::dvec3 closestOnTriangle(const glm::dvec3& p, const Triangle3d& t);

// The closest points of two triangles (solid: distance 0 where they touch or cross).
PointPair closestBetweenTriangles(const Triangle3d& s, const Triangle3d& t);

// A capped cylinder: its axis from `base` to `top` and its radius, all in one frame.
struct CylinderAxis {
  glm::dvec3 base{0.0}, top{0.0};
  double radius = 0.0;
};

// The closest points of two solid cylinders where the closed form holds: their axes' closest
// points lie inside both axes (not at an end) and the axes are farther apart than the radii
// together, so the closest points lie on the two mantles along the axes' common normal (for
// parallel axes, at the middle of the stretch where both run side by side). Otherwise (an end cap
// or an edge is closest, or they overlap) nothing: the caller measures their tessellations.
std::optional<PointPair> closestBetweenCylinders(const CylinderAxis& a, const CylinderAxis& b);

}  // namespace tw
