// The hierarchical-Z pyramid and its box test: the CPU reduction against brute force (odd sizes
// included), the GPU compute build against the CPU one bit for bit on llvmpipe (uploaded and
// rendered depth), projectBox on known cameras and against GPU-rasterized boxes, occluded() on a
// wall, occludedBox halving a long box behind two walls, and a randomized check that neither
// occluded() nor the halving ever hides a box pixel nearer than the depth.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <memory>
#include <random>
#include <stdexcept>
#include <vector>

#define GL_GLEXT_PROTOTYPES 1
#include <GL/glcorearb.h>

#include "camera.h"
#include "egl_context.h"
#include "hzb_builder.h"
#include "hzb_pyramid.h"

namespace tw {
namespace {

// ---------------------------------------------------------------------------------------------
// Helpers

std::vector<float> randomDepth(int width, int height, std::mt19937& rng) {
  std::uniform_real_distribution<float> depth(0.0f, 1.0f);
  std::vector<float> image(size_t(width) * size_t(height));
  for (float& d : image) d = depth(rng);
  return image;
}

// Level-0 pixels covered by texel t of level k along an axis of `size0` pixels with `size_k`
// texels: [t 2^k, (t+1) 2^k - 1], the last texel reaching to the end. Written from the
// definition, independently of the reduction.
std::pair<int, int> footprint(int t, int k, int size0, int size_k) {
  const int lo = t << k;
  const int hi = (t == size_k - 1) ? size0 - 1 : ((t + 1) << k) - 1;
  return {lo, hi};
}

// The camera's view-projection (rotation only: boxes are eye-relative).
glm::mat4 viewProjection(const Camera& camera, int width, int height) {
  return glm::mat4(camera.projection(double(width) / height) * camera.viewRotation());
}

// Reversed-Z depth of a point at eye distance `distance_m` along the view axis (camera.cpp).
double depthAt(const Camera& camera, double distance_m) {
  const double n = camera.near_m, f = camera.far_m;
  return -n / (f - n) + n * f / (f - n) / distance_m;
}

// Whether a pyramid holding `depth` everywhere would call the footprint occluded: tells whether
// a rendered depth lies beyond the test's conservative margin, through the public API only.
bool hiddenBehind(float depth, ScreenFootprint fp) {
  const float one[1] = {depth};
  const HzbPyramid pyramid = HzbPyramid::fromDepth(one, 1, 1);
  fp.min_px = fp.max_px = glm::ivec2(0);
  return pyramid.occluded(fp);
}

// Brute force: the reversed-Z depth of the box's nearest point under the centre of pixel (x, y),
// or -1 when the pixel's ray misses the box (eye at the origin, box eye-relative).
double boxDepthAtPixel(const Camera& camera, const glm::dmat4& view_projection, int width,
                       int height, int x, int y, const glm::dvec3& lo, const glm::dvec3& hi) {
  const double t = std::tan(camera.fov_y_rad * 0.5);
  const double aspect = double(width) / height;
  const double ndc_x = (x + 0.5) / width * 2.0 - 1.0;
  const double ndc_y = (y + 0.5) / height * 2.0 - 1.0;
  const glm::dvec3 dir =
      camera.forward() + camera.right() * (ndc_x * aspect * t) + camera.up() * (ndc_y * t);
  double t_near = 0.0, t_far = 1e300;
  for (int a = 0; a < 3; ++a) {
    if (dir[a] == 0.0) {
      if (0.0 < lo[a] || 0.0 > hi[a]) return -1.0;
      continue;
    }
    double t0 = lo[a] / dir[a], t1 = hi[a] / dir[a];
    if (t0 > t1) std::swap(t0, t1);
    t_near = std::max(t_near, t0);
    t_far = std::min(t_far, t1);
  }
  if (t_near > t_far) return -1.0;
  const glm::dvec4 clip = view_projection * glm::dvec4(dir * t_near, 1.0);
  return clip.z / clip.w;
}

// ---------------------------------------------------------------------------------------------
// CPU pyramid

TEST(HzbPyramid, LevelSizesHalveDownToOne) {
  std::vector<float> depth(13 * 5, 0.5f);
  const HzbPyramid p = HzbPyramid::fromDepth(depth, 13, 5);
  ASSERT_EQ(p.levelCount(), 4);  // 13x5, 6x2, 3x1, 1x1
  EXPECT_EQ(p.levelSize(0), glm::ivec2(13, 5));
  EXPECT_EQ(p.levelSize(1), glm::ivec2(6, 2));
  EXPECT_EQ(p.levelSize(2), glm::ivec2(3, 1));
  EXPECT_EQ(p.levelSize(3), glm::ivec2(1, 1));
  EXPECT_EQ(p.firstLevel(), 0);
  for (int k = 0; k < p.levelCount(); ++k)
    EXPECT_EQ(p.level(k).size(), size_t(p.levelSize(k).x) * size_t(p.levelSize(k).y));
  const std::vector<float> one(1, 0.25f);
  EXPECT_EQ(HzbPyramid::fromDepth(one, 1, 1).levelCount(), 1);
  EXPECT_EQ(HzbPyramid::fromDepth(std::vector<float>(1280 * 720), 1280, 720).levelCount(), 11);
  EXPECT_THROW(p.levelSize(4), std::out_of_range);
  EXPECT_THROW(p.level(-1), std::out_of_range);
}

TEST(HzbPyramid, RejectsBadSizes) {
  std::vector<float> depth(12, 0.0f);
  EXPECT_THROW(HzbPyramid::fromDepth(depth, 5, 2), std::invalid_argument);
  EXPECT_THROW(HzbPyramid::fromDepth(depth, 0, 12), std::invalid_argument);
  EXPECT_THROW(HzbPyramid::fromDepth({}, 0, 0), std::invalid_argument);
  EXPECT_THROW(HzbPyramid::fromDepth(depth, -3, -4), std::invalid_argument);
  HzbPyramid p;
  EXPECT_THROW(p.reset(0, 4, 0), std::invalid_argument);
}

TEST(HzbPyramid, EveryTexelIsTheMinimumOverItsFootprint) {
  std::mt19937 rng(7);
  const std::vector<glm::ivec2> sizes = {{1, 1},  {1, 7},  {7, 1},   {2, 3},   {3, 3},
                                         {5, 3},  {13, 9}, {16, 16}, {64, 33}, {127, 65},
                                         {31, 2}, {2, 31}, {97, 61}};
  for (const glm::ivec2 size : sizes) {
    const std::vector<float> depth = randomDepth(size.x, size.y, rng);
    const HzbPyramid p = HzbPyramid::fromDepth(depth, size.x, size.y);
    for (int k = 0; k < p.levelCount(); ++k) {
      const glm::ivec2 s = p.levelSize(k);
      const std::span<const float> level = p.level(k);
      for (int y = 0; y < s.y; ++y)
        for (int x = 0; x < s.x; ++x) {
          const auto [x0, x1] = footprint(x, k, size.x, s.x);
          const auto [y0, y1] = footprint(y, k, size.y, s.y);
          float m = 2.0f;
          for (int py = y0; py <= y1; ++py)
            for (int px = x0; px <= x1; ++px) m = std::min(m, depth[size_t(py) * size.x + px]);
          ASSERT_EQ(level[size_t(y) * s.x + x], m)
              << size.x << "x" << size.y << " level " << k << " texel " << x << "," << y;
        }
    }
  }
}

// The frame loop rebuilds one pyramid in place (beginBuild, a read-back into level 0,
// finishBuild), its levels not cleared in between: whatever came before, the result is the
// pyramid of this depth image.
TEST(HzbPyramid, RebuildInPlaceEqualsAFreshBuild) {
  std::mt19937 rng(11);
  HzbPyramid reused;
  const std::vector<glm::ivec2> sizes = {{97, 61}, {13, 9}, {128, 72}, {31, 2}, {97, 61}};
  for (const glm::ivec2 size : sizes) {
    const std::vector<float> depth = randomDepth(size.x, size.y, rng);
    const std::span<float> base = reused.beginBuild(size.x, size.y);
    ASSERT_EQ(base.size(), depth.size());
    std::copy(depth.begin(), depth.end(), base.begin());
    reused.finishBuild();
    const HzbPyramid fresh = HzbPyramid::fromDepth(depth, size.x, size.y);
    ASSERT_EQ(reused.levelCount(), fresh.levelCount());
    for (int k = 0; k < fresh.levelCount(); ++k) {
      const std::span<const float> a = reused.level(k), b = fresh.level(k);
      EXPECT_TRUE(std::equal(a.begin(), a.end(), b.begin(), b.end()))
          << size.x << "x" << size.y << " level " << k;
    }
  }
}

TEST(HzbPyramid, OddColumnIsNotLost) {
  // 3x1: the only near pixel is the odd last one; level 1 (1x1) must still see the far one.
  const std::vector<float> depth = {0.9f, 0.9f, 0.1f};
  const HzbPyramid p = HzbPyramid::fromDepth(depth, 3, 1);
  ASSERT_EQ(p.levelCount(), 2);
  EXPECT_EQ(p.level(1)[0], 0.1f);
}

TEST(HzbPyramid, ResetKeepsOnlyTheRequestedLevels) {
  HzbPyramid p;
  p.reset(40, 20, 2);
  EXPECT_EQ(p.levelCount(), 6);
  EXPECT_EQ(p.firstLevel(), 2);
  EXPECT_TRUE(p.level(0).empty());
  EXPECT_TRUE(p.level(1).empty());
  EXPECT_EQ(p.mutableLevel(2).size(), size_t(10 * 5));
  p.reset(40, 20, 99);  // clamped to the last level
  EXPECT_EQ(p.firstLevel(), 5);
}

// ---------------------------------------------------------------------------------------------
// projectBox

class ProjectBox : public ::testing::Test {
 protected:
  static constexpr int kW = 320, kH = 180;
  Camera camera_;  // at the origin looking along +X, Z up
  glm::mat4 vp_ = viewProjection(camera_, kW, kH);
};

TEST_F(ProjectBox, BoxStraightAheadHasTheExpectedRectangleAndDepth) {
  // Camera frame: image right = -Y, image up = +Z, distance = X.
  const glm::vec3 lo(10.0f, -1.0f, -0.5f), hi(12.0f, 1.0f, 0.5f);
  const ScreenFootprint fp = projectBox(lo, hi, vp_, kW, kH);
  ASSERT_FALSE(fp.visible_for_sure);
  ASSERT_FALSE(fp.offscreen);
  const double t = std::tan(camera_.fov_y_rad * 0.5), aspect = double(kW) / kH;
  // Nearest face at 10 m: half-width 1 m, half-height 0.5 m.
  const double half_w_px = 1.0 / (10.0 * aspect * t) * 0.5 * kW;
  const double half_h_px = 0.5 / (10.0 * t) * 0.5 * kH;
  const double x0 = kW / 2.0 - half_w_px, x1 = kW / 2.0 + half_w_px;
  const double y0 = kH / 2.0 - half_h_px, y1 = kH / 2.0 + half_h_px;
  // Rounded outward by one pixel, no more.
  EXPECT_EQ(fp.min_px.x, int(std::floor(x0)) - 1);
  EXPECT_EQ(fp.max_px.x, int(std::floor(x1)) + 1);
  EXPECT_EQ(fp.min_px.y, int(std::floor(y0)) - 1);
  EXPECT_EQ(fp.max_px.y, int(std::floor(y1)) + 1);
  EXPECT_NEAR(fp.nearest_depth, depthAt(camera_, 10.0), 1e-9);
  EXPECT_GE(double(fp.nearest_depth), depthAt(camera_, 10.0) * (1 - 1e-7));
}

TEST_F(ProjectBox, HugeBoxIsClampedToTheViewport) {
  const ScreenFootprint fp = projectBox({5.0f, -1e4f, -1e4f}, {6.0f, 1e4f, 1e4f}, vp_, kW, kH);
  ASSERT_FALSE(fp.visible_for_sure);
  ASSERT_FALSE(fp.offscreen);
  EXPECT_EQ(fp.min_px, glm::ivec2(0, 0));
  EXPECT_EQ(fp.max_px, glm::ivec2(kW - 1, kH - 1));
}

TEST_F(ProjectBox, BoxCrossingTheNearPlaneIsVisibleForSure) {
  // Straddles the eye plane.
  EXPECT_TRUE(projectBox({-1.0f, -1.0f, -1.0f}, {1.0f, 1.0f, 1.0f}, vp_, kW, kH).visible_for_sure);
  // In front of the eye but reaching inside the near plane (0.05 m).
  EXPECT_TRUE(projectBox({0.01f, -0.1f, -0.1f}, {1.0f, 0.1f, 0.1f}, vp_, kW, kH).visible_for_sure);
  // Entirely past the near plane: an ordinary box.
  EXPECT_FALSE(projectBox({0.1f, -0.1f, -0.1f}, {1.0f, 0.1f, 0.1f}, vp_, kW, kH).visible_for_sure);
}

TEST_F(ProjectBox, BoxBehindTheCameraIsNeverOccluded) {
  const ScreenFootprint fp = projectBox({-12.0f, -1.0f, -1.0f}, {-10.0f, 1.0f, 1.0f}, vp_, kW, kH);
  EXPECT_TRUE(fp.visible_for_sure || fp.offscreen);
  // Even against a pyramid full of the nearest possible depth.
  const std::vector<float> near_wall(size_t(kW) * kH, 1.0f);
  EXPECT_FALSE(HzbPyramid::fromDepth(near_wall, kW, kH).occluded(fp));
}

TEST_F(ProjectBox, BoxesBesideOrBeyondTheViewAreOffscreen) {
  EXPECT_TRUE(projectBox({10.0f, 50.0f, -1.0f}, {11.0f, 52.0f, 1.0f}, vp_, kW, kH).offscreen);
  EXPECT_TRUE(projectBox({10.0f, -1.0f, 30.0f}, {11.0f, 1.0f, 31.0f}, vp_, kW, kH).offscreen);
  EXPECT_TRUE(projectBox({30000.0f, -1.0f, -1.0f}, {30001.0f, 1.0f, 1.0f}, vp_, kW, kH).offscreen);
  EXPECT_FALSE(projectBox({10.0f, 5.0f, -1.0f}, {11.0f, 8.0f, 1.0f}, vp_, kW, kH).offscreen);
}

// ---------------------------------------------------------------------------------------------
// A finer span tests at a finer level: it hides a box beside a hole that a coarse test, whose
// texels mix in the hole, cannot.
TEST(HzbPyramidTest, FinerSpanCullsBesideAHole) {
  const int w = 256, h = 256;
  std::vector<float> depth(size_t(w) * h, 0.5f);
  for (int y = 100; y < 156; ++y)
    for (int x = 0; x < 8; ++x) depth[size_t(y) * w + x] = 0.0f;  // a hole at the left edge
  const HzbPyramid p = HzbPyramid::fromDepth(depth, w, h);
  ScreenFootprint fp;
  fp.min_px = {16, 96};
  fp.max_px = {80, 160};  // 65 px: beside the hole, not over it
  fp.nearest_depth = 0.25f;
  EXPECT_FALSE(p.occluded(fp, 1));   // level 6: one texel also covers the hole
  EXPECT_TRUE(p.occluded(fp, 16));   // level 2: the texels under the box are all wall
}

// occluded()

class WallTest : public ProjectBox {
 protected:
  // A wall facing the camera at 10 m: constant depth across the screen (depth depends on the eye
  // distance along the view axis only). Optionally only the left `covered_columns` columns.
  HzbPyramid wall(int covered_columns = kW) const {
    std::vector<float> depth(size_t(kW) * kH, 0.0f);
    const float wall_depth = float(depthAt(camera_, 10.0));
    for (int y = 0; y < kH; ++y)
      for (int x = 0; x < covered_columns; ++x) depth[size_t(y) * kW + x] = wall_depth;
    return HzbPyramid::fromDepth(depth, kW, kH);
  }
};

TEST_F(WallTest, SmallBoxBehindAFullScreenWallIsOccluded) {
  const HzbPyramid p = wall();
  EXPECT_TRUE(p.occluded(projectBox({20.0f, -0.2f, -0.2f}, {20.4f, 0.2f, 0.2f}, vp_, kW, kH)));
  // Just behind the wall: 5 cm at 10 m is far beyond the precision margin.
  EXPECT_TRUE(p.occluded(projectBox({10.05f, -2.0f, -1.0f}, {11.0f, 2.0f, 1.0f}, vp_, kW, kH)));
  // A box far bigger than the screen, still behind.
  EXPECT_TRUE(p.occluded(projectBox({15.0f, -100.0f, -100.0f}, {16.0f, 100.0f, 100.0f}, vp_, kW,
                                    kH)));
}

TEST_F(WallTest, BoxInFrontOfOrTouchingTheWallIsNot) {
  const HzbPyramid p = wall();
  EXPECT_FALSE(p.occluded(projectBox({5.0f, -0.2f, -0.2f}, {5.4f, 0.2f, 0.2f}, vp_, kW, kH)));
  // Reaching through the wall: its nearest point is in front.
  EXPECT_FALSE(p.occluded(projectBox({9.9f, -0.2f, -0.2f}, {20.0f, 0.2f, 0.2f}, vp_, kW, kH)));
  // Its front face exactly on the wall: equal depth is not hidden (strict test).
  EXPECT_FALSE(p.occluded(projectBox({10.0f, -0.2f, -0.2f}, {11.0f, 0.2f, 0.2f}, vp_, kW, kH)));
  // Behind by less than the precision margin (2^-16 relative; here 5e-6): kept, because the
  // rasterized depth of either surface may be off by a few float ulps.
  EXPECT_FALSE(p.occluded(projectBox({10.00005f, -0.2f, -0.2f}, {11.0f, 0.2f, 0.2f}, vp_, kW, kH)));
  // Nothing to test against, or never culled.
  EXPECT_FALSE(HzbPyramid().occluded(projectBox({20.0f, -1.0f, -1.0f}, {21.0f, 1.0f, 1.0f}, vp_,
                                                kW, kH)));
}

TEST_F(WallTest, BoxPartlyBesideTheWallIsNot) {
  const HzbPyramid p = wall(kW / 2);  // left half of the image (image left = +Y)
  // Behind the wall, straddling the wall's right edge (the image centre).
  EXPECT_FALSE(p.occluded(projectBox({20.0f, -1.0f, -0.2f}, {21.0f, 1.0f, 0.2f}, vp_, kW, kH)));
  // Behind and wholly inside the left half.
  EXPECT_TRUE(p.occluded(projectBox({20.0f, 3.0f, -0.2f}, {21.0f, 5.0f, 0.2f}, vp_, kW, kH)));
  // Wholly in the right half: nothing drawn there.
  EXPECT_FALSE(p.occluded(projectBox({20.0f, -5.0f, -0.2f}, {21.0f, -3.0f, 0.2f}, vp_, kW, kH)));
}

TEST_F(WallTest, CoarseLevelsAloneStillCullAndNeverOverCull) {
  // A GPU read-back may skip the fine levels: the test then runs on coarser texels.
  const HzbPyramid full = wall(kW / 2);
  HzbPyramid coarse;
  coarse.reset(kW, kH, 3);
  for (int k = 3; k < full.levelCount(); ++k) {
    const auto src = full.level(k);
    std::copy(src.begin(), src.end(), coarse.mutableLevel(k).begin());
  }
  const ScreenFootprint hidden = projectBox({20.0f, 3.0f, -0.2f}, {20.2f, 3.2f, 0.2f}, vp_, kW, kH);
  EXPECT_TRUE(coarse.occluded(hidden));
  const ScreenFootprint straddling =
      projectBox({20.0f, -0.1f, -0.1f}, {20.2f, 0.1f, 0.1f}, vp_, kW, kH);
  EXPECT_FALSE(coarse.occluded(straddling));
}

// occludedBox: halving a box not hidden as a whole.

class BoxHalving : public ProjectBox {
 protected:
  // Rows below `boundary_row` (the lower part of the image) hold a wall at 10 m, the rows above it
  // one at `upper_m`.
  std::vector<float> depthImage(double upper_m) const {
    std::vector<float> depth(size_t(kW) * kH);
    for (int y = 0; y < kH; ++y)
      for (int x = 0; x < kW; ++x)
        depth[size_t(y) * kW + x] = float(depthAt(camera_, y < kBoundaryRow ? 10.0 : upper_m));
    return depth;
  }
  // Whether the box truly hides behind `depth`: every pixel it covers (ray through the pixel
  // centre) lies farther than the depth there.
  bool trulyHidden(const std::vector<float>& depth, const glm::vec3& lo, const glm::vec3& hi) const {
    for (int y = 0; y < kH; ++y)
      for (int x = 0; x < kW; ++x) {
        const double box = boxDepthAtPixel(camera_, glm::dmat4(vp_), kW, kH, x, y,
                                           glm::dvec3(lo), glm::dvec3(hi));
        if (box >= 0.0 && !(box < depth[size_t(y) * kW + x])) return false;
      }
    return true;
  }
  static constexpr int kBoundaryRow = 70;
  // A beam below the eye running away from it, 12 to 40 m: its near end projects low in the
  // image, behind the 10 m wall; its far end higher up, past the boundary row, where only points
  // from about 19 m on land.
  const glm::vec3 lo_{12.0f, -0.5f, -3.0f}, hi_{40.0f, 0.5f, -2.5f};
};

TEST_F(BoxHalving, LongBoxBehindTwoWallsIsCulledOnlyByItsHalves) {
  const std::vector<float> depth = depthImage(16.0);
  ASSERT_TRUE(trulyHidden(depth, lo_, hi_));
  const HzbPyramid pyramid = HzbPyramid::fromDepth(depth, kW, kH);
  // As a whole: its nearest point, 12 m, is in front of the upper wall its rectangle reaches.
  EXPECT_FALSE(pyramid.occluded(projectBox(lo_, hi_, vp_, kW, kH), 16));
  BoxTest whole;
  whole.split_px = 0;
  EXPECT_EQ(occludedBox(pyramid, lo_, hi_, vp_, whole), BoxVisibility::Visible);
  BoxTest halving;
  halving.split_px = 4;
  EXPECT_EQ(occludedBox(pyramid, lo_, hi_, vp_, halving), BoxVisibility::Occluded);
  // Too few halvings to reach the pieces that are hidden.
  halving.max_splits = 1;
  EXPECT_EQ(occludedBox(pyramid, lo_, hi_, vp_, halving), BoxVisibility::Visible);
}

TEST_F(BoxHalving, BoxPartlyInFrontOfTheFarWallIsNeverCulled) {
  // The upper wall at 24 m: the beam's stretch from about 19 to 24 m shows above the boundary.
  const std::vector<float> depth = depthImage(24.0);
  ASSERT_FALSE(trulyHidden(depth, lo_, hi_));
  const HzbPyramid pyramid = HzbPyramid::fromDepth(depth, kW, kH);
  for (int split_px : {0, 1, 4, 32}) {
    BoxTest test;
    test.split_px = split_px;
    test.max_splits = 16;
    EXPECT_EQ(occludedBox(pyramid, lo_, hi_, vp_, test), BoxVisibility::Visible) << split_px;
  }
}

TEST_F(BoxHalving, OffscreenAndEmptyPyramid) {
  const HzbPyramid pyramid = HzbPyramid::fromDepth(depthImage(16.0), kW, kH);
  EXPECT_EQ(occludedBox(pyramid, {10.0f, 50.0f, -1.0f}, {11.0f, 52.0f, 1.0f}, vp_, BoxTest{}),
            BoxVisibility::Offscreen);
  // Crossing the near plane: visible whatever the depth.
  EXPECT_EQ(occludedBox(pyramid, {-1.0f, -1.0f, -1.0f}, {1.0f, 1.0f, 1.0f}, vp_, BoxTest{}),
            BoxVisibility::Visible);
  EXPECT_EQ(occludedBox(HzbPyramid(), lo_, hi_, vp_, BoxTest{}), BoxVisibility::Visible);
}

// Random depth images (screen-aligned planes at random distances over a background of nothing)
// and random boxes, many placed just behind or just in front of a plane: whenever occluded() says
// true, every pixel the box really covers (ray through the pixel centre) is farther than the
// depth image there. The same for occludedBox's halving, which must also hide whatever the whole
// test hides.
TEST(HzbConservative, OccludedBoxesHaveNoPixelNearerThanTheDepth) {
  std::mt19937 rng(12345);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int occluded_count = 0, tested = 0, halved_only = 0;
  for (int image = 0; image < 24; ++image) {
    const int width = 40 + int(u(rng) * 90), height = 30 + int(u(rng) * 60);
    Camera camera;
    camera.yaw_rad = u(rng) * 6.28;
    camera.pitch_rad = (u(rng) - 0.5) * 2.5;
    camera.fov_y_rad = 0.6 + u(rng) * 1.0;
    camera.near_m = 0.01 + u(rng) * 0.3;
    camera.far_m = 500.0;
    const glm::mat4 vp = viewProjection(camera, width, height);
    const glm::dmat4 vpd(vp);

    // Planes: screen rectangles of constant depth; the nearest wins (reversed Z: max).
    struct Plane {
      glm::ivec2 lo, hi;
      double distance;
    };
    std::vector<Plane> planes;
    std::vector<float> depth(size_t(width) * height, 0.0f);
    for (int i = 0; i < 6; ++i) {
      Plane pl;
      pl.lo = {int(u(rng) * width * 0.7), int(u(rng) * height * 0.7)};
      pl.hi = {pl.lo.x + 3 + int(u(rng) * width * 0.6), pl.lo.y + 3 + int(u(rng) * height * 0.6)};
      pl.hi = glm::min(pl.hi, glm::ivec2(width - 1, height - 1));
      pl.distance = 1.0 + u(rng) * 40.0;
      planes.push_back(pl);
      const float d = float(depthAt(camera, pl.distance));
      for (int y = pl.lo.y; y <= pl.hi.y; ++y)
        for (int x = pl.lo.x; x <= pl.hi.x; ++x)
          depth[size_t(y) * width + x] = std::max(depth[size_t(y) * width + x], d);
    }
    const HzbPyramid pyramid = HzbPyramid::fromDepth(depth, width, height);

    const double t = std::tan(camera.fov_y_rad * 0.5), aspect = double(width) / height;
    for (int b = 0; b < 400; ++b) {
      // Aim at a random pixel of a random plane; put the box's near side around that plane.
      const Plane& pl = planes[size_t(u(rng) * planes.size())];
      const double px = pl.lo.x + u(rng) * (pl.hi.x - pl.lo.x + 1);
      const double py = pl.lo.y + u(rng) * (pl.hi.y - pl.lo.y + 1);
      const glm::dvec3 dir = camera.forward() +
                             camera.right() * ((px / width * 2 - 1) * aspect * t) +
                             camera.up() * ((py / height * 2 - 1) * t);
      const double jitter = u(rng) < 0.5 ? (u(rng) - 0.5) * 1e-3 : (u(rng) - 0.3) * 0.5;
      const double size = std::pow(10.0, -2.0 + u(rng) * 2.5);
      const glm::dvec3 centre = dir * (pl.distance * (1.0 + jitter)) + 0.5 * size * dir;
      glm::dvec3 half(size * (0.2 + u(rng)), size * (0.2 + u(rng)), size * (0.2 + u(rng)));
      const glm::vec3 lo(centre - half), hi(centre + half);
      const ScreenFootprint fp = projectBox(lo, hi, vp, width, height);
      ++tested;
      // Every span the culler may use: a finer test level must stay just as conservative.
      const int span = 1 << (b % 5);  // 1, 2, 4, 8, 16 texels
      // And halving, from every box a few pixels wide on.
      BoxTest halving;
      halving.max_span_texels = span;
      halving.split_px = 2 + b % 7;
      const bool whole = pyramid.occluded(fp, span);
      const bool halved = occludedBox(pyramid, lo, hi, vp, halving) == BoxVisibility::Occluded;
      ASSERT_TRUE(halved || !whole) << "halving never keeps what the whole test hides";
      halved_only += halved && !whole;
      if (!halved) continue;
      ++occluded_count;
      for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
          const double box_depth = boxDepthAtPixel(camera, vpd, width, height, x, y,
                                                   glm::dvec3(lo), glm::dvec3(hi));
          if (box_depth < 0.0) continue;
          ASSERT_LT(box_depth, depth[size_t(y) * width + x])
              << "image " << image << " box " << b << " span " << span << " split "
              << halving.split_px << " pixel " << x << "," << y;
        }
    }
  }
  // The check must have had work to do, and not everything is hidden either.
  EXPECT_GT(occluded_count, tested / 10);
  EXPECT_GT(halved_only, 0);
  EXPECT_LT(occluded_count, tested * 9 / 10);
}

// ---------------------------------------------------------------------------------------------
// GPU

// Depth-only rendering of boxes with the renderer's conventions (reversed Z, GREATER, depth
// cleared to 0) into a DEPTH_COMPONENT32F texture.
class GpuHzb : public ::testing::Test {
 protected:
  void SetUp() override { context_ = std::make_unique<EglContext>(); }
  void TearDown() override {
    if (program_) glDeleteProgram(program_);
    if (vao_) glDeleteVertexArrays(1, &vao_);
    if (fbo_) glDeleteFramebuffers(1, &fbo_);
    if (depth_) glDeleteTextures(1, &depth_);
    context_.reset();
  }

  void makeTarget(int width, int height) {
    if (fbo_) glDeleteFramebuffers(1, &fbo_);
    if (depth_) glDeleteTextures(1, &depth_);
    width_ = width;
    height_ = height;
    glCreateTextures(GL_TEXTURE_2D, 1, &depth_);
    glTextureStorage2D(depth_, 1, GL_DEPTH_COMPONENT32F, width, height);
    glTextureParameteri(depth_, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTextureParameteri(depth_, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glCreateFramebuffers(1, &fbo_);
    glNamedFramebufferTexture(fbo_, GL_DEPTH_ATTACHMENT, depth_, 0);
    ASSERT_EQ(glCheckNamedFramebufferStatus(fbo_, GL_FRAMEBUFFER),
              GLenum(GL_FRAMEBUFFER_COMPLETE));
  }

  void upload(const std::vector<float>& depth) {
    glTextureSubImage2D(depth_, 0, 0, 0, width_, height_, GL_DEPTH_COMPONENT, GL_FLOAT,
                        depth.data());
  }

  void clearDepth() {
    const float zero = 0.0f;
    glClearNamedFramebufferfv(fbo_, GL_DEPTH, 0, &zero);
  }

  void drawBox(const glm::vec3& lo, const glm::vec3& hi, const glm::mat4& vp) {
    if (!program_) buildProgram();
    glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
    glViewport(0, 0, width_, height_);
    glClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_GREATER);
    glDisable(GL_CULL_FACE);
    glUseProgram(program_);
    glUniformMatrix4fv(0, 1, GL_FALSE, &vp[0][0]);
    glUniform3fv(1, 1, &lo[0]);
    glUniform3fv(2, 1, &hi[0]);
    glBindVertexArray(vao_);
    glDrawArrays(GL_TRIANGLES, 0, 36);
    glBindVertexArray(0);
    glUseProgram(0);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
  }

  std::vector<float> readDepth() const {
    std::vector<float> depth(size_t(width_) * height_);
    glGetTextureImage(depth_, 0, GL_DEPTH_COMPONENT, GL_FLOAT, GLsizei(depth.size() * 4),
                      depth.data());
    return depth;
  }

  // Every read-back level equals the CPU pyramid of the same depth, bit for bit.
  static void expectSameLevels(const HzbPyramid& gpu, const HzbPyramid& cpu) {
    ASSERT_EQ(gpu.levelCount(), cpu.levelCount());
    for (int k = gpu.firstLevel(); k < gpu.levelCount(); ++k) {
      ASSERT_EQ(gpu.levelSize(k), cpu.levelSize(k));
      const auto a = gpu.level(k), b = cpu.level(k);
      ASSERT_EQ(a.size(), b.size());
      EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size_bytes()), 0) << "level " << k;
    }
  }

  std::unique_ptr<EglContext> context_;
  GLuint fbo_ = 0, depth_ = 0, program_ = 0, vao_ = 0;
  int width_ = 0, height_ = 0;

 private:
  void buildProgram() {
    // The 8 corners from two uniforms, 12 triangles from a constant index table.
    const char* vs = R"(#version 450
layout(location = 0) uniform mat4 u_vp;
layout(location = 1) uniform vec3 u_lo;
layout(location = 2) uniform vec3 u_hi;
const int kIndex[36] = int[36](0,1,3, 0,3,2, 4,6,7, 4,7,5, 0,4,5, 0,5,1,
                                2,3,7, 2,7,6, 0,2,6, 0,6,4, 1,5,7, 1,7,3);
void main() {
  int c = kIndex[gl_VertexID];
  vec3 p = vec3((c & 1) != 0 ? u_hi.x : u_lo.x, (c & 2) != 0 ? u_hi.y : u_lo.y,
                (c & 4) != 0 ? u_hi.z : u_lo.z);
  gl_Position = u_vp * vec4(p, 1.0);
})";
    const char* fs = "#version 450\nvoid main() {}\n";
    auto compile = [](GLenum stage, const char* text) {
      GLuint s = glCreateShader(stage);
      glShaderSource(s, 1, &text, nullptr);
      glCompileShader(s);
      GLint ok = 0;
      glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
      EXPECT_TRUE(ok);
      return s;
    };
    const GLuint v = compile(GL_VERTEX_SHADER, vs), f = compile(GL_FRAGMENT_SHADER, fs);
    program_ = glCreateProgram();
    glAttachShader(program_, v);
    glAttachShader(program_, f);
    glLinkProgram(program_);
    GLint ok = 0;
    glGetProgramiv(program_, GL_LINK_STATUS, &ok);
    EXPECT_TRUE(ok);
    glDeleteShader(v);
    glDeleteShader(f);
    glCreateVertexArrays(1, &vao_);
  }
};

TEST_F(GpuHzb, UploadedDepthGivesTheCpuPyramidBitForBit) {
  HzbBuilder builder;
  std::mt19937 rng(99);
  const std::vector<glm::ivec2> sizes = {{1280, 720}, {333, 211}, {1, 1},
                                         {1, 5},     {17, 1},    {64, 64}};
  for (const glm::ivec2 size : sizes) {
    SCOPED_TRACE(::testing::Message() << size.x << "x" << size.y);
    makeTarget(size.x, size.y);
    std::vector<float> depth = randomDepth(size.x, size.y, rng);
    // Some exact zeros (nothing drawn) and ones (at the near plane), as a real buffer has.
    for (size_t i = 0; i < depth.size(); i += 7) depth[i] = (i % 2) ? 0.0f : 1.0f;
    upload(depth);
    builder.build(depth_, size.x, size.y);
    HzbPyramid gpu;
    builder.readBack(gpu, 0);
    expectSameLevels(gpu, HzbPyramid::fromDepth(depth, size.x, size.y));
    EXPECT_EQ(glGetError(), GLenum(GL_NO_ERROR));
  }
}

TEST_F(GpuHzb, RenderedBoxesGiveTheCpuPyramidAndPartialReadBack) {
  constexpr int kW = 301, kH = 177;  // odd on both axes
  makeTarget(kW, kH);
  clearDepth();
  Camera camera;
  camera.yaw_rad = 0.3;
  camera.pitch_rad = -0.1;
  const glm::mat4 vp = viewProjection(camera, kW, kH);
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (int i = 0; i < 40; ++i) {
    const glm::vec3 centre = glm::vec3(camera.forward()) * (2.0f + 30.0f * u(rng)) +
                             glm::vec3(u(rng) - 0.5f, u(rng) - 0.5f, u(rng) - 0.5f) * 12.0f;
    const glm::vec3 half(0.2f + 2.0f * u(rng), 0.2f + 2.0f * u(rng), 0.2f + 2.0f * u(rng));
    drawBox(centre - half, centre + half, vp);
  }
  const std::vector<float> depth = readDepth();
  const size_t drawn =
      size_t(std::count_if(depth.begin(), depth.end(), [](float d) { return d > 0.0f; }));
  ASSERT_GT(drawn, depth.size() / 10);  // the scene is not empty
  ASSERT_LT(drawn, depth.size());       // nor a single full-screen wall

  HzbBuilder builder;
  builder.build(depth_, kW, kH);
  const HzbPyramid cpu = HzbPyramid::fromDepth(depth, kW, kH);
  HzbPyramid gpu;
  builder.readBack(gpu, 0);
  expectSameLevels(gpu, cpu);
  // Only the coarse levels, as the frame loop reads them.
  HzbPyramid coarse;
  builder.readBack(coarse, 3);
  EXPECT_EQ(coarse.firstLevel(), 3);
  EXPECT_TRUE(coarse.level(2).empty());
  expectSameLevels(coarse, cpu);
  builder.readBack(coarse, 1000);  // clamped to the 1x1 level
  EXPECT_EQ(coarse.firstLevel(), coarse.levelCount() - 1);
  EXPECT_EQ(coarse.level(coarse.levelCount() - 1)[0], cpu.level(cpu.levelCount() - 1)[0]);
  // A new size reallocates the pyramid.
  makeTarget(64, 48);
  clearDepth();
  builder.build(depth_, 64, 48);
  builder.readBack(gpu, 0);
  EXPECT_EQ(gpu.levelCount(), 7);
  expectSameLevels(gpu, HzbPyramid::fromDepth(std::vector<float>(64 * 48, 0.0f), 64, 48));
  EXPECT_THROW(builder.build(depth_, 0, 48), std::invalid_argument);
  EXPECT_EQ(glGetError(), GLenum(GL_NO_ERROR));
}

// The GPU's own rasterization of a box stays inside projectBox's rectangle, and no rendered
// depth of the box is beyond the test's margin (so the box can never hide itself). (Tightness
// is checked on the box facing the camera above: here the nearest corner may fall between pixel
// centres or off screen, so the rendered maximum can sit well below the corner bound.)
TEST_F(GpuHzb, RasterizedBoxesStayInsideTheirFootprint) {
  constexpr int kW = 257, kH = 143;
  makeTarget(kW, kH);
  std::mt19937 rng(31);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int checked = 0;
  for (int i = 0; i < 60; ++i) {
    Camera camera;
    camera.yaw_rad = u(rng) * 6.28;
    camera.pitch_rad = (u(rng) - 0.5) * 2.0;
    camera.near_m = 0.02 + 0.2 * u(rng);
    camera.far_m = 2000.0;
    const glm::mat4 vp = viewProjection(camera, kW, kH);
    // Distances from centimetres to a kilometre, to probe the depth precision everywhere.
    const double distance = std::pow(10.0, -0.5 + 3.5 * u(rng));
    const glm::dvec3 offset = (camera.right() * (u(rng) - 0.5) + camera.up() * (u(rng) - 0.5)) *
                              distance;
    const glm::dvec3 centre = camera.forward() * distance + offset;
    const glm::dvec3 half = glm::dvec3(u(rng), u(rng), u(rng)) * distance * 0.3 + 1e-3;
    const glm::vec3 lo(centre - half), hi(centre + half);
    const ScreenFootprint fp = projectBox(lo, hi, vp, kW, kH);
    if (fp.visible_for_sure || fp.offscreen) continue;
    clearDepth();
    drawBox(lo, hi, vp);
    const std::vector<float> depth = readDepth();
    float nearest_rendered = 0.0f;
    int pixels = 0;
    for (int y = 0; y < kH; ++y)
      for (int x = 0; x < kW; ++x) {
        const float d = depth[size_t(y) * kW + x];
        if (d == 0.0f) continue;
        ++pixels;
        nearest_rendered = std::max(nearest_rendered, d);
        ASSERT_TRUE(x >= fp.min_px.x && x <= fp.max_px.x && y >= fp.min_px.y && y <= fp.max_px.y)
            << "box " << i << " pixel " << x << "," << y;
      }
    if (pixels == 0) continue;
    ++checked;
    EXPECT_FALSE(hiddenBehind(nearest_rendered, fp))
        << "box " << i << " rendered " << nearest_rendered << " projected " << fp.nearest_depth;
  }
  EXPECT_GT(checked, 30);
}

}  // namespace
}  // namespace tw
