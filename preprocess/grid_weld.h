// Full-resolution vertices snapped to the package's position grid, and welded where they then
// coincide, before the LOD DAG is built.
//
// Why: the package stores a cluster's positions on a power-of-two grid whose cell grows with the
// cluster's extent (page_codec.h), up to about a millimetre for a long cluster. Two vertices the
// DAG keeps apart (a pipe's open end and the elbow that touches it, one float ulp away) can land
// on one grid point and become one vertex in the package, joined by an edge the DAG never saw and
// so never locked: when one side simplifies, the runtime shows a crack and verify reports it.
// Snapping first, to the grid each vertex's level-0 cluster will use, and welding what coincides
// makes the DAG's vertex identity the package's at full resolution: touching parts become one
// surface, locked like any other where it crosses a group border.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "clusterize.h"

namespace tw {

struct GridWeld {
  std::vector<glm::vec3> positions;  // welded, in order of first use by an input vertex
  std::vector<uint32_t> remap;       // input vertex -> welded vertex
  uint64_t moved_vertices = 0;       // input vertices whose position changed
  uint64_t merged_vertices = 0;      // input vertices welded onto an earlier one
};

// The shift the package encoder picks for a cluster with these positions (page_codec.cpp, same
// arithmetic): the smallest one from `min_shift` whose cells hold the extent in 16 bits and the
// grid origin in int32; pkg::kMaxPositionShift + 1 when none does.
uint32_t clusterPositionShift(std::span<const glm::vec3> positions, double position_step_m,
                              uint32_t min_shift = 0);

// Welds every vertex used by `clusters` (triangles of `indices`, three per triangle, into
// `positions`): first, a vertex within `noise_tolerance_m` (per axis; <= 0: one base step) of an
// earlier vertex joins it
// (float noise that a pointwise grid could round apart; joining the first one in reach, never a
// chain, bounds the move); then each such vertex is snapped to the grid of the coarsest shift
// among the clusters of the vertices it stands for, and equal positions are welded. Vertices
// flagged in `keep` (brick seams, which the other brick must meet bit for bit; empty = none)
// neither move nor join. Unused vertices keep their position. Deterministic.
// Throws std::invalid_argument when an index is out of range or `keep` has the wrong size.
GridWeld weldOnPackageGrid(std::span<const glm::vec3> positions,
                           std::span<const uint32_t> indices, const TriangleClusters& clusters,
                           std::span<const uint8_t> keep, double position_step_m,
                           double noise_tolerance_m = 0.0);

}  // namespace tw
