// Back-face culling of closed mesh objects, end to end on llvmpipe: the preprocessor marks
// objects whose meshes bound a solid (and not open or mirrored ones), the frame loop culls their
// back faces only from outside, and the picture (object ids) is the one drawn two-sided.
#include <gtest/gtest.h>

#include "camera_test_support.h"
#include "egl_context.h"
#include "frame_loop.h"
#include "package_view.h"
#include "preprocess_driver.h"
#include "tessellate.h"
#include "test_support.h"
#include "tws_writer.h"

namespace tw {
namespace {

namespace fs = std::filesystem;

constexpr int kWidth = 256, kHeight = 192;

SceneObject meshObject(uint32_t id, const Primitive& primitive, const Transform& transform) {
  SceneObject object;
  object.info.id = id;
  object.info.name = "part " + std::to_string(id);
  object.info.transform = transform;
  TriangleMesh mesh;
  tessellatePrimitive(primitive, 0.002f, mesh);
  object.geometry = std::move(mesh);
  return object;
}

Transform at(const glm::dvec3& origin, const glm::mat3& linear = glm::mat3(1.0f)) {
  Transform t;
  t.origin = origin;
  t.linear = linear;
  return t;
}

// A closed sphere (object 0), an open pipe (1) and a mirrored sphere (2), all as meshes.
fs::path buildPackage() {
  const fs::path dir = test::processScratchDir("mesh_backfaces");
  const fs::path scene = dir / "scene.tws";
  {
    TwsWriter writer(scene);
    writer.onLayer(0, {"parts", 0xff909090u});
    writer.onObject(meshObject(1, Sphere{1.0f}, at({0.0, 0.0, 0.0})));
    writer.onObject(meshObject(2, Cylinder{0.5f, 2.0f, false}, at({3.0, 0.0, -1.0})));
    writer.onObject(meshObject(3, Sphere{1.0f},
                               at({-3.0, 0.0, 0.0}, glm::mat3(glm::vec3(-1, 0, 0),
                                                              glm::vec3(0, 1, 0),
                                                              glm::vec3(0, 0, 1)))));
    writer.finish();
  }
  PreprocessOptions options;
  options.inputs = {scene};
  options.output = dir / "scene.twk";
  runPreprocess(options);
  return options.output;
}

struct Frame {
  std::vector<uint32_t> ids;
  FrameStats stats;
};

// Renders until the cut is complete and steady.
Frame render(const fs::path& package, const Camera& camera, bool cull, bool reference = false) {
  WalkthroughOptions options;
  options.width = kWidth;
  options.height = kHeight;
  options.prefetch = false;
  options.tau_px = 0.25;
  options.occlusion = OcclusionMode::Off;
  options.reference = reference;
  options.cull_closed_backfaces = cull;
  Walkthrough walk(package, options);
  Frame frame;
  int complete = 0;
  for (int i = 0; i < 100 && complete < 3; ++i) {
    frame.stats = walk.renderFrame(camera, 0.0);
    complete = frame.stats.ancestor_fallbacks == 0 && frame.stats.pages_requested == 0
                   ? complete + 1
                   : 0;
  }
  walk.renderer().readObjectIds(frame.ids);
  return frame;
}

class MeshBackfaces : public ::testing::Test {
 protected:
  EglContext context_;
};

TEST(MeshBackfacesPackage, OnlyClosedOutwardMeshesAreMarked) {
  const PackageView view = PackageView::open(buildPackage());
  ASSERT_EQ(view.objects().size(), 3u);
  EXPECT_TRUE(view.objects()[0].flags & pkg::kObjectClosedSurface);   // sphere
  EXPECT_FALSE(view.objects()[1].flags & pkg::kObjectClosedSurface);  // open pipe
  EXPECT_FALSE(view.objects()[2].flags & pkg::kObjectClosedSurface);  // mirrored: inside out
}

// From outside, the sphere's back faces are culled and the picture does not change: every
// object id is where the two-sided drawing puts it.
TEST_F(MeshBackfaces, CulledFromOutsideWithTheSamePicture) {
  const fs::path package = buildPackage();
  const Camera camera = test::lookingAt({0.0, -7.0, 1.0}, {0.0, 0.0, 0.0});
  const Frame culled = render(package, camera, true);
  const Frame both = render(package, camera, false);
  ASSERT_GT(culled.stats.triangles_drawn, 500u);
  EXPECT_EQ(both.stats.two_sided_triangles, both.stats.triangles_drawn);
  EXPECT_LT(culled.stats.two_sided_triangles, culled.stats.triangles_drawn);
  EXPECT_GT(culled.stats.two_sided_triangles, 0u);  // the pipe and the mirrored sphere
  ASSERT_EQ(culled.ids.size(), both.ids.size());
  size_t differ = 0, covered = 0;
  for (size_t i = 0; i < culled.ids.size(); ++i) {
    differ += culled.ids[i] != both.ids[i];
    covered += both.ids[i] != 0;
  }
  EXPECT_GT(covered, size_t(kWidth * kHeight / 20));
  EXPECT_EQ(differ, 0u);

  // The reference draws everything two-sided, whatever the option says.
  const Frame reference = render(package, camera, true, true);
  EXPECT_EQ(reference.stats.two_sided_triangles, reference.stats.triangles_drawn);
}

// Inside the sphere its back faces are all there is to see: nothing is culled, and its inside
// fills the image.
TEST_F(MeshBackfaces, KeptFromInside) {
  const fs::path package = buildPackage();
  const Camera camera = test::lookingAt({0.2, 0.0, 0.1}, {3.0, 0.5, 0.0});
  const Frame inside = render(package, camera, true);
  EXPECT_EQ(inside.stats.two_sided_triangles, inside.stats.triangles_drawn);
  size_t sphere = 0;
  for (uint32_t id : inside.ids) sphere += id == 1u;  // object index 0, plus one
  EXPECT_EQ(sphere, inside.ids.size());
}

}  // namespace
}  // namespace tw
