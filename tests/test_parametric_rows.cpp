// Rows (box_rows.h) on llvmpipe: a deck's plates along a frame line drawn as one box, a frame
// line of thin beams as one band, the member per fragment, each drawing the frame its members
// drawn one by one draw; and a row close enough to be drawn member by member culled member by
// member. The rows themselves (which instances join, and where they break) are in
// test_box_rows.cpp.
#include <gtest/gtest.h>

#include <algorithm>
#include <span>

#include "parametric_render_support.h"
#include "section_planes.h"

namespace tw {
namespace {

using namespace parametric_test;

// The pixels that `alone` (members drawn one by one) covers, and those where `rows` differs from
// it by id or colour; each of the latter must show an object that `alone` shows within a pixel.
struct Differences {
  uint64_t shown = 0, differ = 0;
};
Differences differencesWithinAPixel(const Frame& rows, const Frame& alone) {
  Differences d;
  for (int y = 0; y < kHeight; ++y)
    for (int x = 0; x < kWidth; ++x) {
      const size_t p = size_t(y) * kWidth + size_t(x);
      d.shown += alone.ids[p] != 0u;
      if (rows.ids[p] == alone.ids[p] &&
          std::equal(&rows.rgba[4 * p], &rows.rgba[4 * p] + 4, &alone.rgba[4 * p]))
        continue;
      ++d.differ;
      bool near = false;
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int nx = x + dx, ny = y + dy;
          if (nx >= 0 && ny >= 0 && nx < kWidth && ny < kHeight)
            near = near || alone.ids[size_t(ny) * kWidth + size_t(nx)] == rows.ids[p];
        }
      EXPECT_TRUE(near) << "pixel " << x << ", " << y;
    }
  return d;
}

// Rows of boxes (box_rows.h): a deck of twelve plates in three rows of four, each plate its own
// colour, in clusters of five so that rows run across clusters. Drawn as rows (one box each,
// the plate per fragment) the frame is the one its plates drawn one by one give: from above,
// from below, from afar and with the first plates out of view, with occlusion culling and without.
TEST_F(ParametricRendering, RowsOfBoxesDrawTheFrameTheirBoxesDraw) {
  std::vector<Part> parts;
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 4; ++x)
      parts.push_back({uint32_t(1 + y * 4 + x), Box{glm::vec3(4.0f, 3.5f, 0.075f)},
                       placed({4.0 + 8.0 * x, 3.5 + 7.0 * y, -0.075}),
                       0xff000000u | (0x1f2b3du * uint32_t(1 + y * 4 + x))});
  const fs::path package = buildPackage("deck_rows", parts, false, {}, 5);
  for (const Camera& camera : {lookingAt({-8.0, -9.0, 9.0}, {16.0, 10.5, 0.0}),
                               lookingAt({40.0, 30.0, -7.0}, {16.0, 10.5, 0.0}),
                               lookingAt({-100.0, -80.0, 60.0}, {16.0, 10.5, 0.0}),
                               lookingAt({22.0, 10.5, 5.0}, {40.0, 10.5, 0.0})})
  for (OcclusionMode occlusion : {OcclusionMode::Off, OcclusionMode::Hzb}) {
    const Frame rows = render(package, camera, ParametricMode::Tessellated, occlusion, nullptr,
                              false, 0.25, 0.0, 32, 8192, true, true);
    const Frame boxes = render(package, camera, ParametricMode::Tessellated, occlusion, nullptr,
                               false, 0.25, 0.0, 32, 8192, true, false);
    // A row drawn counts all its members, in view or not.
    EXPECT_GE(rows.stats.parametric_instances_drawn, boxes.stats.parametric_instances_drawn);
    EXPECT_LT(rows.stats.parametric_triangles, boxes.stats.parametric_triangles);
    // Pixels may differ only where two plates meet (a pixel centre on their shared edge goes to
    // one triangle or the other): each such pixel shows a plate that the other frame shows
    // within a pixel of it.
    const auto [shown, differ] = differencesWithinAPixel(rows, boxes);
    EXPECT_GT(shown, 200u);
    EXPECT_LE(differ * 500, shown) << differ << " of " << shown << " pixels shown differ";
  }
  // So far away that a row is under a pixel across but longer than one (a ribbon) and its plates
  // under a pixel every way (points): a row is one band, two triangles, where its plates drawn
  // one by one are four points; the band shows a plate of its row where the points do, within a
  // pixel (fewer pixels: a band under a pixel wide covers the pixel centres it crosses, where a
  // point always lights one).
  Camera far_away = lookingAt({-1000.0, -900.0, 600.0}, {16.0, 10.5, 0.0});
  far_away.far_m = 5000.0;
  const Frame rows = render(package, far_away, ParametricMode::Tessellated, OcclusionMode::Off,
                            nullptr, false, 0.25, 0.0, 32, 8192, true, true);
  const Frame boxes = render(package, far_away, ParametricMode::Tessellated, OcclusionMode::Off,
                             nullptr, false, 0.25, 0.0, 32, 8192, true, false);
  EXPECT_EQ(rows.stats.parametric_instances_drawn, 12u);
  EXPECT_EQ(rows.stats.parametric_thin_instances, 12u);
  EXPECT_EQ(boxes.stats.parametric_thin_instances, 12u);
  EXPECT_EQ(rows.stats.parametric_triangles, 6u);
  EXPECT_EQ(boxes.stats.parametric_triangles, 0u);
  uint64_t shown_rows = 0, shown_boxes = 0;
  for (int y = 0; y < kHeight; ++y)
    for (int x = 0; x < kWidth; ++x) {
      const uint32_t id = rows.ids[size_t(y) * kWidth + size_t(x)];
      shown_boxes += boxes.ids[size_t(y) * kWidth + size_t(x)] != 0u;
      if (id == 0u) continue;
      ++shown_rows;
      const uint32_t row = (id - 1) / 4;  // objects 1-4, 5-8, 9-12
      bool near = false;
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int nx = x + dx, ny = y + dy;
          if (nx < 0 || ny < 0 || nx >= kWidth || ny >= kHeight) continue;
          const uint32_t other = boxes.ids[size_t(ny) * kWidth + size_t(nx)];
          near = near || (other != 0u && (other - 1) / 4 == row);
        }
      EXPECT_TRUE(near) << "pixel " << x << ", " << y << " shows object " << id;
    }
  EXPECT_GT(shown_boxes, 3u);
  EXPECT_GT(shown_rows, 0u);
}

// Tall boxes along a line cut open by a section (section_planes.h), drawn as a row and one by
// one: the cut boxes show their insides in the section colour, and the same boxes placed
// mirrored (their frames reflected, the same solids) draw the very same frame; their triangles
// are turned so that their back faces are the insides.
TEST_F(ParametricRendering, BoxesCutByASectionShowTheirInsidesMirroredOrNot) {
  auto lineOfBoxes = [](bool mirrored) {
    std::vector<Part> parts;
    for (int x = 0; x < 4; ++x) {
      Transform t = placed({4.0 + 8.0 * x, 0.0, 1.5});
      if (mirrored) t.linear = glm::mat3(glm::vec3(-1, 0, 0), glm::vec3(0, 1, 0), glm::vec3(0, 0, 1));
      parts.push_back({uint32_t(1 + x), Box{glm::vec3(4.0f, 2.0f, 1.5f)}, t,
                       0xff000000u | (0x1f2b3du * uint32_t(1 + x))});
    }
    return parts;
  };
  const Camera camera = lookingAt({-6.0, -14.0, 10.0}, {16.0, 0.0, 1.5});
  const SectionPlane cut{{16.0, 0.0, 0.0}, {0.0, -1.0, 0.0}};  // the half toward the eye goes
  auto renderCut = [&](const char* name, bool mirrored, bool rows) {
    const fs::path package = buildPackage(name, lineOfBoxes(mirrored), false, {}, 8);
    Walkthrough* walk = nullptr;
    const Frame whole = render(package, camera, ParametricMode::Tessellated, OcclusionMode::Off,
                               &walk, false, 0.25, 0.0, 32, 8192, true, rows);
    EXPECT_GT(whole.stats.parametric_triangles, 0u);
    walk->setSections(std::span<const SectionPlane>(&cut, 1));
    walk->renderFrame(camera, 0.0);
    Frame frame;
    walk->renderer().readObjectIds(frame.ids);
    walk->renderer().readColor(frame.rgba);
    return frame;
  };
  for (bool rows : {true, false}) {
    SCOPED_TRACE(rows ? "as a row" : "one by one");
    const Frame plain = renderCut("boxes_cut", false, rows);
    const Frame mirrored = renderCut("boxes_cut_mirrored", true, rows);
    uint64_t caps = 0, shown = 0, differ = 0;
    for (size_t p = 0; p < plain.ids.size(); ++p) {
      const uint8_t* c = &plain.rgba[4 * p];
      shown += plain.ids[p] != 0u;
      caps += plain.ids[p] != 0u && c[0] == 199 && c[1] == 56 && c[2] == 46;
      differ += plain.ids[p] != mirrored.ids[p] || !std::equal(c, c + 4, &mirrored.rgba[4 * p]);
    }
    EXPECT_GT(shown, 1000u);
    EXPECT_GT(caps, 200u) << "the insides of the cut boxes, in the section colour";
    EXPECT_LT(caps, shown) << "their outsides shaded";
    EXPECT_LE(differ * 500, shown) << differ << " of " << shown << " pixels differ when mirrored";
  }
}

// A frame line: four I-beams of 8 m end to end along X (objects 1 to 4, colours of their own).
std::vector<Part> frameLineOfBeams() {
  const std::vector<glm::vec2> beam = smallIBeam();
  std::vector<Part> parts;
  for (int k = 0; k < 4; ++k) {
    Transform t = placed({8.0 * k, 0.0, 0.0});
    // The extrusion axis (local Z) along world X, the web (local Y) up.
    t.linear = glm::mat3(glm::vec3(0, 1, 0), glm::vec3(0, 0, 1), glm::vec3(1, 0, 0));
    parts.push_back({uint32_t(1 + k), Extrusion{beam, 8.0f}, t, 0xff000000u | (0x2f4b1du * uint32_t(1 + k))});
  }
  return parts;
}

// A frame line of I-beams end to end, each its own object and colour: from afar, thin across, the
// line is one band whose fragments tell the beam they fall on, where each beam on its own is a
// band of its own; close by, where the beams are not thin, each is drawn as without rows.
TEST_F(ParametricRendering, RowsOfThinBeamsDrawAsOneBand) {
  const fs::path package = buildPackage("beam_rows", frameLineOfBeams(), false, {}, 2);
  // Slanted across the pixel rows: a band under a pixel wide lit where it crosses their centres.
  const Camera far_away = lookingAt({-10.0, -80.0, 28.8}, {16.0, 0.0, 2.0});
  const Frame rows = render(package, far_away, ParametricMode::Tessellated, OcclusionMode::Off,
                            nullptr, false, 0.25, 0.0, 32, 8192, true, true);
  const Frame beams = render(package, far_away, ParametricMode::Tessellated, OcclusionMode::Off,
                             nullptr, false, 0.25, 0.0, 32, 8192, true, false);
  EXPECT_EQ(beams.stats.parametric_thin_instances, 4u);
  EXPECT_EQ(rows.stats.parametric_thin_instances, 4u);
  EXPECT_EQ(beams.stats.parametric_triangles, 8u);
  EXPECT_EQ(rows.stats.parametric_triangles, 2u);
  const auto [shown, differ] = differencesWithinAPixel(rows, beams);
  EXPECT_GT(shown, 20u);
  EXPECT_LE(differ * 5, shown) << differ << " of " << shown << " pixels shown differ";
  // Close by the beams are their profiles or boxes, drawn one by one either way.
  const Camera close = lookingAt({-10.0, -20.0, 7.2}, {16.0, 0.0, 2.0});
  const Frame rows_close = render(package, close, ParametricMode::Tessellated, OcclusionMode::Off,
                                  nullptr, false, 0.25, 0.0, 32, 8192, true, true);
  const Frame beams_close = render(package, close, ParametricMode::Tessellated, OcclusionMode::Off,
                                   nullptr, false, 0.25, 0.0, 32, 8192, true, false);
  EXPECT_EQ(rows_close.stats.parametric_thin_instances, 0u);
  EXPECT_EQ(rows_close.stats.parametric_instances_drawn, beams_close.stats.parametric_instances_drawn);
  EXPECT_EQ(rows_close.stats.parametric_triangles, beams_close.stats.parametric_triangles);
  EXPECT_EQ(rows_close.ids, beams_close.ids);
  EXPECT_EQ(rows_close.rgba, beams_close.rgba);
}

// The same frame line close by, where its beams are drawn one by one: they are culled one by one
// too, by the frustum and behind a wall by the pyramid, as without rows (a row tested as one box
// would draw every beam whenever any part of it shows).
TEST_F(ParametricRendering, RowsDrawnBeamByBeamAreCulledBeamByBeam) {
  std::vector<Part> parts = frameLineOfBeams();
  // A wall before the first two beams, seen from (16, -20, 1).
  parts.push_back({5u, Box{glm::vec3(8.5f, 0.1f, 3.0f)}, placed({8.0, -5.0, 0.0}), 0xff808080u});
  // One cluster holds them all: its box shows, so each beam must be tested on its own.
  const fs::path package = buildPackage("beam_rows_culled", parts, false);
  for (OcclusionMode occlusion : {OcclusionMode::Off, OcclusionMode::Hzb}) {
    // Beside the last beam, the first two out of view.
    const Camera beside = lookingAt({28.0, -6.0, 1.0}, {28.0, 0.0, 0.1});
    const Frame rows = render(package, beside, ParametricMode::Tessellated, occlusion, nullptr,
                              false, 0.25, 0.0, 32, 8192, true, true);
    const Frame beams = render(package, beside, ParametricMode::Tessellated, occlusion, nullptr,
                               false, 0.25, 0.0, 32, 8192, true, false);
    EXPECT_LE(beams.stats.parametric_instances_drawn, 3u);  // beams 3 and 4, and the wall
    EXPECT_EQ(rows.stats.parametric_instances_drawn, beams.stats.parametric_instances_drawn);
    EXPECT_EQ(rows.stats.parametric_triangles, beams.stats.parametric_triangles);
    EXPECT_EQ(rows.ids, beams.ids);
    EXPECT_EQ(rows.rgba, beams.rgba);
  }
  const Camera facing = lookingAt({16.0, -20.0, 1.0}, {16.0, 0.0, 0.1});
  const Frame rows = render(package, facing, ParametricMode::Tessellated, OcclusionMode::Hzb,
                            nullptr, false, 0.25, 0.0, 32, 8192, true, true);
  const Frame beams = render(package, facing, ParametricMode::Tessellated, OcclusionMode::Hzb,
                             nullptr, false, 0.25, 0.0, 32, 8192, true, false);
  const Frame open = render(package, facing, ParametricMode::Tessellated, OcclusionMode::Off,
                            nullptr, false, 0.25, 0.0, 32, 8192, true, true);
  EXPECT_EQ(open.stats.parametric_instances_drawn, 5u);
  EXPECT_LE(beams.stats.parametric_instances_drawn, 3u);  // beams 1 and 2 behind the wall
  EXPECT_EQ(rows.stats.parametric_instances_drawn, beams.stats.parametric_instances_drawn);
  EXPECT_EQ(rows.stats.parametric_triangles, beams.stats.parametric_triangles);
  EXPECT_EQ(rows.ids, beams.ids);
  EXPECT_EQ(rows.rgba, beams.rgba);
  uint64_t wall = 0;
  for (uint32_t id : rows.ids) wall += id == 5u;
  EXPECT_GT(wall, 1000u);
}

}  // namespace
}  // namespace tw
