// View cells: the grid over the model and the OpenVDB inside/outside test that drops solid
// cells. The only OpenVDB translation unit of occlusion/ (it costs ~12 s and ~1 GB to compile).
// See view_cells.h.
#include "view_cells.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <mutex>
#include <stdexcept>
#include <string>

#include <openvdb/openvdb.h>
#include <openvdb/tools/MeshToVolume.h>

namespace tw {
namespace {

// The grid is a dense index space (uint32 grid indices, one record per free cell): beyond this
// many cells an explicit --view-cell-size is a mistake, not a request.
constexpr uint64_t kMaxGridCells = 1ull << 24;

// Narrow band half-widths in voxels. Two is OpenVDB's minimum for a well-formed level set and
// skips its band dilation pass (only wider bands are dilated), which is most of the cost. The
// sign is resolved for the whole grid anyway: tiles beyond the band take the sign of the band
// next to them.
constexpr float kBandVoxels = 2.0f;

void initializeOpenVdb() {
  static std::once_flag once;
  std::call_once(once, [] { openvdb::initialize(); });
}

// 1, 1.25, 1.5, 2, 2.5, 3, 4, 5, 6, 8 times a power of ten: sizes people can read in a report.
double tidySize(double size_m) {
  static constexpr std::array<double, 11> kSteps = {1.0, 1.25, 1.5, 2.0, 2.5, 3.0,
                                                    4.0, 5.0,  6.0, 8.0, 10.0};
  const double decade = std::pow(10.0, std::floor(std::log10(size_m)));
  const double mantissa = size_m / decade;
  double best = kSteps[0];
  for (double step : kSteps)  // nearest in log scale
    if (std::abs(std::log(step / mantissa)) < std::abs(std::log(best / mantissa))) best = step;
  return best * decade;
}

// The edge that gives about `target` cells over `extent`: the cube root of volume / target, where
// an axis thinner than one cell still counts one cell (a flat model is one layer thick). A few
// fixed-point steps settle which axes are thin.
double autoCellSize(const glm::dvec3& extent, uint32_t target) {
  const double cells = std::max<double>(target, 1.0);
  const double longest = std::max({extent.x, extent.y, extent.z});
  if (!(longest > 0.0)) return 0.0;
  double size = longest / std::cbrt(cells);
  for (int i = 0; i < 8; ++i) {
    const double volume = std::max(extent.x, size) * std::max(extent.y, size) *
                          std::max(extent.z, size);
    size = std::cbrt(volume / cells);
  }
  return size;
}

void validateInput(std::span<const glm::vec3> positions, std::span<const uint32_t> indices,
                   const glm::dvec3& bounds_min, const glm::dvec3& bounds_max) {
  for (int a = 0; a < 3; ++a)
    if (!std::isfinite(bounds_min[a]) || !std::isfinite(bounds_max[a]) ||
        bounds_max[a] < bounds_min[a])
      throw std::invalid_argument("buildViewCells: empty, inverted or non-finite bounds");
  if (indices.size() % 3 != 0)
    throw std::invalid_argument("buildViewCells: index count " + std::to_string(indices.size()) +
                                " is not a multiple of 3");
  for (uint32_t i : indices)
    if (i >= positions.size())
      throw std::invalid_argument("buildViewCells: index " + std::to_string(i) +
                                  " out of range (" + std::to_string(positions.size()) +
                                  " positions)");
  for (const glm::vec3& p : positions)
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
      throw std::invalid_argument("buildViewCells: non-finite position");
}

// Signed distance (narrow band) of the triangles on a grid of `voxel_m` whose voxel (0, 0, 0) is
// centred on `grid_min`: with voxel_divisions 4 the cell samples fall on voxel centres.
openvdb::FloatGrid::Ptr levelSet(std::span<const glm::vec3> positions,
                                 std::span<const uint32_t> indices, const glm::dvec3& grid_min,
                                 double voxel_m) {
  initializeOpenVdb();
  auto transform = openvdb::math::Transform::createLinearTransform(voxel_m);
  transform->postTranslate(openvdb::Vec3d(grid_min.x, grid_min.y, grid_min.z));
  // meshToVolume takes points in index space.
  std::vector<openvdb::Vec3s> points(positions.size());
  for (size_t v = 0; v < positions.size(); ++v) {
    const glm::dvec3 p = (glm::dvec3(positions[v]) - grid_min) / voxel_m;
    points[v] = openvdb::Vec3s(float(p.x), float(p.y), float(p.z));
  }
  std::vector<openvdb::Vec3I> triangles(indices.size() / 3);
  for (size_t t = 0; t < triangles.size(); ++t)
    triangles[t] = openvdb::Vec3I(indices[3 * t], indices[3 * t + 1], indices[3 * t + 2]);
  openvdb::tools::QuadAndTriangleDataAdapter<openvdb::Vec3s, openvdb::Vec3I> mesh(
      points.data(), points.size(), triangles.data(), triangles.size());
  // Signed: OpenVDB sweeps the exterior in from the bounds along each axis up to the surface,
  // floods it through the band, and gives every tile beyond the band the sign of its neighbours.
  return openvdb::tools::meshToVolume<openvdb::FloatGrid>(mesh, *transform, kBandVoxels,
                                                          kBandVoxels, 0);
}

}  // namespace

glm::dvec3 ViewCellGrid::cellMin(uint32_t grid_index) const {
  const uint32_t x = grid_index % dims.x;
  const uint32_t y = (grid_index / dims.x) % dims.y;
  const uint32_t z = grid_index / (dims.x * dims.y);
  return min + glm::dvec3(x, y, z) * cell_size_m;
}

ViewCellGrid buildViewCells(std::span<const glm::vec3> positions, std::span<const uint32_t> indices,
                            const glm::dvec3& bounds_min, const glm::dvec3& bounds_max,
                            const ViewCellOptions& options) {
  validateInput(positions, indices, bounds_min, bounds_max);
  if (!(options.cell_size_m >= 0.0) || !std::isfinite(options.cell_size_m))
    throw std::invalid_argument("buildViewCells: cell size must be finite and >= 0");
  const glm::dvec3 extent = bounds_max - bounds_min;

  ViewCellGrid grid;
  double size = options.cell_size_m;
  if (size == 0.0) {
    size = autoCellSize(extent, options.target_cells);
    size = size > 0.0 ? tidySize(size) : 0.0;
    size = std::max(size, options.min_cell_size_m);
    if (!(size > 0.0)) size = 1.0;  // a point model and no minimum: any size will do
  }
  grid.cell_size_m = size;

  double cells = 1.0;  // in double: three axes of up to 2^24 cells overflow any integer
  for (int a = 0; a < 3; ++a) {
    const double n = std::max(1.0, std::ceil(extent[a] / size - 1e-9));
    cells *= n;
    if (cells > double(kMaxGridCells))
      throw std::invalid_argument("buildViewCells: cell size " + std::to_string(size) +
                                  " m gives more than " + std::to_string(kMaxGridCells) +
                                  " cells");
    grid.dims[a] = uint32_t(n);
  }
  // Centred on the bounds, so the slack of the last cell is shared by both sides.
  grid.min = (bounds_min + bounds_max) * 0.5 - glm::dvec3(grid.dims) * size * 0.5;

  const uint32_t divisions = std::max<uint32_t>(options.voxel_divisions, 1);
  grid.voxel_size_m = size / divisions;
  if (indices.empty()) {
    grid.free_cells.resize(grid.cellCount());
    for (uint32_t i = 0; i < grid.free_cells.size(); ++i) grid.free_cells[i] = i;
    return grid;
  }

  const openvdb::FloatGrid::Ptr sdf = levelSet(positions, indices, grid.min, grid.voxel_size_m);
  grid.active_voxels = sdf->activeVoxelCount();

  // A sample is solid when OpenVDB left it inside and beyond the band: at least kBandVoxels from
  // any surface, so a cell is dropped only when it lies wholly inside (the octant centres are a
  // quarter cell from the faces, within half a cell of the band at the default 4 divisions).
  auto accessor = sdf->getConstAccessor();
  auto solid = [&](const glm::dvec3& p) {
    const glm::dvec3 index = (p - grid.min) / grid.voxel_size_m;
    const openvdb::Coord ijk(int(std::lround(index.x)), int(std::lround(index.y)),
                             int(std::lround(index.z)));
    return !accessor.isValueOn(ijk) && accessor.getValue(ijk) < 0.0f;
  };
  static constexpr double kSamples[2] = {0.25, 0.75};
  for (uint32_t cell = 0; cell < grid.cellCount(); ++cell) {
    const glm::dvec3 lo = grid.cellMin(cell);
    bool all_solid = solid(lo + glm::dvec3(0.5 * size));
    for (int s = 0; s < 8 && all_solid; ++s)
      all_solid = solid(lo + glm::dvec3(kSamples[s & 1], kSamples[(s >> 1) & 1],
                                        kSamples[(s >> 2) & 1]) * size);
    if (all_solid) ++grid.solid_cells;
    else grid.free_cells.push_back(cell);
  }
  return grid;
}

}  // namespace tw
