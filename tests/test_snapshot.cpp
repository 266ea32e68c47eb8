// Snapshots: colours where geometry should be, sky elsewhere, automatic framing, PNG output,
// empty scenes, cancellation and a real CAD model.
#include <gtest/gtest.h>

#include <stb_image.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "snapshot.h"
#include "test_support.h"

namespace {

using namespace tw;

// World frame far from zero, as in a plant model.
constexpr glm::dvec3 kFar{5.0e5, 3.0e6, 50.0};

struct Rgb {
  int r, g, b;
};
Rgb pixel(const SnapshotImage& image, uint32_t x, uint32_t y) {
  const uint8_t* p = &image.rgb[(size_t(y) * image.width + x) * 3];
  return {p[0], p[1], p[2]};
}

// A 40 x 40 quad in the plane y = kFar.y + 3 facing -y, coloured through its layer (blue).
SceneObject bluePlane() {
  SceneObject o;
  o.info.id = 1;
  o.info.name = "plane";
  o.info.layer = 0;
  o.info.transform.origin = kFar + glm::dvec3(0.0, 3.0, 0.0);
  TriangleMesh mesh;
  mesh.positions = {{-20, 0, -20}, {20, 0, -20}, {20, 0, 20}, {-20, 0, 20}};
  mesh.indices = {0, 1, 2, 0, 2, 3};
  o.geometry = std::move(mesh);
  return o;
}

// A 2 x 2 x 2 red box primitive centred on kFar, coloured by the object itself.
SceneObject redBox() {
  SceneObject o;
  o.info.id = 2;
  o.info.name = "box";
  o.info.layer = 0;
  o.info.color_rgba = 0xff2020e0u;  // 0xAABBGGRR: red
  o.info.transform.origin = kFar;
  o.geometry = Primitive{Box{glm::vec3(1.0f)}};
  return o;
}

SnapshotScene buildScene(bool with_plane, bool with_box) {
  SnapshotBuilder builder;
  builder.onLayer(0, Layer{"blue", 0xffd04010u});
  if (with_plane) builder.onObject(bluePlane());
  if (with_box) builder.onObject(redBox());
  return builder.finish();
}

SnapshotCamera frontCamera() {
  SnapshotCamera camera;
  camera.eye = kFar + glm::dvec3(0.0, -10.0, 0.0);
  camera.target = kFar;
  camera.up = {0.0, 0.0, 1.0};
  camera.fov_y_deg = 40.0;
  return camera;
}

SnapshotRenderOptions smallOptions() {
  SnapshotRenderOptions options;
  options.width = 64;
  options.height = 48;
  options.samples = 1;
  return options;
}

bool isSky(const SnapshotImage& image, uint32_t x, uint32_t y) {
  glm::vec3 sky = snapshotSkyColor((double(y) + 0.5) / double(image.height));
  Rgb p = pixel(image, x, y);
  auto to8 = [](float c) { return int(std::lround(std::pow(std::clamp(c, 0.0f, 1.0f), 1.0f / 2.2f) * 255.0f)); };
  return std::abs(p.r - to8(sky.r)) <= 1 && std::abs(p.g - to8(sky.g)) <= 1 && std::abs(p.b - to8(sky.b)) <= 1;
}

TEST(Snapshot, RedBoxInFrontOfBluePlane) {
  SnapshotScene scene = buildScene(true, true);
  EXPECT_EQ(scene.objects, 2u);
  EXPECT_EQ(scene.triangles, 2u + 12u);
  EXPECT_EQ(scene.distinct_colors, 2u);
  // Bounds are exact world coordinates of the vertices, far from zero.
  EXPECT_NEAR(scene.bounds.min.x, kFar.x - 20.0, 1e-6);
  EXPECT_NEAR(scene.bounds.max.y, kFar.y + 3.0, 1e-6);

  SnapshotRenderResult r = renderSnapshot(scene, frontCamera(), smallOptions());
  ASSERT_EQ(r.image.width, 64u);
  ASSERT_EQ(r.image.height, 48u);
  ASSERT_EQ(r.image.rgb.size(), 64u * 48u * 3u);
  // The plane fills the frame, so every pixel hits something.
  EXPECT_EQ(r.hit_pixels, 64u * 48u);

  Rgb centre = pixel(r.image, 32, 24);
  EXPECT_GT(centre.r, 2 * centre.g) << centre.r << "," << centre.g << "," << centre.b;
  EXPECT_GT(centre.r, 2 * centre.b);
  EXPECT_GT(centre.r, 60);
  for (auto [x, y] : {std::pair{1u, 24u}, std::pair{62u, 24u}, std::pair{32u, 1u}, std::pair{32u, 46u}}) {
    Rgb edge = pixel(r.image, x, y);
    EXPECT_GT(edge.b, edge.r + 30) << x << "," << y;
    EXPECT_GT(edge.b, edge.g) << x << "," << y;
  }
}

TEST(Snapshot, SmallBatchesGiveTheSamePicture) {
  // Batches of 5 triangles put the two objects in separate Embree geometries (an object part is
  // never split); the per-triangle slots must still find the right colours, and a different
  // origin must not change the picture.
  SnapshotBuildOptions options;
  options.batch_triangles = 5;
  options.origin = kFar + glm::dvec3(3.0, -2.0, 1.0);
  SnapshotBuilder builder(options);
  builder.onLayer(0, Layer{"blue", 0xffd04010u});
  builder.onObject(bluePlane());
  builder.onObject(redBox());
  SnapshotScene split = builder.finish();
  EXPECT_EQ(split.rt->geometryCount(), 2u);
  EXPECT_EQ(split.triangles, 14u);
  SnapshotScene whole = buildScene(true, true);
  EXPECT_EQ(whole.rt->geometryCount(), 1u);

  SnapshotRenderResult a = renderSnapshot(split, frontCamera(), smallOptions());
  SnapshotRenderResult b = renderSnapshot(whole, frontCamera(), smallOptions());
  size_t differing = 0;
  for (size_t i = 0; i < a.image.rgb.size(); ++i) differing += std::abs(int(a.image.rgb[i]) - int(b.image.rgb[i])) > 2;
  EXPECT_LE(differing, a.image.rgb.size() / 100);
}

TEST(Snapshot, VertexColoursWinOverTheLayer) {
  SnapshotBuilder builder;
  builder.onLayer(0, Layer{"blue", 0xffd04010u});
  SceneObject plane = bluePlane();
  auto& mesh = std::get<TriangleMesh>(plane.geometry);
  mesh.colors.assign(mesh.positions.size(), 0xff20d020u);  // green
  builder.onObject(plane);
  SnapshotScene scene = builder.finish();
  SnapshotRenderResult r = renderSnapshot(scene, frontCamera(), smallOptions());
  Rgb centre = pixel(r.image, 32, 24);
  EXPECT_GT(centre.g, centre.r + 30);
  EXPECT_GT(centre.g, centre.b + 30);
}

TEST(Snapshot, ColourByObjectAndShadowsOff) {
  SnapshotScene scene = buildScene(true, true);
  SnapshotRenderOptions options = smallOptions();
  options.color_by = SnapshotColorBy::Object;
  options.shadows = false;
  SnapshotRenderResult by_object = renderSnapshot(scene, frontCamera(), options);
  options.color_by = SnapshotColorBy::Scene;
  SnapshotRenderResult by_scene = renderSnapshot(scene, frontCamera(), options);
  EXPECT_LT(by_scene.rays, 64u * 48u + 1u);  // no shadow rays
  Rgb a = pixel(by_object.image, 32, 24), b = pixel(by_scene.image, 32, 24);
  EXPECT_TRUE(a.r != b.r || a.g != b.g || a.b != b.b);
  // The two objects get different object colours.
  Rgb edge = pixel(by_object.image, 1, 24);
  EXPECT_TRUE(a.r != edge.r || a.g != edge.g || a.b != edge.b);
}

TEST(Snapshot, AutoCameraFramesTheWholeModel) {
  SnapshotScene scene = buildScene(false, true);
  SnapshotOptions options;
  options.render = smallOptions();
  SnapshotImage image;
  SnapshotReport report = renderSceneSnapshot(scene, "", options, nullptr, &image);
  // Looks at (about) the box centre from above and in front.
  EXPECT_LT(glm::length(report.camera.target - kFar), 1.0);
  EXPECT_GT(report.camera.eye.z, kFar.z);
  EXPECT_LT(report.camera.eye.y, kFar.y);
  // The box covers a good part of the picture but touches no border.
  EXPECT_GT(report.hit_pixels, 64u * 48u / 10u);
  for (uint32_t x = 0; x < 64; ++x) {
    EXPECT_TRUE(isSky(image, x, 0)) << x;
    EXPECT_TRUE(isSky(image, x, 47)) << x;
  }
  for (uint32_t y = 0; y < 48; ++y) {
    EXPECT_TRUE(isSky(image, 0, y)) << y;
    EXPECT_TRUE(isSky(image, 63, y)) << y;
  }
  EXPECT_FALSE(isSky(image, 32, 24));
}

TEST(Snapshot, EmptySceneGivesSkyOnly) {
  SnapshotBuilder builder;
  SnapshotScene scene = builder.finish();
  EXPECT_EQ(scene.triangles, 0u);
  SnapshotOptions options;
  options.render = smallOptions();
  SnapshotImage image;
  SnapshotReport report = renderSceneSnapshot(scene, "", options, nullptr, &image);
  EXPECT_EQ(report.hit_pixels, 0u);
  for (uint32_t y = 0; y < 48; y += 7)
    for (uint32_t x = 0; x < 64; x += 9) EXPECT_TRUE(isSky(image, x, y)) << x << "," << y;
}

TEST(Snapshot, PngIsWrittenAndDecodes) {
  SnapshotScene scene = buildScene(true, true);
  SnapshotRenderResult r = renderSnapshot(scene, frontCamera(), smallOptions());
  auto path = test::scratchDir() / "box.png";
  writePng(r.image, path);
  ASSERT_TRUE(std::filesystem::exists(path));
  EXPECT_FALSE(std::filesystem::exists(path.string() + ".tmp"));
  int w = 0, h = 0, channels = 0;
  unsigned char* data = stbi_load(path.string().c_str(), &w, &h, &channels, 3);
  ASSERT_NE(data, nullptr);
  EXPECT_EQ(w, 64);
  EXPECT_EQ(h, 48);
  EXPECT_EQ(channels, 3);
  EXPECT_EQ(std::vector<uint8_t>(data, data + 64 * 48 * 3), r.image.rgb);
  stbi_image_free(data);

  EXPECT_THROW(writePng(r.image, test::scratchDir() / "no-such-dir" / "x.png"), std::runtime_error);
}

TEST(Snapshot, RejectsBadSizesAndHonoursCancel) {
  SnapshotScene scene = buildScene(true, true);
  SnapshotRenderOptions options = smallOptions();
  options.width = 0;
  EXPECT_THROW(renderSnapshot(scene, frontCamera(), options), std::invalid_argument);

  struct CancelAtOnce : Progress {
    void beginStage(std::string_view, uint64_t) override {}
    void update(uint64_t) override {}
    void endStage() override {}
    bool cancelled() const override { return true; }
  } cancel;
  EXPECT_THROW(renderSnapshot(scene, frontCamera(), smallOptions(), &cancel), std::runtime_error);
}

TEST(Snapshot, ParseVec3) {
  EXPECT_EQ(parseVec3("1,2,3"), glm::dvec3(1, 2, 3));
  EXPECT_EQ(parseVec3(" -1.5 , +2e3,0"), glm::dvec3(-1.5, 2000, 0));
  for (const char* bad : {"", "1,2", "1,2,3,4", "a,b,c", "1;2;3", "1,2,nan", "1,2,3x"})
    EXPECT_THROW(parseVec3(bad), std::invalid_argument) << bad;
}

TEST(Snapshot, CameraFrameIsOrthonormalEvenLookingStraightDown) {
  SnapshotCamera camera;
  camera.eye = {0, 0, 10};
  camera.target = {0, 0, 0};
  camera.up = {0, 0, 1};
  CameraFrame f = cameraFrame(camera);
  EXPECT_NEAR(glm::length(f.right), 1.0, 1e-9);
  EXPECT_NEAR(glm::length(f.up), 1.0, 1e-9);
  EXPECT_NEAR(glm::dot(f.right, f.forward), 0.0, 1e-9);
  EXPECT_NEAR(glm::dot(f.up, f.forward), 0.0, 1e-9);
  EXPECT_NEAR(f.up.y, 1.0, 1e-9);  // north-up top view
}

TEST(Snapshot, KicadConnectorFromFile) {
  auto model = test::sharedDataDir() / "kicad_dsub62.obj";
  if (!std::filesystem::exists(model)) GTEST_SKIP() << "no " << model;
  SnapshotOptions options;
  options.render.width = 160;
  options.render.height = 90;
  options.render.samples = 1;
  auto png = test::scratchDir() / "kicad.png";
  SnapshotReport report = snapshotFile(model, png, options);
  EXPECT_EQ(report.triangles, 94176u);
  EXPECT_EQ(report.objects, 648u);
  // A long connector seen from three-quarters: a good part of the frame is geometry.
  EXPECT_GT(report.hit_pixels, 160u * 90u / 5u);
  EXPECT_LT(report.hit_pixels, 160u * 90u);
  int w = 0, h = 0, channels = 0;
  ASSERT_TRUE(stbi_info(png.string().c_str(), &w, &h, &channels));
  EXPECT_EQ(w, 160);
  EXPECT_EQ(h, 90);
}

TEST(Snapshot, UnreadableFileIsAFormatError) {
  auto path = test::scratchDir() / "broken.obj";
  test::writeFile(path, "v 0 0 0\nf 1 2 3\n");
  SnapshotOptions options;
  options.render = smallOptions();
  EXPECT_THROW(snapshotFile(path, test::scratchDir() / "broken.png", options), FormatError);
  EXPECT_FALSE(std::filesystem::exists(test::scratchDir() / "broken.png"));
}

}  // namespace
