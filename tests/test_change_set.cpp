// Change sets: the JSON file keeps every edit exactly and refuses damaged ones; a moved object
// is drawn at its new place and not its old one at every level of detail, in impostors and
// tessellations; `changes apply` carries a move back to the scene, so that the preprocessed new
// scene has the object at its new place.
#include <cmath>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include "camera.h"
#include "camera_path.h"
#include "change_set.h"
#include "generated_plant_support.h"
#include "image_compare.h"
#include "object_queries.h"
#include "package_view.h"
#include "test_support.h"

namespace tw {
namespace {

namespace fs = std::filesystem;

constexpr const char* kPump = "P-1001-A";

Change makeChange(Change::Kind kind, const std::string& key, const std::string& author,
                  const std::string& date) {
  Change c;
  c.kind = kind;
  c.key = key;
  c.author = author;
  c.date = date;
  return c;
}

TEST(ChangeSet, FileKeepsEveryEditExactlyAndUndoRedoWork) {
  const fs::path dir = test::scratchDir();
  ChangeSet set;
  Change move;
  move.kind = Change::Kind::Move;
  move.key = kPump;
  move.author = "ana";
  move.date = "2026-12-06T14:00:00Z";
  move.old_pivot = {612345.125, 7012345.0625, 12.5};
  move.transform = moveTransform(move.old_pivot, {0.4, -0.01, 0.0}, {0, 0, 1}, 0.0872664625997165, 1.0);
  move.new_pivot = glm::dvec3(move.transform * glm::dvec4(move.old_pivot, 1.0));
  set.add(move);
  Change hide = makeChange(Change::Kind::Hide, "V-12", "ana", "2026-12-06T14:01:00Z");
  set.add(hide);
  Change colour = makeChange(Change::Kind::Colour, "V-13", "ana", "2026-12-06T14:02:00Z");
  colour.rgba = 0xff0080ffu;
  set.add(colour);
  Change note = makeChange(Change::Kind::Comment, kPump, "ana", "2026-12-06T14:03:00Z");
  note.text = "clears the walkway now";
  set.add(note);
  EXPECT_LE(glm::length(move.new_pivot - move.old_pivot - glm::dvec3(0.4, -0.01, 0.0)), 1e-9)
      << "a rotation about the pivot leaves the pivot where the translation puts it";

  writeChangeSet(dir / "m.changes.json", set);
  const ChangeSet back = readChangeSet(dir / "m.changes.json");
  ASSERT_EQ(back.changes().size(), 4u);
  const Change& m = back.changes()[0];
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r) EXPECT_EQ(m.transform[c][r], move.transform[c][r]) << c << r;
  EXPECT_EQ(m.old_pivot, move.old_pivot);
  EXPECT_EQ(m.author, "ana");
  EXPECT_EQ(back.changes()[1].kind, Change::Kind::Hide);
  EXPECT_EQ(back.changes()[2].rgba, 0xff0080ffu);
  EXPECT_EQ(back.changes()[3].text, "clears the walkway now");

  ChangeSet edits = back;
  EXPECT_TRUE(edits.undo());
  EXPECT_TRUE(edits.undo());
  EXPECT_EQ(edits.undoable(), 2u);
  EXPECT_TRUE(edits.redo());
  EXPECT_EQ(edits.changes().back().kind, Change::Kind::Colour);
  edits.add(note);  // a new edit drops what was undone
  EXPECT_FALSE(edits.redo());
  EXPECT_EQ(edits.placement(kPump), move.transform);
  EXPECT_EQ(edits.placement("nothing"), glm::dmat4(1.0));

  // Damaged files: an error naming the file and the change; the file is never rewritten.
  auto expectError = [&](const std::string& text, const std::string& message) {
    std::ofstream(dir / "bad.json") << text;
    try {
      readChangeSet(dir / "bad.json");
      ADD_FAILURE() << "accepted: " << text;
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("bad.json"), std::string::npos) << e.what();
    }
  };
  expectError("{\"terawalk_changes\": 1, \"changes\": [", "not JSON");
  expectError("{\"terawalk_changes\": 2, \"changes\": []}", "version 1");
  expectError("{\"terawalk_changes\": 1, \"changes\": [{\"kind\": \"move\", \"key\": \"a\", "
              "\"transform\": [1,0,0]}]}",
              "change 1: 'transform' is not 16 numbers");
  expectError("{\"terawalk_changes\": 1, \"changes\": [{\"kind\": \"melt\", \"key\": \"a\"}]}",
              "unknown kind 'melt'");
  expectError("{\"terawalk_changes\": 1, \"changes\": [{\"kind\": \"colour\", \"key\": \"a\", "
              "\"rgba\": \"red\"}]}",
              "'rgba' 'red' is not RRGGBBAA");
}

// The pump's world box, and a change set moving it `by` metres.
struct PumpMove {
  glm::dvec3 lo, hi;
  glm::dvec3 by;
  fs::path changes;
};

PumpMove movePump(const fs::path& dir, const glm::dvec3& by) {
  const PackageView view = PackageView::open(test::generatedPlant().package);
  PumpMove out;
  out.by = by;
  EXPECT_TRUE(objectsBounds(view, objectsWithKeys(view, {kPump}), out.lo, out.hi));
  ChangeSet set;
  Change move = makeChange(Change::Kind::Move, kPump, "test", "2026-12-06T00:00:00Z");
  move.old_pivot = 0.5 * (out.lo + out.hi);
  move.transform = moveTransform(move.old_pivot, by);
  move.new_pivot = move.old_pivot + by;
  set.add(move);
  out.changes = dir / "plant.changes.json";
  writeChangeSet(out.changes, set);
  return out;
}

// Pixels of a box's projection on the image (its eight corners' screen rectangle).
struct ScreenRect {
  double x0 = 1e30, y0 = 1e30, x1 = -1e30, y1 = -1e30;
  bool contains(double x, double y, double margin) const {
    return x >= x0 - margin && x <= x1 + margin && y >= y0 - margin && y <= y1 + margin;
  }
};

ScreenRect project(const Camera& camera, int width, int height, const glm::dvec3& lo,
                   const glm::dvec3& hi) {
  ScreenRect r;
  for (int k = 0; k < 8; ++k) {
    const glm::dvec3 p((k & 1) ? hi.x : lo.x, (k & 2) ? hi.y : lo.y, (k & 4) ? hi.z : lo.z);
    const std::optional<glm::dvec2> s = imagePoint(camera, width, height, p);
    if (!s) continue;
    r.x0 = std::min(r.x0, s->x);
    r.x1 = std::max(r.x1, s->x);
    r.y0 = std::min(r.y0, s->y);
    r.y1 = std::max(r.y1, s->y);
  }
  return r;
}

TEST(ChangeSet, AMovedObjectIsDrawnAtItsNewPlaceAndNotItsOldOneAtEveryLevel) {
  const fs::path dir = test::scratchDir();
  const PackageView view = PackageView::open(test::generatedPlant().package);
  const std::vector<uint32_t> pump = objectsWithKeys(view, {kPump});
  ASSERT_FALSE(pump.empty());
  // Moved sideways by twice its width, seen from the side and a little above, the rest of the
  // plant hidden so that nothing stands in front of it.
  glm::dvec3 lo, hi;
  ASSERT_TRUE(objectsBounds(view, pump, lo, hi));
  const double size = glm::length(hi - lo);
  const PumpMove move = movePump(dir, {2.5 * (hi.x - lo.x) + 0.5, 0.0, 0.0});
  const glm::dvec3 centre = 0.5 * (lo + hi) + 0.5 * move.by;
  Camera camera;
  camera.position = centre + glm::dvec3(0.0, -3.0 * size, 1.0 * size);
  camera.lookAt(centre);
  CameraPath still;
  still.keys.push_back({0.0, camera});
  writeCameraPath(still, dir / "still.path");
  const int width = 320, height = 200;
  const ScreenRect old_rect = project(camera, width, height, lo, hi);
  const ScreenRect new_rect = project(camera, width, height, lo + move.by, hi + move.by);
  ASSERT_TRUE(old_rect.x1 < new_rect.x0) << "the two places must not overlap on screen";

  for (const std::string variant : {"--tau 1", "--tau 24", "--reference", "--parametrics impostor",
                                    "--parametrics tessellated"}) {
    SCOPED_TRACE(variant);
    for (const bool moved : {false, true}) {
      const fs::path out = dir / (std::string(moved ? "moved" : "still") + std::to_string(variant.size()));
      const test::CommandResult r = test::runTerawalk(
          "render --quiet " + test::generatedPlant().package.string() + " --path " +
          (dir / "still.path").string() + " --size 320x200 --png --out " + out.string() + " " +
          variant + " --isolate-keys " + kPump + (moved ? " --changes " + move.changes.string() : ""));
      ASSERT_EQ(r.exit_code, 0) << r.output;
      const std::vector<uint32_t> ids = idsFromRgba(readPngRgba(out / "ids_00000.png").rgba);
      size_t at_old = 0, at_new = 0, elsewhere = 0;
      for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
          const uint32_t id = ids[size_t(y) * width + x];
          if (id == 0 || std::find(pump.begin(), pump.end(), id - 1) == pump.end()) continue;
          if (old_rect.contains(x + 0.5, y + 0.5, 1.5)) ++at_old;
          else if (new_rect.contains(x + 0.5, y + 0.5, 1.5)) ++at_new;
          else ++elsewhere;
        }
      if (moved) {
        EXPECT_EQ(at_old, 0u) << "nothing of the pump stays at its old place";
        EXPECT_GT(at_new, 100u) << "the pump shows at its new place";
      } else {
        EXPECT_GT(at_old, 100u) << "the pump shows where it stands";
        EXPECT_EQ(at_new, 0u);
      }
      EXPECT_EQ(elsewhere, 0u);
    }
  }
}

// A moved object measures where it was moved: `measure --changes` between the two pumps of a
// pair, one moved 0.5 m farther from the other, gives the distance 0.5 m longer.
TEST(ChangeSet, AMovedObjectMeasuresAtItsNewPlace) {
  const fs::path dir = test::scratchDir();
  const std::string package = test::generatedPlant().package.string();
  auto distance = [&](const std::string& extra) {
    const test::CommandResult r =
        test::runTerawalk("measure " + package + " --between P-1001-A P-1001-B --json" + extra);
    EXPECT_EQ(r.exit_code, 0) << r.output;
    return r.exit_code == 0 ? nlohmann::json::parse(r.output)["distance_m"].get<double>() : -1.0;
  };
  const PackageView view = PackageView::open(test::generatedPlant().package);
  glm::dvec3 a_lo, a_hi, b_lo, b_hi;
  ASSERT_TRUE(objectsBounds(view, objectsWithKeys(view, {"P-1001-A"}), a_lo, a_hi));
  ASSERT_TRUE(objectsBounds(view, objectsWithKeys(view, {"P-1001-B"}), b_lo, b_hi));
  const glm::dvec3 away = glm::normalize(0.5 * (b_lo + b_hi) - 0.5 * (a_lo + a_hi));
  // The pumps stand side by side along one axis: away along it.
  glm::dvec3 axis(0.0);
  const int i = std::abs(away.x) > std::abs(away.y) ? 0 : 1;
  axis[i] = away[i] > 0 ? 1.0 : -1.0;
  ChangeSet set;
  Change move = makeChange(Change::Kind::Move, "P-1001-B", "test", "2026-12-06T00:00:00Z");
  move.old_pivot = 0.5 * (b_lo + b_hi);
  move.new_pivot = move.old_pivot + 0.5 * axis;
  move.transform = moveTransform(move.old_pivot, 0.5 * axis);
  set.add(move);
  writeChangeSet(dir / "c.json", set);
  const double before = distance(""), after = distance(" --changes " + (dir / "c.json").string());
  EXPECT_NEAR(after - before, 0.5, 1e-6) << before << " then " << after;
}

TEST(ChangeSet, ApplyingAMoveToTheScenePutsThePumpAtItsNewPlaceInTheNewPackage) {
  const fs::path dir = test::scratchDir();
  const PumpMove move = movePump(dir, {0.4, -1.25, 0.0});
  const fs::path scene = dir / "moved.tws", package = dir / "moved.twk";
  test::CommandResult r = test::runTerawalk("changes apply " + test::generatedPlant().scene.string() +
                                            " " + move.changes.string() + " -o " + scene.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("1 objects moved"), std::string::npos) << r.output;
  r = test::runTerawalk("preprocess --quiet " + scene.string() + " -o " + package.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const PackageView view = PackageView::open(package);
  glm::dvec3 lo, hi;
  ASSERT_TRUE(objectsBounds(view, objectsWithKeys(view, {kPump}), lo, hi));
  // Both packages quantize positions on their own grids: a few tens of micrometres.
  EXPECT_LE(glm::length(lo - (move.lo + move.by)), 1e-3);
  EXPECT_LE(glm::length(hi - (move.hi + move.by)), 1e-3);

  // A key the scene lacks: an error naming it, and nothing written.
  std::ofstream(dir / "ghost.json") << "{\"terawalk_changes\": 1, \"changes\": [{\"kind\": \"move\", "
                                       "\"key\": \"P-0000\", \"transform\": [1,0,0,0,0,1,0,0,0,0,1,0,1,0,0,1], "
                                       "\"old_pivot\": [0,0,0], \"new_pivot\": [1,0,0]}]}";
  r = test::runTerawalk("changes apply " + test::generatedPlant().scene.string() + " " +
                        (dir / "ghost.json").string() + " -o " + (dir / "ghost.tws").string());
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("has the key 'P-0000'; nothing written"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir / "ghost.tws"));
}

// For IFC input the moves go back into a copy of the IFC: a wall of bcf-architectural.ifc moved
// and turned gets a new IfcLocalPlacement, and the copy, imported again, has the wall where the
// change set put it and every other product where it was.
TEST(ChangeSet, AnIfcModelGetsItsMovedProductsPlacedAnewInACopy) {
  const fs::path dir = test::scratchDir();
  const fs::path ifc = fs::path(TW_SHARED_DATA_DIR) / "bcf-architectural.ifc";
  const std::string wall = "1BGpia0iv9cfH1lqT0_P80", other = "1E8YkwPMfB$h99jtn_uAjI";
  test::CommandResult r = test::runTerawalk("-q preprocess " + ifc.string() + " -o " + (dir / "a.twk").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  glm::dvec3 lo, hi, other_lo, other_hi;
  {
    const PackageView view = PackageView::open(dir / "a.twk");
    ASSERT_TRUE(objectsBounds(view, objectsWithKeys(view, {wall}), lo, hi));
    ASSERT_TRUE(objectsBounds(view, objectsWithKeys(view, {other}), other_lo, other_hi));
  }
  // Turned 90 degrees about Z around its centre, then moved 0.5 m along X and 0.25 m along Y.
  const glm::dvec3 centre = 0.5 * (lo + hi), by(0.5, 0.25, 0.0);
  ChangeSet set;
  Change move = makeChange(Change::Kind::Move, wall, "test", "2026-12-06T00:00:00Z");
  move.old_pivot = centre;
  move.new_pivot = centre + by;
  move.transform = moveTransform(centre, by, {0, 0, 1}, 0.5 * 3.14159265358979323846);
  set.add(move);
  writeChangeSet(dir / "c.json", set);
  r = test::runTerawalk("changes apply " + ifc.string() + " " + (dir / "c.json").string() + " -o " +
                        (dir / "moved.ifc").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("1 products placed anew"), std::string::npos) << r.output;
  r = test::runTerawalk("-q preprocess " + (dir / "moved.ifc").string() + " -o " + (dir / "m.twk").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const PackageView view = PackageView::open(dir / "m.twk");
  glm::dvec3 mlo, mhi, olo, ohi;
  ASSERT_TRUE(objectsBounds(view, objectsWithKeys(view, {wall}), mlo, mhi));
  ASSERT_TRUE(objectsBounds(view, objectsWithKeys(view, {other}), olo, ohi));
  const glm::dvec3 half = 0.5 * (hi - lo);
  const glm::dvec3 turned(half.y, half.x, half.z);  // X and Y extents swap
  EXPECT_LE(glm::length(0.5 * (mlo + mhi) - (centre + by)), 1e-4);
  EXPECT_LE(glm::length(0.5 * (mhi - mlo) - turned), 1e-4);
  EXPECT_LE(glm::length(olo - other_lo), 1e-4) << "the other wall stays";
  EXPECT_LE(glm::length(ohi - other_hi), 1e-4);

  // A scale has no IFC placement: refused, naming the product; nothing written.
  ChangeSet scaled;
  Change grow = move;
  grow.transform = moveTransform(centre, glm::dvec3(0.0), {0, 0, 1}, 0.0, 1.5);
  scaled.add(grow);
  writeChangeSet(dir / "s.json", scaled);
  r = test::runTerawalk("changes apply " + ifc.string() + " " + (dir / "s.json").string() + " -o " +
                        (dir / "scaled.ifc").string());
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("the move scales it, which an IFC placement cannot say"), std::string::npos)
      << r.output;
  EXPECT_FALSE(fs::exists(dir / "scaled.ifc"));
}

}  // namespace
}  // namespace tw
