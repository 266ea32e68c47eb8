// The package's visibility section: view cells over the model and, per cell, its occluder set
// (the few candidate clusters, ranked, whose surfaces are the first hit for most directions seen
// from inside the cell) and optionally its sampled visible set (every candidate cluster a ray
// from the cell hit first: an aggressive potentially visible set).
//
// Candidates are the mesh clusters of one DAG front (occlusion/dag_front.h): the clusters that
// exist when the groups of `candidate_level` are simplified, a complete crack-free surface at
// that level, and (flag kParametricCandidates) the parametric clusters. The runtime draws a cell's occluders into the occlusion depth buffer, and maps a
// visible set onto whatever cut it draws (occlusion/pvs_mapping.h).
//
// Layout (little-endian, inside the byte section SectionType::Visibility, whose offset in the
// file is a multiple of 8): VisibilityHeader (128 bytes), cell_count VisibilityCellRecord
// (32 bytes each, strictly increasing grid_index), occluder_id_count uint32 cluster ids,
// visible_id_count uint32 cluster ids, then parametric_candidate_count uint32 cluster ids
// (strictly ascending; only with kParametricCandidates). An empty section means "no visibility data" (format 1.0
// packages, or `--visibility off`). Spec: docs/package-format.md, "Visibility".
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <glm/glm.hpp>

namespace tw {

namespace pkg {

inline constexpr char kVisibilityMagic[8] = {'T', 'W', 'V', 'I', 'S', '0', '0', '1'};

enum VisibilityFlags : uint32_t {
  kVisibleSetsPresent = 1u,  // cells carry sampled visible sets
  // Parametric instances took part in the sampling (tessellated coarsely, on their true
  // surfaces): occluder and visible ids may name parametric clusters, and the section ends with
  // the parametric candidate list, the parametric clusters every instance of which took part. A
  // listed cluster absent from a visible set was not seen; any other parametric cluster (none,
  // without the flag) counts as always visible.
  kParametricCandidates = 2u,
};

struct VisibilityHeader {
  char magic[8];               // kVisibilityMagic
  uint32_t header_bytes;       // 128
  uint32_t cell_record_bytes;  // 32
  uint32_t grid_dims[3];       // cells per axis (each >= 1); grid index = x + nx * (y + ny * z)
  uint32_t cell_count;         // stored cells: the free ones (not inside solid geometry)
  double grid_min[3];          // package frame (relative to the package origin), metres
  double cell_size_m;          // cells are cubes of this edge, > 0
  uint64_t occluder_id_count;  // uint32 entries after the cell records
  uint64_t visible_id_count;   // uint32 entries after the occluder ids
  uint64_t rays_cast;          // total over all cells
  uint32_t rays_per_cell;
  uint32_t candidate_level;    // DAG front level of the candidate clusters
  uint32_t solid_cells;        // grid cells dropped as inside solid geometry
  uint32_t flags;              // VisibilityFlags; unknown bits are rejected
  uint64_t candidate_triangles;  // triangles of the candidate front
  uint64_t parametric_candidate_count;  // uint32 entries after the visible ids (flag bit 1)
  uint64_t reserved;           // 0
};
static_assert(sizeof(VisibilityHeader) == 128);

struct VisibilityCellRecord {
  uint32_t grid_index;
  uint32_t first_occluder;     // into the occluder ids
  uint32_t occluder_count;
  uint32_t first_visible;      // into the visible ids (0 / 0 when no visible sets)
  uint32_t visible_count;
  float occluder_coverage;     // fraction of the cell's rays whose first hit is in its occluders
  float hit_fraction;          // fraction of the cell's rays that hit any candidate
  uint32_t reserved;           // 0
};
static_assert(sizeof(VisibilityCellRecord) == 32);

}  // namespace pkg

// One stored cell, for building a section.
struct VisibilityCell {
  uint32_t grid_index = 0;
  std::vector<uint32_t> occluders;  // candidate cluster ids, most covering first
  std::vector<uint32_t> visible;    // candidate cluster ids, ascending (empty without visible sets)
  float occluder_coverage = 0.0f;
  float hit_fraction = 0.0f;
};

struct VisibilityData {
  glm::uvec3 grid_dims{0};
  glm::dvec3 grid_min{0.0};
  double cell_size_m = 0.0;
  uint32_t rays_per_cell = 0;
  uint32_t candidate_level = 0;
  uint64_t candidate_triangles = 0;
  uint64_t rays_cast = 0;
  uint32_t solid_cells = 0;
  bool visible_sets = false;
  bool parametric_occluders = false;       // kParametricCandidates
  std::vector<uint32_t> parametric_candidates;  // strictly ascending; only with the flag
  std::vector<VisibilityCell> cells;  // strictly increasing grid_index
};

// Serializes `data`. Throws std::invalid_argument when it breaks the layout's rules (cells not
// strictly increasing or outside the grid, a zero dimension, a non-positive cell size, visible
// ids without visible_sets, counts past uint32).
std::vector<uint8_t> encodeVisibility(const VisibilityData& data);

// A validated, zero-copy view of a visibility section. Spans point into the bytes given to parse,
// which must outlive the view.
class VisibilityView {
 public:
  VisibilityView() = default;  // empty: no visibility data

  // Validates every field, count and id (ids < cluster_count) before anything is used. An empty
  // span gives an empty view. Throws FormatError::atByte(file_name, section_offset + offset,
  // reason) on any inconsistency, truncation or unknown flag; never reads out of bounds.
  static VisibilityView parse(std::span<const uint8_t> bytes, const std::string& file_name,
                              uint64_t section_offset, uint64_t cluster_count);

  bool empty() const { return header_ == nullptr; }
  const pkg::VisibilityHeader& header() const { return *header_; }  // not when empty()
  std::span<const pkg::VisibilityCellRecord> cells() const { return cells_; }
  // The grid cell containing `p` (package frame), clamped to nothing: std::nullopt-like
  // UINT32_MAX when p lies outside the grid.
  uint32_t gridIndexAt(const glm::dvec3& p) const;
  // The stored cell with that grid index, or nullptr (solid cell, outside, or empty view).
  const pkg::VisibilityCellRecord* cell(uint32_t grid_index) const;
  const pkg::VisibilityCellRecord* cellAt(const glm::dvec3& p) const { return cell(gridIndexAt(p)); }
  std::span<const uint32_t> occluders(const pkg::VisibilityCellRecord& cell) const;
  std::span<const uint32_t> visible(const pkg::VisibilityCellRecord& cell) const;
  // The parametric clusters whose every instance was sampled (empty without the flag).
  std::span<const uint32_t> parametricCandidates() const { return parametric_candidate_ids_; }
  // Average occluder set size over stored cells (0 when none).
  double averageOccluders() const;

 private:
  const pkg::VisibilityHeader* header_ = nullptr;
  std::span<const pkg::VisibilityCellRecord> cells_;
  std::span<const uint32_t> occluder_ids_;
  std::span<const uint32_t> visible_ids_;
  std::span<const uint32_t> parametric_candidate_ids_;
};

}  // namespace tw
