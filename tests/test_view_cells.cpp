// View cells: the grid's size and placement, and the OpenVDB inside/outside classification on
// hand-made solids: a block inside a room with a doorway (its inside dropped, the room's air
// kept), a sealed box, open geometry (nothing dropped), and bad input.
#include <gtest/gtest.h>

#include <algorithm>
#include <stdexcept>

#include "test_support.h"
#include "view_cells.h"

namespace tw {
namespace {

// One open quad (two triangles).
void addQuad(TriangleMesh& soup, const glm::vec3& a, const glm::vec3& b, const glm::vec3& c,
             const glm::vec3& d) {
  const auto base = uint32_t(soup.positions.size());
  soup.positions.insert(soup.positions.end(), {a, b, c, d});
  soup.indices.insert(soup.indices.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
}

bool isFree(const ViewCellGrid& grid, uint32_t x, uint32_t y, uint32_t z) {
  const uint32_t index = x + grid.dims.x * (y + grid.dims.y * z);
  return std::binary_search(grid.free_cells.begin(), grid.free_cells.end(), index);
}

// A 12 m room (0.5 m walls of closed boxes, a 2 x 3 m doorway in the +x wall) holding a solid
// 6 m block at [3, 9]^3. Cells are 1 m over [-1, 13]^3, so cell i spans [i - 1, i].
TriangleMesh roomWithBlock() {
  TriangleMesh soup;
  test::appendBox(soup, {-0.5f, -0.5f, -0.5f}, {12.5f, 12.5f, 0.0f});   // floor
  test::appendBox(soup, {-0.5f, -0.5f, 12.0f}, {12.5f, 12.5f, 12.5f});  // roof
  test::appendBox(soup, {-0.5f, -0.5f, 0.0f}, {0.0f, 12.5f, 12.0f});    // -x wall
  test::appendBox(soup, {0.0f, -0.5f, 0.0f}, {12.0f, 0.0f, 12.0f});     // -y wall
  test::appendBox(soup, {0.0f, 12.0f, 0.0f}, {12.0f, 12.5f, 12.0f});    // +y wall
  test::appendBox(soup, {12.0f, -0.5f, 0.0f}, {12.5f, 5.0f, 12.0f});    // +x wall, beside the door
  test::appendBox(soup, {12.0f, 7.0f, 0.0f}, {12.5f, 12.5f, 12.0f});
  test::appendBox(soup, {12.0f, 5.0f, 3.0f}, {12.5f, 7.0f, 12.0f});     // over the door
  test::appendBox(soup, {3.0f, 3.0f, 3.0f}, {9.0f, 9.0f, 9.0f});        // the block
  return soup;
}

TEST(ViewCells, BlockInsideIsDroppedRoomAirIsKept) {
  const TriangleMesh soup = roomWithBlock();
  ViewCellOptions options;
  options.cell_size_m = 1.0;
  const ViewCellGrid grid =
      buildViewCells(soup.positions, soup.indices, glm::dvec3(-1.0), glm::dvec3(13.0), options);
  EXPECT_EQ(grid.dims, glm::uvec3(14));
  EXPECT_DOUBLE_EQ(grid.cell_size_m, 1.0);
  EXPECT_EQ(grid.min, glm::dvec3(-1.0));
  EXPECT_DOUBLE_EQ(grid.voxel_size_m, 0.25);
  EXPECT_GT(grid.active_voxels, 0u);
  EXPECT_TRUE(std::is_sorted(grid.free_cells.begin(), grid.free_cells.end()));
  EXPECT_EQ(grid.free_cells.size() + grid.solid_cells, grid.cellCount());

  // Dropped: exactly the cells wholly at least half a cell inside the block, [4, 8]^3 (cell
  // indices 5..8). A cell touching the block's surface keeps air or near-surface samples.
  EXPECT_EQ(grid.solid_cells, 64u);
  for (uint32_t z = 0; z < 14; ++z)
    for (uint32_t y = 0; y < 14; ++y)
      for (uint32_t x = 0; x < 14; ++x) {
        const bool deep = x >= 5 && x <= 8 && y >= 5 && y <= 8 && z >= 5 && z <= 8;
        EXPECT_EQ(isFree(grid, x, y, z), !deep) << x << "," << y << "," << z;
      }
  // The room's air, the walls and the outside all stay.
  EXPECT_TRUE(isFree(grid, 2, 2, 2));
  EXPECT_TRUE(isFree(grid, 11, 11, 11));
  EXPECT_TRUE(isFree(grid, 0, 0, 0));
}

TEST(ViewCells, SealedBoxInteriorIsSolid) {
  // A closed 10 m box: OpenVDB's flood from outside never reaches its inside.
  TriangleMesh soup;
  test::appendBox(soup, glm::vec3(0.0f), glm::vec3(10.0f));
  ViewCellOptions options;
  options.cell_size_m = 1.0;
  const ViewCellGrid grid =
      buildViewCells(soup.positions, soup.indices, glm::dvec3(-2.0), glm::dvec3(12.0), options);
  ASSERT_EQ(grid.dims, glm::uvec3(14));
  // Cells [1, 9]^3 deep enough: indices 3..10 per axis -> 8^3.
  EXPECT_EQ(grid.solid_cells, 512u);
  EXPECT_FALSE(isFree(grid, 7, 7, 7));
  EXPECT_TRUE(isFree(grid, 2, 7, 7));   // [0, 1]: touches the surface
  EXPECT_TRUE(isFree(grid, 0, 0, 0));   // outside
  EXPECT_TRUE(isFree(grid, 13, 7, 7));  // outside
}

TEST(ViewCells, OpenGeometryKeepsEveryCell) {
  // A floor, a wall and an uncapped square duct: nothing encloses any volume.
  TriangleMesh soup;
  addQuad(soup, {0, 0, 0}, {20, 0, 0}, {20, 20, 0}, {0, 20, 0});
  addQuad(soup, {0, 10, 0}, {20, 10, 0}, {20, 10, 8}, {0, 10, 8});
  addQuad(soup, {2, 2, 2}, {2, 6, 2}, {18, 6, 2}, {18, 2, 2});
  addQuad(soup, {2, 2, 6}, {18, 2, 6}, {18, 6, 6}, {2, 6, 6});
  addQuad(soup, {2, 2, 2}, {18, 2, 2}, {18, 2, 6}, {2, 2, 6});
  addQuad(soup, {2, 6, 2}, {2, 6, 6}, {18, 6, 6}, {18, 6, 2});
  ViewCellOptions options;
  options.cell_size_m = 1.0;
  const ViewCellGrid grid =
      buildViewCells(soup.positions, soup.indices, glm::dvec3(0.0), glm::dvec3(20.0, 20.0, 8.0),
                     options);
  EXPECT_EQ(grid.dims, glm::uvec3(20, 20, 8));
  EXPECT_EQ(grid.solid_cells, 0u);
  EXPECT_EQ(grid.free_cells.size(), grid.cellCount());
}

TEST(ViewCells, NoTrianglesKeepsEveryCell) {
  ViewCellOptions options;
  options.cell_size_m = 2.0;
  const ViewCellGrid grid = buildViewCells({}, {}, glm::dvec3(0.0), glm::dvec3(9.0), options);
  EXPECT_EQ(grid.dims, glm::uvec3(5));
  EXPECT_EQ(grid.free_cells.size(), 125u);
  EXPECT_EQ(grid.min, glm::dvec3(-0.5));  // centred: 10 m of cells over 9 m of model
  EXPECT_EQ(grid.cellMin(1 + 5 * (2 + 5 * 3)), glm::dvec3(1.5, 3.5, 5.5));
}

TEST(ViewCells, AutomaticSizeIsTidyAndNearTheTarget) {
  ViewCellOptions options;
  options.target_cells = 4096;
  const ViewCellGrid plant =
      buildViewCells({}, {}, glm::dvec3(0.0), glm::dvec3(330.0, 170.0, 60.0), options);
  const std::vector<double> tidy = {1, 1.25, 1.5, 2, 2.5, 3, 4, 5, 6, 8, 10, 12.5, 15, 20};
  EXPECT_NE(std::find(tidy.begin(), tidy.end(), plant.cell_size_m), tidy.end())
      << plant.cell_size_m;
  EXPECT_GT(plant.cellCount(), 4096u / 2);
  EXPECT_LT(plant.cellCount(), 4096u * 2);

  // A flat model is one cell thick, and the cells over it still number about the target.
  const ViewCellGrid flat =
      buildViewCells({}, {}, glm::dvec3(0.0), glm::dvec3(640.0, 640.0, 0.0), options);
  EXPECT_EQ(flat.dims.z, 1u);
  EXPECT_GT(flat.cellCount(), 4096u / 2);
  EXPECT_LT(flat.cellCount(), 4096u * 2);

  // The default target gives cells under the generated plant's 9 m storeys.
  const ViewCellGrid plant10m =
      buildViewCells({}, {}, glm::dvec3(0.0), glm::dvec3(330.0, 170.0, 60.0), ViewCellOptions{});
  EXPECT_LT(plant10m.cell_size_m, 9.0);

  // A small model: the minimum size wins.
  const ViewCellGrid small =
      buildViewCells({}, {}, glm::dvec3(0.0), glm::dvec3(5.0, 4.0, 3.0), ViewCellOptions{});
  EXPECT_DOUBLE_EQ(small.cell_size_m, 2.0);
  EXPECT_EQ(small.dims, glm::uvec3(3, 2, 2));
}

TEST(ViewCells, RejectsBadInput) {
  TriangleMesh soup;
  test::appendBox(soup, glm::vec3(0.0f), glm::vec3(1.0f));
  ViewCellOptions options;
  EXPECT_THROW(buildViewCells(soup.positions, soup.indices, glm::dvec3(1.0), glm::dvec3(0.0),
                              options),
               std::invalid_argument);
  std::vector<uint32_t> bad = soup.indices;
  bad[4] = 99;
  EXPECT_THROW(buildViewCells(soup.positions, bad, glm::dvec3(0.0), glm::dvec3(1.0), options),
               std::invalid_argument);
  bad.pop_back();
  EXPECT_THROW(buildViewCells(soup.positions, bad, glm::dvec3(0.0), glm::dvec3(1.0), options),
               std::invalid_argument);
  options.cell_size_m = 0.001;  // 10^12 cells over a kilometre
  EXPECT_THROW(buildViewCells({}, {}, glm::dvec3(0.0), glm::dvec3(1000.0), options),
               std::invalid_argument);
  options.cell_size_m = -1.0;
  EXPECT_THROW(buildViewCells({}, {}, glm::dvec3(0.0), glm::dvec3(1.0), options),
               std::invalid_argument);
}

}  // namespace
}  // namespace tw
