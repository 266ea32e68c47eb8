// A front of the package's LOD DAG: the mesh clusters that exist when the groups of one level
// are simplified. It is a complete, crack-free surface at that level (the cut with every group
// below the level refined and none at or above it), which makes it the candidate set of the
// visibility preprocess: coarse enough to cast millions of rays at, fine enough to occlude.
#pragma once

#include <cstdint>
#include <vector>

#include "package_view.h"

namespace tw {

struct DagFront {
  uint32_t level = 0;
  std::vector<uint32_t> clusters;  // mesh cluster ids, ascending
  uint64_t triangles = 0;
};

// Front of `level`: mesh clusters of level <= `level` that are roots or whose parent group has
// level >= `level`. Level 0 gives every level-0 mesh cluster.
DagFront dagFront(const PackageView& view, uint32_t level);

// The finest front holding at most max_triangles triangles (the coarsest level's front when none
// does, so there is always an answer for a non-empty package).
DagFront finestFrontWithin(const PackageView& view, uint64_t max_triangles);

}  // namespace tw
