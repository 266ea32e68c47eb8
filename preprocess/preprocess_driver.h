// The preprocessor end to end: inputs -> bricks on disk -> per-brick LOD DAGs -> merged upper
// levels -> one package. This is the only stage that does I/O and owns the work directory; the
// stages it calls are pure functions over buffers.
//
// Resume: the work directory ("<output>.work", or `work_dir`) keeps the bricked scene, its seams
// and every finished brick's DAG, keyed by a hash of the inputs (paths, sizes, modification
// times) and the options. With `resume`, a run reuses what a killed run with the same arguments finished and writes a
// byte-identical package; without it the work directory is cleared first. It is removed after a
// successful run. The same stages also run as separate steps over a shared work directory
// (preprocess_steps.h: plan, one job per brick, merge).
//
// Memory: one brick is built at a time; finished brick DAGs wait in the resume store (only their
// roots, for the merge, stay in memory) and are re-read one at a time when packed; pages stream
// to a spill file in the work directory. What still grows with the input is listed in
// docs/preprocess.md ("Memory").
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "cluster_dag.h"
#include "progress.h"
#include "read_options.h"
#include "up_axis.h"

namespace tw {

struct PreprocessOptions {
  std::vector<std::filesystem::path> inputs;
  std::filesystem::path output;
  // Where the bricks, the resume store and the spill files go (empty: "<output>.work").
  std::filesystem::path work_dir;
  // Objects of the layers of these names are left out of the package (the layer table keeps
  // them, empty).
  std::vector<std::string> exclude_layers;
  // The project database the objects' keys refer to, named in the package (empty: none).
  std::filesystem::path database;
  uint64_t memory_budget_bytes = 2ull << 30;
  uint32_t threads = 0;          // 0: all cores
  uint32_t cluster_size = 256;   // triangles per cluster
  // Instances per parametric cluster (1..65536): 64 lets occlusion hide parts of a pipe run
  // (10M plant, decks path: 155.9 ms median frame against 176.5 ms at 256; docs/occlusion.md).
  uint32_t parametric_cluster_size = 64;
  uint64_t max_brick_triangles = 0;  // 0: derived from the memory budget
  bool resume = false;
  bool keep_work_dir = false;    // for inspection and tests
  Progress* progress = nullptr;  // cancelled() is polled between bricks
  // View cells and occluder sets. Off by default here, so library callers (tests building
  // small packages) pay nothing unless they ask; `terawalk preprocess` turns it on unless
  // `--visibility off`.
  bool visibility = false;
  uint32_t visibility_rays = 1024;  // rays per view cell
  double view_cell_size_m = 0.0;    // 0: chosen from the bounds (view_cells.h)
  bool parametric_occluders = true;  // parametric clusters are candidates (visibility_build.h)
  UpAxis up = UpAxis::Auto;          // the inputs' up axis (formats/up_axis.h)
  CadOptions cad;                    // how CAD importers mesh (ReadOptions::cad)
};

// What the visibility stage built (all zero when it was off or found no mesh clusters).
struct VisibilitySummary {
  bool ran = false;
  uint32_t candidate_level = 0;
  uint64_t candidate_triangles = 0;
  uint64_t parametric_clusters = 0;    // parametric clusters sampled (some instance taken)
  uint64_t parametric_candidates = 0;  // of those, every instance taken
  uint64_t parametric_instances = 0;   // instances taken, the widest first
  uint64_t parametric_instances_total = 0;
  float parametric_min_width_m = 0.0f;  // narrowest instance taken
  uint64_t parametric_triangles = 0;   // their coarse tessellation
  double cell_size_m = 0.0;
  uint32_t free_cells = 0;
  uint32_t solid_cells = 0;
  uint64_t rays = 0;
  double average_occluders = 0.0;
  double average_visible = 0.0;
  uint64_t section_bytes = 0;
  double rays_per_second = 0.0;  // over the sampling step alone
  double decode_s = 0.0, voxelize_s = 0.0, embree_build_s = 0.0, sampling_s = 0.0;
};

struct StageTime {
  std::string name;
  double seconds = 0.0;
};

struct PreprocessReport {
  std::vector<StageTime> stages;
  uint64_t input_triangles = 0;   // mesh + tessellated NURBS
  uint64_t primitives = 0;        // parametric instances, not tessellated
  uint64_t objects = 0;
  uint32_t bricks = 0;
  uint32_t bricks_reused = 0;     // taken from the resume store
  uint64_t seam_edges = 0;        // edges open in two bricks, locked in both brick DAGs
  uint64_t welded_across_bricks = 0;  // rim positions moved onto another brick's (cross_brick_weld.h)
  bool bricking_reused = false;
  std::vector<uint64_t> triangles_per_level;
  uint64_t root_triangles = 0;
  uint64_t merge_front_triangles = 0;  // all bricks' roots, held in memory for the merge
  uint32_t brick_stop_level = 0;       // the level at which brick DAGs stop (brickStopLevel)
  uint64_t shared_positions = 0;       // seam and root positions in the snapping table
  uint32_t bricks_resolved = 0;        // brick snapping solved again (a re-read each)
  uint64_t clusters = 0;
  uint64_t parametric_clusters = 0;
  uint32_t parametric_sort_runs = 0;  // sorted runs the parametric clustering spilled (0: in memory)
  uint64_t triangles_turned = 0;      // mesh triangles reversed to agree with their piece
  uint64_t triangles_repeated = 0;    // exact copies of another triangle, dropped
  GroupMethodCounts groups_by_method{};  // DAG groups by how they were simplified
  uint64_t sealed_run_members = 0;    // instances marked as open parts of sealed pipe runs
  uint64_t sealed_run_closers = 0;    // and as the capped cylinders closing them
  uint64_t covered_box_faces = 0;     // box faces marked as covered by another box's face
  uint64_t package_bytes = 0;
  VisibilitySummary visibility;
  uint64_t peak_rss_bytes = 0;
  double seconds = 0.0;
};

// Throws FormatError for unreadable input, std::runtime_error for I/O failure or cancellation
// ("cancelled"); the work directory is kept then, so --resume can continue.
PreprocessReport runPreprocess(const PreprocessOptions& options);

}  // namespace tw
