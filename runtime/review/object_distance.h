// The minimum distance between two sets of objects of a package, measured on their
// full-resolution geometry (level-0 mesh triangles as stored, parametric instances tessellated
// finely or, for pairs of cylinders, in closed form), with the two closest points; and the
// distance between their centre lines (the axes of their cylinders), as Navisworks offers.
// What `terawalk measure --between` prints and the viewer's measure tool will draw.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "closest_points.h"
#include "package_view.h"

namespace tw {

// Objects' geometry for measuring, in the package frame (metres from the package origin).
struct MeasureShape {
  std::vector<Triangle3d> triangles;   // mesh triangles, and every parametric tessellated
  std::vector<CylinderAxis> cylinders;  // the cylinder instances (round, unskewed) exactly
  double tessellation_error_m = 0.0;   // how far the tessellated parametrics lie inside theirs
  uint32_t parametric_instances = 0;
};

// The objects' level-0 mesh triangles (their clusters decoded from the package) and parametric
// instances, tessellated at `chordal_tolerance_m`. Throws FormatError for a page that does not
// decode.
MeasureShape measureShape(const PackageView& view, std::span<const uint32_t> objects,
                          double chordal_tolerance_m);

struct MeasuredDistance {
  PointPair points;        // world coordinates (the package origin added back)
  double error_bound_m = 0.0;  // the true distance lies in [distance - bound, distance]
  std::string method;      // "cylinders (closed form)", "triangles", "centre lines"
};

// The minimum distance between the two shapes: over every pair of triangles (a bounding volume
// hierarchy over b's prunes the pairs), and in closed form between cylinders where it holds
// (closest_points.h), which is exact and never above the tessellations' value. Throws
// std::invalid_argument when a shape is empty.
MeasuredDistance minimumDistance(const PackageView& view, const MeasureShape& a,
                                 const MeasureShape& b);

// The shortest distance between the centre lines of the two shapes' cylinders (segment to
// segment). Throws std::invalid_argument when a shape has no cylinder.
MeasuredDistance centreLineDistance(const PackageView& view, const MeasureShape& a,
                                    const MeasureShape& b);

}  // namespace tw
