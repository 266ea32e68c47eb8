// Ray sampling from view cells: from sample points inside each cell, rays over the sphere of
// directions are cast with Embree at the candidate clusters; the first hit of each ray names a
// candidate. A cell's occluder set is then chosen greedily (the candidate that is the first hit
// of most still-uncovered rays, again and again, until coverage_target of the rays that hit
// anything are covered or max_occluders are chosen); its sampled visible set is every candidate
// some ray hit first.
//
// Rays: rays_per_cell per cell, spread over sample points (stratified jitter inside the cell)
// and directions (a spherical Fibonacci set, rotated per sample point); deterministic for a seed.
// Cells run in parallel with TBB, each casting its rays one by one (EmbreeScene::intersect; the
// batched intersect per cell measured no faster, docs/occlusion.md). Cost: cells x rays_per_cell
// rays, reported. Polls progress->cancelled() between chunks of cells and throws
// std::runtime_error("cancelled") when it is set.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "embree_scene.h"
#include "progress.h"
#include "view_cells.h"
#include "visibility_section.h"

namespace tw {

struct VisibilitySamplingOptions {
  uint32_t rays_per_cell = 1024;
  uint32_t samples_per_cell = 8;       // ray origins per cell
  uint32_t max_occluders = 32;
  float coverage_target = 0.9f;        // of the rays that hit something
  bool visible_sets = true;
  uint64_t seed = 1;
  Progress* progress = nullptr;        // stage "visibility rays", one step per cell
};

// `scene` must be committed and every geometry's user_id must be the candidate cluster id its
// triangles belong to (one addMesh per candidate cluster). Returns cells, ids and counts filled
// (grid fields copied from `grid`; candidate_level and candidate_triangles left to the caller).
// Throws std::invalid_argument for an uncommitted scene or zero rays.
VisibilityData sampleVisibility(const EmbreeScene& scene, const ViewCellGrid& grid,
                                const VisibilitySamplingOptions& options);

}  // namespace tw
