// Circular arcs in a plane, sampled into polyline points: how IFC profiles' curved edges (trimmed
// circles of composite curves, arc segments of indexed polycurves) become the polygons an
// extrusion or a mesh prism takes.
#pragma once

#include <vector>

#include <glm/glm.hpp>

namespace tw {

// At most this angle between consecutive samples: 10 degrees.
constexpr double kArcStepRad = 3.14159265358979323846 / 18.0;

// The arc of radius `r` about `centre` from angle `t0` (radians, from +X) turning by `sweep`
// (positive counter-clockwise), both ends included, in at least `min_steps` chords.
std::vector<glm::dvec2> arcPoints(const glm::dvec2& centre, double r, double t0, double sweep,
                                  int min_steps = 1);

// The arc from `a` through `b` to `c` (IFC's IfcArcIndex), its ends exactly `a` and `c`; the
// three points themselves when they are collinear.
std::vector<glm::dvec2> arcThrough(const glm::dvec2& a, const glm::dvec2& b, const glm::dvec2& c);

}  // namespace tw
