// PackageSummary: what a .twk package holds, per LOD level and in total, for `terawalk info`.
//
// Computed from the records alone (a pass over the resident tables; page data is not read, so a
// many-GB package is summarised in the time it takes to read its tables). Sizes are bytes,
// errors and positions metres (positions relative to the package origin).
#pragma once

#include <array>
#include <cstdint>
#include <glm/glm.hpp>
#include <string>
#include <vector>

#include "package_format.h"
#include "package_view.h"

namespace tw {

struct PackageLevelSummary {
  uint32_t level = 0;
  uint64_t clusters = 0;  // mesh + parametric
  uint64_t parametric_clusters = 0;
  uint64_t triangles = 0;      // mesh triangles
  uint64_t vertices = 0;       // mesh vertices as stored (border vertices duplicated)
  uint64_t instances = 0;      // in parametric clusters
  uint64_t roots = 0;          // clusters with no parent group
  uint64_t groups = 0;         // groups whose children are at this level
  uint64_t encoded_bytes = 0;  // encoded mesh clusters (raw page bytes they use)
  float min_error_m = 0.0f;    // over the level's clusters
  float max_error_m = 0.0f;
  double mean_error_m = 0.0;
};

struct PackageSummary {
  std::string file;
  uint64_t file_bytes = 0;
  uint32_t version = 0, minor_version = 0;
  glm::dvec3 origin{0.0};
  double position_step_m = 0.0;
  glm::vec3 bounds_min{0.0f}, bounds_max{0.0f};
  uint32_t level_count = 0;
  uint64_t total_triangles = 0;      // level 0, as the header records
  uint64_t all_level_triangles = 0;  // every level
  uint64_t far_proxy_clusters = 0, far_proxy_triangles = 0;  // pkg::kClusterFarProxy
  uint32_t max_cluster_triangles = 0;
  uint32_t target_page_bytes = 0;
  uint64_t input_hash = 0;
  std::vector<PackageLevelSummary> levels;  // index = level

  uint64_t clusters = 0, groups = 0;
  uint64_t pages = 0, pages_compressed = 0;
  uint64_t page_stored_bytes = 0, page_raw_bytes = 0;  // over all pages
  std::array<uint64_t, pkg::kSectionCount> section_bytes{};      // in the file
  std::array<uint64_t, pkg::kSectionCount> section_raw_bytes{};  // of the records (decompressed)
  std::array<uint64_t, pkg::kPrimitiveTypeCount> instances_by_type{};
  uint64_t instances = 0, profile_points = 0;
  bool sealed_runs_marked = false;  // kHeaderSealedRunsMarked: the counts below are the search's
  uint64_t sealed_run_members = 0, sealed_run_closers = 0;
  bool covered_faces_marked = false;  // kHeaderCoveredFacesMarked: the count below is the search's
  uint64_t covered_box_faces = 0;
  uint64_t objects = 0, objects_with_db_key = 0;
  uint64_t closed_objects = 0;  // kObjectClosedSurface: back faces may be culled
  std::string database_path;    // as stored (relative to the package's folder); empty: none
  struct Layer {
    std::string name;
    uint32_t color_rgba = 0;
    uint64_t objects = 0;
  };
  std::vector<Layer> layers;

  // The visibility section (visibility_section.h); present == false when it is empty.
  struct Visibility {
    bool present = false;
    uint64_t bytes = 0;  // the section's size
    uint64_t cells = 0;  // stored (free) cells
    uint64_t solid_cells = 0;
    glm::uvec3 grid_dims{0};
    glm::dvec3 grid_min{0.0};  // package frame, metres
    double cell_size_m = 0.0;
    uint64_t rays_cast = 0;
    uint32_t rays_per_cell = 0;
    uint32_t candidate_level = 0;
    uint64_t candidate_triangles = 0;
    bool visible_sets = false;
    bool parametric_candidates = false;  // kParametricCandidates
    uint64_t occluder_ids = 0, visible_ids = 0;
    double average_occluders = 0.0;  // per stored cell
    double average_visible = 0.0;    // per stored cell (0 without visible sets)
    double average_coverage = 0.0;   // mean fraction of a cell's rays its occluders take
  } visibility;

  // File bytes per level-0 (input) triangle; 0 when there are none.
  double bytesPerInputTriangle() const {
    return total_triangles ? double(file_bytes) / double(total_triangles) : 0.0;
  }
};

// Names of pkg::PrimitiveType values, for output ("cylinder", "cone", ...).
const char* packagePrimitiveTypeName(uint32_t type);

PackageSummary summarizePackage(const PackageView& view);

}  // namespace tw
