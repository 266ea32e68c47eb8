// View cells: a regular grid of cubes over the model's bounds, minus the cells that lie inside
// solid geometry, where no camera stands. Each remaining cell later gets an occluder set.
//
// Inside/outside comes from an OpenVDB voxelization of the candidate surface: the triangles are
// turned into a narrow-band level set (openvdb::tools::meshToVolume), whose sign OpenVDB resolves
// by flooding from outside; voxels it leaves inside, beyond the band, are solid. A cell is
// dropped when every one of a few sample points in it (its centre and the centres of its eight
// octants) is solid. Voxels are cell_size / voxel_divisions, so thin walls never seal a cell
// that has air in it, and the voxelization stays small (its cost is reported).
//
// Pure function over caller-owned buffers; deterministic.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

namespace tw {

struct ViewCellOptions {
  // Edge of a cell, metres. 0: chosen from the bounds so that the grid holds about
  // target_cells cells (rounded to a tidy value), and never below min_cell_size_m.
  double cell_size_m = 0.0;
  // 8192: about 8 m cells over the 10M generated plant (330 x 170 x 60 m), under its 9 m storey
  // height, for ~7 M rays at 1024 rays per cell (docs/occlusion.md, "Preprocessing").
  uint32_t target_cells = 8192;
  double min_cell_size_m = 2.0;
  uint32_t voxel_divisions = 4;  // voxels per cell edge for the inside/outside voxelization
};

struct ViewCellGrid {
  glm::dvec3 min{0.0};  // package frame, metres (the grid covers [min, min + dims * size])
  double cell_size_m = 0.0;
  glm::uvec3 dims{0};
  std::vector<uint32_t> free_cells;  // grid indices x + nx * (y + ny * z), ascending
  uint32_t solid_cells = 0;          // dropped
  double voxel_size_m = 0.0;
  uint64_t active_voxels = 0;        // of the level set (its cost)

  glm::dvec3 cellMin(uint32_t grid_index) const;
  uint32_t cellCount() const { return dims.x * dims.y * dims.z; }
};

// Grid over [bounds_min, bounds_max] (package frame) and the solid classification of the
// triangles (positions in the package frame, three indices per triangle). Throws
// std::invalid_argument for empty or inverted bounds or bad indices.
ViewCellGrid buildViewCells(std::span<const glm::vec3> positions, std::span<const uint32_t> indices,
                            const glm::dvec3& bounds_min, const glm::dvec3& bounds_max,
                            const ViewCellOptions& options);

}  // namespace tw
