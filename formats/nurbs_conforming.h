// NURBS patch sets tessellated without T-vertices (the seed system's algorithm; docs/nurbs.md).
//
// CAD hulls and equipment come as many adjacent untrimmed patches. Tessellating each patch on its
// own puts different points on the two sides of a shared border: T-vertices and cracks. Here:
//  1. each patch border is evaluated as a string of points;
//  2. borders are walked patch after patch; where an adjacent patch already placed vertices on
//     the shared border (found geometrically, whatever the two patches' parameterisation:
//     reversed direction, other degree or knot spacing), exactly those vertices are used on this
//     side too; elsewhere points are chosen by a chordal-error and edge-length criterion;
//  3. the interior is a uniform N x M grid whose density follows the chordal tolerance, joined
//     to the border vertices by a single strip of triangles.
// Output vertices on shared borders and corners are bit-identical across patches (welded).
#pragma once

#include <cstdint>

#include "scene.h"

namespace tw {

struct ConformingTessellationStats {
  uint32_t patches = 0;
  uint32_t shared_borders = 0;   // border pairs found shared between two patches
  uint64_t border_vertices = 0;
  uint64_t interior_vertices = 0;
  uint64_t triangles = 0;
};

// Appends the triangles of `patches` (positions, normals, indices; in the set's local frame, as
// tessellateNurbs in formats/tessellate.h) to `out`, with `chordal_tolerance` the largest distance
// (scene units) between the surface and its triangles. Invalid patches throw
// std::invalid_argument naming the patch index and the reason (validateNurbsPatch).
void tessellateNurbsConforming(const NurbsPatchSet& patches, float chordal_tolerance,
                               TriangleMesh& out, ConformingTessellationStats* stats = nullptr);

// The number of triangles tessellateNurbsConforming makes of `patches`. Unlike the per-patch
// count (nurbsTriangleCount), it tessellates the set to know: borders shared with a neighbour
// take that neighbour's points. A scene holds few NURBS sets (hulls, equipment shells), each a
// few milliseconds. Throws as tessellateNurbsConforming.
uint64_t nurbsConformingTriangleCount(const NurbsPatchSet& patches, float chordal_tolerance);

}  // namespace tw
