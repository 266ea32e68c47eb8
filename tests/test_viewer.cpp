// The viewer (`terawalk view`) as a person sees it: a real X server (Xvfb), the viewer's window on
// it, and the X screen itself read back and checked, not the renderer's own buffer.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdlib>
#include <string>
#include <thread>

#include "image_compare.h"
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

}  // namespace
}  // namespace tw
