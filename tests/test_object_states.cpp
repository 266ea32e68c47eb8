// Per-object state (runtime/object_states.h) as the renderer shows it: hidden layers and isolated
// objects in the id images of a generated plant, from far (coarse clusters, far proxies) to near,
// with pages evicted and reloaded on the way, and hidden objects occluding nothing.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <set>
#include <string>

#include "image_compare.h"
#include "object_states.h"
#include "package_view.h"
#include "generated_plant_support.h"
#include "test_support.h"

namespace tw {
namespace {

TEST(ObjectStates, CountsHiddenObjectsInRanges) {
  ObjectStates states(10);
  EXPECT_TRUE(states.noneHidden());
  EXPECT_FALSE(states.allHidden(0, 9));
  states.set(3, kObjectHidden, true);
  states.set(4, kObjectHidden, true);
  EXPECT_TRUE(states.allHidden(3, 4));
  EXPECT_FALSE(states.allHidden(2, 4));
  EXPECT_TRUE(states.anyHidden(0, 3));
  EXPECT_FALSE(states.anyHidden(5, 9));
  EXPECT_FALSE(states.allHidden(4, 400));  // clamped to the table: 5..9 show
  EXPECT_TRUE(states.anyHidden(4, 400));
  states.markUploaded();
  states.set(4, kObjectHidden, true);  // no change
  EXPECT_FALSE(states.changed());
  states.setAll(kObjectHidden, false);
  EXPECT_TRUE(states.changed());
  EXPECT_TRUE(states.noneHidden());
  states.set(7, kObjectSelected, true);
  EXPECT_TRUE(states.noneHidden());
  EXPECT_EQ(states.flags(7), kObjectSelected);
}

// Renders `path_args` (an orbit or a fly-through) with `extra` flags; returns every frame's ids.
std::vector<std::vector<uint32_t>> renderIds(const std::filesystem::path& dir,
                                             const std::string& name, const std::string& path_args,
                                             const std::string& extra,
                                             nlohmann::json* summary = nullptr) {
  const auto out = dir / name;
  test::CommandResult r = test::runTerawalk("render --quiet " + test::generatedPlant().package.string() + " " +
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

}  // namespace
}  // namespace tw
