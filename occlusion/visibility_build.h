// The visibility stage of the preprocessor, from a written package to its visibility section:
// pick the candidate front (dag_front.h), decode its clusters, build the view cells
// (view_cells.h), load the candidates into Embree, sample (visibility_sampling.h) and encode.
// `terawalk preprocess` runs it after writing the package and stores the result with
// replacePackageSection; `--visibility off` skips it.
#pragma once

#include <cstdint>
#include <vector>

#include "package_view.h"
#include "progress.h"
#include "view_cells.h"
#include "visibility_sampling.h"

namespace tw {

struct VisibilityBuildOptions {
  // The candidate front is the finest one holding at most this many triangles.
  uint64_t max_candidate_triangles = 1u << 20;
  // The solid/free classification of view cells voxelizes the finest front holding at most this
  // many triangles (coarser than the candidates: OpenVDB's cost grows with the triangle count,
  // and simplification errors are far below the voxel size). 0: the candidate front itself.
  uint64_t max_classification_triangles = 1u << 18;
  ViewCellOptions cells;
  VisibilitySamplingOptions sampling;
  Progress* progress = nullptr;  // stages "visibility cells", "visibility rays"
};

struct VisibilityBuildReport {
  uint32_t candidate_level = 0;
  uint64_t candidate_clusters = 0;
  uint64_t candidate_triangles = 0;
  uint32_t grid_cells = 0;
  uint32_t free_cells = 0;
  uint32_t solid_cells = 0;
  double cell_size_m = 0.0;
  uint64_t rays = 0;
  double average_occluders = 0.0;
  double average_visible = 0.0;
  uint64_t section_bytes = 0;
  double decode_s = 0.0, voxelize_s = 0.0, embree_build_s = 0.0, sampling_s = 0.0;
};

// Computes the section bytes for `view` (empty bytes for a package without mesh clusters).
// Throws FormatError if the package's pages are damaged.
std::vector<uint8_t> buildVisibilitySection(const PackageView& view,
                                            const VisibilityBuildOptions& options,
                                            VisibilityBuildReport* report = nullptr);

}  // namespace tw
