// Does a triangle mesh bound a solid, seen only from outside? The test behind back-face culling.
//
// A renderer may skip the triangles facing away from the eye only where every one of them is
// hidden behind a front face of the same surface: the surface must be closed (every edge used
// exactly once in each direction, so there are no holes, cracks or T-junctions, and neighbouring
// triangles agree on their orientation) and it must face outward (each connected piece encloses
// a positive volume; an inside-out piece would show its far side). Overlapping closed pieces (a
// motor and its fins) are fine: a back face of one is then behind a front face of it. Vertices
// are welded by exact position first (exact_weld.h), so split normals do not open a surface.
#pragma once

#include <cstdint>

#include "scene.h"

namespace tw {

struct ClosedSurfaceReport {
  uint64_t triangles = 0;         // after welding; degenerate ones are counted in `skipped`
  uint64_t skipped = 0;           // an index out of range or a repeated welded vertex
  uint64_t unpaired_edges = 0;    // directed edges without exactly one opposite partner
  uint64_t components = 0;        // connected pieces (through shared welded vertices)
  uint64_t inward_components = 0;  // pieces enclosing no clearly positive volume

  // Closed, consistently oriented, every piece facing outward, and not empty.
  bool enclosesSolid() const {
    return triangles > 0 && skipped == 0 && unpaired_edges == 0 && inward_components == 0;
  }
};

// Pure function, O(n log n) in the triangle count.
ClosedSurfaceReport checkClosedSurface(const TriangleMesh& mesh);

}  // namespace tw
