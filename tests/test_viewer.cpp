// The viewer (`terawalk view`) as a person sees it: a real X server (Xvfb), the viewer's window on
// it, and the X screen itself read back and checked, not the renderer's own buffer.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <string>
#include <thread>

#include <nlohmann/json.hpp>

#include "camera.h"
#include "image_compare.h"
#include "package_view.h"
#include "generated_plant_support.h"
#include "test_support.h"
#include "x_screen_support.h"

namespace tw {
namespace {

std::filesystem::path bunnyPackage() {
  static const std::filesystem::path path = [] {
    auto out = test::processScratchDir("viewer_bunny") / "bunny.twk";
    test::CommandResult r = test::runTerawalk(
        "preprocess --quiet " + (test::sharedDataDir() / "stanford-bunny.obj").string() + " -o " +
        out.string());
    EXPECT_EQ(r.exit_code, 0) << r.output;
    return out;
  }();
  return path;
}

bool haveXvfb() { return std::system("command -v Xvfb > /dev/null 2>&1") == 0; }

// ImGui's dark window background over the model, and its white text: the panel.
bool isPanelBackground(const uint8_t* p) {
  return p[0] < 48 && p[1] < 48 && p[2] < 48 && std::abs(int(p[0]) - int(p[2])) < 12;
}
bool isText(const uint8_t* p) { return p[0] > 200 && p[1] > 200 && p[2] > 200; }

struct PanelCount {
  int dark = 0, text = 0, total = 0;
};

// In the rectangle where the panel opens (ImGui puts it at 8, 8).
template <typename Image>
PanelCount countPanelPixels(const Image& image, int x0, int y0, int x1, int y1) {
  PanelCount count;
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x) {
      const uint8_t* p = &image.rgba[(size_t(y) * image.width + x) * 4];
      count.dark += isPanelBackground(p);
      count.text += isText(p);
      ++count.total;
    }
  return count;
}

bool showsPanel(const PanelCount& c) { return c.dark * 2 > c.total && c.text > 20; }

// Whether the whole window is on the screen file: X draws and clears it top down (the window
// appearing, or the root's black coming back when it closes), so a capture taken meanwhile has
// black rows at the bottom of the window.
bool windowDrawn(const test::ScreenImage& screen, int width, int height) {
  if (screen.width < width || screen.height < height) return false;
  for (int x = 0; x < width; ++x) {
    const uint8_t* p = screen.at(x, height - 1);
    if (p[0] == 0 && p[1] == 0 && p[2] == 0) return false;
  }
  return true;
}

// The window on the X screen shows the model and, on top of it, the statistics panel; the
// renderer's own buffer (--screenshot) holds the model alone. The capture is kept as x-screen.png.
TEST(Viewer, TheXScreenShowsTheModelAndThePanel) {
  if (!haveXvfb()) GTEST_SKIP() << "no Xvfb";
  if (!std::filesystem::exists(test::sharedDataDir() / "stanford-bunny.obj"))
    GTEST_SKIP() << "shared data not present";
  const auto package = bunnyPackage();
  const auto dir = test::scratchDir();
  test::XvfbScreen screen(dir / "x", 1024, 768);
  const auto shot = dir / "renderer.png";
  test::BackgroundProcess view({TW_TERAWALK_EXE, "view", package.string(), "--size", "800x600",
                                "--frames", "120", "--screenshot", shot.string()},
                               {"DISPLAY=" + screen.display()}, dir / "view.log");
  // Captures while the window is up; the last one that shows the panel is the one checked.
  std::optional<test::ScreenImage> seen;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
  while (view.running() && std::chrono::steady_clock::now() < deadline) {
    auto capture = screen.capture();
    if (capture && windowDrawn(*capture, 800, 600) &&
        showsPanel(countPanelPixels(*capture, 12, 40, 200, 90)))
      seen = std::move(capture);
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  ASSERT_EQ(view.wait(), 0) << test::readFile(dir / "view.log");
  ASSERT_TRUE(seen) << "no capture of the X screen showed the panel; " << test::readFile(dir / "view.log");
  writePngRgba(dir / "x-screen.png", seen->width, seen->height, seen->rgba);

  // The renderer's buffer: the model, no panel.
  const RgbaImage model = readPngRgba(shot);
  ASSERT_EQ(model.width, 800);
  ASSERT_EQ(model.height, 600);
  EXPECT_FALSE(showsPanel(countPanelPixels(model, 12, 40, 200, 90)));
  // Right of and below the panel, the window's pixels are the renderer's (the window sits at 0, 0).
  int same = 0, total = 0, covered = 0;
  for (int y = 400; y < 600; ++y)
    for (int x = 520; x < 800; ++x) {
      const uint8_t* a = seen->at(x, y);
      const uint8_t* b = &model.rgba[(size_t(y) * model.width + x) * 4];
      same += a[0] == b[0] && a[1] == b[1] && a[2] == b[2];
      ++total;
    }
  for (int y = 0; y < 600; ++y)
    for (int x = 0; x < 800; ++x) {
      const uint8_t* b = &model.rgba[(size_t(y) * model.width + x) * 4];
      // Not the background (0.72, 0.80, 0.90).
      covered += std::abs(b[0] - 184) > 3 || std::abs(b[1] - 204) > 3 || std::abs(b[2] - 230) > 3;
    }
  EXPECT_GT(same, total * 99 / 100) << same << " of " << total;
  EXPECT_GT(covered, 800 * 600 / 20) << "the bunny should cover some of the frame";
}


// Pixels in a box around (cx, cy) that came clearly closer to the selection tint (orange,
// gl_shaders.h kSelectedTint) from `before` to `after`.
int tintedPixels(const test::ScreenImage& before, const test::ScreenImage& after, int cx, int cy,
                 int half) {
  const int tint[3] = {255, 140, 13};
  auto distance = [&](const uint8_t* p) {
    return std::abs(p[0] - tint[0]) + std::abs(p[1] - tint[1]) + std::abs(p[2] - tint[2]);
  };
  int n = 0;
  for (int y = cy - half; y < cy + half; ++y)
    for (int x = cx - half; x < cx + half; ++x)
      n += distance(after.at(x, y)) + 60 < distance(before.at(x, y));
  return n;
}

// Clicking a valve, as a script of the viewer does at frame 30: the X screen shows the valve
// tinted and the properties panel grown by its record, and the viewer names the valve and its
// record. The capture is kept as x-screen-pick.png.
TEST(Viewer, ClickingAValveSelectsItAndShowsItsRecord) {
  if (!haveXvfb()) GTEST_SKIP() << "no Xvfb";
  const auto dir = test::scratchDir();
  const PackageView view = PackageView::open(test::generatedPlant().package);
  // A valve seen from just above: the first whose centre pixel `pick` says is that valve.
  std::string key;
  Camera camera;
  for (uint32_t o = 0; o < view.objects().size() && key.empty(); ++o) {
    if (view.layerName(view.objects()[o].layer) != "valves") continue;
    const pkg::ObjectRecord& r = view.objects()[o];
    const glm::dvec3 centre =
        view.origin() + 0.5 * (glm::dvec3(r.aabb_min[0], r.aabb_min[1], r.aabb_min[2]) +
                               glm::dvec3(r.aabb_max[0], r.aabb_max[1], r.aabb_max[2]));
    camera.position = centre + glm::dvec3(0.6, 0.5, 1.4);
    camera.lookAt(centre);
    test::CommandResult picked = test::runTerawalk(
        "pick " + test::generatedPlant().package.string() + " --eye " +
        test::vec3Arg(camera.position) + " --target " + test::vec3Arg(centre) +
        " --size 800x600 --pixel 400,300 --json");
    ASSERT_EQ(picked.exit_code, 0) << picked.output;
    const auto j = nlohmann::json::parse(picked.output);
    if (!j["object"].is_null() && j["object"] == o) key = std::string(view.objectDbKey(o));
  }
  ASSERT_FALSE(key.empty()) << "no valve could be seen from above";
  char line[256];
  std::snprintf(line, sizeof line, "0 %.9f %.9f %.9f %.9f %.9f 60\n", camera.position.x,
                camera.position.y, camera.position.z, glm::degrees(camera.yaw_rad),
                glm::degrees(camera.pitch_rad));
  test::writeFile(dir / "valve.path", std::string("# terawalk camera path 1\n") + line);
  test::writeFile(dir / "click.script", "30 click 400 300\n150 quit\n");

  test::XvfbScreen screen(dir / "x", 1024, 768);
  test::BackgroundProcess viewer(
      {TW_TERAWALK_EXE, "view", test::generatedPlant().package.string(), "--size", "800x600", "--path",
       (dir / "valve.path").string(), "--db", test::generatedPlant().db.string(), "--script",
       (dir / "click.script").string()},
      {"DISPLAY=" + screen.display()}, dir / "view.log");
  std::optional<test::ScreenImage> before, after;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
  while (viewer.running() && std::chrono::steady_clock::now() < deadline) {
    const bool picked = test::readFile(dir / "view.log").find("view: picked") != std::string::npos;
    auto capture = screen.capture();
    if (capture && windowDrawn(*capture, 800, 600) &&
        showsPanel(countPanelPixels(*capture, 12, 40, 200, 90)))
      (picked ? after : before) = std::move(capture);
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  const std::string log = test::readFile(dir / "view.log");
  ASSERT_EQ(viewer.wait(), 0) << log;
  EXPECT_NE(log.find("key " + key + " at"), std::string::npos) << log;
  EXPECT_NE(log.find("record found"), std::string::npos) << log;
  ASSERT_TRUE(before && after) << log;
  // The window's part of the screen, for docs/images/viewer-pick.png.
  std::vector<uint8_t> window(800 * 600 * 4);
  for (int y = 0; y < 600; ++y)
    std::copy_n(after->at(0, y), 800 * 4, &window[size_t(y) * 800 * 4]);
  writePngRgba(dir / "x-screen-pick.png", 800, 600, window);
  writePngRgba(dir / "x-screen-before.png", before->width, before->height, before->rgba);
  // The valve, tinted, at the centre.
  EXPECT_GT(tintedPixels(*before, *after, 400, 300, 60), 100);
  EXPECT_EQ(tintedPixels(*before, *after, 700, 500, 60), 0);  // elsewhere nothing changed
  // The properties panel at the top right has grown by the record's lines (right of the
  // statistics panel, where the model showed before), down to its help line.
  const PanelCount grown_after = countPanelPixels(*after, 530, 90, 790, 280);
  const PanelCount grown_before = countPanelPixels(*before, 530, 90, 790, 280);
  EXPECT_GT(grown_after.dark * 2, grown_after.total) << grown_after.dark;
  EXPECT_LT(grown_before.dark * 2, grown_before.total) << grown_before.dark;
  EXPECT_GT(countPanelPixels(*after, 530, 276, 790, 292).text, 20);
}

}  // namespace
}  // namespace tw
