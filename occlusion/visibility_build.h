// The visibility stage of the preprocessor, from a written package to its visibility section:
// pick the candidate front (dag_front.h), decode its clusters, build the view cells
// (view_cells.h), load the candidates into Embree, sample (visibility_sampling.h) and encode.
// Parametric clusters are candidates too (decks, walls and equipment of a plant are boxes and
// extrusions): their instances are tessellated at a coarse chordal tolerance, one Embree geometry
// per cluster, so rays stop at them and the occluder and visible sets name them.
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
  // Parametric clusters as candidates (kParametricCandidates). Their instances are tessellated at
  // parametric_tolerance_m (vertices on the true surfaces, faces within the tolerance of them),
  // the widest first (the second largest placed edge of the canonical box: a pipe's diameter)
  // while the triangles stay within max_parametric_triangles; narrower ones let rays through.
  // The clusters all of whose instances were taken are listed as parametric candidates: the
  // runtime's pvs mode may drop them where a cell's visible set does not name them.
  bool parametric_candidates = true;
  float parametric_tolerance_m = 0.02f;
  uint64_t max_parametric_triangles = 1u << 20;
  ViewCellOptions cells;
  VisibilitySamplingOptions sampling;
  Progress* progress = nullptr;  // stages "visibility cells", "visibility rays"
};

struct VisibilityBuildReport {
  uint32_t candidate_level = 0;
  uint64_t candidate_clusters = 0;
  uint64_t candidate_triangles = 0;  // mesh front
  uint64_t parametric_clusters = 0;    // parametric clusters with a taken instance
  uint64_t parametric_candidates = 0;  // of those, the ones with every instance taken
  uint64_t parametric_instances = 0;   // instances taken (the widest)
  uint64_t parametric_instances_total = 0;
  float parametric_min_width_m = 0.0f;  // width of the narrowest instance taken
  uint64_t parametric_triangles = 0;   // their tessellation
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
