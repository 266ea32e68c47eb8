// B-spline faces of a STEP part tessellated by the conforming NURBS tessellator
// (formats/nurbs_conforming.h) on the B-rep's own edge discretization.
//
// BRepMesh meshes every face of a part at once, and the nodes it puts on an edge are shared by
// the faces on both sides. A B-spline face that covers its whole parameter rectangle (one wire
// running round the rectangle's sides: an untrimmed patch, or a periodic one cut at its seam)
// keeps those border nodes and gets its inside from the conforming tessellator: the interior grid
// its curvature and the chordal tolerance ask for, zipped to the border by one strip per side.
// So the borders the B-rep says are shared stay shared (no guessing by distance), the shell stays
// closed, and no T-vertex appears between a patch and its neighbours, whether they are patches,
// planes or cones. Trimmed B-spline faces (a wire cutting across the rectangle, holes) take the
// same interior grid clipped to their wires (step_face_mesher.h).
#pragma once

#include <Poly_Triangulation.hxx>
#include <TopoDS_Face.hxx>
#include <gp_Trsf.hxx>

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "scene.h"

namespace tw {

// Appends `face`'s triangles to `out` when the face is a B-spline (or Bézier) surface covering its
// parameter rectangle; returns false, adding nothing, otherwise. `triangulation` is BRepMesh's
// for this face, `placement` its location, `node_vertex` maps each of its nodes (1-based) to the
// vertex of `out` it was welded to, and positions in `out` are relative to `centre`.
bool tessellateBSplineFace(const TopoDS_Face& face, const Poly_Triangulation& triangulation,
                           const gp_Trsf& placement, const glm::dvec3& centre,
                           const std::vector<uint32_t>& node_vertex, double deflection,
                           TriangleMesh& out);

// The conforming tessellator's interior grid for a B-spline (or Bézier) face over its parameter
// rectangle [u0, u1] x [v0, v1] at `deflection`: `n` x `m` segments, uniform in the parameters.
// Returns false when the face is not such a surface or the rectangle is empty.
bool planBSplineFaceGrid(const TopoDS_Face& face, double u0, double u1, double v0, double v1,
                         double deflection, uint32_t& n, uint32_t& m);

}  // namespace tw
