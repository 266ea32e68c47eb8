// Per-object state (runtime/object_states.h) as the renderer shows it: hidden layers and isolated
// objects in the id images of a generated plant, from far (coarse clusters, far proxies) to near,
// with pages evicted and reloaded on the way, and hidden objects occluding nothing.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <set>
#include <string>

#include "image_compare.h"
#include "object_states.h"
#include "package_view.h"
#include "generated_plant_support.h"
#include "test_support.h"

namespace tw {
namespace {

TEST(ObjectStates, CountsLooksInRanges) {
  ObjectStates states(10);
  EXPECT_TRUE(states.everyObjectOpaque());
  EXPECT_TRUE(states.allOpaque(0, 9));
  states.set(3, kObjectHidden, true);
  states.set(4, kObjectHidden, true);
  EXPECT_FALSE(states.anyOpaque(3, 4));
  EXPECT_TRUE(states.anyOpaque(2, 4));
  EXPECT_FALSE(states.allOpaque(0, 3));
  EXPECT_TRUE(states.allOpaque(5, 9));
  EXPECT_TRUE(states.anyOpaque(4, 400));  // clamped to the table: 5..9 show
  EXPECT_FALSE(states.allOpaque(4, 400));
  EXPECT_FALSE(states.anyOpaque(40, 400));  // nothing of the table
  states.markUploaded();
  states.set(4, kObjectHidden, true);  // no change
  EXPECT_FALSE(states.changed());
  states.setAll(kObjectHidden, false);
  EXPECT_TRUE(states.changed());
  EXPECT_TRUE(states.everyObjectOpaque());
  states.set(7, kObjectSelected, true);
  EXPECT_TRUE(states.everyObjectOpaque());
  EXPECT_TRUE(states.anySelected());
  EXPECT_EQ(states.flags(7), kObjectSelected);
}

TEST(ObjectStates, XrayGhostsAllButSelectedAndHiddenObjects) {
  ObjectStates states(6);
  states.setAll(kObjectXray, true);
  states.set(2, kObjectSelected, true);  // selected: opaque even when X-rayed
  states.set(4, kObjectHidden, true);    // hidden: drawn nowhere
  EXPECT_EQ(states.look(0), ObjectLook::Ghosted);
  EXPECT_EQ(states.look(2), ObjectLook::Opaque);
  EXPECT_EQ(states.look(4), ObjectLook::Hidden);
  EXPECT_TRUE(drawnIn(states.flags(0), SurfacePass::Xray));
  EXPECT_FALSE(drawnIn(states.flags(0), SurfacePass::Opaque));
  EXPECT_TRUE(drawnIn(states.flags(2), SurfacePass::Opaque));
  EXPECT_FALSE(drawnIn(states.flags(4), SurfacePass::Xray));
  EXPECT_FALSE(states.everyObjectOpaque());
  EXPECT_TRUE(states.anyGhosted());
  EXPECT_FALSE(states.anyOpaque(0, 1));
  EXPECT_TRUE(states.anyOpaque(1, 3));
  EXPECT_FALSE(states.anyGhosted(4, 4));
  EXPECT_TRUE(states.anyGhosted(4, 5));
  states.set(2, kObjectHidden, true);
  EXPECT_FALSE(states.anySelected()) << "a hidden selection shows no outline";
}

// Renders `path_args` (an orbit or a fly-through) of `package` with `extra` flags; returns every
// frame's ids.
std::vector<std::vector<uint32_t>> renderPackageIds(const std::filesystem::path& package,
                                                    const std::filesystem::path& dir,
                                                    const std::string& name,
                                                    const std::string& path_args,
                                                    const std::string& extra,
                                                    nlohmann::json* summary = nullptr) {
  const auto out = dir / name;
  test::CommandResult r = test::runTerawalk("render --quiet " + package.string() + " " +
                                            path_args + " --size 320x180 --png --out " +
                                            out.string() + " " + extra);
  EXPECT_EQ(r.exit_code, 0) << r.output;
  if (summary) *summary = nlohmann::json::parse(test::readFile(out / "summary.json"));
  std::vector<std::vector<uint32_t>> frames;
  for (int i = 0;; ++i) {
    char file[32];
    std::snprintf(file, sizeof file, "ids_%05d.png", i);
    if (!std::filesystem::exists(out / file)) break;
    frames.push_back(idsFromRgba(readPngRgba(out / file).rgba));
  }
  return frames;
}

// The same, of the generated plant.
std::vector<std::vector<uint32_t>> renderIds(const std::filesystem::path& dir,
                                             const std::string& name, const std::string& path_args,
                                             const std::string& extra,
                                             nlohmann::json* summary = nullptr) {
  return renderPackageIds(test::generatedPlant().package, dir, name, path_args, extra, summary);
}

// Pixels per frame whose object satisfies `test` (ids are object index + 1, 0 = nothing).
template <typename Test>
std::vector<uint64_t> pixelsWhere(const std::vector<std::vector<uint32_t>>& frames, Test test) {
  std::vector<uint64_t> out;
  for (const auto& ids : frames) {
    uint64_t n = 0;
    for (uint32_t id : ids) n += id != 0 && test(id - 1);
    out.push_back(n);
  }
  return out;
}

uint64_t sum(const std::vector<uint64_t>& v) {
  uint64_t s = 0;
  for (uint64_t x : v) s += x;
  return s;
}

const std::string kFar = "--orbit 6 --fps 30";  // the whole plant on screen

// From 140 m off the module down into its second storey (the module stands at the site origin),
// two frames a path second: far, coarse levels first, then finer ones, then inside.
std::string nearPath() {
  static const std::filesystem::path path = [] {
    const auto file = test::processScratchDir("object_states_path") / "approach.path";
    test::writeFile(file,
                    "# terawalk camera path 1\n"
                    "# t_s x y z yaw_deg pitch_deg fov_y_deg\n"
                    "0 -100 -16 40 0 -12 60\n"
                    "2 0 -16 20 0 -8 60\n"
                    "4 36 -16 13.7 5 -4 70\n"
                    "6 50 -14 13.7 20 -4 70\n");
    return file;
  }();
  return "--path " + path.string() + " --fps 2";
}

TEST(ObjectStates, AHiddenLayerShowsAtNoDistance) {
  const auto dir = test::scratchDir();
  const PackageView view = PackageView::open(test::generatedPlant().package);
  uint32_t structure = UINT32_MAX;
  for (uint32_t l = 0; l < view.layers().size(); ++l)
    if (view.layerName(l) == "structure") structure = l;
  ASSERT_NE(structure, UINT32_MAX);
  auto in_layer = [&](uint32_t o) { return view.objects()[o].layer == structure; };
  for (const std::string& path : {kFar, nearPath()}) {
    const auto shown = renderIds(dir, "all", path, "");
    ASSERT_FALSE(shown.empty());
    EXPECT_GT(sum(pixelsWhere(shown, in_layer)), 100u) << path << ": the layer should show";
    const auto hidden = renderIds(dir, "hidden", path, "--hide-layer structure");
    ASSERT_EQ(hidden.size(), shown.size());
    EXPECT_EQ(sum(pixelsWhere(hidden, in_layer)), 0u) << path;
    // The rest still shows.
    EXPECT_GT(sum(pixelsWhere(hidden, [&](uint32_t o) { return !in_layer(o); })), 1000u) << path;
  }
  // A pool so small that pages are evicted and loaded again along the approach: the state
  // lives by object, not in the pages.
  nlohmann::json summary;
  const auto tight = renderIds(dir, "tight", nearPath(),
                               "--hide-layer structure --gpu-budget 1M --evict-after 1",
                               &summary);
  const auto frames = nlohmann::json::parse(
      test::readFile(dir / "tight" / "frames.json"));
  uint64_t evicted = 0;
  for (const auto& f : frames.at("frames"))
    evicted = std::max<uint64_t>(evicted, f.value("pages_evicted", 0));
  EXPECT_GT(evicted, 0u) << "the budget should evict pages";
  EXPECT_EQ(sum(pixelsWhere(tight, in_layer)), 0u);
}

TEST(ObjectStates, IsolatedKeysAreAllThatShows) {
  const auto dir = test::scratchDir();
  const PackageView view = PackageView::open(test::generatedPlant().package);
  // The valves' keys: small objects, seen from near only.
  std::set<uint32_t> valves;
  std::string keys;
  for (uint32_t o = 0; o < view.objects().size() && valves.size() < 40; ++o)
    if (view.layerName(view.objects()[o].layer) == "valves" && !view.objectDbKey(o).empty()) {
      keys += (keys.empty() ? "" : ",") + std::string(view.objectDbKey(o));
      valves.insert(o);
    }
  ASSERT_GT(valves.size(), 10u);
  std::set<std::string> key_set;
  for (uint32_t o : valves) key_set.insert(std::string(view.objectDbKey(o)));
  auto isolated = [&](uint32_t o) { return key_set.count(std::string(view.objectDbKey(o))) > 0; };
  for (const std::string& path : {kFar, nearPath()}) {
    const auto frames = renderIds(dir, "isolated", path, "--isolate-keys " + keys);
    EXPECT_EQ(sum(pixelsWhere(frames, [&](uint32_t o) { return !isolated(o); })), 0u) << path;
    if (path != kFar) {
      EXPECT_GT(sum(pixelsWhere(frames, isolated)), 0u) << path;
    }
  }
}

// Inside the module, the decks and walls hidden: what they hid shows, and the two-pass
// occlusion culling loses nothing to them (each frame drawn again unculled gives the same ids).
TEST(ObjectStates, HiddenObjectsOccludeNothing) {
  const auto dir = test::scratchDir();
  nlohmann::json with, without;
  const auto walls = renderIds(dir, "walls", nearPath(), "--check-occlusion", &with);
  const auto no_walls =
      renderIds(dir, "no-walls", nearPath(), "--check-occlusion --hide-layer 'decks and walls'", &without);
  auto distinct = [](const std::vector<std::vector<uint32_t>>& frames) {
    std::set<uint32_t> ids;
    for (const auto& f : frames) ids.insert(f.begin(), f.end());
    return ids.size();
  };
  EXPECT_GT(distinct(no_walls), distinct(walls)) << "objects behind the walls should show";
  EXPECT_LE(without["occlusion_lost_share"].get<double>(), 1e-4);
}

// The share of pixels, over all frames, that show the same scene object (ObjectRecord::id) in
// two renders of two packages, or nothing in both.
double sameObjectShare(const PackageView& a_view, const std::vector<std::vector<uint32_t>>& a,
                       const PackageView& b_view, const std::vector<std::vector<uint32_t>>& b) {
  auto scene_id = [](const PackageView& view, uint32_t id) -> int64_t {
    return id == 0 ? -1 : int64_t(view.objects()[id - 1].id);
  };
  uint64_t same = 0, total = 0;
  for (size_t f = 0; f < std::min(a.size(), b.size()); ++f)
    for (size_t p = 0; p < std::min(a[f].size(), b[f].size()); ++p) {
      same += scene_id(a_view, a[f][p]) == scene_id(b_view, b[f][p]);
      ++total;
    }
  return total ? double(same) / double(total) : 0.0;
}

// A hidden layer occludes nothing, at any distance: along the approach, the plant with its decks
// and walls hidden shows what the same plant built without them shows, object for object (up
// to the simplification of coarse levels, which differs between the two builds), and far more
// so than the plant with them shown does.
TEST(ObjectStates, AHiddenLayerOccludesWhatThePlantWithoutItShows) {
  const auto dir = test::scratchDir();
  const auto without = dir / "without-walls.twk";
  test::CommandResult built =
      test::runTerawalk("preprocess --quiet " + test::generatedPlant().scene.string() + " -o " +
                        without.string() + " --exclude-layer 'decks and walls'");
  ASSERT_EQ(built.exit_code, 0) << built.output;
  const PackageView plant_view = PackageView::open(test::generatedPlant().package);
  const PackageView without_view = PackageView::open(without);
  const auto hidden = renderIds(dir, "hidden", nearPath(), "--hide-layer 'decks and walls'");
  const auto shown = renderIds(dir, "shown", nearPath(), "");
  const auto reference = renderPackageIds(without, dir, "without", nearPath(), "");
  ASSERT_FALSE(reference.empty());
  ASSERT_EQ(hidden.size(), reference.size());
  const double hidden_share = sameObjectShare(plant_view, hidden, without_view, reference);
  const double shown_share = sameObjectShare(plant_view, shown, without_view, reference);
  std::printf("same object: hidden layer %.4f, shown layer %.4f of the pixels\n", hidden_share,
              shown_share);
  EXPECT_GE(hidden_share, 0.995);
  EXPECT_LT(shown_share, hidden_share - 0.05) << "the walls should cover much of the view";
}

// The colour frames of a render made by renderIds (frame_NNNNN.png, RGBA).
std::vector<std::vector<uint8_t>> renderedColors(const std::filesystem::path& dir,
                                                 const std::string& name) {
  std::vector<std::vector<uint8_t>> frames;
  for (int i = 0;; ++i) {
    char file[32];
    std::snprintf(file, sizeof file, "frame_%05d.png", i);
    if (!std::filesystem::exists(dir / name / file)) break;
    frames.push_back(readPngRgba(dir / name / file).rgba);
  }
  return frames;
}

// X-ray: with the equipment isolated and the rest ghosted, the equipment behind the decks and
// walls shows through them. Where the plain render shows a wall and the X-ray render shows
// equipment, the X-ray colour lies most of the way from the wall's colour to the equipment's
// (as drawn with the rest hidden), short of it by the tint of the ghosts in front (each face at
// GlRenderer::kXrayAlpha). Ghosts write no ids, so the X-ray ids hold equipment only.
// `mode`: how parametrics are drawn (--parametrics).
void expectEquipmentThroughWalls(const std::filesystem::path& dir, const std::string& mode) {
  SCOPED_TRACE(mode);
  const PackageView view = PackageView::open(test::generatedPlant().package);
  auto layer_of = [&](uint32_t o) { return std::string(view.layerName(view.objects()[o].layer)); };
  const std::string path = nearPath();
  const std::string drawn = " --parametrics " + mode;
  const auto shown = renderIds(dir, "shown", path, drawn);
  const auto xray = renderIds(dir, "xray", path, "--isolate-layer equipment --xray-others" + drawn);
  const auto alone = renderIds(dir, "alone", path, "--isolate-layer equipment" + drawn);
  const auto shown_rgba = renderedColors(dir, "shown");
  const auto xray_rgba = renderedColors(dir, "xray");
  const auto alone_rgba = renderedColors(dir, "alone");
  ASSERT_FALSE(shown.empty());
  ASSERT_EQ(xray.size(), shown.size());
  ASSERT_EQ(xray_rgba.size(), shown.size());
  ASSERT_EQ(alone_rgba.size(), shown.size());
  EXPECT_EQ(sum(pixelsWhere(xray, [&](uint32_t o) { return layer_of(o) != "equipment"; })), 0u)
      << "ghosts must not write ids";

  // How far each X-ray pixel lies from the wall's colour toward the equipment's, projected on
  // the line between them, summed over the pixels (0: the wall, 1: the equipment untinted).
  uint64_t through = 0;
  double along = 0.0, length2 = 0.0;
  for (size_t f = 0; f < shown.size(); ++f)
    for (size_t p = 0; p < shown[f].size(); ++p) {
      if (shown[f][p] == 0 || xray[f][p] == 0 || alone[f][p] != xray[f][p]) continue;
      if (layer_of(shown[f][p] - 1) != "decks and walls") continue;
      ++through;
      for (int c = 0; c < 3; ++c) {
        const double wall = shown_rgba[f][4 * p + c];
        const double to_equipment = double(alone_rgba[f][4 * p + c]) - wall;
        along += (double(xray_rgba[f][4 * p + c]) - wall) * to_equipment;
        length2 += to_equipment * to_equipment;
      }
    }
  ASSERT_GT(through, 200u) << "equipment should show through the walls";
  ASSERT_GT(length2, 0.0);
  const double share = along / length2;
  std::printf("%s: %llu pixels of equipment behind a wall: their X-ray colour lies %.2f of the "
              "way from the wall's to the equipment's\n",
              mode.c_str(), static_cast<unsigned long long>(through), share);
  EXPECT_GT(share, 0.4) << "what shows is the equipment, not the wall";
  EXPECT_LT(share, 0.97) << "the ghosts in front should tint what shows through";
}

// Both ways of drawing parametrics: tessellated (llvmpipe's default) and ray-cast impostors.
TEST(ObjectStates, XrayShowsWhatIsBehindAWall) {
  const auto dir = test::scratchDir();
  expectEquipmentThroughWalls(dir, "tessellated");
  expectEquipmentThroughWalls(dir, "impostor");
}

// The selection outline: pixels of the outline colour ring the selected objects, within two
// pixels of them, and appear nowhere without a selection. Far and near: it reads the id buffer,
// so it follows the object at whatever level it is drawn.
TEST(ObjectStates, SelectedObjectsAreOutlined) {
  const auto dir = test::scratchDir();
  const PackageView view = PackageView::open(test::generatedPlant().package);
  std::string key;  // the largest piece of equipment
  float largest = 0.0f;
  for (uint32_t o = 0; o < view.objects().size(); ++o) {
    const pkg::ObjectRecord& r = view.objects()[o];
    const float size = (r.aabb_max[0] - r.aabb_min[0]) + (r.aabb_max[1] - r.aabb_min[1]) +
                       (r.aabb_max[2] - r.aabb_min[2]);
    if (view.layerName(r.layer) == "equipment" && size > largest) {
      largest = size;
      key = view.objectDbKey(o);
    }
  }
  ASSERT_FALSE(key.empty());
  const int width = 320, height = 180;
  for (const std::string& path : {kFar, nearPath()}) {
    const auto ids = renderIds(dir, "selected", path, "--select " + key);
    const auto rgba = renderedColors(dir, "selected");
    renderIds(dir, "plain", path, "");
    const auto plain_rgba = renderedColors(dir, "plain");
    ASSERT_EQ(rgba.size(), ids.size());
    auto outline = [](const std::vector<uint8_t>& image, size_t p) {
      return image[4 * p] == 255 && image[4 * p + 1] == 219 && image[4 * p + 2] == 0;
    };
    uint64_t ring = 0, stray = 0, plain = 0;
    for (size_t f = 0; f < ids.size(); ++f)
      for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
          const size_t p = size_t(y) * width + x;
          plain += outline(plain_rgba[f], p);
          if (!outline(rgba[f], p)) continue;
          bool near_selected = false;
          for (int dy = -2; dy <= 2; ++dy)
            for (int dx = -2; dx <= 2; ++dx) {
              const int nx = std::clamp(x + dx, 0, width - 1), ny = std::clamp(y + dy, 0, height - 1);
              const uint32_t id = ids[f][size_t(ny) * width + nx];
              near_selected |= id != 0 && view.objectDbKey(id - 1) == key;
            }
          (near_selected ? ring : stray) += 1;
        }
    std::printf("%s: %llu outline pixels around %s\n", path.c_str(),
                static_cast<unsigned long long>(ring), key.c_str());
    EXPECT_GT(ring, 20u) << path;
    EXPECT_EQ(stray, 0u) << path;
    EXPECT_EQ(plain, 0u) << path;
  }
}

}  // namespace
}  // namespace tw
