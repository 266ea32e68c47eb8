// How a package's mesh DAG shrinks level by level: for each level L, the front of level L (the
// complete surface made of the clusters of level <= L that no group of level < L replaced:
// level L itself plus lower-level roots, and after a brick merge the brick roots a higher group
// takes as children), its triangles and clusters, its ratio to the front below, the largest
// error among its clusters, and whether it halves all the way to one root cluster. Fronts, not
// per-level sums: bricks of different depths put their roots at different levels, and only a
// front is a surface the cut can draw. `verify` prints it, so a user sees at once whether the
// coarse levels of a model are usable (a level that collapses leaves the cut nothing between
// "fine" and "proxy"; one that does not shrink makes the far view as costly as the near one).
#pragma once

#include <cstdint>
#include <vector>

#include "package_view.h"

namespace tw {

struct DagLevel {
  uint64_t triangles = 0;  // of the level's front
  uint32_t clusters = 0;
  double ratio = 1.0;      // triangles / the front below's (level 0: 1)
  float max_error = 0.0f;  // largest cluster error of the front
};

struct DagLevels {
  std::vector<DagLevel> levels;  // mesh clusters only, level 0 first
  uint32_t root_clusters = 0;    // mesh clusters without a parent group
  // Every front whose lower neighbour holds more than kHalvingFloor triangles is between
  // kHalvingMin and kHalvingMax of it.
  bool halves = true;
  bool errors_monotone = true;  // each front's largest error >= the front below's

  static constexpr uint64_t kHalvingFloor = 1000;
  static constexpr double kHalvingMin = 0.3, kHalvingMax = 0.65;
};

DagLevels dagLevels(const PackageView& view);

}  // namespace tw
