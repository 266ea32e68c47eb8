// Topological check of an indexed triangle mesh: is it a closed, consistently oriented 2-manifold?
//
// The preprocessor runs it on tessellated NURBS patch sets and primitives (ENVIRON verified its
// crack-free NURBS tessellation the same way). Vertices are welded by exact position first, so a
// mesh that splits vertices for hard normals (a box, a capped cylinder) is still judged on its
// shape: what matters is that the surface has no holes, cracks or T-junctions.
#pragma once

#include <cstdint>

#include "scene.h"

namespace tw {

struct MeshTopologyReport {
  uint64_t vertices = 0;            // distinct positions (bitwise equal, -0 == +0) used by faces
  uint64_t faces = 0;               // triangles added to the half-edge mesh
  uint64_t degenerate_faces = 0;    // triangles skipped: an index out of range or a repeated vertex
  uint64_t rejected_faces = 0;      // triangles OpenMesh refused (complex edge or vertex)
  uint64_t boundary_edges = 0;      // edges with a face on one side only (holes, cracks, T-junctions)
  uint64_t non_manifold_edges = 0;  // edges used by more than two triangles, or twice the same way

  // Closed, manifold and consistently oriented, with at least one face.
  bool watertight() const {
    return faces > 0 && boundary_edges == 0 && non_manifold_edges == 0 && rejected_faces == 0 &&
           degenerate_faces == 0;
  }
};

// Builds an OpenMesh half-edge mesh from `mesh` (positions and indices; normals and colours are
// ignored) and reports its topology. Pure function; cost is linear in the mesh size.
MeshTopologyReport checkWatertight(const TriangleMesh& mesh);

}  // namespace tw
