// Verification of a tessellated patch set through OpenMesh: the mesh is assembled as one
// half-edge mesh with vertices welded only where positions are bit-identical, then checked for
// what a crack-free tessellation must not have. Used by tests, `terawalk` diagnostics and
// benchmarks of nurbs_conforming.h. OpenMesh stays inside the .cpp.
#pragma once

#include <cstdint>
#include <string>

#include "scene.h"

namespace tw {

struct PatchMeshReport {
  uint64_t vertices = 0;             // after the exact weld
  uint64_t faces = 0;
  uint64_t refused_faces = 0;        // OpenMesh refused them (non-manifold or flipped)
  uint64_t boundary_edges = 0;       // all of them
  uint64_t inner_boundary_edges = 0; // boundary edges not on the set's outer border
  uint64_t t_vertices = 0;           // vertices lying inside another boundary edge
  uint64_t inconsistent_orientation = 0;  // edges whose two faces disagree
  uint64_t degenerate_faces = 0;     // zero area
  bool ok() const;                   // no refused, inner boundary, T-vertex, orientation problem
  std::string first_problem;         // human-readable, empty when ok()
};

// Checks `mesh` (from tessellateNurbsConforming or any tessellation of `patches`). Boundary
// edges count as the outer border when both ends lie on a border of some patch that no other
// patch shares (within `tolerance`, scene units).
PatchMeshReport checkPatchMesh(const TriangleMesh& mesh, const NurbsPatchSet& patches,
                               float tolerance = 1e-5f);

}  // namespace tw
