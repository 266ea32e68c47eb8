// The camera (orientation, reversed-Z projection, frustum tests) and camera paths (the text
// format's reader and writer, interpolation, generated orbit and fly-through paths).
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <string>

#include "camera.h"
#include "camera_path.h"
#include "format_error.h"
#include "test_support.h"

namespace tw {
namespace {

namespace fs = std::filesystem;
constexpr double kPi = std::numbers::pi;
constexpr double kDeg = kPi / 180.0;

glm::dvec4 clipOf(const Camera& camera, double aspect, const glm::dvec3& world) {
  return camera.projection(aspect) * camera.viewRotation() *
         glm::dvec4(world - camera.position, 1.0);
}

glm::dvec3 ndcOf(const Camera& camera, double aspect, const glm::dvec3& world) {
  glm::dvec4 clip = clipOf(camera, aspect, world);
  return glm::dvec3(clip) / clip.w;
}

void expectNear(const glm::dvec3& a, const glm::dvec3& b, double tolerance) {
  EXPECT_NEAR(a.x, b.x, tolerance);
  EXPECT_NEAR(a.y, b.y, tolerance);
  EXPECT_NEAR(a.z, b.z, tolerance);
}

double planeDistance(const glm::dvec4& plane, const glm::dvec3& p) {
  return glm::dot(glm::dvec3(plane), p) + plane.w;
}

// The eight corners of the camera's frustum with its eye at `eye`.
std::vector<glm::dvec3> frustumCorners(const Camera& camera, const glm::dvec3& eye, double aspect) {
  std::vector<glm::dvec3> corners;
  double ty = std::tan(camera.fov_y_rad / 2), tx = ty * aspect;
  for (double d : {camera.near_m, camera.far_m})
    for (double sx : {-1.0, 1.0})
      for (double sy : {-1.0, 1.0})
        corners.push_back(eye + camera.forward() * d + camera.right() * (sx * tx * d) +
                          camera.up() * (sy * ty * d));
  return corners;
}

TEST(Camera, OrientationFollowsYawAndPitch) {
  Camera camera;
  expectNear(camera.forward(), {1, 0, 0}, 1e-15);
  expectNear(camera.right(), {0, -1, 0}, 1e-15);
  expectNear(camera.up(), {0, 0, 1}, 1e-15);
  camera.yaw_rad = kPi / 2;
  expectNear(camera.forward(), {0, 1, 0}, 1e-15);
  expectNear(camera.right(), {1, 0, 0}, 1e-15);
  camera.yaw_rad = 0.3;
  camera.pitch_rad = 0.4;
  glm::dvec3 f = camera.forward(), r = camera.right(), u = camera.up();
  EXPECT_NEAR(glm::length(f), 1.0, 1e-15);
  EXPECT_NEAR(glm::length(r), 1.0, 1e-15);
  EXPECT_NEAR(glm::length(u), 1.0, 1e-15);
  EXPECT_NEAR(glm::dot(f, r), 0.0, 1e-15);
  EXPECT_NEAR(glm::dot(f, u), 0.0, 1e-15);
  EXPECT_GT(u.z, 0.0);           // image up leans toward world up
  EXPECT_NEAR(f.z, std::sin(0.4), 1e-15);
  EXPECT_EQ(r.z, 0.0);           // right stays horizontal
}

TEST(Camera, ViewRotationMapsToEyeAxes) {
  Camera camera;
  camera.yaw_rad = 1.1;
  camera.pitch_rad = -0.3;
  glm::dmat4 view = camera.viewRotation();
  expectNear(glm::dvec3(view * glm::dvec4(camera.right(), 0)), {1, 0, 0}, 1e-14);
  expectNear(glm::dvec3(view * glm::dvec4(camera.up(), 0)), {0, 1, 0}, 1e-14);
  expectNear(glm::dvec3(view * glm::dvec4(camera.forward(), 0)), {0, 0, -1}, 1e-14);
  expectNear(glm::dvec3(view * glm::dvec4(1, 2, 3, 1)) - glm::dvec3(view * glm::dvec4(0, 0, 0, 1)),
             glm::dvec3(view * glm::dvec4(1, 2, 3, 0)), 1e-14);  // no translation
}

TEST(Camera, ReversedZProjectionOfKnownPoints) {
  Camera camera;
  camera.position = {500000.0, 7000000.0, 3.0};  // plant coordinates: eye-relative math
  camera.yaw_rad = 0.7;
  camera.pitch_rad = 0.2;
  camera.fov_y_rad = 70 * kDeg;
  camera.near_m = 0.1;
  camera.far_m = 5000.0;
  const double aspect = 16.0 / 9.0;
  glm::dvec3 f = camera.forward(), r = camera.right(), u = camera.up();
  EXPECT_NEAR(ndcOf(camera, aspect, camera.position + f * camera.near_m).z, 1.0, 1e-9);
  EXPECT_NEAR(ndcOf(camera, aspect, camera.position + f * camera.far_m).z, 0.0, 1e-9);
  // Depth decreases with distance (reversed Z) and stays in [0, 1].
  double previous = 2.0;
  for (double d : {0.1, 0.5, 3.0, 40.0, 700.0, 5000.0}) {
    double z = ndcOf(camera, aspect, camera.position + f * d).z;
    EXPECT_LT(z, previous);
    EXPECT_GE(z, -1e-12);
    previous = z;
  }
  // The edges of the field of view land on the edges of the image.
  double d = 25.0, ty = std::tan(camera.fov_y_rad / 2);
  glm::dvec3 top = ndcOf(camera, aspect, camera.position + f * d + u * (ty * d));
  EXPECT_NEAR(top.x, 0.0, 1e-9);
  EXPECT_NEAR(top.y, 1.0, 1e-9);
  glm::dvec3 right_edge = ndcOf(camera, aspect, camera.position + f * d + r * (ty * aspect * d));
  EXPECT_NEAR(right_edge.x, 1.0, 1e-9);
  EXPECT_NEAR(right_edge.y, 0.0, 1e-9);
  // A point behind the eye has w < 0.
  EXPECT_LT(clipOf(camera, aspect, camera.position - f * 2.0).w, 0.0);
}

TEST(Camera, PixelScaleMatchesProjection) {
  Camera camera;
  camera.fov_y_rad = 90 * kDeg;
  EXPECT_NEAR(camera.pixelScale(720), 360.0, 1e-9);
  camera.fov_y_rad = 50 * kDeg;
  camera.yaw_rad = -0.4;
  const double height = 600, aspect = 4.0 / 3.0;
  double scale = camera.pixelScale(height);
  // An offset of 0.3 m at 12 m spans 0.3 * scale / 12 pixels on screen.
  glm::dvec3 p = camera.position + camera.forward() * 12.0 + camera.up() * 0.3;
  double pixels = ndcOf(camera, aspect, p).y * height / 2.0;
  EXPECT_NEAR(pixels, 0.3 * scale / 12.0, 1e-9);
}

TEST(Camera, LookAtPointsTheCameraAtTheTarget) {
  Camera camera;
  camera.position = {500000.0, 7000000.0, 10.0};
  glm::dvec3 target = camera.position + glm::dvec3(-3.0, 4.0, -5.0);
  camera.lookAt(target);
  expectNear(camera.forward(), glm::normalize(target - camera.position), 1e-12);
  // Straight down keeps the yaw; a target at the eye changes nothing.
  double yaw = camera.yaw_rad;
  camera.lookAt(camera.position + glm::dvec3(0, 0, -1));
  EXPECT_EQ(camera.yaw_rad, yaw);
  EXPECT_NEAR(camera.pitch_rad, -kPi / 2, 1e-15);
  Camera before = camera;
  camera.lookAt(camera.position);
  EXPECT_EQ(camera.yaw_rad, before.yaw_rad);
  EXPECT_EQ(camera.pitch_rad, before.pitch_rad);
}

TEST(Frustum, PlanesContainTheCornersAndPointInward) {
  Camera camera;
  camera.yaw_rad = 2.2;
  camera.pitch_rad = 0.5;
  camera.near_m = 0.5;
  camera.far_m = 300.0;
  const double aspect = 1.5;
  glm::dvec3 eye(12.0, -4.0, 7.0);
  Frustum frustum = makeFrustum(camera, eye, aspect);
  for (const glm::dvec4& plane : frustum.planes)
    EXPECT_NEAR(glm::length(glm::dvec3(plane)), 1.0, 1e-12);
  auto corners = frustumCorners(camera, eye, aspect);
  // Each corner lies on exactly three planes and inside the other three.
  for (const glm::dvec3& corner : corners) {
    int on = 0;
    for (const glm::dvec4& plane : frustum.planes) {
      double d = planeDistance(plane, corner);
      EXPECT_GE(d, -1e-9);
      if (std::abs(d) < 1e-9) ++on;
    }
    EXPECT_EQ(on, 3);
  }
  glm::dvec3 inside = eye + camera.forward() * 50.0;
  for (const glm::dvec4& plane : frustum.planes) EXPECT_GT(planeDistance(plane, inside), 0.0);
}

TEST(Frustum, SphereTestsInsideOutsideStraddling) {
  Camera camera;  // at the origin looking along +X, fov 60
  camera.near_m = 1.0;
  camera.far_m = 100.0;
  Frustum frustum = makeFrustum(camera, camera.position, 1.0);
  EXPECT_TRUE(frustum.intersectsSphere({50, 0, 0}, 1.0));     // inside
  EXPECT_FALSE(frustum.intersectsSphere({-5, 0, 0}, 1.0));    // behind
  EXPECT_TRUE(frustum.intersectsSphere({0.5, 0, 0}, 0.6));    // straddles the near plane
  EXPECT_FALSE(frustum.intersectsSphere({0.5, 0, 0}, 0.4));   // just in front of the eye
  EXPECT_TRUE(frustum.intersectsSphere({100.5, 0, 0}, 0.6));  // straddles the far plane
  EXPECT_FALSE(frustum.intersectsSphere({101, 0, 0}, 0.5));   // beyond it
  // Against the left plane (normal r + f tan30, through the eye): a centre at distance s
  // outside it intersects iff s <= radius.
  glm::dvec3 normal = glm::dvec3(frustum.planes[2]);
  glm::dvec3 on_plane = glm::dvec3(20, 20 * std::tan(kPi / 6), 0);  // left edge at 20 m
  EXPECT_NEAR(planeDistance(frustum.planes[2], on_plane), 0.0, 1e-12);
  EXPECT_TRUE(frustum.intersectsSphere(on_plane - normal * 0.99, 1.0));
  EXPECT_FALSE(frustum.intersectsSphere(on_plane - normal * 1.01, 1.0));
}

TEST(Frustum, BoxTestsInsideOutsideStraddling) {
  Camera camera;
  camera.near_m = 1.0;
  camera.far_m = 100.0;
  Frustum frustum = makeFrustum(camera, camera.position, 1.0);
  EXPECT_TRUE(frustum.intersectsBox({40, -1, -1}, {42, 1, 1}));    // inside
  EXPECT_FALSE(frustum.intersectsBox({-10, -1, -1}, {-2, 1, 1}));  // behind
  EXPECT_TRUE(frustum.intersectsBox({-10, -1, -1}, {2, 1, 1}));    // through the near plane
  EXPECT_FALSE(frustum.intersectsBox({10, 30, -1}, {12, 40, 1}));  // left of the view
  EXPECT_TRUE(frustum.intersectsBox({10, 5, -1}, {12, 40, 1}));    // across the left plane
  EXPECT_FALSE(frustum.intersectsBox({150, -1, -1}, {160, 1, 1}));  // beyond the far plane
  EXPECT_TRUE(frustum.intersectsBox({-1000, -1000, -1000}, {1000, 1000, 1000}));  // encloses it
}

// The frustum and the projection agree: random points are inside the planes exactly when their
// clip coordinates are inside the reversed-Z clip volume (eye at plant coordinates).
TEST(Frustum, AgreesWithTheProjection) {
  Camera camera;
  camera.position = {500000.0, 7000000.0, 20.0};
  camera.yaw_rad = -2.0;
  camera.pitch_rad = -0.3;
  camera.near_m = 0.2;
  camera.far_m = 400.0;
  const double aspect = 16.0 / 9.0;
  Frustum frustum = makeFrustum(camera, camera.position, aspect);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> coordinate(-300.0, 300.0);
  int inside_count = 0, checked = 0;
  for (int i = 0; i < 20000; ++i) {
    glm::dvec3 p = camera.position + glm::dvec3(coordinate(rng), coordinate(rng), coordinate(rng));
    glm::dvec4 clip = clipOf(camera, aspect, p);
    bool by_clip = clip.w > 0 && std::abs(clip.x) <= clip.w && std::abs(clip.y) <= clip.w &&
                   clip.z >= 0 && clip.z <= clip.w;
    bool by_planes = frustum.intersectsSphere(p, 0.0);
    // Skip points within a hair of a plane, where rounding may differ.
    double margin = 1e9;
    for (const glm::dvec4& plane : frustum.planes)
      margin = std::min(margin, std::abs(planeDistance(plane, p)));
    if (margin < 1e-6) continue;
    ++checked;
    EXPECT_EQ(by_clip, by_planes) << p.x << " " << p.y << " " << p.z;
    inside_count += by_planes;
  }
  EXPECT_GT(inside_count, 100);  // the sample covers both cases
  EXPECT_GT(checked - inside_count, 100);
}

// ---- Camera paths ----

CameraPath plantPath() {
  CameraPath path;
  for (int i = 0; i < 5; ++i) {
    CameraKey key;
    key.time_s = i * 0.1 + (i == 3 ? 1e-7 : 0.0);
    key.camera.position = {500000.0 + i * 1.234567891, 7000000.0 - i * 0.1, 0.0 + i / 3.0};
    key.camera.yaw_rad = 0.1 * i - 1.0;
    key.camera.pitch_rad = -0.05 * i;
    key.camera.fov_y_rad = (60 - i) * kDeg;
    path.keys.push_back(key);
  }
  return path;
}

TEST(CameraPath, RoundTripKeepsPlantCoordinatesExact) {
  CameraPath path = plantPath();
  fs::path file = test::scratchDir() / "plant.path";
  writeCameraPath(path, file);
  EXPECT_FALSE(fs::exists(file.string() + ".tmp"));
  CameraPath back = readCameraPath(file);
  ASSERT_EQ(back.keys.size(), path.keys.size());
  for (size_t i = 0; i < path.keys.size(); ++i) {
    EXPECT_EQ(back.keys[i].time_s, path.keys[i].time_s);
    EXPECT_EQ(back.keys[i].camera.position, path.keys[i].camera.position);  // bit-exact
    EXPECT_NEAR(back.keys[i].camera.yaw_rad, path.keys[i].camera.yaw_rad, 1e-14);
    EXPECT_NEAR(back.keys[i].camera.pitch_rad, path.keys[i].camera.pitch_rad, 1e-14);
    EXPECT_NEAR(back.keys[i].camera.fov_y_rad, path.keys[i].camera.fov_y_rad, 1e-14);
  }
  EXPECT_NEAR(back.durationS(), 0.4, 1e-12);
}

TEST(CameraPath, ReadsTheSampleWithCommentsBlankLinesAndCrlf) {
  CameraPath path = readCameraPath(test::dataDir() / "paths" / "bunny_walk.path");
  ASSERT_EQ(path.keys.size(), 5u);
  EXPECT_EQ(path.keys[2].time_s, 4.0);
  EXPECT_EQ(path.keys[2].camera.position, glm::dvec3(-0.417, 0.110, 0.05));
  EXPECT_NEAR(path.keys[2].camera.fov_y_rad, 45 * kDeg, 1e-15);
  EXPECT_EQ(path.durationS(), 8.0);

  fs::path file = test::scratchDir() / "crlf.path";
  test::writeFile(file, "# terawalk camera path 1\r\n\r\n  # indented comment\r\n"
                        "0 1 2 3 0 0 60\r\n\t1.5\t4 5 6 90 -10 50   \r\n");
  CameraPath crlf = readCameraPath(file);
  ASSERT_EQ(crlf.keys.size(), 2u);
  test::writeFile(file, "\xEF\xBB\xBF# terawalk camera path 1\n0 1 2 3 0 0 60\n");  // BOM
  EXPECT_EQ(readCameraPath(file).keys.size(), 1u);
  EXPECT_EQ(crlf.keys[1].camera.position, glm::dvec3(4, 5, 6));
  EXPECT_NEAR(crlf.keys[1].camera.pitch_rad, -10 * kDeg, 1e-15);
}

// Each bad input is rejected with a FormatError at its line, naming the file and the reason.
TEST(CameraPath, BadInputsNameTheLineAndReason) {
  struct Case {
    std::string text;
    uint64_t line;
    std::string reason;
  };
  const std::string header = "# terawalk camera path 1\n";
  const Case cases[] = {
      {"", 1, "empty file"},
      {"0 1 2 3 0 0 60\n", 1, "first line must be"},
      {"# terawalk camera path\n0 1 2 3 0 0 60\n", 1, "no version"},
      {"# terawalk camera path 2\n0 1 2 3 0 0 60\n", 1, "unsupported camera path version 2"},
      {header + "0 1 2 3 0 0\n", 2, "expected 7 fields"},
      {header + "# c\n0 1 2 3 0 0 60 7\n", 3, "found more"},
      {header + "0 1 2 3 0 0 60\n1 1 two 3 0 0 60\n", 3, "y is not a number: 'two'"},
      {header + "0 1 2 3 0 0 60x\n", 2, "fov_y_deg is not a number"},
      {header + "0 nan 2 3 0 0 60\n", 2, "non-finite x"},
      {header + "0 1 2 -inf 0 0 60\n", 2, "non-finite z"},
      {header + "0 1 2 3 1e999 0 60\n", 2, "yaw_deg"},
      {header + "0 1 2 3 0 0 60\n\n0.5 1 2 3 0 0 60\n0.5 1 2 3 0 0 60\n", 5,
       "time does not increase"},
      {header + "1 1 2 3 0 0 60\n0.5 1 2 3 0 0 60\n", 3, "time does not increase"},
      {header + "0 1 2 3 0 95 60\n", 2, "pitch_deg outside"},
      {header + "0 1 2 3 0 0 180\n", 2, "fov_y_deg outside"},
      {header + "# only comments\n", 2, "no key frames"},
  };
  fs::path file = test::scratchDir() / "bad.path";
  for (const Case& c : cases) {
    test::writeFile(file, c.text);
    try {
      readCameraPath(file);
      ADD_FAILURE() << "accepted: " << c.text;
    } catch (const FormatError& e) {
      EXPECT_EQ(e.where(), FormatError::Where::Line) << e.what();
      EXPECT_EQ(e.position(), c.line) << e.what();
      EXPECT_NE(e.reason().find(c.reason), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("bad.path"), std::string::npos) << e.what();
    }
  }
}

TEST(CameraPath, MissingFileAndUnwritableTargetThrow) {
  fs::path dir = test::scratchDir();
  EXPECT_THROW(readCameraPath(dir / "missing.path"), std::runtime_error);
  EXPECT_THROW(writeCameraPath(plantPath(), dir / "no-such-dir" / "x.path"), std::runtime_error);
}

TEST(CameraPath, RobustToTruncationAndCorruption) {
  std::string original = test::readFile(test::dataDir() / "paths" / "bunny_walk.path");
  ASSERT_GT(original.size(), 200u);
  int rejected = test::expectRobustToDamage(
      original, "walk.path", [](const fs::path& p, SceneSink&) { readCameraPath(p); });
  EXPECT_GT(rejected, 100);  // most truncations cut the header or a key line
  // A generated path too, with long numbers.
  fs::path file = test::scratchDir() / "generated.path";
  writeCameraPath(plantPath(), file);
  test::expectRobustToDamage(test::readFile(file), "generated.path",
                             [](const fs::path& p, SceneSink&) { readCameraPath(p); }, 200);
}

TEST(CameraPath, SampleInterpolatesAndClamps) {
  CameraPath path;
  CameraKey a, b;
  a.time_s = 1.0;
  a.camera.position = {500000.0, 7000000.0, 0.0};
  a.camera.yaw_rad = 350 * kDeg;
  a.camera.pitch_rad = 0.0;
  a.camera.fov_y_rad = 40 * kDeg;
  b.time_s = 3.0;
  b.camera.position = {500010.0, 7000020.0, 4.0};
  b.camera.yaw_rad = 10 * kDeg;
  b.camera.pitch_rad = 0.2;
  b.camera.fov_y_rad = 60 * kDeg;
  path.keys = {a, b};
  EXPECT_EQ(path.durationS(), 2.0);

  Camera base;
  base.near_m = 0.3;
  base.far_m = 900.0;
  Camera mid = path.sample(2.0, base);
  // Two keys: the Catmull-Rom tangents are the chord, so the curve is the straight line.
  expectNear(mid.position, {500005.0, 7000010.0, 2.0}, 1e-9);
  // Yaw goes the short way through 0 (20 degrees), not back through 180 (340 degrees).
  EXPECT_NEAR(std::cos(mid.yaw_rad), 1.0, 1e-12);
  EXPECT_NEAR(std::sin(mid.yaw_rad), 0.0, 1e-12);
  EXPECT_NEAR(mid.pitch_rad, 0.1, 1e-12);
  EXPECT_NEAR(mid.fov_y_rad, 50 * kDeg, 1e-12);
  EXPECT_EQ(mid.near_m, 0.3);
  EXPECT_EQ(mid.far_m, 900.0);
  Camera quarter = path.sample(1.5, base);
  EXPECT_NEAR(std::remainder(quarter.yaw_rad - 355 * kDeg, 2 * kPi), 0.0, 1e-12);

  EXPECT_EQ(path.sample(-5.0).position, a.camera.position);  // clamped
  EXPECT_EQ(path.sample(1.0).position, a.camera.position);   // exact at keys
  EXPECT_EQ(path.sample(99.0).position, b.camera.position);
  EXPECT_EQ(path.sample(3.0).yaw_rad, b.camera.yaw_rad);
  EXPECT_EQ(CameraPath{}.sample(1.0, base).near_m, 0.3);  // empty path: the base camera
}

TEST(CameraPath, SampleIsSmoothThroughInteriorKeys) {
  CameraPath path = plantPath();
  // Exact at every key, and continuous across them (no jump at a key).
  for (size_t i = 0; i < path.keys.size(); ++i) {
    EXPECT_EQ(path.sample(path.keys[i].time_s).position, path.keys[i].camera.position);
    if (i == 0 || i + 1 == path.keys.size()) continue;
    double t = path.keys[i].time_s;
    glm::dvec3 before = path.sample(t - 1e-6).position, after = path.sample(t + 1e-6).position;
    EXPECT_LT(glm::length(after - before), 1e-3);
    // The velocity is continuous too (C1): compare difference quotients on each side.
    glm::dvec3 v_before = (path.sample(t).position - path.sample(t - 1e-4).position) / 1e-4;
    glm::dvec3 v_after = (path.sample(t + 1e-4).position - path.sample(t).position) / 1e-4;
    EXPECT_LT(glm::length(v_after - v_before), 0.05 * glm::length(v_before) + 1e-3);
  }
}

TEST(CameraPath, OrbitFramesTheBoundsAndLooksAtTheCentre) {
  Aabb bounds;
  bounds.add(glm::dvec3(500000.0, 7000000.0, 0.0));
  bounds.add(glm::dvec3(500120.0, 7000080.0, 45.0));
  CameraPath path = generateOrbitPath(bounds, 90, 30.0);
  ASSERT_EQ(path.keys.size(), 90u);
  EXPECT_NEAR(path.durationS(), 89.0 / 30.0, 1e-12);
  glm::dvec3 center = bounds.center();
  double first_distance = glm::length(path.keys[0].camera.position - center);
  double angle_sum = 0.0;
  for (size_t i = 0; i < path.keys.size(); ++i) {
    const Camera& camera = path.keys[i].camera;
    EXPECT_NEAR(path.keys[i].time_s, i / 30.0, 1e-12);
    EXPECT_NEAR(glm::length(camera.position - center), first_distance, 1e-6);
    EXPECT_GT(camera.position.z, center.z);  // from slightly above
    EXPECT_NEAR(glm::dot(camera.forward(), glm::normalize(center - camera.position)), 1.0, 1e-12);
    // The whole box is in view at 16:9.
    Frustum frustum = makeFrustum(camera, camera.position, 16.0 / 9.0);
    for (int corner = 0; corner < 8; ++corner) {
      glm::dvec3 p((corner & 1) ? bounds.max.x : bounds.min.x,
                   (corner & 2) ? bounds.max.y : bounds.min.y,
                   (corner & 4) ? bounds.max.z : bounds.min.z);
      EXPECT_TRUE(frustum.intersectsSphere(p, 0.0)) << "key " << i << " corner " << corner;
    }
    if (i > 0) {
      glm::dvec3 a = path.keys[i - 1].camera.position - center, b = camera.position - center;
      angle_sum += std::atan2(a.x * b.y - a.y * b.x, a.x * b.x + a.y * b.y);
    }
  }
  EXPECT_NEAR(angle_sum, 2 * kPi * 89 / 90, 1e-9);  // one full turn, one step short
  EXPECT_THROW(generateOrbitPath(Aabb{}, 10), std::invalid_argument);
  EXPECT_THROW(generateOrbitPath(bounds, 0), std::invalid_argument);
}

TEST(CameraPath, FlythroughCrossesTheLongestHorizontalAxis) {
  Aabb bounds;
  bounds.add(glm::dvec3(500000.0, 7000000.0, 0.0));
  bounds.add(glm::dvec3(500040.0, 7000200.0, 30.0));  // longest along Y
  CameraPath path = generateFlythroughPath(bounds, 60, 30.0);
  ASSERT_EQ(path.keys.size(), 60u);
  const Camera& first = path.keys.front().camera;
  const Camera& last = path.keys.back().camera;
  EXPECT_LT(first.position.y, bounds.min.y);  // enters from outside
  EXPECT_GT(last.position.y, bounds.max.y);   // and leaves at the far end
  bool passed_centre = false;
  for (const CameraKey& key : path.keys) {
    EXPECT_NEAR(key.camera.position.x, bounds.center().x, 1e-9);
    EXPECT_NEAR(key.camera.position.z, 10.0, 1e-9);  // a third of the height
    expectNear(key.camera.forward(), {0, 1, 0}, 1e-12);  // looking ahead
    if (std::abs(key.camera.position.y - bounds.center().y) < 5.0) passed_centre = true;
  }
  EXPECT_TRUE(passed_centre);
  // Evenly spaced in time and in space.
  for (size_t i = 1; i < path.keys.size(); ++i) {
    EXPECT_NEAR(path.keys[i].time_s - path.keys[i - 1].time_s, 1 / 30.0, 1e-12);
    EXPECT_NEAR(path.keys[i].camera.position.y - path.keys[i - 1].camera.position.y,
                (last.position.y - first.position.y) / 59.0, 1e-6);
  }
  // Longest along X: flies along +X.
  Aabb wide;
  wide.add(glm::dvec3(0, 0, 0));
  wide.add(glm::dvec3(100, 10, 10));
  expectNear(generateFlythroughPath(wide, 2).keys[0].camera.forward(), {1, 0, 0}, 1e-12);
}

// The soak's random walk: one key per frame, the same for one seed and different for another,
// always inside the bounds grown by a tenth, and made of the four kinds of segment: teleports
// (a jump of more than a tenth of the model between two frames), fast flights (steady steps of
// about the model's length a second), turns in place and walks at 1.5 m/s.
TEST(CameraPath, RandomWalkTeleportsFliesTurnsAndWalksInsideTheModel) {
  Aabb bounds;
  bounds.add(glm::dvec3(1000.0, 2000.0, 0.0));
  bounds.add(glm::dvec3(1040.0, 2020.0, 10.0));
  const CameraPath path = generateRandomWalkPath(bounds, 3000, 30.0, 7);
  ASSERT_EQ(path.keys.size(), 3000u);
  const glm::dvec3 grown = bounds.extent() * 0.1;
  int teleports = 0, flight_steps = 0, turn_steps = 0, walk_steps = 0;
  for (size_t i = 0; i < path.keys.size(); ++i) {
    const Camera& c = path.keys[i].camera;
    EXPECT_NEAR(path.keys[i].time_s, double(i) / 30.0, 1e-9);
    for (int a = 0; a < 3; ++a) {
      EXPECT_GE(c.position[a], bounds.min[a] - grown[a] - 1e-9);
      EXPECT_LE(c.position[a], bounds.max[a] + grown[a] + 1e-9);
    }
    if (i == 0) continue;
    const Camera& b = path.keys[i - 1].camera;
    const double step = glm::length(c.position - b.position);
    const double turn = std::abs(std::remainder(c.yaw_rad - b.yaw_rad, 2.0 * std::numbers::pi));
    if (step > 4.0) ++teleports;                          // 40 m model: over a tenth
    else if (step > 0.5) ++flight_steps;                  // about 40 m/s at 30 frames a second
    else if (std::abs(step - 0.05) < 1e-6) ++walk_steps;  // 1.5 m/s
    else if (step == 0.0 && turn > 0.05) ++turn_steps;    // a turn in one to two seconds
  }
  EXPECT_GE(teleports, 10);
  EXPECT_GE(flight_steps, 100);
  EXPECT_GE(turn_steps, 300);
  EXPECT_GE(walk_steps, 300);
  const CameraPath again = generateRandomWalkPath(bounds, 3000, 30.0, 7);
  const CameraPath other = generateRandomWalkPath(bounds, 3000, 30.0, 8);
  EXPECT_EQ(again.keys.back().camera.position, path.keys.back().camera.position);
  EXPECT_NE(other.keys.back().camera.position, path.keys.back().camera.position);
}

// A walk recorded by hand (a straight line at 1.5 m/s, 30 keys a second, jittered by up to 5 cm
// and 2 degrees): the smoothed path keeps its ends and its time, lies within a few centimetres of
// the line (under a fifth of the jitter) and keeps its heading.
TEST(CameraPath, SmoothingAWalkAveragesItsJitterAndKeepsItsEnds) {
  std::mt19937 random(7);
  std::uniform_real_distribution<double> jitter(-1.0, 1.0);
  CameraPath walk;
  for (int i = 0; i <= 300; ++i) {
    CameraKey key;
    key.time_s = i / 30.0;
    key.camera.position = glm::dvec3(500000.0 + 1.5 * key.time_s, 7000000.0, 12.0) +
                          0.05 * glm::dvec3(jitter(random), jitter(random), jitter(random));
    key.camera.yaw_rad = glm::radians(179.0 + 2.0 * jitter(random));  // across the +-180 seam
    key.camera.fov_y_rad = glm::radians(60.0);
    walk.keys.push_back(key);
  }
  const CameraPath smooth = smoothCameraPath(walk, 1.0, 25.0);
  ASSERT_EQ(smooth.keys.size(), 251u);  // 10 s at 25 a second
  EXPECT_EQ(smooth.keys.front().camera.position, walk.keys.front().camera.position);
  EXPECT_EQ(smooth.keys.back().camera.position, walk.keys.back().camera.position);
  EXPECT_DOUBLE_EQ(smooth.keys.back().time_s, 10.0);
  double worst_off_line = 0.0, worst_raw = 0.0, worst_yaw = 0.0;
  for (const CameraKey& k : smooth.keys) {
    if (k.time_s < 1.0 || k.time_s > 9.0) continue;  // the ends keep their recorded jitter
    const glm::dvec3 on_line(500000.0 + 1.5 * k.time_s, 7000000.0, 12.0);
    worst_off_line = std::max(worst_off_line, glm::length(k.camera.position - on_line));
    worst_yaw = std::max(worst_yaw, std::abs(std::remainder(k.camera.yaw_rad - glm::radians(179.0), 2.0 * std::numbers::pi)));
  }
  for (const CameraKey& k : walk.keys)
    worst_raw = std::max(worst_raw, glm::length(k.camera.position - glm::dvec3(500000.0 + 1.5 * k.time_s, 7000000.0, 12.0)));
  EXPECT_LT(worst_off_line, 0.2 * worst_raw) << worst_off_line << " m against " << worst_raw << " m";
  EXPECT_LT(worst_yaw, glm::radians(0.5)) << "yaw stays by 179 degrees, across the seam";
  EXPECT_THROW(smoothCameraPath(walk, 0.0, 25.0), std::invalid_argument);
}

}  // namespace
}  // namespace tw
