// Occlusion culling in the frame loop, on llvmpipe: a wall hides a field of balls. hzb draws far
// fewer clusters than off with an identical id image; walking around the wall, every frame's id
// image equals the unculled one (the second pass catches what becomes visible in the same frame);
// pvs filters the cut through a view cell's visible set; off draws the whole cut.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <thread>

#include "camera_test_support.h"
#include "egl_context.h"
#include "frame_loop.h"
#include "package_rewrite.h"
#include "preprocess_driver.h"
#include "test_support.h"
#include "tws_writer.h"
#include "visibility_section.h"

namespace tw {
namespace {

namespace fs = std::filesystem;

constexpr uint32_t kBallsX = 4, kBallsY = 6, kBallsZ = 3;
constexpr uint32_t kBalls = kBallsX * kBallsY * kBallsZ;

// A UV sphere: curved, so simplification has a real error and the LOD keeps balls apart.
TriangleMesh sphere(float radius, int rings, int segments) {
  TriangleMesh mesh;
  for (int i = 0; i <= rings; ++i) {
    const double theta = M_PI * i / rings;
    for (int j = 0; j < segments; ++j) {
      const double phi = 2.0 * M_PI * j / segments;
      mesh.positions.push_back(radius * glm::vec3(std::sin(theta) * std::cos(phi),
                                                  std::sin(theta) * std::sin(phi),
                                                  std::cos(theta)));
    }
  }
  for (int i = 0; i < rings; ++i)
    for (int j = 0; j < segments; ++j) {
      const uint32_t a = i * segments + j, b = i * segments + (j + 1) % segments;
      const uint32_t c = a + segments, d = b + segments;
      mesh.indices.insert(mesh.indices.end(), {a, c, d, a, d, b});
    }
  return mesh;
}

// Object 0: a wall 0.4 m thick, 24 m wide (y), 12 m high, at x = 0. Objects 1..kBalls: balls
// behind it (x from 6 to 12 m), all within the wall's shadow seen from x = -10 m.
fs::path wallPackage() {
  static const fs::path path = [] {
    const fs::path dir = test::processScratchDir("occlusion_culling");
    const fs::path scene = dir / "wall.tws";
    {
      TwsWriter writer(scene);
      writer.onLayer(0, {"scene", 0xff808080u});
      SceneObject wall;
      wall.info.id = 0;
      wall.info.name = "wall";
      wall.info.transform.origin = glm::dvec3(0.0, 0.0, 6.0);
      wall.geometry = test::subdividedBox(glm::vec3(0.2f, 12.0f, 6.0f), 6);
      writer.onObject(wall);
      uint32_t id = 1;
      for (uint32_t ix = 0; ix < kBallsX; ++ix)
        for (uint32_t iy = 0; iy < kBallsY; ++iy)
          for (uint32_t iz = 0; iz < kBallsZ; ++iz) {
            SceneObject ball;
            ball.info.id = id;
            ball.info.name = "ball " + std::to_string(id);
            ball.info.transform.origin =
                glm::dvec3(6.0 + 2.0 * ix, -7.5 + 3.0 * iy, 2.5 + 3.0 * iz);
            ball.geometry = sphere(0.6f, 12, 16);
            writer.onObject(ball);
            ++id;
          }
      writer.finish();
    }
    const fs::path out = dir / "wall.twk";
    PreprocessOptions options;
    options.inputs = {scene};
    options.output = out;
    options.visibility = false;  // the pvs test adds its own section
    runPreprocess(options);
    return out;
  }();
  return path;
}

using test::lookingAt;

const glm::dvec3 kFront(-10.0, 0.0, 6.0);   // sees only the wall
const glm::dvec3 kTarget(8.0, 0.0, 6.0);    // the balls' centre

WalkthroughOptions smallOptions(OcclusionMode mode) {
  WalkthroughOptions options;
  options.width = 192;
  options.height = 128;
  options.occlusion = mode;
  options.prefetch = false;
  options.hzb.rest_after_frames = 0;  // the culling itself; resting has a test of its own
  return options;
}

// Renders until nothing has been missing (every page the cut wants resident) and the pager has
// been idle (nothing queued, loading or waiting for upload) for three frames in a row, or 2,000
// frames. One complete frame is not enough: on the frame the last pages arrive the cut changes,
// none of it was visible the frame before, and without the final-depth rebuild the whole cut is
// next frame's pass 1; the frame after that is the steady one. The pager must be idle too, because
// pages wanted outside the cut (a cell's occluders) leave the queue while a loader still decodes
// them, and a loaded machine may take many frames to finish.
FrameStats settle(Walkthrough& walk, const Camera& camera) {
  FrameStats stats;
  int complete_frames = 0;
  for (int i = 0; i < 2000 && complete_frames < 3; ++i) {
    stats = walk.renderFrame(camera, 0.0);
    const PagerStats pager = walk.pager().stats();
    const bool idle = pager.pages_requested + pager.pages_loading + pager.pages_ready == 0;
    const bool complete = stats.ancestor_fallbacks == 0 && idle;
    complete_frames = complete ? complete_frames + 1 : 0;
    if (!idle) std::this_thread::sleep_for(std::chrono::milliseconds(1));  // let the loaders run
  }
  return stats;
}

// Pixels whose id or depth differs between the frame just drawn and the same cut drawn unculled.
size_t lostPixels(Walkthrough& walk, size_t* ball_pixels = nullptr) {
  std::vector<uint32_t> culled, unculled;
  std::vector<float> culled_depth, unculled_depth;
  walk.renderer().readObjectIds(culled);
  walk.renderer().readDepth(culled_depth);
  walk.redrawUnculled();
  walk.renderer().readObjectIds(unculled);
  walk.renderer().readDepth(unculled_depth);
  size_t lost = 0;
  for (size_t i = 0; i < culled.size(); ++i)
    lost += culled[i] != unculled[i] || culled_depth[i] != unculled_depth[i];
  if (ball_pixels) {
    *ball_pixels = 0;
    for (uint32_t id : unculled) *ball_pixels += id > 1;  // id = object + 1; the wall is 1
  }
  return lost;
}

class OcclusionCulling : public ::testing::Test {
 protected:
  EglContext context_;
};

TEST(OcclusionModes, NamesRoundTripAndBadNamesThrow) {
  for (OcclusionMode mode : {OcclusionMode::Off, OcclusionMode::Hzb, OcclusionMode::Pvs})
    EXPECT_EQ(parseOcclusionMode(occlusionModeName(mode)), mode);
  EXPECT_THROW(parseOcclusionMode("HZB"), std::invalid_argument);
  EXPECT_THROW(parseOcclusionMode(""), std::invalid_argument);
  EXPECT_EQ(hzbTestLevel(1280, 720), 2);  // 320 x 180
  EXPECT_EQ(hzbTestLevel(320, 200), 0);
  EXPECT_EQ(hzbTestLevel(321, 1), 1);
  EXPECT_EQ(hzbTestLevel(3840, 2160), 4);  // 240 wide
}

TEST_F(OcclusionCulling, OffDrawsTheWholeCut) {
  Walkthrough walk(wallPackage(), smallOptions(OcclusionMode::Off));
  const FrameStats stats = settle(walk, lookingAt(kFront, kTarget));
  EXPECT_GT(stats.nodes_drawn, 0u);
  EXPECT_EQ(stats.occlusion_culled, 0u);
  EXPECT_EQ(stats.pass1_clusters + stats.pass2_clusters, 0u);
  EXPECT_EQ(stats.hzb_build_ms, 0.0);
  EXPECT_EQ(stats.view_cell, -1);
  EXPECT_EQ(walk.redrawUnculled(), stats.triangles_drawn);
  EXPECT_EQ(lostPixels(walk), 0u);
}

TEST_F(OcclusionCulling, HzbCullsWhatTheWallHidesAndLosesNoPixel) {
  const Camera front = lookingAt(kFront, kTarget);
  Walkthrough off(wallPackage(), smallOptions(OcclusionMode::Off));
  const FrameStats off_stats = settle(off, front);
  Walkthrough hzb(wallPackage(), smallOptions(OcclusionMode::Hzb));
  settle(hzb, front);
  const FrameStats stats = hzb.renderFrame(front, 0.0);  // steady: last frame's visible set known
  // The same cut, far less drawn.
  EXPECT_EQ(stats.nodes_drawn + stats.occlusion_culled, off_stats.nodes_drawn);
  EXPECT_GT(stats.occlusion_culled, 0u);
  EXPECT_LT(stats.nodes_drawn * 3, off_stats.nodes_drawn)
      << "hzb " << stats.nodes_drawn << " clusters, off " << off_stats.nodes_drawn;
  EXPECT_LT(stats.triangles_drawn * 3, off_stats.triangles_drawn);
  EXPECT_GT(stats.pass1_clusters, 0u);
  EXPECT_GT(stats.hzb_build_ms, 0.0);
  EXPECT_EQ(stats.view_cell, -1);  // no visibility section: two passes only
  EXPECT_EQ(lostPixels(hzb), 0u);
  // And the same image as the walkthrough that never culls.
  std::vector<uint32_t> a, b;
  hzb.renderFrame(front, 0.0);
  hzb.renderer().readObjectIds(a);
  off.renderFrame(front, 0.0);
  off.renderer().readObjectIds(b);
  EXPECT_EQ(a, b);
}

TEST_F(OcclusionCulling, BallsAppearInTheFrameTheyBecomeVisible) {
  Walkthrough walk(wallPackage(), smallOptions(OcclusionMode::Hzb));
  settle(walk, lookingAt(kFront, kTarget));
  // Step sideways past the wall's end (y = 12 m) in 1 m steps, to y = 24 m, always looking at the balls:
  // they come into view a few at a time, and no frame may miss a pixel of them.
  size_t first_visible_step = 0, max_ball_pixels = 0;
  uint32_t max_pass2 = 0;
  for (int step = 1; step <= 24; ++step) {
    const Camera camera = lookingAt(kFront + glm::dvec3(0.0, 1.0 * step, 0.0), kTarget);
    const FrameStats stats = walk.renderFrame(camera, step / 30.0);
    size_t ball_pixels = 0;
    EXPECT_EQ(lostPixels(walk, &ball_pixels), 0u) << "step " << step;
    if (ball_pixels > 0 && first_visible_step == 0) {
      first_visible_step = size_t(step);
      // Not visible the frame before, so nothing of them was in pass 1: pass 2 drew them.
      EXPECT_GT(stats.pass2_clusters, 0u) << "step " << step;
    }
    max_ball_pixels = std::max(max_ball_pixels, ball_pixels);
    if (std::getenv("TW_TEST_VERBOSE"))
      std::printf("step %d: drawn %u culled %u pass1 %u pass2 %u ball px %zu\n", step,
                  stats.nodes_drawn, stats.occlusion_culled, stats.pass1_clusters,
                  stats.pass2_clusters, ball_pixels);
    max_pass2 = std::max(max_pass2, stats.pass2_clusters);
  }
  EXPECT_GT(first_visible_step, 1u) << "the balls must start hidden";
  EXPECT_GT(max_ball_pixels, 200u) << "the path must reveal the balls";
  EXPECT_GT(max_pass2, 0u);
}

TEST_F(OcclusionCulling, TurningAroundKeepsTheImageExact) {
  // Big rotations between frames: last frame's visible set says little, pass 2 does the work.
  // Both ways of choosing next frame's visible set.
  for (bool rebuild : {false, true}) {
    WalkthroughOptions options = smallOptions(OcclusionMode::Hzb);
    options.hzb.rebuild_from_final_depth = rebuild;
    Walkthrough walk(wallPackage(), options);
    const glm::dvec3 eye(3.0, 0.0, 6.0);  // between the wall and the balls
    for (int step = 0; step < 10; ++step) {
      Camera camera = lookingAt(eye, kTarget);
      camera.yaw_rad += step * M_PI / 4.0;
      const FrameStats stats = walk.renderFrame(camera, step / 30.0);
      EXPECT_EQ(lostPixels(walk), 0u) << "step " << step << " rebuild " << rebuild;
      if (step >= 8) {  // the second turn: last frame's set is the one before, not stale
        EXPECT_GT(stats.pass1_clusters, 0u) << "step " << step << " rebuild " << rebuild;
      }
    }
    // Read-back widths: the full-resolution pyramid and a very coarse one lose nothing either.
    for (int width : {1024, 24}) {
      options.hzb.read_width_px = width;
      Walkthrough narrow(wallPackage(), options);
      settle(narrow, lookingAt(kFront, kTarget));
      const FrameStats stats = narrow.renderFrame(lookingAt(kFront, kTarget), 0.0);
      EXPECT_GT(stats.occlusion_culled, 0u) << "width " << width;
      EXPECT_EQ(lostPixels(narrow), 0u) << "width " << width;
    }
  }
}

// A visibility section by hand: one cell around kFront whose visible set is the wall's level-0
// clusters (the balls are hidden from there), over a 4 x 4 x 4 grid of 8 m cells.
void addVisibility(const fs::path& package, glm::uvec3* cell_coord) {
  std::vector<uint32_t> wall_clusters;
  uint32_t candidate_count = 0;
  {
    const PackageView view = PackageView::open(package);
    for (uint32_t c = 0; c < view.clusters().size(); ++c) {
      const pkg::ClusterRecord& r = view.clusters()[c];
      if (r.kind != uint8_t(pkg::ClusterKind::Mesh) || r.level != 0) continue;
      ++candidate_count;
      if (r.object_min == 0) wall_clusters.push_back(c);
    }
    VisibilityData data;
    data.grid_dims = glm::uvec3(4, 4, 4);
    data.grid_min = glm::dvec3(-16.0, -15.0, -9.0) - view.origin();
    data.cell_size_m = 8.0;
    data.candidate_level = 0;
    data.visible_sets = true;
    data.rays_per_cell = 1;
    const glm::dvec3 local = (kFront - glm::dvec3(-16.0, -15.0, -9.0)) / 8.0;
    *cell_coord = glm::uvec3(local);
    VisibilityCell cell;
    cell.grid_index = cell_coord->x + 4 * (cell_coord->y + 4 * cell_coord->z);
    cell.visible = wall_clusters;
    cell.occluders = wall_clusters;
    cell.occluder_coverage = 1.0f;
    cell.hit_fraction = 1.0f;
    data.cells.push_back(cell);
    const std::vector<uint8_t> bytes = encodeVisibility(data);
    replacePackageSection(package, pkg::SectionType::Visibility, bytes);
  }
  ASSERT_GT(candidate_count, wall_clusters.size());
  ASSERT_FALSE(wall_clusters.empty());
}

TEST_F(OcclusionCulling, PvsFiltersTheCutInsideAStoredCell) {
  const fs::path package = test::scratchDir() / "wall_pvs.twk";
  fs::copy_file(wallPackage(), package);
  glm::uvec3 cell_coord;
  addVisibility(package, &cell_coord);

  const Camera front = lookingAt(kFront, kTarget);
  Walkthrough off(package, smallOptions(OcclusionMode::Off));
  const FrameStats off_stats = settle(off, front);
  Walkthrough pvs(package, smallOptions(OcclusionMode::Pvs));
  ASSERT_TRUE(pvs.occlusionCuller().hasVisibleSets());
  const FrameStats stats = settle(pvs, front);
  EXPECT_EQ(stats.view_cell, int64_t(cell_coord.x + 4 * (cell_coord.y + 4 * cell_coord.z)));
  EXPECT_GT(stats.occlusion_culled, 0u);
  EXPECT_EQ(stats.nodes_drawn + stats.occlusion_culled, off_stats.nodes_drawn);
  EXPECT_LT(stats.triangles_drawn, off_stats.triangles_drawn);
  // The set is right from here: nothing visible was dropped.
  EXPECT_EQ(lostPixels(pvs), 0u);

  // Outside every stored cell nothing is filtered.
  const Camera outside = lookingAt(glm::dvec3(-10.0, 14.0, 6.0), kTarget);
  const FrameStats outside_stats = settle(pvs, outside);
  EXPECT_EQ(outside_stats.view_cell, -1);
  EXPECT_EQ(outside_stats.occlusion_culled, 0u);

  // hzb on the same package draws the cut's clusters standing for the cell's occluders first.
  Walkthrough hzb(package, smallOptions(OcclusionMode::Hzb));
  FrameStats hzb_stats = settle(hzb, front);
  hzb_stats = hzb.renderFrame(front, 0.0);
  EXPECT_EQ(hzb_stats.occluders_drawn, 0u);  // seed: last frame's visible set is enough now
  EXPECT_GE(hzb_stats.view_cell, 0);
  EXPECT_EQ(lostPixels(hzb), 0u);
  // With no visible set (forgotten by a mode switch), the occluders alone make pass 1 and hide
  // the balls.
  hzb.setOcclusion(OcclusionMode::Off);
  hzb.setOcclusion(OcclusionMode::Hzb);
  const FrameStats first = hzb.renderFrame(front, 0.0);
  EXPECT_GT(first.occluders_drawn, 0u);
  EXPECT_EQ(first.pass1_clusters, first.occluders_drawn);
  EXPECT_GT(first.occlusion_culled, 0u);
  EXPECT_EQ(lostPixels(hzb), 0u);

  // The coarse path draws the occluder clusters themselves into a depth copy instead.
  WalkthroughOptions coarse_options = smallOptions(OcclusionMode::Hzb);
  coarse_options.hzb.occluders = HzbOptions::Occluders::Coarse;
  Walkthrough coarse(package, coarse_options);
  settle(coarse, front);  // the occluders' pages load
  coarse.setOcclusion(OcclusionMode::Off);
  coarse.setOcclusion(OcclusionMode::Hzb);
  const FrameStats coarse_first = coarse.renderFrame(front, 0.0);
  EXPECT_GT(coarse_first.occluders_drawn, 0u);
  EXPECT_EQ(coarse_first.pass1_clusters, 0u);
  EXPECT_GT(coarse_first.occlusion_culled, 0u);
}

// The wall as a parametric box, a floor in front of it, the balls and a row of parametric pipes
// behind it, built by
// the preprocessor with its own visibility stage, with and without parametric candidates.
fs::path parametricWallPackage(const fs::path& dir, bool parametric_occluders) {
  const fs::path scene = dir / "parametric_wall.tws";
  {
    TwsWriter writer(scene);
    writer.onLayer(0, {"scene", 0xff808080u});
    SceneObject wall;
    wall.info.id = 0;
    wall.info.name = "wall";
    wall.info.transform.origin = glm::dvec3(0.0, 0.0, 6.0);
    wall.geometry = Primitive{Box{glm::vec3(0.2f, 12.0f, 6.0f)}};
    writer.onObject(wall);
    SceneObject floor;  // in front of the wall, so the view cells reach the camera
    floor.info.id = 1;
    floor.info.name = "floor";
    floor.info.transform.origin = glm::dvec3(-8.5, 0.0, -0.25);
    floor.geometry = test::subdividedBox(glm::vec3(7.5f, 12.0f, 0.25f), 4);
    writer.onObject(floor);
    uint32_t id = 2;
    for (uint32_t ix = 0; ix < kBallsX; ++ix)
      for (uint32_t iy = 0; iy < kBallsY; ++iy) {
        SceneObject ball;
        ball.info.id = id;
        ball.info.name = "ball " + std::to_string(id++);
        ball.info.transform.origin = glm::dvec3(6.0 + 2.0 * ix, -7.5 + 3.0 * iy, 5.5);
        ball.geometry = sphere(0.6f, 12, 16);
        writer.onObject(ball);
      }
    for (uint32_t iy = 0; iy < 6; ++iy) {
      SceneObject pipe;  // vertical, 4 m tall, from z = 2
      pipe.info.id = id;
      pipe.info.name = "pipe " + std::to_string(id++);
      pipe.info.transform.origin = glm::dvec3(4.0, -7.5 + 3.0 * iy, 2.0);
      pipe.geometry = Primitive{Cylinder{0.15f, 4.0f, true}};
      writer.onObject(pipe);
    }
    writer.finish();
  }
  const fs::path out = dir / (parametric_occluders ? "with.twk" : "without.twk");
  PreprocessOptions options;
  options.inputs = {scene};
  options.output = out;
  options.visibility = true;
  options.visibility_rays = 512;
  options.view_cell_size_m = 4.0;
  options.parametric_occluders = parametric_occluders;
  runPreprocess(options);
  return out;
}

// With parametric candidates, the visible set seen from in front of a parametric wall holds the
// wall alone: pvs drops the balls and pipes behind it (losing no pixel), and hzb's first frame
// draws the wall as the cell's occluder. Without them the rays went through the wall: pvs keeps
// the balls they reached and every parametric cluster.
TEST_F(OcclusionCulling, ParametricWallIsAnOccluderOfItsViewCells) {
  const Camera front = lookingAt(kFront, kTarget);
  const fs::path dir = test::scratchDir();
  const fs::path with = parametricWallPackage(dir, true);
  const fs::path without = parametricWallPackage(dir, false);

  Walkthrough off(with, smallOptions(OcclusionMode::Off));
  const FrameStats off_stats = settle(off, front);
  EXPECT_GE(off_stats.parametric_clusters_drawn, 2u) << "the wall and the pipes";

  Walkthrough pvs(with, smallOptions(OcclusionMode::Pvs));
  const FrameStats pvs_stats = settle(pvs, front);
  ASSERT_GE(pvs_stats.view_cell, 0);
  EXPECT_LT(pvs_stats.triangles_drawn, off_stats.triangles_drawn) << "the balls are behind the wall";
  EXPECT_EQ(pvs_stats.parametric_clusters_drawn, 1u) << "the wall's cluster";
  EXPECT_EQ(lostPixels(pvs), 0u);

  Walkthrough pvs_without(without, smallOptions(OcclusionMode::Pvs));
  const FrameStats without_stats = settle(pvs_without, front);
  ASSERT_GE(without_stats.view_cell, 0);
  EXPECT_GT(without_stats.triangles_drawn, pvs_stats.triangles_drawn) << "rays reached balls";
  EXPECT_EQ(without_stats.parametric_clusters_drawn, off_stats.parametric_clusters_drawn);

  // hzb, first frame after a mode switch: the wall (the cell's occluder) makes pass 1 alone and
  // hides the balls' clusters.
  Walkthrough hzb(with, smallOptions(OcclusionMode::Hzb));
  settle(hzb, front);
  hzb.setOcclusion(OcclusionMode::Off);
  hzb.setOcclusion(OcclusionMode::Hzb);
  const FrameStats first = hzb.renderFrame(front, 0.0);
  EXPECT_GE(first.occluders_drawn, 1u);
  EXPECT_EQ(first.pass1_clusters, first.occluders_drawn);
  EXPECT_GT(first.occlusion_culled, 0u);
  EXPECT_EQ(lostPixels(hzb), 0u);
}

TEST_F(OcclusionCulling, SwitchingModesAtRunTime) {
  Walkthrough walk(wallPackage(), smallOptions(OcclusionMode::Hzb));
  const Camera front = lookingAt(kFront, kTarget);
  settle(walk, front);
  const FrameStats culled = walk.renderFrame(front, 0.0);
  walk.setOcclusion(OcclusionMode::Off);
  const FrameStats off = walk.renderFrame(front, 0.0);
  EXPECT_EQ(off.occlusion_culled, 0u);
  EXPECT_GT(off.nodes_drawn, culled.nodes_drawn);
  walk.setOcclusion(OcclusionMode::Hzb);
  const FrameStats first = walk.renderFrame(front, 0.0);  // starts over: no pass 1
  EXPECT_EQ(first.pass1_clusters, 0u);
  EXPECT_EQ(lostPixels(walk), 0u);
}

// Resting: frames that hide too little stop building and testing pyramids for a while and draw
// the whole cut, losing no pixel; the last resting frame hands the next a visible set, so culling
// resumes at once where it pays.
TEST_F(OcclusionCulling, RestsWhereOcclusionHidesTooLittleAndResumesWhereItPays) {
  const Camera front = lookingAt(kFront, kTarget);
  {  // Every frame counts as poor: 8 frames, then 24 resting ones, then one probe, then rest again.
    WalkthroughOptions options = smallOptions(OcclusionMode::Hzb);
    options.hzb.rest_after_frames = 8;
    options.hzb.rest_frames = 24;
    options.hzb.min_hidden_share = 2.0;
    Walkthrough walk(wallPackage(), options);
    settle(walk, front);  // a rest may have started while pages loaded: let it end
    for (int i = 0; i < 30 && walk.occlusionCuller().resting(); ++i) walk.renderFrame(front, 0.0);
    ASSERT_FALSE(walk.occlusionCuller().resting());
    int frames_to_rest = 0;  // then a rest starts afresh
    while (!walk.occlusionCuller().resting() && frames_to_rest < 20) {
      walk.renderFrame(front, 0.0);
      ++frames_to_rest;
    }
    ASSERT_TRUE(walk.occlusionCuller().resting());
    EXPECT_LE(frames_to_rest, 8);
    for (int i = 0; i < 24; ++i) {
      const FrameStats stats = walk.renderFrame(front, 0.0);
      EXPECT_EQ(stats.occlusion_culled, 0u) << "resting frame " << i;
      EXPECT_EQ(stats.pass2_clusters, 0u);
      EXPECT_EQ(stats.pass1_clusters, stats.nodes_drawn);
      // No pyramid, except on the last resting frame (the next frame's visible set).
      if (i < 23) EXPECT_EQ(stats.hzb_build_ms, 0.0) << "resting frame " << i;
      else EXPECT_GT(stats.hzb_build_ms, 0.0);
      EXPECT_EQ(lostPixels(walk), 0u) << "resting frame " << i;
    }
    EXPECT_FALSE(walk.occlusionCuller().resting());
    const FrameStats probe = walk.renderFrame(front, 0.0);  // culls with last frame's set
    EXPECT_GT(probe.occlusion_culled, 0u);
    EXPECT_LT(probe.pass1_clusters, probe.nodes_drawn + probe.occlusion_culled);
    EXPECT_EQ(lostPixels(walk), 0u);
    EXPECT_TRUE(walk.occlusionCuller().resting()) << "one poor frame after a rest rests again";
  }
  {  // The defaults: the wall hides most of the cut, so the culler never rests.
    WalkthroughOptions options = smallOptions(OcclusionMode::Hzb);
    options.hzb = HzbOptions{};
    Walkthrough walk(wallPackage(), options);
    settle(walk, front);
    for (int i = 0; i < 40; ++i) {
      const FrameStats stats = walk.renderFrame(front, 0.0);
      EXPECT_FALSE(walk.occlusionCuller().resting()) << "frame " << i;
      EXPECT_GT(stats.occlusion_culled, 0u) << "frame " << i;
    }
  }
}

}  // namespace
}  // namespace tw
