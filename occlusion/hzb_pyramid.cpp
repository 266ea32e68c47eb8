// The CPU hierarchical-Z pyramid and the conservative box test (contract in hzb_pyramid.h).
// The reduction here is the reference the GPU builder (hzb_builder.cpp) must match bit for bit.
#include "hzb_pyramid.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace tw {
namespace {

// A corner this close to the eye plane (clip w, metres for camera.h's projection) or behind it
// projects to nonsense: the box is treated as covering the eye.
constexpr double kMinClipW = 1e-6;

// Margins of the depth comparison, in the conservative direction (a box counts as slightly
// nearer than computed). The GPU rasterizes occluders in float: interpolated depth carries a
// few ulps of relative error, plus an absolute error of about ulp(near-plane term) / distance
// from the cancellation in (n f / (f - n) - z n / (f - n)) / z near the far plane. 2^-16
// relative (15 mm at 1 km) and 2^-30 absolute are far above both and cost no real culling.
constexpr float kRelativeDepthMargin = 1.0f / 65536.0f;
constexpr float kAbsoluteDepthMargin = 1.0f / 1073741824.0f;

// Texels per axis the test may read at the chosen level: 4 x 4 at most.

int levelCountFor(int width, int height) {
  int count = 1;
  while (width > 1 || height > 1) {
    width = std::max(1, width / 2);
    height = std::max(1, height / 2);
    ++count;
  }
  return count;
}

void checkSize(int width, int height, const char* who) {
  if (width < 1 || height < 1)
    throw std::invalid_argument(std::string(who) + ": size " + std::to_string(width) + "x" +
                                std::to_string(height) + " is not positive");
}

// Level k + 1 from level k: each destination texel takes the minimum of its 2x2 source texels,
// and the last column/row also takes the odd source column/row (3 along that axis). A 1-texel
// axis stays 1 and maps onto itself.
void reduceLevel(std::span<const float> src, glm::ivec2 src_size, std::span<float> dst,
                 glm::ivec2 dst_size) {
  for (int y = 0; y < dst_size.y; ++y) {
    const int y0 = 2 * y;
    int y1 = std::min(y0 + 1, src_size.y - 1);
    if (y == dst_size.y - 1) y1 = src_size.y - 1;
    float* out = dst.data() + size_t(y) * size_t(dst_size.x);
    const float* row0 = src.data() + size_t(y0) * size_t(src_size.x);
    // The texels before the last column, from two rows: exactly 2x2 each (a loop the compiler
    // vectorizes; this is most of a build).
    int x = 0;
    if (y1 == y0 + 1) {
      const float* row1 = row0 + src_size.x;
      for (; x + 1 < dst_size.x; ++x)
        out[x] = std::min(std::min(row0[2 * x], row0[2 * x + 1]),
                          std::min(row1[2 * x], row1[2 * x + 1]));
    }
    // The rest: a third row or column at the odd edge, or a 1-texel axis.
    for (; x < dst_size.x; ++x) {
      const int x0 = 2 * x;
      int x1 = std::min(x0 + 1, src_size.x - 1);
      if (x == dst_size.x - 1) x1 = src_size.x - 1;
      float m = row0[x0];
      for (int sy = y0; sy <= y1; ++sy) {
        const float* row = src.data() + size_t(sy) * size_t(src_size.x);
        for (int sx = x0; sx <= x1; ++sx) m = std::min(m, row[sx]);
      }
      out[x] = m;
    }
  }
}

// Rounds a double up to the next float at or above it, so a depth kept in float never becomes
// farther than the value computed.
float roundUpToFloat(double value) {
  float f = static_cast<float>(value);
  if (double(f) < value) f = std::nextafter(f, std::numeric_limits<float>::infinity());
  return f;
}

}  // namespace

ScreenFootprint projectBox(const glm::vec3& box_min, const glm::vec3& box_max,
                           const glm::mat4& view_projection, int width, int height) {
  ScreenFootprint footprint;
  if (width < 1 || height < 1) {
    footprint.offscreen = true;
    return footprint;
  }
  // Double arithmetic on the float inputs, so our own rounding is far below the margins.
  const glm::dmat4 m(view_projection);
  double ndc_min_x = std::numeric_limits<double>::infinity(), ndc_max_x = -ndc_min_x;
  double ndc_min_y = ndc_min_x, ndc_max_y = -ndc_min_x;
  double depth_max = -ndc_min_x;
  // Corners as the min corner's clip position plus edge vectors along each axis: 3 column
  // scalings instead of 8 matrix products.
  const glm::dvec4 base = m * glm::dvec4(glm::dvec3(box_min), 1.0);
  const glm::dvec3 extent = glm::dvec3(box_max) - glm::dvec3(box_min);
  const glm::dvec4 edge_x = m[0] * extent.x, edge_y = m[1] * extent.y, edge_z = m[2] * extent.z;
  for (int corner = 0; corner < 8; ++corner) {
    glm::dvec4 clip = base;
    if (corner & 1) clip += edge_x;
    if (corner & 2) clip += edge_y;
    if (corner & 4) clip += edge_z;
    // Behind or on the eye plane (or garbage): the projection of the box is unbounded.
    if (!(clip.w > kMinClipW) || !std::isfinite(clip.x) || !std::isfinite(clip.y) ||
        !std::isfinite(clip.z)) {
      footprint.visible_for_sure = true;
      return footprint;
    }
    const double inv_w = 1.0 / clip.w;
    const double x = clip.x * inv_w, y = clip.y * inv_w, z = clip.z * inv_w;
    ndc_min_x = std::min(ndc_min_x, x);
    ndc_max_x = std::max(ndc_max_x, x);
    ndc_min_y = std::min(ndc_min_y, y);
    ndc_max_y = std::max(ndc_max_y, y);
    depth_max = std::max(depth_max, z);
  }
  // With w > 0 at every corner, w > 0 over the whole box, and x/w, y/w, z/w (ratios of linear
  // functions) take their extremes over the box at corners: the corner bounds are exact.
  footprint.nearest_depth = roundUpToFloat(depth_max);
  // Reversed Z with GL_ZERO_TO_ONE: depth 1 is the near plane. A corner in front of it means the
  // box crosses the near plane, where clipping could show its inside anywhere.
  if (depth_max >= 1.0) {
    footprint.visible_for_sure = true;
    return footprint;
  }
  // Wholly beyond the far plane (depth < 0), or beside the viewport: nothing is drawn.
  if (depth_max < 0.0 || ndc_max_x < -1.0 || ndc_min_x > 1.0 || ndc_max_y < -1.0 ||
      ndc_min_y > 1.0) {
    footprint.offscreen = true;
    return footprint;
  }
  // NDC -> pixels (row 0 at the bottom, as GL). The inclusive rectangle runs from the pixel left
  // of the one holding the smallest extent to the pixel right of the one holding the largest:
  // one pixel of slack for rasterization rules and rounding. Clamped in double (no int overflow).
  const double px_min_x = (ndc_min_x * 0.5 + 0.5) * width;
  const double px_max_x = (ndc_max_x * 0.5 + 0.5) * width;
  const double px_min_y = (ndc_min_y * 0.5 + 0.5) * height;
  const double px_max_y = (ndc_max_y * 0.5 + 0.5) * height;
  auto clampPx = [](double v, int size) {
    return static_cast<int>(std::clamp(v, 0.0, double(size - 1)));
  };
  footprint.min_px = {clampPx(std::floor(px_min_x) - 1.0, width),
                      clampPx(std::floor(px_min_y) - 1.0, height)};
  footprint.max_px = {clampPx(std::floor(px_max_x) + 1.0, width),
                      clampPx(std::floor(px_max_y) + 1.0, height)};
  return footprint;
}

HzbPyramid HzbPyramid::fromDepth(std::span<const float> depth, int width, int height) {
  checkSize(width, height, "HzbPyramid::fromDepth");
  if (depth.size() != size_t(width) * size_t(height))
    throw std::invalid_argument("HzbPyramid::fromDepth: " + std::to_string(depth.size()) +
                                " depth values for a " + std::to_string(width) + "x" +
                                std::to_string(height) + " image");
  HzbPyramid pyramid;
  pyramid.build(depth, width, height);
  return pyramid;
}

void HzbPyramid::build(std::span<const float> depth, int width, int height) {
  checkSize(width, height, "HzbPyramid::build");
  if (depth.size() != size_t(width) * size_t(height))
    throw std::invalid_argument("HzbPyramid::build: " + std::to_string(depth.size()) +
                                " depth values for a " + std::to_string(width) + "x" +
                                std::to_string(height) + " image");
  std::copy(depth.begin(), depth.end(), beginBuild(width, height).begin());
  finishBuild();
}

std::span<float> HzbPyramid::beginBuild(int width, int height) {
  reset(width, height, 0);  // keeps the levels' storage: no allocation frame after frame
  return levels_[0];
}

void HzbPyramid::finishBuild() {
  for (int k = 1; k < levelCount(); ++k)
    reduceLevel(levels_[size_t(k) - 1], sizes_[size_t(k) - 1], levels_[size_t(k)],
                sizes_[size_t(k)]);
}

glm::ivec2 HzbPyramid::levelSize(int level) const {
  if (level < 0 || level >= levelCount())
    throw std::out_of_range("HzbPyramid::levelSize: level " + std::to_string(level) + " of " +
                            std::to_string(levelCount()));
  return sizes_[size_t(level)];
}

std::span<const float> HzbPyramid::level(int level) const {
  if (level < 0 || level >= levelCount())
    throw std::out_of_range("HzbPyramid::level: level " + std::to_string(level) + " of " +
                            std::to_string(levelCount()));
  return levels_[size_t(level)];
}

void HzbPyramid::reset(int width, int height, int first_level) {
  checkSize(width, height, "HzbPyramid::reset");
  const int count = levelCountFor(width, height);
  width_ = width;
  height_ = height;
  first_level_ = std::clamp(first_level, 0, count - 1);
  sizes_.resize(size_t(count));
  levels_.resize(size_t(count));
  glm::ivec2 size(width, height);
  for (int k = 0; k < count; ++k) {
    sizes_[size_t(k)] = size;
    std::vector<float>& data = levels_[size_t(k)];
    if (k < first_level_) {
      data.clear();
      data.shrink_to_fit();
    } else {
      data.resize(size_t(size.x) * size_t(size.y));  // filled next, so not cleared first
    }
    size = glm::max(size / 2, glm::ivec2(1));
  }
}

std::span<float> HzbPyramid::mutableLevel(int level) {
  if (level < 0 || level >= levelCount())
    throw std::out_of_range("HzbPyramid::mutableLevel: level " + std::to_string(level) + " of " +
                            std::to_string(levelCount()));
  return levels_[size_t(level)];
}

bool HzbPyramid::occluded(const ScreenFootprint& footprint, int max_span_texels) const {
  if (levels_.empty() || footprint.visible_for_sure || footprint.offscreen) return false;
  // Clamp to the viewport (projectBox already does; a hand-made footprint may not).
  const glm::ivec2 lo = glm::max(footprint.min_px, glm::ivec2(0));
  const glm::ivec2 hi = glm::min(footprint.max_px, glm::ivec2(width_ - 1, height_ - 1));
  if (hi.x < lo.x || hi.y < lo.y) return false;
  if (!(footprint.nearest_depth == footprint.nearest_depth)) return false;  // NaN
  // A texel of level k covers at most 2^(k+1) - 1 pixels per axis (the last one takes the odd
  // rest), so a rectangle of at least 2^(k+3) pixels spans more than 4 texels there: skip those
  // levels without looking.
  int span_log2 = 0;
  while (span_log2 < 16 && (2 << span_log2) <= max_span_texels) ++span_log2;
  const int span = 1 << span_log2;  // max_span_texels rounded down to a power of two, >= 1
  const int extent_px = std::max(hi.x - lo.x, hi.y - lo.y) + 1;
  int k = first_level_;
  while (k + 1 < levelCount() && (extent_px >> std::min(k + span_log2 + 1, 30)) != 0) ++k;
  glm::ivec2 t0, t1;
  for (;; ++k) {
    // Pixel p lies in texel p >> k, except past the last texel, which also covers the odd rest.
    const glm::ivec2 last = sizes_[size_t(k)] - 1;
    t0 = glm::min(glm::ivec2(lo.x >> k, lo.y >> k), last);
    t1 = glm::min(glm::ivec2(hi.x >> k, hi.y >> k), last);
    if ((t1.x - t0.x < span && t1.y - t0.y < span) || k + 1 == levelCount())
      break;
  }
  const float threshold =
      footprint.nearest_depth + std::abs(footprint.nearest_depth) * kRelativeDepthMargin +
      kAbsoluteDepthMargin;
  const std::vector<float>& data = levels_[size_t(k)];
  const size_t row_texels = size_t(sizes_[size_t(k)].x);
  for (int y = t0.y; y <= t1.y; ++y) {
    const float* row = data.data() + size_t(y) * row_texels;
    for (int x = t0.x; x <= t1.x; ++x)
      if (!(row[x] > threshold)) return false;
  }
  return true;
}

namespace {

bool hiddenOrOffscreen(const HzbPyramid& pyramid, const glm::vec3& lo, const glm::vec3& hi,
                       const glm::mat4& view_projection, const BoxTest& test, int splits_left);

// Whether both halves of a box not hidden as a whole (footprint `whole`) are hidden or off
// screen, with `splits_left` halvings allowed (BoxTest::split_px).
bool halvesHidden(const HzbPyramid& pyramid, const ScreenFootprint& whole, const glm::vec3& lo,
                  const glm::vec3& hi, const glm::mat4& view_projection, const BoxTest& test,
                  int splits_left) {
  const glm::ivec2 size = whole.max_px - whole.min_px + 1;
  if (splits_left <= 0 || test.split_px <= 0 || std::max(size.x, size.y) < test.split_px)
    return false;
  const glm::vec3 extent = hi - lo;
  const int axis = extent.x >= extent.y && extent.x >= extent.z ? 0 : (extent.y >= extent.z ? 1 : 2);
  // One middle value for both halves: no gap between them, whatever the rounding.
  const float middle = lo[axis] + 0.5f * extent[axis];
  if (!(middle > lo[axis] && middle < hi[axis])) return false;  // too thin to halve
  glm::vec3 near_hi = hi, far_lo = lo;
  near_hi[axis] = far_lo[axis] = middle;
  return hiddenOrOffscreen(pyramid, lo, near_hi, view_projection, test, splits_left - 1) &&
         hiddenOrOffscreen(pyramid, far_lo, hi, view_projection, test, splits_left - 1);
}

bool hiddenOrOffscreen(const HzbPyramid& pyramid, const glm::vec3& lo, const glm::vec3& hi,
                       const glm::mat4& view_projection, const BoxTest& test, int splits_left) {
  const ScreenFootprint footprint =
      projectBox(lo, hi, view_projection, pyramid.width(), pyramid.height());
  if (footprint.visible_for_sure) return false;
  if (footprint.offscreen || pyramid.occluded(footprint, test.max_span_texels)) return true;
  return halvesHidden(pyramid, footprint, lo, hi, view_projection, test, splits_left);
}

}  // namespace

BoxVisibility occludedBox(const HzbPyramid& pyramid, const glm::vec3& box_min,
                          const glm::vec3& box_max, const glm::mat4& view_projection,
                          const BoxTest& test) {
  if (pyramid.levelCount() == 0) return BoxVisibility::Visible;
  const ScreenFootprint footprint =
      projectBox(box_min, box_max, view_projection, pyramid.width(), pyramid.height());
  if (footprint.visible_for_sure) return BoxVisibility::Visible;
  if (footprint.offscreen) return BoxVisibility::Offscreen;
  if (pyramid.occluded(footprint, test.max_span_texels)) return BoxVisibility::Occluded;
  return halvesHidden(pyramid, footprint, box_min, box_max, view_projection, test, test.max_splits)
             ? BoxVisibility::Occluded
             : BoxVisibility::Visible;
}

}  // namespace tw
