// The viewer (`terawalk view`) as a person sees it: a real X server (Xvfb), the viewer's window on
// it, and the X screen itself read back and checked, not the renderer's own buffer.
#include <gtest/gtest.h>

#include <algorithm>
#include <set>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <string>
#include <thread>

#include <nlohmann/json.hpp>

#include "camera.h"
#include "camera_path.h"
#include "image_compare.h"
#include "package_view.h"
#include "generated_plant_support.h"
#include "test_support.h"
#include "x_screen_support.h"
#include "change_set.h"
#include "object_queries.h"

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
// record from the database the package names (no --db). The capture is kept as
// x-screen-pick.png.
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
        " --size 1024x768 --pixel 512,384 --json");
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
  test::writeFile(dir / "click.script", "30 click 512 384\n150 quit\n");

  test::XvfbScreen screen(dir / "x", 1024, 768);
  test::BackgroundProcess viewer(
      {TW_TERAWALK_EXE, "view", test::generatedPlant().package.string(), "--size", "1024x768",
       "--path", (dir / "valve.path").string(), "--script", (dir / "click.script").string()},
      {"DISPLAY=" + screen.display()}, dir / "view.log");
  std::optional<test::ScreenImage> before, after;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
  while (viewer.running() && std::chrono::steady_clock::now() < deadline) {
    const bool picked = test::readFile(dir / "view.log").find("view: picked") != std::string::npos;
    auto capture = screen.capture();
    if (capture && windowDrawn(*capture, 1024, 768) &&
        showsPanel(countPanelPixels(*capture, 12, 40, 200, 90)))
      (picked ? after : before) = std::move(capture);
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  const std::string log = test::readFile(dir / "view.log");
  ASSERT_EQ(viewer.wait(), 0) << log;
  EXPECT_NE(log.find("key " + key + " at"), std::string::npos) << log;
  EXPECT_NE(log.find("record found"), std::string::npos) << log;
  ASSERT_TRUE(before && after) << log;
  // The screen is the window, for docs/images/viewer-pick.png.
  writePngRgba(dir / "x-screen-pick.png", after->width, after->height, after->rgba);
  writePngRgba(dir / "x-screen-before.png", before->width, before->height, before->rgba);
  // The valve, tinted, at the centre.
  EXPECT_GT(tintedPixels(*before, *after, 512, 384, 60), 100);
  EXPECT_EQ(tintedPixels(*before, *after, 850, 600, 60), 0);  // elsewhere nothing changed
  // The properties panel at the top right has grown by the record's lines (right of the
  // statistics panel, where the model showed before), down to its help line.
  const PanelCount grown_after = countPanelPixels(*after, 580, 90, 1010, 280);
  const PanelCount grown_before = countPanelPixels(*before, 580, 90, 1010, 280);
  EXPECT_GT(grown_after.dark * 2, grown_after.total) << grown_after.dark;
  EXPECT_LT(grown_before.dark * 2, grown_before.total) << grown_before.dark;
  EXPECT_GT(countPanelPixels(*after, 580, 276, 1010, 292).text, 20);
}

// Pixels of the model in the window's part right of the review panel (not the background).
int modelPixels(const test::ScreenImage& screen, int x0, int y0, int x1, int y1) {
  int n = 0;
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x) {
      const uint8_t* p = screen.at(x, y);
      n += std::abs(p[0] - 184) > 12 || std::abs(p[1] - 204) > 12 || std::abs(p[2] - 230) > 12;
    }
  return n;
}

// Pixels of the selection outline's colour (gl_shaders.h kOutline).
int outlinePixels(const test::ScreenImage& screen, int x0, int y0, int x1, int y1) {
  int n = 0;
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x) {
      const uint8_t* p = screen.at(x, y);
      n += p[0] == 255 && p[1] == 219 && p[2] == 0;
    }
  return n;
}

// Runs the viewer on `package` with `script` under a fresh Xvfb; keeps the last capture taken
// before the log held `first_marker` and the last one after it held `marker`.
struct ScriptedRun {
  std::optional<test::ScreenImage> before, after;
  std::string log;
  int exit_code = -1;
};
ScriptedRun runViewerScript(const std::filesystem::path& package, const std::filesystem::path& dir,
                            const std::string& name, const std::string& script,
                            const std::string& first_marker, const std::string& marker) {
  const auto script_file = dir / (name + ".script");
  const auto log_file = dir / (name + ".log");
  test::writeFile(script_file, script);
  test::XvfbScreen screen(dir / ("x-" + name), 1024, 768);
  test::BackgroundProcess viewer({TW_TERAWALK_EXE, "view", package.string(), "--size", "1024x768",
                                  "--script", script_file.string()},
                                 {"DISPLAY=" + screen.display()}, log_file);
  ScriptedRun run;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
  while (viewer.running() && std::chrono::steady_clock::now() < deadline) {
    // "After" needs the marker logged before the capture began; "before" needs the first marker
    // still unlogged when the capture is done, since the viewer may have acted and drawn a
    // frame while the screen was being read (a slow capture on a loaded machine did).
    const bool reached = test::readFile(log_file).find(marker) != std::string::npos;
    auto capture = screen.capture();
    const bool started = test::readFile(log_file).find(first_marker) != std::string::npos;
    if (capture && windowDrawn(*capture, 1024, 768) &&
        showsPanel(countPanelPixels(*capture, 12, 40, 200, 90))) {
      if (!started) run.before = std::move(capture);
      else if (reached) run.after = std::move(capture);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  run.exit_code = viewer.wait();
  run.log = test::readFile(log_file);
  return run;
}

// The review panel as a reviewer uses it, through the viewer's script: a query over the project
// database (the one the package names), its results isolated and selected, and both saved as
// sets next to the package; then, in a second session, the visibility set restored. The X screen
// shows the review panel, the plant reduced to the sea-water service and outlined, and the same
// plant again after the restore; the sets file holds exactly what `terawalk find` finds.
// The capture is kept as x-screen-review.png.
TEST(Viewer, ReviewPanelQueriesIsolatesAndRestoresSets) {
  if (!haveXvfb()) GTEST_SKIP() << "no Xvfb";
  const auto dir = test::scratchDir();
  // The sets live next to the package: a copy of it here, so the shared one stays clean.
  const auto package = dir / "plant.twk";
  std::filesystem::copy_file(test::generatedPlant().package, package);
  std::filesystem::copy_file(test::generatedPlant().db, dir / "plant.db");
  const std::string query = "service = 'sea water'";
  const ScriptedRun run = runViewerScript(
      package, dir, "review",
      "20 query " + query + "\n25 isolate-results\n30 select-results\n"
      "35 save-selection sea water\n40 save-visibility sea water only\n150 quit\n",
      "view: query", "saved set 'sea water only'");
  ASSERT_EQ(run.exit_code, 0) << run.log;
  ASSERT_TRUE(run.before && run.after) << run.log;
  writePngRgba(dir / "x-screen-review.png", run.after->width, run.after->height, run.after->rgba);
  EXPECT_NE(run.log.find("query '" + query + "': "), std::string::npos) << run.log;

  // The review panel, left under the statistics: dark, with its layer rows' text.
  const PanelCount panel = countPanelPixels(*run.after, 12, 240, 220, 520);
  EXPECT_GT(panel.dark * 2, panel.total) << panel.dark;
  EXPECT_GT(panel.text, 500);
  // Right of it, the plant shrank to the sea-water service, outlined as selected.
  const int all = modelPixels(*run.before, 460, 120, 1024, 768);
  const int isolated = modelPixels(*run.after, 460, 120, 1024, 768);
  EXPECT_GT(isolated, 50);
  EXPECT_LT(isolated * 3, all) << isolated << " of " << all;
  EXPECT_GT(outlinePixels(*run.after, 460, 120, 1024, 768), 20);
  EXPECT_EQ(outlinePixels(*run.before, 460, 120, 1024, 768), 0);

  // The file: the selection is what find finds, by scene id; the visibility hides the rest.
  const PackageView view = PackageView::open(package);
  test::CommandResult found =
      test::runTerawalk("find " + package.string() + " \"" + query + "\" --json");
  ASSERT_EQ(found.exit_code, 0) << found.output;
  std::set<uint32_t> expected;
  const nlohmann::json found_json = nlohmann::json::parse(found.output);
  for (const auto& o : found_json["objects"])
    expected.insert(view.objects()[o["object"].get<uint32_t>()].id);
  ASSERT_FALSE(expected.empty()) << found.output;
  const auto sets = nlohmann::json::parse(test::readFile(dir / "plant.sets.json"));
  ASSERT_EQ(sets["sets"].size(), 2u) << sets.dump();
  const auto selected = sets["sets"][0]["selected"].get<std::vector<uint32_t>>();
  EXPECT_EQ(std::set<uint32_t>(selected.begin(), selected.end()), expected);
  EXPECT_EQ(sets["sets"][1]["kind"], "visibility");
  EXPECT_EQ(sets["sets"][1]["hidden"].size(), view.objects().size() - expected.size());

  // A second session restores the visibility from the file: the same plant shows again.
  const ScriptedRun again = runViewerScript(
      package, dir, "restore", "20 restore sea water only\n150 quit\n", "restored set",
      "restored set");
  ASSERT_EQ(again.exit_code, 0) << again.log;
  ASSERT_TRUE(again.before && again.after) << again.log;
  const int restored = modelPixels(*again.after, 460, 120, 1024, 768);
  EXPECT_LT(std::abs(restored - isolated), isolated / 4 + 20) << restored << " against " << isolated;

  // A damaged sets file is reported, naming it, and never written over.
  test::writeFile(dir / "plant.sets.json", "{\"terawalk_selection_sets\": 1, \"sets\": [");
  const ScriptedRun damaged = runViewerScript(package, dir, "damaged",
                                              "20 save-visibility again\n60 quit\n", "not saved",
                                              "not saved");
  EXPECT_EQ(damaged.exit_code, 0) << damaged.log;
  EXPECT_NE(damaged.log.find("plant.sets.json: not JSON"), std::string::npos) << damaged.log;
  EXPECT_NE(damaged.log.find("set 'again' not saved"), std::string::npos) << damaged.log;
  EXPECT_EQ(test::readFile(dir / "plant.sets.json"), "{\"terawalk_selection_sets\": 1, \"sets\": [");
}


// Pixels in the gizmo's axis colours (view_edits.cpp kAxisColours), drawn over the frame.
int gizmoPixels(const test::ScreenImage& screen, int x0, int y0, int x1, int y1) {
  int n = 0;
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x) {
      const uint8_t* p = screen.at(x, y);
      n += (p[0] == 220 && p[1] == 50 && p[2] == 40) || (p[0] == 40 && p[1] == 180 && p[2] == 60) ||
           (p[0] == 50 && p[1] == 90 && p[2] == 230);
    }
  return n;
}

// The way back to CAD as a reviewer takes it: in the viewer (scripted), the pump P-1001-A is
// found, selected and framed; its gizmo's Z arrow is dragged up on the X screen, and it is moved
// 0.4 m along X; the last edit is undone and redone, and the change set saved. `changes apply`
// writes the moves into the scene, and the preprocessed new scene has the pump at its new place.
// The X screen shows the gizmo on the pump; the capture is kept as x-screen-gizmo.png.
TEST(Viewer, TheGizmoMovesAPumpAndTheChangeSetCarriesItToTheScene) {
  if (!haveXvfb()) GTEST_SKIP() << "no Xvfb";
  const auto dir = test::scratchDir();
  const auto package = dir / "plant.twk";
  std::filesystem::copy_file(test::generatedPlant().package, package);
  // Framed, the pump's centre is the window's centre; its Z arrow points up from there.
  const ScriptedRun run = runViewerScript(
      package, dir, "gizmo",
      "20 search P-1001-A\n22 select-results\n24 zoom-results\n30 gizmo\n40 drag 512 320 512 270\n"
      "50 move 0.4,0,0\n60 undo\n62 redo\n70 save-changes\n150 quit\n",
      "edits: gizmo drag", "changes saved");
  ASSERT_EQ(run.exit_code, 0) << run.log;
  ASSERT_TRUE(run.before) << run.log;
  ASSERT_TRUE(run.after) << run.log;
  writePngRgba(dir / "x-screen-gizmo.png", run.after->width, run.after->height, run.after->rgba);
  EXPECT_GT(gizmoPixels(*run.after, 300, 150, 724, 618), 200) << "the gizmo is drawn on the pump";

  const ChangeSet changes = readChangeSet(dir / "plant.changes.json");
  ASSERT_EQ(changes.changes().size(), 2u) << run.log;
  const Change& lift = changes.changes()[0];
  const glm::dvec3 up = lift.new_pivot - lift.old_pivot;
  EXPECT_EQ(lift.key, "P-1001-A");
  EXPECT_EQ(up.x, 0.0);
  EXPECT_EQ(up.y, 0.0);
  EXPECT_GT(up.z, 0.0) << "dragged up along Z";
  EXPECT_NEAR(up.z / 0.01, std::round(up.z / 0.01), 1e-6) << "snapped to 10 mm";
  const glm::dvec3 along = changes.changes()[1].new_pivot - changes.changes()[1].old_pivot;
  EXPECT_LE(glm::length(along - glm::dvec3(0.4, 0.0, 0.0)), 1e-9);

  const PackageView view = PackageView::open(package);
  glm::dvec3 lo, hi;
  ASSERT_TRUE(objectsBounds(view, objectsWithKeys(view, {"P-1001-A"}), lo, hi));
  test::CommandResult r = test::runTerawalk("changes apply " + test::generatedPlant().scene.string() +
                                            " " + (dir / "plant.changes.json").string() + " -o " +
                                            (dir / "moved.tws").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = test::runTerawalk("preprocess --quiet " + (dir / "moved.tws").string() + " -o " +
                        (dir / "moved.twk").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const PackageView moved = PackageView::open(dir / "moved.twk");
  glm::dvec3 lo2, hi2;
  ASSERT_TRUE(objectsBounds(moved, objectsWithKeys(moved, {"P-1001-A"}), lo2, hi2));
  EXPECT_LE(glm::length(lo2 - (lo + up + along)), 1e-3);
  EXPECT_LE(glm::length(hi2 - (hi + up + along)), 1e-3);
}

// The exploded view: the pumps pushed from their common centre (the X screen changes), then
// collapsed: the screen over the model is what it was before. The view is framed and left to
// settle (its pages loaded) before the explode, so both captures show the same cut.
TEST(Viewer, ExplodingAndCollapsingGivesTheOriginalFrame) {
  if (!haveXvfb()) GTEST_SKIP() << "no Xvfb";
  const auto dir = test::scratchDir();
  const auto package = dir / "plant.twk";
  std::filesystem::copy_file(test::generatedPlant().package, package);
  const ScriptedRun exploded = runViewerScript(
      package, dir, "explode",
      "20 search pump\n22 select-results\n24 zoom-results\n30 settle\n150 explode 3\n250 quit\n",
      "explode to 3.00", "explode to 3.00");
  const ScriptedRun collapsed = runViewerScript(
      package, dir, "collapse",
      "20 search pump\n22 select-results\n24 zoom-results\n30 settle\n150 explode 3\n200 collapse\n"
      "230 settle\n350 quit\n",
      "explode to 3.00", "explode to 1.00");
  ASSERT_EQ(exploded.exit_code, 0) << exploded.log;
  ASSERT_EQ(collapsed.exit_code, 0) << collapsed.log;
  ASSERT_TRUE(exploded.before && exploded.after && collapsed.before && collapsed.after);
  auto differing = [](const test::ScreenImage& a, const test::ScreenImage& b) {
    int n = 0;  // over the model, right of the review panel
    for (int y = 200; y < 480; ++y)
      for (int x = 460; x < 760; ++x) n += std::memcmp(a.at(x, y), b.at(x, y), 3) != 0;
    return n;
  };
  EXPECT_GT(differing(*exploded.before, *exploded.after), 500) << "the pumps moved apart";
  const int changed = differing(*collapsed.before, *collapsed.after);
  EXPECT_EQ(changed, 0) << "collapsed, as before";
  if (changed != 0) {  // kept for a look
    writePngRgba(dir / "x-collapse-before.png", collapsed.before->width, collapsed.before->height,
                 collapsed.before->rgba);
    writePngRgba(dir / "x-collapse-after.png", collapsed.after->width, collapsed.after->height,
                 collapsed.after->rgba);
  }
}

// Sections in the viewer: a plane placed on the vessel's surface under the window's centre
// (its normal the surface's, toward the eye) and dragged 0.3 m into it cuts the vessel open; the
// cut is capped in the section colour on the X screen.
TEST(Viewer, ASectionPlacedOnASurfaceAndDraggedCutsItOpen) {
  if (!haveXvfb()) GTEST_SKIP() << "no Xvfb";
  const auto dir = test::scratchDir();
  const ScriptedRun run = runViewerScript(
      test::generatedPlant().package, dir, "section",
      "20 search V-1002\n22 select-results\n24 zoom-results\n60 section-at 512 384\n"
      "62 section-offset -0.3\n150 quit\n",
      "sections: plane 1 at", "moved -0.300 m");
  ASSERT_EQ(run.exit_code, 0) << run.log;
  ASSERT_TRUE(run.before && run.after) << run.log;
  writePngRgba(dir / "x-screen-section.png", run.after->width, run.after->height, run.after->rgba);
  auto caps = [](const test::ScreenImage& screen) {
    int n = 0;  // the section colour (gl_shaders.h kSectionCap), right of the review panel
    for (int y = 0; y < 768; ++y)
      for (int x = 460; x < 1024; ++x) {
        const uint8_t* p = screen.at(x, y);
        n += p[0] == 199 && p[1] == 56 && p[2] == 46;
      }
    return n;
  };
  EXPECT_EQ(caps(*run.before), 0);
  EXPECT_GT(caps(*run.after), 500) << "the vessel is cut open and capped";
}

// Named viewpoints: a view of the vessel cut open and selected, saved in one session, is a topic
// of the review's BCF archive (camera, selection, clipping plane, snapshot); a second session
// that goes to it shows the cut and the outline again.
TEST(Viewer, ANamedViewpointIsSavedToTheReviewAndRestoredInTheNextSession) {
  if (!haveXvfb()) GTEST_SKIP() << "no Xvfb";
  const auto dir = test::scratchDir();
  const auto package = dir / "plant.twk";
  std::filesystem::copy_file(test::generatedPlant().package, package);
  const ScriptedRun first = runViewerScript(
      package, dir, "save",
      "20 search V-1002\n22 select-results\n24 zoom-results\n60 section-at 512 384\n"
      "62 section-offset -0.3\n80 save-viewpoint vessel cut\n150 quit\n",
      "sections: plane 1 at", "viewpoints: saved");
  ASSERT_EQ(first.exit_code, 0) << first.log;
  const nlohmann::json list = nlohmann::json::parse([&] {
    const test::CommandResult r = test::runTerawalk("bcf list --json " + (dir / "plant.review.bcfzip").string());
    EXPECT_EQ(r.exit_code, 0) << r.output;
    return r.output.substr(r.output.find('{'));
  }());
  ASSERT_EQ(list["topics"].size(), 1u);
  EXPECT_EQ(list["topics"][0]["title"], "vessel cut");
  const auto& v = list["topics"][0]["viewpoints"][0];
  EXPECT_EQ(v["selection"].size(), 1u) << "the vessel's key";
  EXPECT_EQ(v["clipping_planes"].size(), 1u);
  EXPECT_GT(v["snapshot_bytes"].get<size_t>(), 1000u);

  const ScriptedRun second = runViewerScript(package, dir, "go",
                                             "40 go-viewpoint vessel cut\n150 quit\n",
                                             "viewpoints: went to", "viewpoints: went to");
  ASSERT_EQ(second.exit_code, 0) << second.log;
  ASSERT_TRUE(second.before && second.after) << second.log;
  writePngRgba(dir / "x-screen-viewpoint.png", second.after->width, second.after->height,
               second.after->rgba);
  EXPECT_NE(second.log.find("went to 'vessel cut' (11 selected"), std::string::npos) << second.log;
  auto caps = [](const test::ScreenImage& screen) {
    int n = 0;
    for (int y = 0; y < 768; ++y)
      for (int x = 460; x < 1024; ++x) {
        const uint8_t* p = screen.at(x, y);
        n += p[0] == 199 && p[1] == 56 && p[2] == 46;
      }
    return n;
  };
  EXPECT_EQ(caps(*second.before), 0);
  EXPECT_GT(caps(*second.after), 500) << "the cut is back";
  EXPECT_GT(outlinePixels(*second.after, 460, 120, 1024, 768), 20) << "and the selection";
}

// Measuring in the viewer: the minimum distance between the two selected pumps is the one
// `terawalk measure --between` gives, and its closest points are drawn on the X screen; two
// clicked points give a distance with its X, Y, Z parts, each point snapped.
TEST(Viewer, MeasuringBetweenTwoPumpsMatchesTheCommandAndDrawsTheClosestPoints) {
  if (!haveXvfb()) GTEST_SKIP() << "no Xvfb";
  const auto dir = test::scratchDir();
  const ScriptedRun run = runViewerScript(
      test::generatedPlant().package, dir, "measure",
      "20 search P-1001\n22 select-results\n24 zoom-results\n40 measure-between\n"
      "100 measure-at 512 384\n102 measure-at 540 400\n150 quit\n",
      "measure: between", "measure: between");
  ASSERT_EQ(run.exit_code, 0) << run.log;
  ASSERT_TRUE(run.before && run.after) << run.log;
  const test::CommandResult cli = test::runTerawalk(
      "measure " + test::generatedPlant().package.string() + " --between P-1001-A P-1001-B --json");
  ASSERT_EQ(cli.exit_code, 0) << cli.output;
  const double expected = nlohmann::json::parse(cli.output)["distance_m"].get<double>();
  const size_t at = run.log.find("measure: between P-1001-A to P-1001-B: ");
  ASSERT_NE(at, std::string::npos) << run.log;
  const double shown = std::stod(run.log.substr(at + 39));
  EXPECT_NEAR(shown, expected, 1e-6);
  int magenta = 0;
  for (int y = 0; y < 768; ++y)
    for (int x = 460; x < 1024; ++x) {
      const uint8_t* p = run.after->at(x, y);
      magenta += p[0] == 255 && p[1] == 0 && p[2] == 255;
    }
  EXPECT_GT(magenta, 20) << "the closest points and the line between them";
  EXPECT_NE(run.log.find("measure: point 2 ("), std::string::npos) << run.log;
  EXPECT_NE(run.log.find("measure: distance "), std::string::npos) << run.log;
}

// The ocean and the sky switched on in the viewer (its script, as the panel's checkboxes do): on
// the X screen the background above the plant turns to sky and the lower part of the window to
// water. The capture is kept as x-screen-ocean.png.
TEST(Viewer, TheOceanAndTheSkyShowOnTheXScreen) {
  if (!haveXvfb()) GTEST_SKIP() << "no Xvfb";
  const auto dir = test::scratchDir();
  const auto package = dir / "plant.twk";
  std::filesystem::copy_file(test::generatedPlant().package, package);
  const ScriptedRun run = runViewerScript(package, dir, "ocean", "60 ocean on\n61 sky on\n160 quit\n",
                                          "ocean on", "sky on");
  ASSERT_EQ(run.exit_code, 0) << run.log;
  ASSERT_TRUE(run.before && run.after) << run.log;
  writePngRgba(dir / "x-screen-ocean.png", run.after->width, run.after->height, run.after->rgba);
  // Right of the review panel, the top rows (sky) and the bottom rows (water).
  auto region = [](const test::ScreenImage& s, int y0, int y1, double& r, double& g, double& b) {
    r = g = b = 0.0;
    int n = 0;
    for (int y = y0; y < y1; ++y)
      for (int x = 700; x < 1000; x += 2, ++n) {
        r += s.at(x, y)[0];
        g += s.at(x, y)[1];
        b += s.at(x, y)[2];
      }
    r /= n, g /= n, b /= n;
  };
  double r0, g0, b0, r1, g1, b1;
  region(*run.before, 700, 760, r0, g0, b0);
  region(*run.after, 700, 760, r1, g1, b1);
  EXPECT_LT(r1 + g1 + b1, 0.6 * (r0 + g0 + b0)) << "deep water is darker than the background was";
  EXPECT_GT(b1, r1 + 10.0) << "and blue";
  region(*run.after, 250, 300, r1, g1, b1);
  EXPECT_GT(b1, r1 + 20.0) << "the sky above the horizon is blue";
  EXPECT_NE(run.log.find("ocean on (waterline 0.00 m, 8 waves)"), std::string::npos) << run.log;
}

// Stereo in the window, top and bottom: on the X screen the two halves show the plant from the
// two eyes. With the eyes together the halves are the same picture; a metre apart, they differ.
TEST(Viewer, TopAndBottomStereoShowsBothEyesOnTheXScreen) {
  if (!haveXvfb()) GTEST_SKIP() << "no Xvfb";
  const auto dir = test::scratchDir();
  const auto package = dir / "plant.twk";
  std::filesystem::copy_file(test::generatedPlant().package, package);
  auto halvesDiffer = [&](const std::string& name, const std::string& separation) {
    const auto script_file = dir / (name + ".script");
    test::writeFile(script_file, "");
    test::XvfbScreen screen(dir / ("x-" + name), 1024, 768);
    test::BackgroundProcess viewer({TW_TERAWALK_EXE, "view", package.string(), "--size", "1024x768",
                                    "--frames", "100", "--stereo", "top-bottom", "--eye-separation",
                                    separation, "--zero-parallax", "20"},
                                   {"DISPLAY=" + screen.display()}, dir / (name + ".log"));
    // Right of the review panel and of the pointer, below the statistics: the top half's rows
    // against the bottom half's. The X screen file is often caught while the window is redrawn
    // (the root's black showing through part of it), so only the pairs of rows both drawn (no
    // black pixel) are compared, in the capture that has the most of them; a tear between two
    // frames of the still camera is invisible.
    auto rowDrawn = [](const test::ScreenImage& image, int y) {
      for (int x = 540; x < 900; ++x)
        if (image.at(x, y)[0] == 0 && image.at(x, y)[1] == 0 && image.at(x, y)[2] == 0) return false;
      return true;
    };
    int best_rows = 0, differing = -1;
    while (viewer.running()) {
      auto capture = screen.capture();
      if (capture && capture->width >= 1024 && capture->height >= 768) {
        int rows = 0, differ = 0;
        for (int y = 210; y < 384; ++y) {
          if (!rowDrawn(*capture, y) || !rowDrawn(*capture, y + 384)) continue;
          ++rows;
          for (int x = 540; x < 900; ++x) differ += std::memcmp(capture->at(x, y), capture->at(x, y + 384), 3) != 0;
        }
        if (rows > best_rows) {
          best_rows = rows;
          differing = differ;
          writePngRgba(dir / ("x-screen-" + name + ".png"), capture->width, capture->height, capture->rgba);
        }
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    EXPECT_EQ(viewer.wait(), 0) << test::readFile(dir / (name + ".log"));
    EXPECT_GE(best_rows, 60) << "too few rows of both halves seen drawn";
    return differing;
  };
  EXPECT_EQ(halvesDiffer("together", "0"), 0);
  EXPECT_GT(halvesDiffer("apart", "1"), 200);
}

// The path player, as a reviewer drives it through the Path panel (here its script): an orbit
// paused and moved along with the time slider shows the plant from another side on the X
// screen; smoothed and written, the path reads back with its keys 1/30 s apart.
TEST(Viewer, APathPausedAndSoughtMovesTheCameraAndIsWrittenSmoothed) {
  if (!haveXvfb()) GTEST_SKIP() << "no Xvfb";
  const auto dir = test::scratchDir();
  const auto package = dir / "plant.twk";
  std::filesystem::copy_file(test::generatedPlant().package, package);
  const auto orbit = dir / "orbit.path";
  ASSERT_EQ(test::runTerawalk("render --quiet " + package.string() + " --orbit 120 --max-frames 1 --size 64x64 --save-path " +
                              orbit.string()).exit_code, 0);
  const auto smoothed = dir / "smooth.path";
  const auto script_file = dir / "path.script";
  test::writeFile(script_file, "5 path-pause\n10 path-seek 0.5\n70 path-seek 2.5\n75 path-smooth 0.5\n76 path-save " +
                                   smoothed.string() + "\n140 quit\n");
  const auto log_file = dir / "path.log";
  test::XvfbScreen screen(dir / "x-path", 1024, 768);
  test::BackgroundProcess viewer({TW_TERAWALK_EXE, "view", package.string(), "--size", "1024x768", "--path",
                                  orbit.string(), "--script", script_file.string()},
                                 {"DISPLAY=" + screen.display()}, log_file);
  std::optional<test::ScreenImage> at_half, at_two_and_half;
  while (viewer.running()) {
    const std::string log = test::readFile(log_file);
    auto capture = screen.capture();
    if (capture && windowDrawn(*capture, 1024, 768)) {
      if (log.find("path at 2.50") != std::string::npos) at_two_and_half = std::move(capture);
      else if (log.find("path at 0.50") != std::string::npos) at_half = std::move(capture);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  ASSERT_EQ(viewer.wait(), 0) << test::readFile(log_file);
  ASSERT_TRUE(at_half && at_two_and_half) << test::readFile(log_file);
  int differing = 0;  // right of the review panel, below the statistics
  for (int y = 210; y < 760; ++y)
    for (int x = 460; x < 1020; ++x) differing += std::memcmp(at_half->at(x, y), at_two_and_half->at(x, y), 3) != 0;
  EXPECT_GT(differing, 2000) << "the camera moved along the orbit";
  const CameraPath written = readCameraPath(smoothed);
  ASSERT_GT(written.keys.size(), 100u);
  EXPECT_NEAR(written.keys[1].time_s - written.keys[0].time_s, 1.0 / 30.0, 1e-9);
  EXPECT_NE(test::readFile(log_file).find("path smoothed: 120 keys to"), std::string::npos);
}

// Quad-buffered stereo needs a stereo GL context; Xvfb (Mesa) offers none, and the viewer says
// so in one line instead of opening a window that shows one eye. Where a display does offer one,
// the viewer runs.
TEST(Viewer, QuadBufferedStereoWithoutAStereoContextIsAClearError) {
  if (!haveXvfb()) GTEST_SKIP() << "no Xvfb";
  const auto dir = test::scratchDir();
  test::XvfbScreen screen(dir / "x-quad", 640, 480);
  const auto log_file = dir / "quad.log";
  test::BackgroundProcess viewer({TW_TERAWALK_EXE, "view", test::generatedPlant().package.string(), "--size",
                                  "640x480", "--frames", "5", "--stereo", "quad-buffered"},
                                 {"DISPLAY=" + screen.display()}, log_file);
  const int exit_code = viewer.wait();
  const std::string log = test::readFile(log_file);
  if (exit_code == 0) GTEST_SKIP() << "this display offers quad-buffered stereo";
  EXPECT_EQ(exit_code, 1) << log;
  EXPECT_NE(log.find("--stereo quad-buffered: this display offers no quad-buffered stereo GL context"),
            std::string::npos)
      << log;
}

}  // namespace
}  // namespace tw
