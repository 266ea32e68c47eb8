// How a package's mesh DAG shrinks level by level: triangles and clusters per level, each
// level's ratio to the one below, its largest error, and whether it halves all the way to one
// root cluster. `verify` and `info` print it, so a user sees at once whether the coarse levels of
// a model are usable (a level that collapses leaves the cut nothing between "fine" and "proxy";
// one that does not shrink makes the far view as costly as the near one).
#pragma once

#include <cstdint>
#include <vector>

#include "package_view.h"

namespace tw {

struct DagLevel {
  uint64_t triangles = 0;
  uint32_t clusters = 0;
  double ratio = 1.0;     // triangles / the level below's (level 0: 1)
  float max_error = 0.0f;  // largest cluster error of the level
};

struct DagLevels {
  std::vector<DagLevel> levels;  // mesh clusters only, level 0 first
  uint32_t root_clusters = 0;    // mesh clusters without a parent group
  // Every level whose lower neighbour holds more than kHalvingFloor triangles is between
  // kHalvingMin and kHalvingMax of it.
  bool halves = true;
  bool errors_monotone = true;  // each level's largest error >= the level below's

  static constexpr uint64_t kHalvingFloor = 1000;
  static constexpr double kHalvingMin = 0.3, kHalvingMax = 0.65;
};

DagLevels dagLevels(const PackageView& view);

}  // namespace tw
