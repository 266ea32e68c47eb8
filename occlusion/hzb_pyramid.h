// A hierarchical-Z pyramid on the CPU, and the conservative test of a node's bounds against it.
//
// Depth is reversed Z (camera.h): 1 at the near plane, 0 at infinity, 0 where nothing was drawn.
// Level 0 has the depth buffer's size; each texel of level k + 1 holds the minimum (farthest)
// of the level-k texels it covers, 2x2 of them, or 3 along an axis whose level-k size is odd (the
// last texel also takes the odd row/column), so every texel bounds every pixel under it. Sizes
// halve (rounding down, at least 1) until 1x1.
//
// The GPU builds the same pyramid (hzb_builder.h) and reads back the levels the test needs; the
// CPU builder here is the reference for tests and a fallback.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

namespace tw {

// A box's footprint on screen: pixel rectangle (inclusive, clamped to the viewport) and the
// reversed-Z depth of its nearest point.
struct ScreenFootprint {
  glm::ivec2 min_px{0}, max_px{-1};
  float nearest_depth = 1.0f;  // reversed Z: the largest depth of any point of the box
  bool visible_for_sure = false;  // crosses the near plane or covers the eye: never culled
  bool offscreen = false;         // entirely outside the viewport
};

// Projects the box [box_min, box_max] (eye-relative metres, i.e. world minus eye, in double then
// rounded) with `view_projection` (rotation-only view times the reversed-Z projection of
// camera.h) onto a width x height viewport. Conservative: the rectangle covers every pixel the
// box could touch (corners projected, then rounded outward by one pixel).
ScreenFootprint projectBox(const glm::vec3& box_min, const glm::vec3& box_max,
                           const glm::mat4& view_projection, int width, int height);

class HzbPyramid;

// How a box is tested against a pyramid (occludedBox).
struct BoxTest {
  int max_span_texels = 16;  // HzbPyramid::occluded
  // A box that is not hidden as a whole and whose footprint spans at least split_px pixels
  // (either axis) is halved along its longest axis, and is hidden when both halves are, each
  // tested the same way, at most max_splits halvings deep. A long box whose near end hides
  // behind one occluder and whose far end behind another, or whose rectangle reaches past an
  // occluder's edge only where the box itself does not, is then culled. 0: no halving.
  int split_px = 32;
  int max_splits = 8;
};

enum class BoxVisibility {
  Visible,    // possibly: some part of the box may show
  Occluded,   // certainly hidden by the pyramid's depth
  Offscreen,  // entirely beside the viewport or beyond the far plane
};

// Tests the box [box_min, box_max] (eye-relative, as projectBox) against `pyramid` (which must
// have been built for the same width x height viewport). Conservative like occluded(): the halves
// of a split box share their middle plane exactly, so together they are the box, and a half is
// hidden only when its own footprint is occluded or off screen.
BoxVisibility occludedBox(const HzbPyramid& pyramid, const glm::vec3& box_min,
                          const glm::vec3& box_max, const glm::mat4& view_projection,
                          const BoxTest& test);

class HzbPyramid {
 public:
  HzbPyramid() = default;

  // Builds every level from a full-resolution depth image (row 0 = bottom row, as GL reads).
  // Throws std::invalid_argument when depth.size() != width * height or a size is < 1.
  static HzbPyramid fromDepth(std::span<const float> depth, int width, int height);
  // The same into this pyramid, reusing its storage (the frame loop rebuilds it every frame).
  void build(std::span<const float> depth, int width, int height);
  // The same without the copy: beginBuild sizes the levels and returns level 0 for the caller to
  // fill with the depth image (a read-back straight into it); finishBuild makes the others.
  std::span<float> beginBuild(int width, int height);
  void finishBuild();

  // The level-0 size, the number of levels and each level's size.
  int width() const { return width_; }
  int height() const { return height_; }
  int levelCount() const { return int(levels_.size()); }
  glm::ivec2 levelSize(int level) const;
  // Level data, row-major, row 0 at the bottom. Levels below firstLevel() are absent (a GPU
  // read-back may skip the large ones); their data() is empty.
  std::span<const float> level(int level) const;
  int firstLevel() const { return first_level_; }

  // For the GPU read-back: sets the level sizes for a width x height depth buffer and keeps room
  // for levels [first_level, levelCount()), whose values are left as they were (stale) until
  // filled through mutableLevel.
  void reset(int width, int height, int first_level);
  std::span<float> mutableLevel(int level);

  // True only when the footprint is certainly hidden: every pyramid texel under its rectangle, at
  // the finest available level where the rectangle spans at most max_span_texels texels per axis
  // (rounded down to a power of two), is nearer (strictly greater depth) than the footprint's
  // nearest depth. A larger span tests at a finer level: more texels read, fewer far texels
  // mixed in, more culled. False for visible_for_sure, for an empty pyramid and for offscreen
  // footprints (the caller culls those by frustum).
  bool occluded(const ScreenFootprint& footprint, int max_span_texels = 4) const;

 private:
  int width_ = 0, height_ = 0, first_level_ = 0;
  std::vector<glm::ivec2> sizes_;
  std::vector<std::vector<float>> levels_;
};

}  // namespace tw
