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

#include <array>
#include <cstdint>
#include <vector>

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

// One side of a patch whose border someone else placed: vertices already in the output mesh, in
// the patch's counter-clockwise order (side 0 runs along v = v0 with u rising, then u = u1,
// v = v1, u = u0), each with its parameter t in [0, 1] along the side (0 and 1 at the corners).
// A collapsed side (a pole) is its one vertex.
struct PatchSideString {
  std::vector<uint32_t> vertices;
  std::vector<double> t;
};

// The inside of one patch whose four border strings are given, as a B-rep importer has them
// from the edge discretization its neighbouring faces share: the interior grid the chordal
// tolerance asks for, joined to the strings by one strip per side, the same steps 3 and 5 as
// above. Appends the interior vertices (positions; normals too when `out` carries them) and the
// triangles to `out`; `flip` reverses the triangles. Returns false, adding nothing, when the patch
// is invalid or the strings do not close (side s must end at the vertex side s + 1 starts with).
bool tessellatePatchInside(const NurbsPatch& patch, const std::array<PatchSideString, 4>& sides,
                           float chordal_tolerance, bool flip, TriangleMesh& out,
                           ConformingTessellationStats* stats = nullptr);

// The interior grid the tessellator plans for `patch` at `chordal_tolerance`: `n` x `m` segments,
// uniform over the patch's parameter rectangle, so that the surface between the grid's triangles
// stays within the tolerance (at least 2 a direction). Returns false, setting nothing, for an
// invalid patch. A B-rep importer uses it for trimmed faces, clipping the grid to the face's wires.
bool planPatchGrid(const NurbsPatch& patch, float chordal_tolerance, uint32_t& n, uint32_t& m);

// The number of triangles tessellateNurbsConforming makes of `patches`. Unlike the per-patch
// count (nurbsTriangleCount), it tessellates the set to know: borders shared with a neighbour
// take that neighbour's points. A scene holds few NURBS sets (hulls, equipment shells), each a
// few milliseconds. Throws as tessellateNurbsConforming.
uint64_t nurbsConformingTriangleCount(const NurbsPatchSet& patches, float chordal_tolerance);

}  // namespace tw
