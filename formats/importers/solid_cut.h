// Boolean differences (and intersections) of scene solids, through OpenCASCADE's boolean operations.
//
// IFC cuts its solids: a window's opening is subtracted from its wall (IfcRelVoidsElement), a
// wall is clipped under a sloped roof by a half-space (IfcBooleanClippingResult). Drawing the
// wall whole would fill the window and push the wall through the roof, so the importer builds
// the host and the cutters as OpenCASCADE solids (primitives exactly, closed meshes sewn face by
// face), subtracts them, and meshes what is left. The result is a mesh: a cut box is no longer a
// box.
#pragma once

#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <glm/glm.hpp>

#include "scene.h"

namespace tw {

// Solids in one frame: closed mesh shells given in that frame, and primitives placed in it by
// rigid frames (rotation and translation only).
struct SolidSet {
  TriangleMesh mesh;
  std::vector<std::pair<glm::dmat4, Primitive>> primitives;

  bool empty() const { return mesh.indices.empty() && primitives.empty(); }
};

// A half-space: everything on one side of a plane, optionally only inside a prism (IFC's
// IfcPolygonalBoundedHalfSpace: a polygon in the XY plane of `boundary_frame`, swept along that
// frame's Z without end).
struct HalfSpace {
  glm::dmat4 plane{1.0};        // origin on the plane, Z its normal; rigid
  bool material_below = true;   // the half-space lies on the plane's -Z side
  std::vector<glm::dvec2> boundary;  // empty: unbounded
  glm::dmat4 boundary_frame{1.0};    // rigid
};

class SolidCutError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The most mesh triangles a host or cutter may have: sewing them into a solid costs far more
// than the cut, and a larger mesh is kept uncut.
constexpr size_t kMaxCutMeshTriangles = 20000;

// `host` less every solid of `cutters` and every half-space, meshed at `chordal_tolerance_m`
// (and 20 degrees between facets), in the sets' frame. Throws SolidCutError naming the reason
// when a solid cannot be built (a mesh that is not closed or too large, a degenerate
// primitive) or OpenCASCADE's operation fails. The result may be empty (the cutters covered
// the host).
TriangleMesh subtractSolids(const SolidSet& host, const SolidSet& cutters,
                            const std::vector<HalfSpace>& half_spaces, double chordal_tolerance_m);

// What `host` has in common with `others` and the half-spaces (IFC's INTERSECTION), the same way;
// an intersection with nothing is an error.
TriangleMesh intersectSolids(const SolidSet& host, const SolidSet& others,
                             const std::vector<HalfSpace>& half_spaces, double chordal_tolerance_m);

}  // namespace tw
