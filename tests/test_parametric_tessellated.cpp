// Tessellated mode on llvmpipe: each visible parametric instance drawn at the resolution its own
// distance asks for (parametric_instance_meshes.h), against impostors and fine meshes: coverage,
// resolution by distance, thin things as ribbons and boxes, coarse pipes' width and shading, back faces culled
// only where hidden (closed solids from outside, sealed pipe runs, closed extrusions), far
// extrusions as boxes, instance-by-instance occlusion, the first pass prepared on another
// thread, and the clusters expanded in runs on TBB.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <numbers>
#include <set>
#include <span>
#include <thread>

#include "gl_renderer.h"
#include "package_view.h"
#include "package_summary.h"
#include "package_writer.h"
#include "parametrics/parametric_clusters.h"
#include "parametric_render_support.h"
#include "parametrics/parametric_renderer.h"

namespace tw {
namespace {

using namespace parametric_test;

// One part of each type case, ids from 1, in a row along x 2.6 m apart.
std::vector<Part> typeCaseRow() {
  std::vector<Part> parts;
  uint32_t id = 1;
  for (const TypeCase& c : typeCases()) {
    Part p{id, c.primitive, c.transform};
    p.transform.origin += glm::dvec3(2.6 * (id - 1), 0.0, 0.0);
    parts.push_back(p);
    ++id;
  }
  return parts;
}

// Tessellated mode (meshes by distance) covers what impostor mode covers, within a silhouette
// band, for every type.
TEST_F(ParametricRendering, TessellatedModeCoversLikeImpostors) {
  const std::vector<Part> parts = typeCaseRow();
  const fs::path pkg = buildPackage("all_types", parts, false);
  const Camera camera = lookingAt({6.5, -9.0, 3.0}, {6.5, 0.0, 0.5});
  const Frame impostor = render(pkg, camera, ParametricMode::Impostor);
  const Frame tessellated = render(pkg, camera, ParametricMode::Tessellated);
  EXPECT_GT(tessellated.stats.parametric_triangles, 100u);
  EXPECT_EQ(tessellated.stats.parametric_instances_drawn, parts.size());
  Agreement g = compare(impostor, tessellated, 5e-3);
  EXPECT_GT(g.covered, 2000u);
  EXPECT_LT(g.mismatchShare(), 0.03) << g.mismatched << " of " << g.covered;
  // Half a pixel of chordal error at about 9 m is up to 2.7 cm: depth agrees to about 1 cm.
  EXPECT_LT(g.depthQuantile(0.5), 3e-3);
  EXPECT_GT(g.depthShare(), 0.8);
}

// Tessellated mode, each type on its own against the same primitive tessellated at 0.1 mm: the
// per-instance meshes (unit meshes shaped by the instance's parameters, at a quarter pixel of
// chordal error here) cover the same pixels with the same ids, at nearly the same depth.
TEST_F(ParametricRendering, TessellatedEachTypeMatchesAFineTessellation) {
  const Camera camera = lookingAt({3.2, -2.4, 2.2}, {0.0, 0.0, 0.7});
  std::vector<TypeCase> cases = typeCases();
  // Revolutions are swept from their own profile, simplified to the tolerance: a vessel with
  // elliptical heads (on the axis at both ends), whole and as a half turn.
  std::vector<glm::vec2> vessel;
  for (int k = 0; k <= 8; ++k) {
    const double a = 0.5 * std::numbers::pi * k / 8;
    vessel.push_back({float(0.6 * std::sin(a)), float(0.3 * (1.0 - std::cos(a)))});
  }
  for (int k = 8; k >= 0; --k) {
    const double a = 0.5 * std::numbers::pi * k / 8;
    vessel.push_back({float(0.6 * std::sin(a)), float(1.2 + 0.3 * std::cos(a))});
  }
  cases.push_back({"revolution", Revolution{vessel, 6.2831853f}, placed({0, 0, 0}, {10, -20, 0})});
  cases.push_back({"half_revolution", Revolution{vessel, 3.1415927f}, placed({0, 0, 0}, {0, 0, 200})});
  for (const TypeCase& c : cases) {
    SCOPED_TRACE(c.name);
    const std::vector<Part> parts = {{1, c.primitive, c.transform}};
    const fs::path package = buildPackage(std::string("imp_") + c.name, parts, false);
    const Frame tessellated = render(package, camera, ParametricMode::Tessellated);
    const Frame mesh = render(buildPackage(std::string("mesh_") + c.name, parts, true), camera,
                              ParametricMode::Impostor, OcclusionMode::Off, nullptr, true);
    EXPECT_EQ(tessellated.stats.parametric_instances_drawn, 1u);
    // A box seen from outside submits only the faces turned to the eye (2 to 6 triangles).
    EXPECT_GT(tessellated.stats.parametric_triangles, std::string(c.name) == "box" ? 1u : 10u);
    Agreement g = compare(tessellated, mesh, 2e-3);
    EXPECT_GT(g.covered, 1000u);
    EXPECT_LT(g.mismatchShare(), 0.02) << g.mismatched << " of " << g.covered;
    // A quarter pixel at about 4.5 m is about 7 mm, 1.5e-3 of the distance: the facets lie
    // within it of the surface.
    EXPECT_LT(g.depthQuantile(0.5), 2e-3);
    EXPECT_LT(g.depthQuantile(0.95), 5e-3) << g.depth_close << " of " << g.both;
    // Colour: curved surfaces carry their true normals, so even a coarse mesh (4 px of chordal
    // error) shades much like the fine one; compare per pixel where both show the object. (With
    // facet normals, as the mesh pass has, the sphere and the torus match on under 40 % here.)
    const Frame coarse = render(package, camera, ParametricMode::Tessellated, OcclusionMode::Off,
                                nullptr, false, 4.0);
    size_t close = 0, both = 0;
    for (size_t i = 0; i < coarse.ids.size(); ++i) {
      if (coarse.ids[i] == 0 || mesh.ids[i] == 0) continue;
      ++both;
      int worst = 0;
      for (int k = 0; k < 3; ++k)
        worst = std::max(worst, std::abs(int(coarse.rgba[4 * i + k]) - int(mesh.rgba[4 * i + k])));
      close += worst <= 8;
    }
    if (!std::holds_alternative<Revolution>(c.primitive)) {  // faceted, like the reference
      EXPECT_GT(double(close) / std::max<size_t>(both, 1), 0.5) << close << " of " << both;
    }
  }
}

// A closed surface seen from outside submits only its triangles that face the eye: a box seen
// across a corner its three near faces (6 of 12 triangles), face-on one face (2). The pictures,
// and a capped pipe's seen from the side (where every face is near edge-on at its silhouette),
// match the fine meshes: no face turned to the eye is left out.
TEST_F(ParametricRendering, ClosedSurfacesSubmitOnlyTheirFrontFaces) {
  const std::vector<Part> box = {{1, Box{{0.6f, 0.4f, 0.3f}}, placed({0, 0, 0})}};
  const std::vector<Part> pipe = {{1, Cylinder{0.3f, 3.0f, true}, placed({-1.5, 0, 0}, {0, 90, 0})}};
  struct View {
    const char* name;
    const std::vector<Part>& parts;
    Camera camera;
    uint64_t triangles;  // submitted; 0: not counted
  };
  const View views[] = {
      {"box_corner", box, lookingAt({3.0, -4.0, 2.5}, {0.0, 0.0, 0.0}), 6},
      {"box_face", box, lookingAt({0.0, -4.0, 0.0}, {0.0, 0.0, 0.0}), 2},
      {"pipe_side", pipe, lookingAt({0.5, -5.0, 1.0}, {0.0, 0.0, 0.0}), 0},
  };
  for (const View& v : views) {
    SCOPED_TRACE(v.name);
    const Frame frame = render(buildPackage(std::string("front_") + v.name, v.parts, false), v.camera,
                               ParametricMode::Tessellated);
    const Frame fine = render(buildPackage(std::string("front_mesh_") + v.name, v.parts, true),
                              v.camera, ParametricMode::Impostor, OcclusionMode::Off, nullptr, true);
    EXPECT_EQ(frame.stats.parametric_two_sided_triangles, 0u);
    if (v.triangles > 0) {
      EXPECT_EQ(frame.stats.parametric_triangles, v.triangles);
    }
    const Agreement g = compare(frame, fine, 2e-3);
    EXPECT_GT(g.covered, 1000u);
    EXPECT_LT(g.mismatchShare(), 0.02) << g.mismatched << " of " << g.covered;
  }
}

// Standing under a deck beside a long capped pipe, the eye is inside both bounding spheres but
// outside both solids: their back faces are hidden, so they are culled (with the sphere test
// alone, all of both were drawn two-sided). The picture is unchanged: it matches the fine
// meshes, which draw both faces. Inside a room-sized box, its faces must stay two-sided.
TEST_F(ParametricRendering, BackFacesCulledOutsideTheSolidNotItsSphere) {
  const Part deck{1, Box{{4.0f, 4.0f, 0.075f}}, placed({0, 0, 2.0})};
  const Part pipe{2, Cylinder{0.1f, 12.0f, true}, placed({-6, 0.5, 1.6}, {0, 90, 0})};
  const Camera camera = lookingAt({0.0, -0.8, 0.3}, {0.5, 0.6, 2.0});
  const Frame culled = render(buildPackage("backfaces", {deck, pipe}, false), camera,
                              ParametricMode::Tessellated);
  const Frame mesh = render(buildPackage("backfaces_mesh", {deck, pipe}, true), camera,
                            ParametricMode::Impostor, OcclusionMode::Off, nullptr, true);
  EXPECT_EQ(culled.stats.parametric_instances_drawn, 2u);
  EXPECT_GT(culled.stats.parametric_triangles, 20u);
  EXPECT_EQ(culled.stats.parametric_two_sided_triangles, 0u);
  Agreement g = compare(culled, mesh, 2e-3);
  EXPECT_GT(g.covered, size_t(kWidth * kHeight / 2));
  EXPECT_LT(g.mismatchShare(), 0.01) << g.mismatched << " of " << g.covered;
  EXPECT_EQ(idAt(culled, pixelOf(camera, {0.5, 0.5, 1.6})), 2u);

  const Part room{1, Box{{2.0f, 2.0f, 1.5f}}, placed({0, 0, 1.5})};
  const Camera inside = lookingAt({0.0, 0.0, 1.5}, {1.0, 0.3, 1.6});
  const Frame room_frame = render(buildPackage("backfaces_room", {room}, false), inside,
                                  ParametricMode::Tessellated);
  EXPECT_GT(room_frame.stats.parametric_two_sided_triangles, 0u);
  size_t walls = 0;
  for (uint32_t id : room_frame.ids) walls += id == 1u;  // the package's first object
  EXPECT_EQ(walls, room_frame.ids.size());

  // A sheared capped cylinder (its axis leans 0.8 m per metre along x): its caps stick out past
  // the planes through the axis's ends, so the tube test does not apply, and from inside its
  // walls fill the image.
  Transform sheared;
  sheared.origin = {0.0, 0.0, 0.0};
  sheared.linear = glm::mat3(glm::vec3(1, 0, 0), glm::vec3(0, 1, 0), glm::vec3(0.8f, 0, 1));
  const Part leaning{1, Cylinder{1.0f, 2.0f, true}, sheared};
  const Camera in_cylinder = lookingAt({-0.66, 0.0, 0.3}, {0.5, 0.2, 0.9});
  const Frame leaning_frame = render(buildPackage("backfaces_sheared", {leaning}, false),
                                     in_cylinder, ParametricMode::Tessellated);
  size_t wall_px = 0;
  for (uint32_t id : leaning_frame.ids) wall_px += id == 1u;
  EXPECT_EQ(wall_px, leaning_frame.ids.size());
}

// A pipe run of the plant's shape (sealed_pipe_runs.h): flange, spool along +x, a 90 degree
// elbow, spool along +y, and (when `far_flange`) a flange closing the far end.
std::vector<Part> pipeRun(bool far_flange) {
  const float r = 0.4f, bend = 1.0f, length = 3.0f;
  auto flange_at = [&](uint32_t id, const glm::dvec3& centre, const glm::vec3& axis_deg,
                       const glm::dvec3& dir) {
    return Part{id, Cylinder{1.5f * r, 0.1f, true}, placed(centre - 0.05 * dir, axis_deg)};
  };
  Transform elbow;
  elbow.origin = {length, bend, 0.0};
  elbow.linear = glm::mat3(glm::vec3(0, -1, 0), glm::vec3(1, 0, 0), glm::vec3(0, 0, 1));
  std::vector<Part> parts = {
      flange_at(1, {0, 0, 0}, {0, 90, 0}, {1, 0, 0}),
      Part{2, Cylinder{r, length, false}, placed({0, 0, 0}, {0, 90, 0})},
      Part{3, TorusSegment{bend, r, 0.5f * std::numbers::pi_v<float>}, elbow},
      Part{4, Cylinder{r, length, false}, placed({length + bend, bend, 0}, {-90, 0, 0})}};
  if (far_flange)
    parts.push_back(flange_at(5, {length + bend, bend + length, 0}, {-90, 0, 0}, {0, 1, 0}));
  return parts;
}

// Seen from beyond the first spool's end plane, the open spools and the elbow of a run closed by
// flanges have their back faces culled, and the picture is the fine mesh's; left open at one end,
// the run is drawn with both faces; with the eye inside it, too, and its inside fills the view.
TEST_F(ParametricRendering, SealedPipeRunCullsBackFacesUntilTheEyeIsInside) {
  const Camera outside = lookingAt({-1.5, -1.2, 1.2}, {2.0, 1.0, 0.0});
  const fs::path sealed = buildPackage("sealed_run", pipeRun(true), false);
  // The preprocessor found the run: two spools and the elbow are members, the flanges close it.
  auto roles = [](const fs::path& package) {
    const PackageView view = PackageView::open(package, PackageView::Verify::Headers);
    EXPECT_TRUE(view.header().flags & pkg::kHeaderSealedRunsMarked);
    std::pair<int, int> members_closers{0, 0};
    for (const pkg::InstanceRecord& in : view.instances()) {
      members_closers.first += (in.flags & pkg::kInstanceSealedRunMember) != 0;
      members_closers.second += (in.flags & pkg::kInstanceSealedRunCloser) != 0;
    }
    return members_closers;
  };
  EXPECT_EQ(roles(sealed), std::make_pair(3, 2));
  {  // `terawalk info` counts them
    const PackageSummary summary =
        summarizePackage(PackageView::open(sealed, PackageView::Verify::Headers));
    EXPECT_TRUE(summary.sealed_runs_marked);
    EXPECT_EQ(summary.sealed_run_members, 3u);
    EXPECT_EQ(summary.sealed_run_closers, 2u);
  }
  const Frame culled = render(sealed, outside, ParametricMode::Tessellated);
  const Frame mesh = render(buildPackage("sealed_run_mesh", pipeRun(true), true), outside,
                            ParametricMode::Impostor, OcclusionMode::Off, nullptr, true);
  EXPECT_EQ(culled.stats.parametric_instances_drawn, 5u);
  EXPECT_GT(culled.stats.parametric_triangles, 100u);
  EXPECT_EQ(culled.stats.parametric_two_sided_triangles, 0u);
  Agreement g = compare(culled, mesh, 2e-3);
  EXPECT_GT(g.covered, size_t(kWidth * kHeight / 20));
  EXPECT_LT(g.mismatchShare(), 0.01) << g.mismatched << " of " << g.covered;

  const fs::path open_run = buildPackage("open_run", pipeRun(false), false);
  EXPECT_EQ(roles(open_run), std::make_pair(0, 0));
  const Frame open = render(open_run, outside, ParametricMode::Tessellated);
  EXPECT_GT(open.stats.parametric_two_sided_triangles, 100u);

  // Inside the second spool, 1 m from the far flange, looking at it.
  const Camera inside = lookingAt({4.0, 3.0, 0.0}, {4.0, 4.0, 0.05});
  const Frame in_run = render(sealed, inside, ParametricMode::Tessellated);
  EXPECT_GT(in_run.stats.parametric_two_sided_triangles, 100u);
  size_t background = 0;
  for (uint32_t id : in_run.ids) background += id == 0u;
  EXPECT_EQ(background, 0u);
}

// A package written without the sealed-run mark (formats before 1.4, or any writer that skips the
// search) is searched by the runtime at start-up: the same run seen from the same place is culled
// just as the preprocessed one.
TEST_F(ParametricRendering, UnmarkedPackageIsSearchedAtStartUp) {
  const std::vector<Part> parts = pipeRun(true);
  PackageStorage storage;
  storage.origin = glm::dvec3(0.0);
  storage.addLayer({"parts", 0xff909090u});
  std::vector<ParametricItem> items;
  for (const Part& part : parts) {
    ObjectInfo info;
    info.id = part.id;
    info.name = "part " + std::to_string(part.id);
    info.color_rgba = part.color;
    const uint32_t object = storage.addObject(info, glm::vec3(-10.0f), glm::vec3(10.0f));
    items.push_back({object, part.primitive, part.transform});
  }
  addParametricClusters(items, clusterPrimitives(items, storage.origin), storage);
  const fs::path unmarked = test::processScratchDir("parametric_renderer") / "unmarked_run.twk";
  writePackage(storage, unmarked);
  ASSERT_FALSE(PackageView::open(unmarked, PackageView::Verify::Headers).header().flags &
               pkg::kHeaderSealedRunsMarked);

  const Camera outside = lookingAt({-1.5, -1.2, 1.2}, {2.0, 1.0, 0.0});
  const Frame culled = render(unmarked, outside, ParametricMode::Tessellated);
  EXPECT_EQ(culled.stats.parametric_instances_drawn, 5u);
  EXPECT_GT(culled.stats.parametric_triangles, 100u);
  EXPECT_EQ(culled.stats.parametric_two_sided_triangles, 0u);
  const Frame marked =
      render(buildPackage("sealed_run", parts, false), outside, ParametricMode::Tessellated);
  EXPECT_EQ(culled.ids, marked.ids);
}

// A deck of twelve plates, one per bay, meeting edge to edge: the preprocessor marks the sides
// they share (covered_box_faces.h) and the runtime leaves those faces out. Seen from outside, the
// frame is the one an unmarked package of the same plates gives, for fewer triangles.
TEST_F(ParametricRendering, CoveredBoxFacesAreLeftOutAndTheFrameStaysTheSame) {
  std::vector<Part> parts;
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 4; ++x)
      parts.push_back({uint32_t(1 + y * 4 + x), Box{glm::vec3(4.0f, 3.5f, 0.075f)},
                       placed({4.0 + 8.0 * x, 3.5 + 7.0 * y, -0.075}),
                       0xff000000u | (0x203040u * uint32_t(1 + (x + y) % 3))});
  const fs::path marked_package = buildPackage("covered_deck", parts, false);
  ASSERT_TRUE(PackageView::open(marked_package, PackageView::Verify::Headers).header().flags &
              pkg::kHeaderCoveredFacesMarked);

  PackageStorage storage;
  storage.origin = glm::dvec3(0.0);
  storage.addLayer({"parts", 0xff909090u});
  std::vector<ParametricItem> items;
  for (const Part& part : parts) {
    ObjectInfo info;
    info.id = part.id;
    info.name = "part " + std::to_string(part.id);
    info.color_rgba = part.color;
    const uint32_t object = storage.addObject(info, glm::vec3(-40.0f), glm::vec3(40.0f));
    items.push_back({object, part.primitive, part.transform});
  }
  addParametricClusters(items, clusterPrimitives(items, storage.origin), storage);
  const fs::path unmarked = test::processScratchDir("parametric_renderer") / "uncovered_deck.twk";
  writePackage(storage, unmarked);

  // From above and from below the deck, looking across it.
  for (const Camera& camera : {lookingAt({-8.0, -9.0, 9.0}, {16.0, 10.5, 0.0}),
                               lookingAt({40.0, 30.0, -7.0}, {16.0, 10.5, 0.0})}) {
    const Frame covered = render(marked_package, camera, ParametricMode::Tessellated);
    const Frame every = render(unmarked, camera, ParametricMode::Tessellated);
    EXPECT_EQ(covered.stats.parametric_instances_drawn, 12u);
    EXPECT_EQ(every.stats.parametric_instances_drawn, 12u);
    // Each plate shows its top or bottom and up to two sides; 17 shared sides, about half of
    // them facing the eye from each plate.
    EXPECT_LE(covered.stats.parametric_triangles + 2u * 12u, every.stats.parametric_triangles);
    uint64_t shown = 0;
    for (uint32_t id : every.ids) shown += id != 0u;
    EXPECT_GT(shown, 3000u);
    EXPECT_EQ(covered.ids, every.ids);
    EXPECT_EQ(covered.rgba, every.rgba);
  }
}

// A deck plate 15 cm thick: where its rims are narrower than min_thin_px (0.4) at its nearest
// point, they are left out as a ribbon that narrow would be, and the plate is its top; where they
// are wider, the two rims facing the eye are drawn too.
TEST_F(ParametricRendering, PlateRimsNarrowerThanTheSmallestThinFormAreLeftOut) {
  const fs::path package = buildPackage(
      "far_plate", {Part{1, Box{glm::vec3(4.0f, 3.5f, 0.075f)}, placed({0.0, 0.0, 0.0})}}, false);
  const glm::dvec3 direction = glm::normalize(glm::dvec3(0.3, -1.0, 0.6));
  const double radius = std::sqrt(4.0 * 4.0 + 3.5 * 3.5 + 0.075 * 0.075);
  // The eye where the rims are rim_px wide at the plate's nearest point.
  auto eyeAt = [&](double rim_px) {
    const double pixel_scale = lookingAt(direction, {0.0, 0.0, 0.0}).pixelScale(kHeight);
    return lookingAt(direction * (radius + 0.15 * pixel_scale / rim_px), {0.0, 0.0, 0.0});
  };
  const Camera far_eye = eyeAt(0.3), near_eye = eyeAt(0.5);
  const Frame far = render(package, far_eye, ParametricMode::Tessellated);
  const Frame near = render(package, near_eye, ParametricMode::Tessellated);
  EXPECT_EQ(far.stats.parametric_instances_drawn, 1u);
  EXPECT_EQ(far.stats.parametric_triangles, 2u);   // the top
  EXPECT_EQ(near.stats.parametric_triangles, 6u);  // the top, the -Y rim and the +X rim
  // The plate shows where it is, from afar too.
  EXPECT_EQ(idAt(far, pixelOf(far_eye, {0.0, 0.0, 0.075})), 1u);
  EXPECT_EQ(idAt(near, pixelOf(near_eye, {0.0, 0.0, 0.075})), 1u);
}

// Two equal cylinders in one parametric cluster, one near the eye and one far: the far one is
// drawn with fewer segments, so the pair costs far less than twice the near one alone (a
// per-cluster resolution would draw both at the near one's).
TEST_F(ParametricRendering, TessellatedResolutionFollowsEachInstance) {
  const Part near_pipe{1, Cylinder{0.3f, 2.0f, true}, placed({0, 0, 0})};
  const Part far_pipe{2, Cylinder{0.3f, 2.0f, true}, placed({3, 10, 0})};
  const Camera camera = lookingAt({0.0, -1.5, 1.0}, {1.5, 10.0, 1.0});
  const Frame near_only = render(buildPackage("lod_near", {near_pipe}, false), camera,
                                 ParametricMode::Tessellated);
  const Frame both = render(buildPackage("lod_both", {near_pipe, far_pipe}, false), camera,
                            ParametricMode::Tessellated);
  EXPECT_EQ(both.stats.parametric_clusters_drawn, 1u);
  EXPECT_EQ(both.stats.parametric_instances_drawn, 2u);
  EXPECT_GT(near_only.stats.parametric_triangles, 100u);
  EXPECT_GT(both.stats.parametric_triangles, near_only.stats.parametric_triangles);
  EXPECT_LT(double(both.stats.parametric_triangles), 1.3 * near_only.stats.parametric_triangles);
  // The far pipe is there all the same.
  EXPECT_EQ(idAt(both, pixelOf(camera, {3.0, 10.0, 1.0})), 2u);
}

// A pipe thinner than a pixel (0.7 px across, 60 m away) is a ribbon of two triangles in
// tessellated mode; one of 0.2 px is left out (the true surface would cover a fifth of the pixels
// along it). Impostors draw both as lines.
TEST_F(ParametricRendering, ThinPipeIsARibbonOrNothing) {
  const Camera camera = lookingAt({0.0, 0.0, 0.0}, {0.0, 60.0, 0.0});
  const double metres_per_px = 60.0 / camera.pixelScale(kHeight);
  const glm::ivec2 a = pixelOf(camera, {-8.0, 60.0, 0.0}), b = pixelOf(camera, {8.0, 60.0, 0.0});
  ASSERT_GT(b.x - a.x, 40);
  auto columnsHit = [&](const Frame& f) {
    int columns = 0;
    for (int x = a.x; x <= b.x; ++x) {
      bool hit = false;
      for (int dy = -1; dy <= 1; ++dy) hit = hit || idAt(f, {x, a.y + dy}) == 1u;
      columns += hit;
    }
    return columns;
  };
  for (double width_px : {0.7, 0.2}) {
    SCOPED_TRACE(width_px);
    const float radius = static_cast<float>(0.5 * width_px * metres_per_px);
    const fs::path pkg = buildPackage(
        "thin" + std::to_string(int(width_px * 10)),
        {{1, Cylinder{radius, 20.0f, false}, placed({-10, 60, 0}, {0, 90, 0})}}, false);
    const Frame f = render(pkg, camera, ParametricMode::Tessellated);
    if (width_px > 0.5) {
      EXPECT_EQ(f.stats.parametric_triangles, 2u);
      EXPECT_EQ(f.stats.parametric_instances_drawn, 1u);
    } else {
      EXPECT_EQ(f.stats.parametric_triangles, 0u);
      EXPECT_EQ(columnsHit(f), 0);
      EXPECT_EQ(f.stats.parametric_instances_drawn, 0u);
    }
    // Impostors grow thin tubes to half a pixel: a continuous line at both widths, though this
    // pipe lies exactly between two pixel rows (their centres sit on the grown silhouette).
    const Frame impostor = render(pkg, camera, ParametricMode::Impostor);
    EXPECT_GE(columnsHit(impostor), (b.x - a.x + 1) * 95 / 100);
  }
}

// Things thinner than a pixel but not left out (a pipe, a cone, an elbow, a beam; 0.5 to 0.8 px
// across, 60 m away, at slants that cross pixel rows) cover the pixels the same shapes finely
// tessellated cover: ribbons and boxes sample pixel centres as the true surfaces do, where the
// one-pixel lines these were drawn as before covered every column along them.
TEST_F(ParametricRendering, ThinThingsCoverThePixelsOfTheirTrueSurface) {
  const Camera camera = lookingAt({0.0, 0.0, 0.0}, {0.0, 60.0, 0.0});
  const float px = static_cast<float>(60.0 / camera.pixelScale(kHeight));  // metres per pixel
  const std::vector<Part> parts = {
      {1, Cylinder{0.35f * px, 16.0f, true}, placed({-8, 60, 1.0}, {0, 80, 0})},
      {2, Cylinder{0.25f * px, 14.0f, false}, placed({-7, 60, 4.0}, {0, 96, 0})},
      {3, Cone{0.4f * px, 0.25f * px, 12.0f, true}, placed({-6, 60, -3.0}, {0, 85, 0})},
      {4, TorusSegment{10.0f, 0.35f * px, 2.0f}, placed({-4, 60, -14.0}, {90, 0, 0})},
      {5, Box{glm::vec3(8.0f, 0.3f * px, 0.3f * px)}, placed({0, 60, 7.0}, {0, -7, 0})},
      // Rolled about its length: seen across its diagonal, wider than its side.
      {6, Box{glm::vec3(7.0f, 0.3f * px, 0.2f * px)}, placed({1, 60, -8.0}, {45, 0, 6})},
  };
  const Frame thin = render(buildPackage("thin_true", parts, false), camera,
                            ParametricMode::Tessellated, OcclusionMode::Off, nullptr, false, 1.0);
  const Frame fine = render(buildPackage("thin_true_mesh", parts, true), camera,
                            ParametricMode::Impostor, OcclusionMode::Off, nullptr, true);
  EXPECT_EQ(thin.stats.parametric_instances_drawn, parts.size());
  EXPECT_EQ(thin.stats.parametric_thin_instances, parts.size());  // the beam a ribbon too
  EXPECT_LT(thin.stats.parametric_triangles, 60u);
  for (const Part& part : parts) {
    SCOPED_TRACE(part.id);
    const auto covered = [&](const Frame& f) {
      return double(std::count(f.ids.begin(), f.ids.end(), part.id));
    };
    ASSERT_GT(covered(fine), 10.0);
    EXPECT_NEAR(covered(thin) / covered(fine), 1.0, 0.15);
  }
  EXPECT_LT(compare(thin, fine, 0.01).mismatchShare(), 0.1);
}

// A beam thinner than a pixel both ways, rolled 45 degrees about its length, shows the eye two
// long faces, one lit from the sky and one facing the ground. Its band is one pair of triangles,
// and each pixel it covers takes the colour of the face under the pixel's centre, as the finely
// tessellated box does: one shade for the whole band would get half of them wrong.
TEST_F(ParametricRendering, ThinBeamShadesEachFaceItsOwn) {
  const Camera camera = lookingAt({0.0, 0.0, 0.0}, {0.0, 60.0, 0.0});
  const float px = static_cast<float>(60.0 / camera.pixelScale(kHeight));  // metres per pixel
  const std::vector<Part> parts = {
      {1, Box{glm::vec3(14.0f, 0.3f * px, 0.3f * px)}, placed({0, 60, 1.0}, {45, 5, 0})},
  };
  const Frame thin = render(buildPackage("thin_beam", parts, false), camera,
                            ParametricMode::Tessellated, OcclusionMode::Off, nullptr, false, 1.0);
  const Frame fine = render(buildPackage("thin_beam_mesh", parts, true), camera,
                            ParametricMode::Impostor, OcclusionMode::Off, nullptr, true);
  EXPECT_EQ(thin.stats.parametric_thin_instances, 1u);
  EXPECT_LE(thin.stats.parametric_triangles, 2u);
  auto colourAt = [](const Frame& f, size_t i) {
    return glm::ivec3(f.rgba[4 * i], f.rgba[4 * i + 1], f.rgba[4 * i + 2]);
  };
  auto close = [](const glm::ivec3& a, const glm::ivec3& b) {
    return glm::all(glm::lessThanEqual(glm::abs(a - b), glm::ivec3(24)));
  };
  size_t both = 0, same_colour = 0;
  std::vector<glm::ivec3> fine_colours;
  for (size_t i = 0; i < fine.ids.size(); ++i) {
    if (fine.ids[i] != 1) continue;
    fine_colours.push_back(colourAt(fine, i));
    if (thin.ids[i] != 1) continue;
    ++both;
    same_colour += close(colourAt(thin, i), colourAt(fine, i));
  }
  // The fine box shows two shades, far enough apart that one shade could not match both.
  ASSERT_GT(fine_colours.size(), 40u);
  const bool two_shades = std::any_of(fine_colours.begin(), fine_colours.end(),
                                      [&](const glm::ivec3& c) { return !close(c, fine_colours[0]); });
  ASSERT_TRUE(two_shades);
  ASSERT_GT(both, 40u);
  EXPECT_GT(double(same_colour) / double(both), 0.9) << same_colour << " of " << both;
}

// A pipe about 6 px across, upright 20 m ahead, turned about its own axis: at tau = 1 its ring
// has a handful of segments. Seen from any side it covers about the pixels of the true pipe
// (straddling rings); inscribed rings would make it up to 30 % thinner seen flat-on, and about
// 10 % on average, which opens the gaps between the pipes of a rack.
TEST_F(ParametricRendering, CoarsePipeKeepsItsWidthFromEverySide) {
  const Camera camera = lookingAt({0.0, 0.0, 0.0}, {0.0, 20.0, 0.0});
  const double metres_per_px = 20.0 / camera.pixelScale(kHeight);
  const float radius = static_cast<float>(3.0 * metres_per_px);
  const float height = static_cast<float>(100.0 * metres_per_px);
  double sum_ratio = 0.0;
  int views = 0;
  for (float roll : {0.0f, 9.0f, 18.0f, 27.0f, 36.0f, 45.0f}) {
    SCOPED_TRACE(roll);
    const std::vector<Part> parts = {
        {1, Cylinder{radius, height, false}, placed({0.0, 20.0, -0.5 * height}, {0, 0, roll})}};
    const std::string name = "width" + std::to_string(int(roll));
    const Frame coarse = render(buildPackage(name, parts, false), camera,
                                ParametricMode::Tessellated, OcclusionMode::Off, nullptr, false, 1.0);
    const Frame fine = render(buildPackage(name + "_mesh", parts, true), camera,
                              ParametricMode::Impostor, OcclusionMode::Off, nullptr, true);
    EXPECT_LT(coarse.stats.parametric_triangles, 40u);  // a coarse ring: the case in question
    const auto covered = [](const Frame& f) {
      return double(std::count(f.ids.begin(), f.ids.end(), 1u));
    };
    ASSERT_GT(covered(fine), 400.0);
    const double ratio = covered(coarse) / covered(fine);
    EXPECT_NEAR(ratio, 1.0, 0.12);
    sum_ratio += ratio;
    ++views;
  }
  EXPECT_NEAR(sum_ratio / views, 1.0, 0.04);
}

// A coarse pipe is shaded like the true one: where both cover a pixel, the colours agree. Near a
// silhouette the interpolated normal of a coarse ring leans away from the eye; were it flipped
// toward the eye, lit pixels there would turn dark.
TEST_F(ParametricRendering, CoarsePipeHasNoDarkSpecks) {
  size_t both = 0, dark = 0;
  for (double eye_z : {4.0, -4.0}) {
    const Camera camera = lookingAt({0.0, 0.0, eye_z}, {0.0, 20.0, 0.0});
    const double metres_per_px = 20.4 / camera.pixelScale(kHeight);
    const float radius = static_cast<float>(5.0 * metres_per_px);
    const float length = static_cast<float>(150.0 * metres_per_px);
    for (float roll : {0.0f, 20.0f, 40.0f}) {
      const std::vector<Part> parts = {
          {1, Cylinder{radius, length, false}, placed({-0.5 * length, 20.0, 0.0}, {roll, 90, 0})}};
      const std::string name = "specks" + std::to_string(int(roll));
      const Frame coarse = render(buildPackage(name, parts, false), camera, ParametricMode::Tessellated,
                                  OcclusionMode::Off, nullptr, false, 1.0);
      const Frame fine = render(buildPackage(name + "_mesh", parts, true), camera,
                                ParametricMode::Impostor, OcclusionMode::Off, nullptr, true);
      for (size_t i = 0; i < coarse.ids.size(); ++i) {
        if (coarse.ids[i] != 1u || fine.ids[i] != 1u) continue;
        ++both;
        int coarse_sum = 0, fine_sum = 0;
        for (int k = 0; k < 3; ++k) {
          coarse_sum += coarse.rgba[4 * i + k];
          fine_sum += fine.rgba[4 * i + k];
        }
        dark += coarse_sum + 3 * 40 < fine_sum;  // darker by more than 40 of 255 a channel
      }
    }
  }
  ASSERT_GT(both, 5000u);
  EXPECT_LE(dark, both / 1000) << dark << " of " << both;
}

// A pipe tessellated whole at a fixed tolerance (how references draw parametrics) shades like the
// smooth surface, not facet by facet: a reference and a coarser level of the same pipe then differ
// by their silhouettes, not by the bands of their facets. The pipe is 40 pixels in radius and its
// ring 13 segments, each about 19 pixels wide. Shaded facet by facet, 1,621 of the 18,265 pixels
// both cover missed the fine mesh's colour by more than 12 of 255.
TEST_F(ParametricRendering, FixedTolerancePipeShadesLikeTheSurface) {
  const Camera camera = lookingAt({0.0, 0.0, 0.0}, {0.0, 20.0, 0.0});
  const double metres_per_px = 20.0 / camera.pixelScale(kHeight);
  const float radius = static_cast<float>(40.0 * metres_per_px);
  const float length = static_cast<float>(200.0 * metres_per_px);
  const std::vector<Part> parts = {
      {1, Cylinder{radius, length, false}, placed({-0.5 * length, 20.0 + radius, 0.0}, {20, 90, 0})}};
  const double tolerance_m = 0.03 * radius;  // 13 segments a ring
  ASSERT_EQ(arcSegments(radius, 2.0f * std::numbers::pi_v<float>, float(tolerance_m)), 13u);
  const Frame coarse = render(buildPackage("bands", parts, false), camera, ParametricMode::Tessellated,
                              OcclusionMode::Off, nullptr, true, 0.25, tolerance_m);
  const Frame fine = render(buildPackage("bands_mesh", parts, true), camera, ParametricMode::Impostor,
                            OcclusionMode::Off, nullptr, true);
  size_t both = 0, banded = 0;
  for (size_t i = 0; i < coarse.ids.size(); ++i) {
    if (coarse.ids[i] != 1u || fine.ids[i] != 1u) continue;
    ++both;
    int worst = 0;
    for (int k = 0; k < 3; ++k)
      worst = std::max(worst, std::abs(int(coarse.rgba[4 * i + k]) - int(fine.rgba[4 * i + k])));
    banded += worst > 12;
  }
  ASSERT_GT(both, 10000u);
  EXPECT_LT(double(banded) / double(both), 0.01) << banded << " of " << both;
}

// An extrusion's cluster mesh at a tolerance coarser than its flanges (10 mm) but finer than its
// recesses (70 mm) loses the flange tips' corners: fewer triangles, none outside the profile's
// box; a reference (no simplification) and a finer tolerance keep them all. Drawn at 6 m (that
// tolerance's bucket) it still covers the fine mesh's pixels, its back faces culled.
TEST_F(ParametricRendering, ExtrusionMeshLosesProfileDetailBelowItsTolerance) {
  const std::vector<glm::vec2> beam = smallIBeam();
  const std::vector<Part> parts = {{1, Extrusion{beam, 6.0f}, placed({0, 0, 0})}};
  const fs::path pkg = buildPackage("beam_simplified", parts, false);
  const PackageView view = PackageView::open(pkg);
  uint32_t cluster = ~0u;
  for (uint32_t c = 0; c < view.clusters().size(); ++c)
    if (view.clusters()[c].kind == static_cast<uint8_t>(pkg::ClusterKind::Parametric)) cluster = c;
  ASSERT_NE(cluster, ~0u);
  auto triangles = [&](float tolerance, bool simplify, glm::vec3* lo = nullptr, glm::vec3* hi = nullptr) {
    std::vector<ParametricVertex> vertices;
    std::vector<uint32_t> indices;
    tessellateCluster(view, cluster, tolerance, vertices, indices, nullptr, simplify);
    for (const ParametricVertex& v : vertices) {
      if (lo) *lo = glm::min(*lo, v.position);
      if (hi) *hi = glm::max(*hi, v.position);
    }
    return indices.size() / 3;
  };
  const size_t full = triangles(0.001f, false);
  EXPECT_EQ(triangles(0.001f, true), full);
  EXPECT_EQ(triangles(0.016f, false), full);
  glm::vec3 lo(1e30f), hi(-1e30f), full_lo(1e30f), full_hi(-1e30f);
  const size_t simplified = triangles(0.016f, true, &lo, &hi);
  triangles(0.001f, false, &full_lo, &full_hi);
  EXPECT_LT(simplified, full);
  EXPECT_GT(simplified, 12u);  // not the box: the recesses stay
  EXPECT_TRUE(glm::all(glm::greaterThanEqual(lo, full_lo - 1e-5f)));
  EXPECT_TRUE(glm::all(glm::lessThanEqual(hi, full_hi + 1e-5f)));

  const Camera camera = lookingAt({6.0, -1.5, 3.0}, {0.0, 0.0, 3.0});
  const Frame frame = render(pkg, camera, ParametricMode::Tessellated, OcclusionMode::Off, nullptr,
                             false, 1.0);
  const Frame fine = render(buildPackage("beam_simplified_mesh", parts, true), camera,
                            ParametricMode::Impostor, OcclusionMode::Off, nullptr, true);
  EXPECT_EQ(frame.stats.parametric_triangles, simplified);  // the profile at 16 mm, not the box
  EXPECT_EQ(frame.stats.parametric_two_sided_triangles, 0u);
  const Agreement g = compare(frame, fine, 1e-2);
  EXPECT_GT(g.covered, 200u);
  EXPECT_LT(g.mismatchShare(), 0.05) << g.mismatched << " of " << g.covered;
}

// An I-beam (an extrusion) close by is drawn from its profile; at a distance where the profile's
// recesses are below a pixel it is its box (12 triangles), covering the same pixels but for a
// thin band.
TEST_F(ParametricRendering, FarExtrusionIsItsBox) {
  const std::vector<glm::vec2> beam = smallIBeam();
  const fs::path pkg = buildPackage("beam", {{1, Extrusion{beam, 6.0f}, placed({0, 0, 0})}}, false);
  const fs::path fine = buildPackage("beam_mesh", {{1, Extrusion{beam, 6.0f}, placed({0, 0, 0})}}, true);
  // Seen from the side at about 10 m.
  Camera far_camera = lookingAt({10.0, -2.0, 3.0}, {0.0, 0.0, 3.0});
  const double metres_per_px = 10.2 / far_camera.pixelScale(kHeight);
  ASSERT_GT(0.075, metres_per_px) << "the recess must be visible as a pixel or more";
  const Frame near_frame = render(pkg, lookingAt({1.5, -0.8, 3.0}, {0.0, 0.0, 3.0}),
                                  ParametricMode::Tessellated, OcclusionMode::Off, nullptr, false, 1.0);
  EXPECT_GT(near_frame.stats.parametric_triangles, 12u);
  // 0.075 m (half the flange width, the most the box can stray from the profile) is within
  // tau = 3 px at the beam's nearest possible point (its bounding sphere, 3.2 m nearer): the box.
  ASSERT_LT(0.075, 3.0 * metres_per_px * (10.2 - 3.2) / 10.2);
  const Frame far_frame = render(pkg, far_camera, ParametricMode::Tessellated, OcclusionMode::Off,
                                 nullptr, false, 3.0);
  EXPECT_EQ(far_frame.stats.parametric_triangles, 4u);  // the box's two faces turned to the eye
  const Frame reference = render(fine, far_camera, ParametricMode::Impostor, OcclusionMode::Off,
                                 nullptr, true);
  const Agreement g = compare(far_frame, reference, 1e-2);
  EXPECT_GT(g.covered, 50u);
  EXPECT_LT(g.mismatchShare(), 0.35) << g.mismatched << " of " << g.covered;
}

// Extrusions drawn from their profile: a closed one (an I-beam, plain or mirrored) seen from
// outside has its back faces culled and looks like the fine mesh; with the eye inside its box, or
// with a profile that crosses itself, both faces are drawn.
TEST_F(ParametricRendering, ClosedExtrusionCullsBackFacesFromOutside) {
  const std::vector<glm::vec2> beam = {{-0.3f, -0.6f}, {0.3f, -0.6f}, {0.3f, -0.52f},
                                       {0.04f, -0.52f}, {0.04f, 0.52f}, {0.3f, 0.52f},
                                       {0.3f, 0.6f},   {-0.3f, 0.6f}, {-0.3f, 0.52f},
                                       {-0.04f, 0.52f}, {-0.04f, -0.52f}, {-0.3f, -0.52f}};
  Transform mirrored = placed({0, 0, 0}, {-90, 0, 0});
  mirrored.linear = mirrored.linear * glm::mat3(glm::vec3(-1, 0, 0), glm::vec3(0, 1, 0), glm::vec3(0, 0, 1));
  ASSERT_LT(glm::determinant(mirrored.linear), 0.0f);
  const Camera outside = lookingAt({3.0, -2.5, 1.8}, {0.0, 3.0, 0.0});
  for (const Transform& t : {placed({0, 0, 0}, {-90, 0, 0}), mirrored}) {
    const Part part{1, Extrusion{beam, 6.0f}, t};
    const Frame culled = render(buildPackage("closed_beam", {part}, false), outside,
                                ParametricMode::Tessellated, OcclusionMode::Off, nullptr, false, 0.5);
    const Frame mesh = render(buildPackage("closed_beam_mesh", {part}, true), outside,
                              ParametricMode::Impostor, OcclusionMode::Off, nullptr, true);
    EXPECT_GT(culled.stats.parametric_triangles, 12u);  // the profile, not the box
    EXPECT_EQ(culled.stats.parametric_two_sided_triangles, 0u);
    const Agreement g = compare(culled, mesh, 2e-3);
    EXPECT_GT(g.covered, size_t(kWidth * kHeight / 20));
    EXPECT_LT(g.mismatchShare(), 0.01) << g.mismatched << " of " << g.covered;
    EXPECT_GT(g.depthShare(), 0.99);  // the near faces, not the far ones
  }
  // Standing in the web's recess, inside the beam's box: both faces.
  const Part part{1, Extrusion{beam, 6.0f}, placed({0, 0, 0}, {-90, 0, 0})};
  const Camera recess = lookingAt({0.2, 1.0, 0.0}, {0.2, 5.0, 0.3});
  const Frame inside = render(buildPackage("closed_beam", {part}, false), recess,
                              ParametricMode::Tessellated, OcclusionMode::Off, nullptr, false, 0.5);
  EXPECT_GT(inside.stats.parametric_two_sided_triangles, 0u);
  // A profile that crosses itself (an uneven bow tie): its caps do not close it.
  const std::vector<glm::vec2> bow_tie = {{0.0f, 0.0f}, {0.6f, 0.6f}, {0.6f, 0.0f}, {0.0f, 0.3f}};
  const Part crossed{1, Extrusion{bow_tie, 6.0f}, placed({0, 0, 0}, {-90, 0, 0})};
  const Frame crossed_frame = render(buildPackage("crossed_beam", {crossed}, false), outside,
                                     ParametricMode::Tessellated, OcclusionMode::Off, nullptr, false, 0.5);
  EXPECT_GT(crossed_frame.stats.parametric_triangles, 0u);
  EXPECT_EQ(crossed_frame.stats.parametric_two_sided_triangles,
            crossed_frame.stats.parametric_triangles);
}

// hzb, tessellated mode: two spheres in one parametric cluster, one in front of a mesh wall and
// one behind it. The cluster is visible, so only the instance test can leave the hidden sphere
// out: it does, the image equals the unculled redraw, and when the camera rises above the wall
// the hidden sphere shows in the very frame it becomes visible.
TEST_F(ParametricRendering, HzbCullsHiddenInstancesOfAVisibleCluster) {
  SceneObject wall;
  wall.info.id = 1;
  wall.info.name = "wall";
  wall.info.color_rgba = 0xff808080u;
  wall.info.transform.origin = glm::dvec3(0.0, 0.0, 1.0);
  wall.geometry = test::subdividedBox(glm::vec3(0.1f, 4.0f, 1.0f), 4);
  const std::vector<Part> balls = {{2, Sphere{0.5f}, placed({-2.0, 0, 1.0})},
                                   {3, Sphere{0.5f}, placed({3.0, 0, 1.0})}};
  const fs::path pkg = buildPackage("hidden_ball", balls, false, {wall});
  const Camera low = lookingAt({-6.0, 0.0, 1.0}, {3.0, 0.0, 1.0});
  Walkthrough* walk = nullptr;
  const Frame f = render(pkg, low, ParametricMode::Tessellated, OcclusionMode::Hzb, &walk);
  EXPECT_EQ(f.stats.parametric_clusters_drawn, 1u);
  EXPECT_EQ(f.stats.parametric_instances_drawn, 1u);
  EXPECT_EQ(f.stats.parametric_occluded, 1u);
  const uint32_t near_id = idAt(f, pixelOf(low, {-2.0, 0.0, 1.0}));
  ASSERT_GT(near_id, 0u);
  EXPECT_EQ(walk->package().objects()[near_id - 1].id, 2u);
  std::vector<uint32_t> unculled;
  walk->redrawUnculled();
  walk->renderer().readObjectIds(unculled);
  EXPECT_EQ(unculled, f.ids);

  // Over the wall: the far sphere's first frame already shows it.
  const Camera high = lookingAt({-6.0, 0.0, 9.0}, {3.0, 0.0, 1.0});
  const FrameStats up = walk->renderFrame(high, 1.0);
  std::vector<uint32_t> ids;
  walk->renderer().readObjectIds(ids);
  const glm::ivec2 far_px = pixelOf(high, {3.0, 0.0, 1.3});
  const uint32_t far_id = ids[size_t(far_px.y) * kWidth + size_t(far_px.x)];
  ASSERT_GT(far_id, 0u);
  EXPECT_EQ(walk->package().objects()[far_id - 1].id, 3u);
  EXPECT_EQ(up.parametric_instances_drawn, 2u);
}

// The frame loop expands the first pass's instances on a worker thread (prepare) while it submits
// the meshes: the draw that follows must show exactly what a plain draw shows, and a prepare made
// for other clusters must be dropped, not drawn.
TEST_F(ParametricRendering, PreparedOnAnotherThreadDrawsTheSameAsADraw) {
  const std::vector<Part> parts = {{1, Cylinder{0.3f, 3.0f, true}, placed({-1.5, 0, 0}, {0, 90, 0})},
                                   {2, Sphere{0.6f}, placed({1.0, 1.0, 0.3})},
                                   {3, Box{{0.5f, 0.4f, 0.3f}}, placed({0.5, -1.2, 0.0}, {0, 0, 30})}};
  const fs::path package = buildPackage("prepared", parts, false);
  PackageView view = PackageView::open(package, PackageView::Verify::Headers);
  RendererOptions renderer_options;
  renderer_options.width = kWidth;
  renderer_options.height = kHeight;
  GlRenderer renderer(renderer_options);
  std::vector<uint32_t> colors;
  for (const pkg::ObjectRecord& o : view.objects()) colors.push_back(o.color_rgba);
  renderer.setObjectColors(colors);
  ParametricRenderer parametric(view, renderer);
  std::vector<uint32_t> clusters;
  for (uint32_t c = 0; c < view.clusters().size(); ++c)
    if (view.clusters()[c].kind == static_cast<uint8_t>(pkg::ClusterKind::Parametric))
      clusters.push_back(c);
  ASSERT_GE(clusters.size(), 2u);  // one per primitive type
  const Camera camera = lookingAt(view.origin() + glm::dvec3(0.0, -6.0, 3.0), view.origin());
  ParametricView pv;
  pv.eye = camera.position - view.origin();
  pv.forward = camera.forward();
  pv.near_m = camera.near_m;
  pv.pixel_scale = camera.pixelScale(kHeight);
  const glm::mat4 rotation(camera.viewRotation());
  const glm::mat4 projection(camera.projection(double(kWidth) / kHeight));
  auto frame = [&](const std::function<void()>& before_draw, ParametricDrawStats* stats) {
    renderer.beginFrame(rotation, projection);
    before_draw();
    *stats = parametric.draw(clusters, pv, ParametricMode::Tessellated, 1);
    renderer.endFrame();
    std::vector<uint32_t> ids;
    renderer.readObjectIds(ids);
    return ids;
  };
  ParametricDrawStats plain_stats, prepared_stats, dropped_stats;
  const std::vector<uint32_t> plain = frame([] {}, &plain_stats);
  const std::vector<uint32_t> prepared = frame(
      [&] {
        std::thread worker([&] { parametric.prepare(clusters, pv, ParametricMode::Tessellated); });
        worker.join();
      },
      &prepared_stats);
  const std::vector<uint32_t> dropped = frame(
      [&] {
        parametric.prepare(std::span(clusters).first(1), pv, ParametricMode::Tessellated);
      },
      &dropped_stats);
  std::set<uint32_t> seen(plain.begin(), plain.end());
  EXPECT_EQ(seen.size(), 4u);  // the three parts and the background
  EXPECT_EQ(prepared, plain);
  EXPECT_EQ(dropped, plain);
  EXPECT_EQ(prepared_stats.instances_drawn, plain_stats.instances_drawn);
  EXPECT_EQ(prepared_stats.mesh_triangles, plain_stats.mesh_triangles);
  EXPECT_EQ(dropped_stats.mesh_triangles, plain_stats.mesh_triangles);
}

// prepare() expands the frame's clusters in runs, each into a part of its own: a first or only
// pass's runs streamed (a worker expands them while submit() draws each as it is done), a second
// pass's appended in order into one batch. The frame must be the one a single run draws, pixel
// for pixel and count for count, with occlusion's two passes too. Every form is there: closed
// and open surfaces, boxes, profiles, lathes, ribbons and points.
TEST_F(ParametricRendering, ExpandedInRunsDrawsWhatOneRunDraws) {
  std::vector<Part> parts = typeCaseRow();
  auto id = static_cast<uint32_t>(parts.size() + 1);
  // Far thin pipes and small spheres behind them: ribbons and points.
  for (int k = 0; k < 40; ++k) {
    parts.push_back({id++, Cylinder{0.06f, 3.0f, false}, placed({-4.0 + 0.5 * k, 30.0, 0.0}, {90, 0, 0})});
    parts.push_back({id++, Sphere{0.08f}, placed({-4.0 + 0.5 * k, 45.0, 1.0})});
  }
  const fs::path pkg = buildPackage("expanded_in_runs", parts, false);
  const Camera camera = lookingAt({6.5, -9.0, 3.0}, {6.5, 0.0, 0.5});
  for (OcclusionMode occlusion : {OcclusionMode::Off, OcclusionMode::Hzb}) {
    SCOPED_TRACE(occlusionModeName(occlusion));
    const Frame one = render(pkg, camera, ParametricMode::Tessellated, occlusion, nullptr, false,
                             0.25, 0.0, 0);
    const Frame runs = render(pkg, camera, ParametricMode::Tessellated, occlusion, nullptr, false,
                              0.25, 0.0, 1);
    EXPECT_GE(one.stats.parametric_clusters_drawn, 4u);  // so there are several runs
    if (occlusion == OcclusionMode::Off) {
      EXPECT_GT(one.stats.parametric_thin_instances, 20u);
    }
    EXPECT_EQ(runs.stats.parametric_instances_drawn, one.stats.parametric_instances_drawn);
    EXPECT_EQ(runs.stats.parametric_triangles, one.stats.parametric_triangles);
    EXPECT_EQ(runs.stats.parametric_thin_instances, one.stats.parametric_thin_instances);
    EXPECT_EQ(runs.ids, one.ids);
    EXPECT_EQ(runs.rgba, one.rgba);
  }
}

TEST_F(ParametricRendering, DrawnInFlushedPartsDrawsWhatOneDrawDraws) {
  // A far view's batch, drawn in parts (fewer than four primitives an instance): rows of thin
  // pipes and small spheres (ribbons and points), and capped tubes seen from outside (the
  // back-face culled batch).
  std::vector<Part> parts;
  uint32_t id = 1;
  for (int row = 0; row < 10; ++row) {
    for (int k = 0; k < 30; ++k) {
      parts.push_back({id++, Cylinder{0.06f, 3.0f, false},
                       placed({-4.0 + 0.5 * k, 30.0 + 2.0 * row, 0.0}, {90, 0, 0})});
      parts.push_back({id++, Sphere{0.08f}, placed({-4.0 + 0.5 * k, 55.0 + 2.0 * row, 1.0})});
    }
  }
  for (int k = 0; k < 10; ++k)
    parts.push_back({id++, Cylinder{0.3f, 1.0f, true}, placed({-2.0 + 1.5 * k, 15.0, -1.0})});
  const fs::path pkg = buildPackage("flushed_parts", parts, false);
  const Camera camera = lookingAt({6.5, -9.0, 3.0}, {6.5, 0.0, 0.5});
  for (OcclusionMode occlusion : {OcclusionMode::Off, OcclusionMode::Hzb}) {
    SCOPED_TRACE(occlusionModeName(occlusion));
    const Frame whole = render(pkg, camera, ParametricMode::Tessellated, occlusion, nullptr, false,
                               0.25, 0.0, 32, 0);
    // Seven primitives a part: parts end inside every batch, points included.
    const Frame in_parts = render(pkg, camera, ParametricMode::Tessellated, occlusion, nullptr,
                                  false, 0.25, 0.0, 32, 7);
    EXPECT_GT(whole.stats.parametric_triangles, 7u * 10u);
    // Fewer than four primitives an instance (at most one point each), so the batch goes in parts.
    EXPECT_LT(whole.stats.parametric_triangles + whole.stats.parametric_instances_drawn,
              4u * whole.stats.parametric_instances_drawn);
    if (occlusion == OcclusionMode::Off) {
      EXPECT_GT(whole.stats.parametric_thin_instances, 200u);
    }
    EXPECT_EQ(in_parts.stats.parametric_instances_drawn, whole.stats.parametric_instances_drawn);
    EXPECT_EQ(in_parts.stats.parametric_triangles, whole.stats.parametric_triangles);
    EXPECT_EQ(in_parts.ids, whole.ids);
    EXPECT_EQ(in_parts.rgba, whole.rgba);
  }
}

// A far view visits only the instances its distance lets show (InstanceScaleIndex): the frame,
// and every count, must be the one testing each instance gives. Rows of everything that can be
// too small to show from afar: thin long pipes (ribbons or nothing), short wide ones like flanges
// (points from afar), spheres, beams, elbows and boxes, at distances from near to far.
TEST_F(ParametricRendering, ScaleIndexDrawsWhatTestingEveryInstanceDraws) {
  std::vector<Part> parts;
  uint32_t id = 1;
  for (int row = 0; row < 8; ++row) {
    const double y = 10.0 + 12.0 * row;
    for (int k = 0; k < 12; ++k) {
      const double x = -6.0 + 1.1 * k;
      parts.push_back({id++, Cylinder{0.02f + 0.01f * float(k % 3), 4.0f, false},
                       placed({x, y, 0.0}, {90, 0, 0})});
      parts.push_back({id++, Cylinder{0.05f + 0.03f * float(k % 3), 0.04f + 0.03f * float(k % 4), true},
                       placed({x, y + 2.0, 1.0})});
      parts.push_back({id++, Sphere{0.02f + 0.03f * float(k % 4)}, placed({x, y + 4.0, 2.0})});
      parts.push_back({id++, Box{{0.02f, 0.03f, 1.5f}}, placed({x, y + 6.0, 0.5}, {0, 90, 0})});
      parts.push_back({id++, Box{{0.05f + 0.05f * float(k % 3), 0.1f, 0.08f}},
                       placed({x, y + 8.0, 2.5})});
      parts.push_back({id++, TorusSegment{0.3f, 0.02f + 0.02f * float(k % 2), 1.5708f},
                       placed({x, y + 10.0, 1.5})});
    }
  }
  const fs::path pkg = buildPackage("scale_index", parts, false);
  const Camera camera = lookingAt({0.0, -20.0, 6.0}, {0.0, 40.0, 0.0});
  for (OcclusionMode occlusion : {OcclusionMode::Off, OcclusionMode::Hzb}) {
    SCOPED_TRACE(occlusionModeName(occlusion));
    const Frame every = render(pkg, camera, ParametricMode::Tessellated, occlusion, nullptr, false,
                               1.0, 0.0, 32, 8192, false);
    const Frame indexed = render(pkg, camera, ParametricMode::Tessellated, occlusion, nullptr,
                                 false, 1.0, 0.0, 32, 8192, true);
    // Something is drawn, something left out, and the index visits fewer than all.
    EXPECT_GT(every.stats.parametric_instances_drawn, 100u);
    EXPECT_GT(every.stats.parametric_thin_instances, 50u);
    EXPECT_LT(every.stats.parametric_instances_drawn, parts.size() - 50);
    EXPECT_EQ(every.stats.parametric_instances_tested, parts.size());
    EXPECT_LT(indexed.stats.parametric_instances_tested, every.stats.parametric_instances_tested);
    EXPECT_EQ(indexed.stats.parametric_instances_drawn, every.stats.parametric_instances_drawn);
    EXPECT_EQ(indexed.stats.parametric_thin_instances, every.stats.parametric_thin_instances);
    EXPECT_EQ(indexed.stats.parametric_triangles, every.stats.parametric_triangles);
    EXPECT_EQ(indexed.ids, every.ids);
    EXPECT_EQ(indexed.rgba, every.rgba);
  }
}

}  // namespace
}  // namespace tw
