// BRepMesh over a STEP part, its B-spline faces meshed on the conforming tessellator's grid.
//
// A trimmed B-spline face (a wire cutting across its parameter rectangle, holes in it) cannot be
// zipped to four border strings as an untrimmed one is (step_bspline_faces.h). It still takes its
// inside from the tessellator: the interior grid the tessellator plans for the face's surface at
// the chordal tolerance, clipped to the face's wires (nodes outside a wire, or nearer to it than
// a third of a grid step, left out), triangulated together with the B-rep's own edge nodes by
// OpenCASCADE's constrained Delaunay, and then refined by BRepMesh's deflection control where a
// triangle still deviates from the surface by more than the deflection (along the wires, where
// the clipped grid leaves gaps: the grid alone gave 0.41 mm at 0.23 mm on the Ventilator; see
// docs/importers.md). The border is the edge discretization the neighbouring faces share, so the
// shell stays closed without T-vertices. Faces of other kinds keep BRepMesh's own algorithms.
#pragma once

#include <TopTools_MapOfShape.hxx>
#include <TopoDS_Shape.hxx>

namespace tw {

// Meshes every face of `shape` (BRepMesh_IncrementalMesh at `deflection` metres and
// `angle_rad`, one thread), the B-spline and Bézier faces on the tessellator's planned grid.
// `planned` receives the faces that were.
void meshShapeFaces(const TopoDS_Shape& shape, double deflection, double angle_rad,
                    TopTools_MapOfShape& planned);

}  // namespace tw
