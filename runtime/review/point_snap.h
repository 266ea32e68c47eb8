// Snapping a picked point to what a reviewer means by it: the centre of a cylinder's end, else the
// nearest vertex of the object's full-resolution geometry, else the nearest point of one of its
// edges, each within a radius; otherwise the picked point itself. What the viewer's measure tool
// does with each click.
#pragma once

#include <glm/glm.hpp>

#include "object_distance.h"

namespace tw {

struct SnappedPoint {
  enum class Kind { AxisEnd, Vertex, Edge, Surface };
  Kind kind = Kind::Surface;
  glm::dvec3 world{0.0};
};

const char* snapKindName(SnappedPoint::Kind kind);

// `shape`: the object's geometry (measureShape: package frame); `picked` and the result in world
// metres.
SnappedPoint snapPoint(const PackageView& view, const MeasureShape& shape, const glm::dvec3& picked,
                       double radius_m);

}  // namespace tw
