// Parametric objects drawn by GPU shaders, on llvmpipe: each impostor type against the same
// primitive finely tessellated and drawn as a mesh (coverage, ids, depth), caps, torus sweep ends,
// ids per object, exact depth against a mesh wall, far-from-origin stability, mode off and auto,
// and the generated plant (parametric pixels, exact --check-occlusion with hzb). Tessellated mode,
// instance by instance, is in test_parametric_tessellated.cpp.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "camera_path.h"
#include "parametrics/parametric_gpu.h"
#include "parametric_render_support.h"

namespace tw {
namespace {

using namespace parametric_test;

TEST(ParametricGpu, ModesRoundTripAndLayoutIsStd430) {
  for (ParametricMode m : {ParametricMode::Impostor, ParametricMode::Tessellated,
                           ParametricMode::Off, ParametricMode::Auto})
    EXPECT_EQ(parseParametricMode(parametricModeName(m)), m);
  EXPECT_EQ(parseParametricMode("auto"), ParametricMode::Auto);
  EXPECT_THROW(parseParametricMode("rays"), std::invalid_argument);
  EXPECT_EQ(sizeof(gpu::GpuInstance), 96u);
  EXPECT_EQ(gpu::kGpuTorusSegment, static_cast<uint32_t>(pkg::PrimitiveType::TorusSegment));
  EXPECT_EQ(gpu::kGpuBox, static_cast<uint32_t>(pkg::PrimitiveType::Box));
  EXPECT_EQ(gpu::kGpuCapped, pkg::kInstanceCapped);
}

// The image of each impostor type matches the same primitive tessellated at 0.1 mm: coverage
// and ids agree but for a thin silhouette band, depth agrees where both cover.
TEST_F(ParametricRendering, EachTypeMatchesAFineTessellation) {
  const Camera camera = lookingAt({3.2, -2.4, 2.2}, {0.0, 0.0, 0.7});
  for (const TypeCase& c : typeCases()) {
    SCOPED_TRACE(c.name);
    const std::vector<Part> parts = {{1, c.primitive, c.transform}};
    const Frame impostor = render(buildPackage(std::string("imp_") + c.name, parts, false), camera,
                                  ParametricMode::Impostor);
    const Frame mesh = render(buildPackage(std::string("mesh_") + c.name, parts, true), camera,
                              ParametricMode::Impostor, OcclusionMode::Off, nullptr, true);
    EXPECT_EQ(impostor.stats.parametric_clusters_drawn, 1u);
    EXPECT_EQ(impostor.stats.parametric_instances_drawn, 1u);
    EXPECT_EQ(impostor.stats.parametric_skipped, 0u);
    EXPECT_EQ(mesh.stats.parametric_clusters_drawn, 0u);
    Agreement g = compare(impostor, mesh, 2e-3);
    EXPECT_GT(g.covered, 1000u);
    EXPECT_LT(g.mismatchShare(), 0.02) << g.mismatched << " of " << g.covered;
    // Depth: relative distance differences; 1e-4 is 0.45 mm at the 4.5 m of the view (the
    // reference's facets lie up to 0.1 mm inside the surface, more along grazing rays).
    EXPECT_LT(g.depthQuantile(0.5), 1e-4);
    EXPECT_LT(g.depthQuantile(0.95), 5e-4) << g.depth_close << " of " << g.both;
    // Colour: the same object colour and lighting formula (the mesh is faceted, the impostor
    // smooth, so compare the mean over the covered pixels).
    double sum_i = 0.0, sum_m = 0.0;
    for (size_t i = 0; i < impostor.ids.size(); ++i)
      if (impostor.ids[i] != 0 && mesh.ids[i] != 0)
        for (int k = 0; k < 3; ++k) {
          sum_i += impostor.rgba[4 * i + k];
          sum_m += mesh.rgba[4 * i + k];
        }
    EXPECT_NEAR(sum_i / std::max(sum_m, 1.0), 1.0, 0.05);
  }
}

// Looking down the axis: a capped cylinder shows its top disc at the centre; an open one shows
// its inside wall around and nothing through the middle.
TEST_F(ParametricRendering, CapsOnlyWhenCapped) {
  const Camera camera = lookingAt({0.001, 0.0, 5.0}, {0.0, 0.0, 0.0});
  for (ParametricMode mode : {ParametricMode::Impostor, ParametricMode::Tessellated})
  for (bool capped : {true, false}) {
    SCOPED_TRACE(std::string(parametricModeName(mode)) + (capped ? " capped" : " open"));
    const fs::path cyl = buildPackage(capped ? "cap_cyl" : "open_cyl",
                                      {{1, Cylinder{0.5f, 1.0f, capped}, placed({0, 0, 0})}}, false);
    const Frame f = render(cyl, camera, mode);
    const glm::ivec2 centre = pixelOf(camera, {0, 0, 1});
    EXPECT_EQ(idAt(f, centre), capped ? 1u : 0u);
    // Inside the rim, a quarter radius in: the cap, or the inner wall further down.
    const glm::ivec2 inner = pixelOf(camera, {0.45, 0.0, 1.0});
    EXPECT_EQ(idAt(f, inner), 1u);
    if (capped) {
      // Cap depth: the plane z = 1 at distance 4 from the eye; reversed Z ~ near / distance.
      EXPECT_NEAR(depthAt(f, centre), 0.05 / 4.0, 0.05 / 4.0 * 0.01);
    } else if (mode == ParametricMode::Tessellated) {
      // The inside wall seen through the open end: its back faces are not culled from here.
      EXPECT_LT(depthAt(f, inner), 0.05 / 4.0 * 0.999);
    } else {
      EXPECT_LT(depthAt(f, inner), 0.05 / 4.0 * 0.99);  // deeper than the top plane
    }
    const fs::path cone = buildPackage(capped ? "cap_cone" : "open_cone",
                                       {{1, Cone{0.3f, 0.6f, 1.0f, capped}, placed({0, 0, 0})}},
                                       false);
    const Frame g = render(cone, camera, mode);
    EXPECT_EQ(idAt(g, centre), capped ? 1u : 0u);
  }
}

// A quarter elbow seen from above: present inside its sweep, absent beyond both ends.
TEST_F(ParametricRendering, TorusSweepEnds) {
  const Camera camera = lookingAt({0.001, 0.0, 6.0}, {0.0, 0.0, 0.0});
  const fs::path pkg = buildPackage(
      "elbow", {{1, TorusSegment{1.0f, 0.2f, float(std::numbers::pi / 2)}, placed({0, 0, 0})}},
      false);
  for (ParametricMode mode : {ParametricMode::Impostor, ParametricMode::Tessellated}) {
    SCOPED_TRACE(parametricModeName(mode));
    const Frame f = render(pkg, camera, mode);
    auto onRing = [&](double deg) {
      const double a = glm::radians(deg);
      return idAt(f, pixelOf(camera, {std::cos(a), std::sin(a), 0.2}));
    };
    EXPECT_EQ(onRing(5), 1u);
    EXPECT_EQ(onRing(45), 1u);
    EXPECT_EQ(onRing(85), 1u);
    EXPECT_EQ(onRing(-10), 0u);
    EXPECT_EQ(onRing(100), 0u);
    EXPECT_EQ(onRing(180), 0u);
    EXPECT_EQ(onRing(270), 0u);
  }
}

// Five objects of five types side by side: the id under each one's centre is that object.
TEST_F(ParametricRendering, IdBufferHoldsEachObject) {
  std::vector<Part> parts = {
      {11, Cylinder{0.3f, 0.6f, true}, placed({-2.0, 0, 0})},
      {12, Cone{0.4f, 0.1f, 0.6f, true}, placed({-1.0, 0, 0})},
      {13, Sphere{0.35f}, placed({0.0, 0, 0.3})},
      {14, TorusSegment{0.3f, 0.1f, 6.2831853f}, placed({1.0, 0, 0.3}, {90, 0, 0})},
      {15, Box{glm::vec3(0.3f)}, placed({2.0, 0, 0.3})},
  };
  const fs::path pkg = buildPackage("five", parts, false);
  const Camera camera = lookingAt({0.0, -6.0, 0.3}, {0.0, 0.0, 0.3});
  Walkthrough* walk = nullptr;
  const Frame f = render(pkg, camera, ParametricMode::Impostor, OcclusionMode::Off, &walk);
  const glm::dvec3 centres[5] = {{-2.0, 0, 0.3}, {-1.0, 0, 0.15}, {0, 0, 0.3}, {1.3, 0, 0.3}, {2.0, 0, 0.3}};
  for (int k = 0; k < 5; ++k) {
    const uint32_t id = idAt(f, pixelOf(camera, centres[k]));
    ASSERT_GT(id, 0u) << "object " << parts[k].id;
    ASSERT_LE(id, walk->package().objects().size());
    EXPECT_EQ(walk->package().objects()[id - 1].id, parts[k].id);
  }
  EXPECT_EQ(f.stats.parametric_instances_drawn, 5u);
  EXPECT_EQ(f.stats.parametric_clusters_drawn, 5u);  // one cluster per type
}

// A cylinder impostor through a mesh wall: exact depth (gl_FragDepth) clips it where the wall
// is, as the fully tessellated scene does.
TEST_F(ParametricRendering, ImpostorCrossingAMeshWallIsClippedByDepth) {
  SceneObject wall;
  wall.info.id = 1;
  wall.info.name = "wall";
  wall.info.color_rgba = 0xff808080u;
  wall.info.transform.origin = glm::dvec3(0.0, 0.0, 1.0);
  wall.geometry = test::subdividedBox(glm::vec3(0.05f, 2.0f, 1.0f), 4);
  const std::vector<Part> pipe = {{2, Cylinder{0.3f, 3.0f, true}, placed({-1.5, 0, 1.0}, {0, 90, 0})}};
  const Camera camera = lookingAt({-2.5, -3.0, 2.2}, {0.0, 0.0, 1.0});
  const Frame impostor =
      render(buildPackage("wall_imp", pipe, false, {wall}), camera, ParametricMode::Impostor);
  const Frame mesh = render(buildPackage("wall_mesh", pipe, true, {wall}), camera,
                            ParametricMode::Impostor, OcclusionMode::Off, nullptr, true);
  const Agreement g = compare(impostor, mesh, 2e-3);
  EXPECT_LT(g.mismatchShare(), 0.02) << g.mismatched << " of " << g.covered;
  EXPECT_GT(g.depthShare(), 0.99);
  size_t pipe_px = 0, wall_px = 0;
  for (uint32_t id : impostor.ids) {
    pipe_px += id != 0 && id != impostor.ids[0] && id == idAt(impostor, pixelOf(camera, {-1.0, 0, 1.0}));
    wall_px += id != 0;
  }
  EXPECT_GT(pipe_px, 500u);
  EXPECT_GT(wall_px, pipe_px);
  // The pipe's far half is behind the wall: its axis point at x = +1 shows the wall.
  EXPECT_NE(idAt(impostor, pixelOf(camera, {1.0, 0, 1.0})),
            idAt(impostor, pixelOf(camera, {-1.0, 0, 1.0})));
}

// The same scene 500 km east and 7000 km north renders the same image: eye-relative in double.
TEST_F(ParametricRendering, FarFromOriginRendersTheSame) {
  const glm::dvec3 far(500000.0, 7000000.0, 0.0);
  std::vector<Part> near_parts = {
      {1, Cylinder{0.05f, 1.5f, true}, placed({0, 0, 0}, {0, 90, 0})},
      {2, TorusSegment{0.3f, 0.05f, float(std::numbers::pi / 2)}, placed({1.5, 0.3, 0.0}, {0, 0, -90})},
      {3, Sphere{0.2f}, placed({0.0, 0.8, 0.2})},
      {4, Box{glm::vec3(1.0f, 1.0f, 0.02f)}, placed({0.5, 0.5, -0.3})},
  };
  std::vector<Part> far_parts = near_parts;
  for (Part& p : far_parts) p.transform.origin += far;
  const Camera near_camera = lookingAt({-0.8, -1.2, 0.9}, {0.7, 0.3, 0.0});
  Camera far_camera = near_camera;
  far_camera.position += far;
  const Frame a = render(buildPackage("origin", near_parts, false), near_camera, ParametricMode::Impostor);
  const Frame b = render(buildPackage("far", far_parts, false), far_camera, ParametricMode::Impostor);
  const Agreement g = compare(a, b, 1e-4);
  EXPECT_GT(g.covered, 5000u);
  EXPECT_LE(g.mismatched, g.covered / 1000) << g.mismatched << " of " << g.covered;
  EXPECT_GT(g.depthShare(), 0.999);
}

// The default resolves by the renderer: these tests run on llvmpipe, where tessellated measured
// faster; explicit modes stay as asked.
TEST_F(ParametricRendering, AutoPicksTessellatedOnLlvmpipe) {
  EXPECT_EQ(resolveParametricMode(ParametricMode::Auto), ParametricMode::Tessellated);
  EXPECT_EQ(resolveParametricMode(ParametricMode::Impostor), ParametricMode::Impostor);
  const fs::path pkg = buildPackage("auto", {{1, Sphere{0.8f}, placed({0, 0, 0})}}, false);
  WalkthroughOptions options;
  options.width = kWidth;
  options.height = kHeight;
  EXPECT_EQ(options.parametrics, ParametricMode::Auto);
  Walkthrough walk(pkg, options);
  EXPECT_EQ(walk.parametrics(), ParametricMode::Tessellated);
  const FrameStats stats = walk.renderFrame(lookingAt({0.0, -4.0, 0.0}, {0, 0, 0}), 0.0);
  EXPECT_GT(stats.parametric_triangles, 0u);
}

TEST_F(ParametricRendering, OffDrawsNoneAndCountsThemSkipped) {
  const fs::path pkg = buildPackage("off", {{1, Sphere{0.8f}, placed({0, 0, 0})},
                                            {2, Box{glm::vec3(0.5f)}, placed({2, 0, 0})}}, false);
  const Camera camera = lookingAt({1.0, -5.0, 1.0}, {1.0, 0.0, 0.0});
  const Frame off = render(pkg, camera, ParametricMode::Off);
  EXPECT_EQ(off.stats.parametric_skipped, 2u);
  EXPECT_EQ(off.stats.parametric_clusters_drawn, 0u);
  for (uint32_t id : off.ids) ASSERT_EQ(id, 0u);
  const Frame on = render(pkg, camera, ParametricMode::Impostor);
  EXPECT_EQ(on.stats.parametric_skipped, 0u);
  EXPECT_EQ(on.stats.parametric_clusters_drawn, 2u);
}
// The generated plant: most of it is parametric. Impostors show it; hzb with parametrics in pass
// 1 loses no pixel against the same cut drawn unculled.
TEST_F(ParametricRendering, GeneratedPlantShowsParametricPixels) {
  const fs::path dir = test::processScratchDir("parametric_renderer");
  const fs::path scene = dir / "plant.tws";
  const test::CommandResult gen =
      test::runTerawalk("gen plant --triangles 200K -o " + scene.string());
  ASSERT_EQ(gen.exit_code, 0) << gen.output;
  const fs::path pkg = dir / "plant.twk";
  PreprocessOptions options;
  options.inputs = {scene};
  options.output = pkg;
  runPreprocess(options);

  const CameraPath path = readCameraPath(test::dataDir() / "paths" / "plant-decks.path");
  Camera base;
  base.near_m = 0.05;
  base.far_m = 5000.0;
  const Camera camera = path.sample(path.keys.front().time_s, base);
  Walkthrough* walk = nullptr;
  const Frame f = render(pkg, camera, ParametricMode::Impostor, OcclusionMode::Hzb, &walk);
  std::set<uint32_t> parametric_objects;
  for (const pkg::InstanceRecord& in : walk->package().instances()) parametric_objects.insert(in.object);
  size_t parametric_px = 0;
  for (uint32_t id : f.ids) parametric_px += id != 0 && parametric_objects.count(id - 1);
  EXPECT_GT(double(parametric_px) / f.ids.size(), 0.3);
  EXPECT_GT(f.stats.parametric_clusters_drawn, 0u);

  // --check-occlusion stays exact: the unculled redraw draws the parametrics too.
  std::vector<uint32_t> culled = f.ids, unculled;
  walk->redrawUnculled();
  walk->renderer().readObjectIds(unculled);
  size_t lost = 0;
  for (size_t i = 0; i < culled.size(); ++i) lost += culled[i] != unculled[i];
  EXPECT_EQ(lost, 0u);

  const Frame off = render(pkg, camera, ParametricMode::Off);
  size_t off_px = 0;
  for (uint32_t id : off.ids) off_px += id != 0 && parametric_objects.count(id - 1);
  EXPECT_EQ(off_px, 0u);
  EXPECT_GT(off.stats.parametric_skipped, 0u);
}

}  // namespace
}  // namespace tw
