// Picking (runtime/object_pick.h, `terawalk pick`) on a generated plant: the object under a
// pixel, from far (coarse levels and far proxies) and from near, for the NURBS hull, parametric
// pipes and meshes; its point lies on the object; the command prints the same object and its
// database record.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdio>
#include <string>

#include "egl_context.h"
#include "frame_loop.h"
#include "object_pick.h"
#include "page_codec.h"
#include "package_view.h"
#include "generated_plant_support.h"
#include "test_support.h"

namespace tw {
namespace {

constexpr int kWidth = 320, kHeight = 180;

struct View {
  const char* name;
  glm::dvec3 eye, target;
  std::vector<std::string> layers;  // each must show, and be picked, from here
};

TEST(Pick, NamesTheObjectUnderThePixelFromFarAndNear) {
  EglContext context;
  WalkthroughOptions options;
  options.width = kWidth;
  options.height = kHeight;
  options.prefetch = false;
  Walkthrough walk(test::generatedPlant().package, options);
  const PackageView& view = walk.package();
  const glm::dvec3 lo = walk.worldMin(), hi = walk.worldMax();
  const glm::dvec3 centre = 0.5 * (lo + hi);
  const double diagonal = glm::length(hi - lo);
  uint64_t level0 = 0;
  for (const auto& c : view.clusters()) level0 += c.level == 0 ? c.triangle_count : 0;

  const View views[] = {
      // The whole plant from four diagonals away: coarse levels only.
      {"far", centre + glm::dvec3(-1.6, -2.4, 1.2) * diagonal, centre, {"hull"}},
      // Inside the module's second storey, looking along it.
      {"near", {36.0, -16.0, 13.7}, {60.0, -10.0, 13.0}, {"decks and walls", "structure"}},
      // Over the module's piping from above the deck: parametric pipes and elbows.
      {"pipes", {20.0, -30.0, 30.0}, {48.0, -14.0, 8.0}, {"piping process", "piping utility"}},
  };
  for (const View& v : views) {
    SCOPED_TRACE(v.name);
    Camera camera;
    camera.position = v.eye;
    camera.lookAt(v.target);
    camera.far_m = 10.0 * diagonal + glm::length(v.eye - centre);
    bool settled = false;
    const FrameStats stats = walk.renderSettled(camera, &settled);
    EXPECT_TRUE(settled);
    if (std::string(v.name) == "far") {
      EXPECT_LT(stats.triangles_drawn * 4, level0);
    }
    std::vector<uint32_t> ids;
    walk.renderer().readObjectIds(ids, true);
    for (const std::string& layer : v.layers) {
      SCOPED_TRACE(layer);
      // The middle one of the pixels that show the layer.
      std::vector<int> pixels;
      for (int p = 0; p < kWidth * kHeight; ++p)
        if (ids[p] != 0 && view.layerName(view.objects()[ids[p] - 1].layer) == layer)
          pixels.push_back(p);
      ASSERT_FALSE(pixels.empty()) << "the layer should show from here";
      const int p = pixels[pixels.size() / 2], x = p % kWidth, y = p / kWidth;
      const std::optional<Pick> pick = pickPixel(walk.renderer(), camera, x, y);
      ASSERT_TRUE(pick);
      EXPECT_EQ(pick->object, ids[p] - 1);
      // The point is on the object: inside its box, grown by what the level shown may stray.
      const pkg::ObjectRecord& o = view.objects()[pick->object];
      const double slack = 0.05 + 0.01 * pick->distance_m;
      for (int a = 0; a < 3; ++a) {
        EXPECT_GE(pick->world[a], view.origin()[a] + o.aabb_min[a] - slack) << a;
        EXPECT_LE(pick->world[a], view.origin()[a] + o.aabb_max[a] + slack) << a;
      }
      // The command sees the same pixel the same way, and reads the object's record.
      const test::GeneratedPlant& files = test::generatedPlant();
      test::CommandResult r = test::runTerawalk(
          "pick " + files.package.string() + " --eye " + test::vec3Arg(v.eye) + " --target " +
          test::vec3Arg(v.target) + " --size " + std::to_string(kWidth) + "x" +
          std::to_string(kHeight) + " --pixel " + std::to_string(x) + "," + std::to_string(y) +
          " --db " + files.db.string() + " --json");
      ASSERT_EQ(r.exit_code, 0) << r.output;
      const auto j = nlohmann::json::parse(r.output);
      EXPECT_EQ(j["object"], pick->object);
      EXPECT_EQ(j["layer"], layer);
      EXPECT_EQ(j["db_key"], std::string(view.objectDbKey(pick->object)));
      ASSERT_TRUE(j["record"].is_object()) << r.output;
      EXPECT_EQ(j["record"]["db_key"], j["db_key"]);
      for (int a = 0; a < 3; ++a) EXPECT_NEAR(j["point"][a].get<double>(), pick->world[a], 1e-3);
    }
  }
}

// From far, a real MEP model (926 pipes, ducts and fittings) is drawn from simplified clusters
// where small parts have been merged (vertex clustering) or replaced. An object whose triangles
// in the frame's cut are all in simplified clusters shows only through them; picking its pixels
// names it, at a point on its box grown by the clusters' error.
TEST(Pick, NamesTheObjectACoarseClusterStandsFor) {
  const auto model = test::sharedDataDir() / "duplex-mep.obj";
  if (!std::filesystem::exists(model)) GTEST_SKIP() << "shared data not present";
  const auto package = test::processScratchDir("pick_far_proxy") / "duplex-mep.twk";
  test::CommandResult built =
      test::runTerawalk("preprocess --quiet " + model.string() + " -o " + package.string());
  ASSERT_EQ(built.exit_code, 0) << built.output;
  EglContext context;
  WalkthroughOptions options;
  options.width = kWidth;
  options.height = kHeight;
  options.prefetch = false;
  Walkthrough walk(package, options);
  const PackageView& view = walk.package();
  const glm::dvec3 lo = walk.worldMin(), hi = walk.worldMax();
  const glm::dvec3 centre = 0.5 * (lo + hi);
  const double diagonal = glm::length(hi - lo);
  int proxy_pixels_picked = 0, outside_box = 0;
  std::vector<uint8_t> raw;
  DecodedCluster decoded;
  for (double away : {1.5, 3.0, 4.5, 6.0, 9.0}) {
    Camera camera;
    camera.position = centre + glm::dvec3(-0.6, -0.8, 0.5) * (away * diagonal);
    camera.lookAt(centre);
    camera.far_m = 20.0 * diagonal;
    walk.renderSettled(camera);
    std::vector<uint32_t> ids;
    walk.renderer().readObjectIds(ids, true);
    // Per object, the largest error of the simplified clusters that carry it, and whether any
    // full-resolution cluster of the cut does.
    std::vector<float> proxy_error(view.objects().size(), -1.0f);
    std::vector<bool> elsewhere(view.objects().size(), false);
    for (uint32_t c : walk.lastCut()) {
      const pkg::ClusterRecord& r = view.clusters()[c];
      view.readPage(r.page, raw);
      view.decodeCluster(c, raw, decoded);
      for (uint32_t o : decoded.triangle_objects) {
        if (r.error > 0.0f) proxy_error[o] = std::max(proxy_error[o], r.error);
        else elsewhere[o] = true;
      }
    }
    int picked_here = 0;
    for (int p = 0; p < kWidth * kHeight && picked_here < 40; ++p) {
      if (ids[p] == 0) continue;
      const uint32_t object = ids[p] - 1;
      if (proxy_error[object] < 0.0f || elsewhere[object]) continue;
      const int x = p % kWidth, y = p / kWidth;
      SCOPED_TRACE("pixel " + std::to_string(x) + "," + std::to_string(y));
      const std::optional<Pick> pick = pickPixel(walk.renderer(), camera, x, y);
      ASSERT_TRUE(pick);
      EXPECT_EQ(pick->object, object);
      const pkg::ObjectRecord& o = view.objects()[object];
      const double slack = double(proxy_error[object]) + 0.01 * pick->distance_m;
      bool inside = true;
      for (int a = 0; a < 3; ++a)
        inside = inside && pick->world[a] >= view.origin()[a] + o.aabb_min[a] - slack &&
                 pick->world[a] <= view.origin()[a] + o.aabb_max[a] + slack;
      outside_box += !inside;
      ++picked_here;
    }
    std::printf("%.1f diagonals away: %d pixels\n", away, picked_here);
    proxy_pixels_picked += picked_here;
  }
  std::printf("%d pixels of objects drawn only by simplified clusters picked, %d off the "
              "object's grown box\n", proxy_pixels_picked, outside_box);
  EXPECT_GT(proxy_pixels_picked, 10) << "the far views should show simplified clusters";
  // A triangle edge collapse left between two welded parts takes the majority id of its three
  // corners, so it may reach into the neighbour part (cluster_dag.h, "Object ids"): a few
  // pixels may lie off the named object's box, never many.
  EXPECT_LE(outside_box * 50, proxy_pixels_picked);
}

TEST(Pick, NothingUnderThePixelAndBadPixels) {
  const std::string base = "pick " + test::generatedPlant().package.string() +
                           " --eye 0,0,5000 --target 0,0,10000 --size 64x36 --pixel ";
  test::CommandResult sky = test::runTerawalk(base + "10,10 --json");
  ASSERT_EQ(sky.exit_code, 0) << sky.output;
  EXPECT_TRUE(nlohmann::json::parse(sky.output)["object"].is_null());
  test::CommandResult outside = test::runTerawalk(base + "64,0");
  EXPECT_NE(outside.exit_code, 0);
  EXPECT_NE(outside.output.find("outside"), std::string::npos) << outside.output;
  test::CommandResult garbled = test::runTerawalk(base + "ten,3");
  EXPECT_NE(garbled.exit_code, 0);
  EXPECT_NE(garbled.output.find("--pixel"), std::string::npos) << garbled.output;
}

}  // namespace
}  // namespace tw
