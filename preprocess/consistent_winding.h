// Consistent winding of a mesh piece before it is simplified.
//
// Why: models often wind a cap or a patch against the surface it closes (an end disc of a pump
// wound inward, one side of a duct flipped). The edge between them is then used twice in the same
// direction, edge collapse sees a border there and the piece hardly coarsens; on the generated
// plant such pumps made the coarse levels carry three times the error at the same triangle counts
// (docs/preprocess.md, "Winding"). Closed pieces wound inside out also miss back-face culling
// (closed_surface.h).
// How: vertices welded by exact position (exact_weld.h). Across every edge shared by exactly two
// triangles the second is turned to agree with the first, breadth first from each piece's first
// triangle; edges used by one triangle or by three and more do not connect. Then a closed piece (no
// such edge) is turned, if need be, to enclose a positive volume, and an open piece keeps the
// orientation most of its area had. A piece that cannot be oriented (a Moebius strip) keeps its
// first assignment, counted as a conflict. Rendering does not change: shading is two-sided.
#pragma once

#include <cstdint>
#include <vector>

#include "scene.h"

namespace tw {

struct WindingReport {
  uint64_t triangles = 0;  // examined: after welding, degenerate ones left as they are
  uint64_t pieces = 0;     // connected through edges shared by exactly two triangles
  uint64_t turned = 0;     // triangles whose winding is reversed
  uint64_t conflicts = 0;  // edges left disagreeing because their piece is not orientable
};

// The triangles of `mesh` (index t for mesh.indices[3t..3t+2]) to reverse, in increasing order.
// Pure function, O(n log n) in the triangle count.
std::vector<uint32_t> trianglesToTurn(const TriangleMesh& mesh, WindingReport* report = nullptr);

// Reverses each listed triangle of `mesh` (swaps its second and third index).
void turnTriangles(TriangleMesh& mesh, const std::vector<uint32_t>& triangles);

}  // namespace tw
