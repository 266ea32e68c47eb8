// The GPU hierarchical-Z build (contract in hzb_builder.h): compute passes copy the depth texture
// into level 0 of an R32F mip chain and take the minimum over each texel's 2x2 footprint (3 along
// an odd axis), the same reduction as HzbPyramid::fromDepth, two levels per pass. Min of floats
// is exact, so the GPU and CPU pyramids agree bit for bit.
#include "hzb_builder.h"

#define GL_GLEXT_PROTOTYPES 1
#include <GL/glcorearb.h>

#include <algorithm>
#include <stdexcept>
#include <string>

#include "gl_program.h"

namespace tw {
namespace {

// 8x8 invocations per group: enough to fill SIMD lanes on llvmpipe and GPUs alike.
constexpr int kGroupSize = 8;

// One pass writes up to two levels below its source level: an invocation owns one texel of the
// lowest level written (the "top" of the pass) and walks the texels it covers, so each pass
// reads its source once and the pyramid takes ceil((levels - 1) / 2) passes, not levels - 1.
// Footprints partition each level (the last column/row takes the odd source column/row), so no
// two invocations write the same texel. The first pass reads the depth texture (texelFetch
// returns the stored 32-bit float unchanged) and also writes it into level 0.
//   u_from_depth: source is the depth sampler (and level 0 is written); else image u_src.
//   u_count: levels written below the source (0 only for a 1x1 depth: the copy alone).
//   u_size0/1/2: sizes of the source level and the one or two levels below it.
// The #version line and the group size are prepended by buildProgram (from kGroupSize).
constexpr const char* kShaderBody = R"(
layout(binding = 0) uniform sampler2D u_depth;
layout(binding = 0, r32f) uniform readonly image2D u_src;
layout(binding = 1, r32f) uniform writeonly image2D u_dst1;
layout(binding = 2, r32f) uniform writeonly image2D u_dst2;
layout(binding = 3, r32f) uniform writeonly image2D u_level0;
layout(location = 0) uniform bool u_from_depth;
layout(location = 1) uniform int u_count;
layout(location = 2) uniform ivec2 u_size0;
layout(location = 3) uniform ivec2 u_size1;
layout(location = 4) uniform ivec2 u_size2;

// Source texels [lo, hi] covered by texel p of a level of size dst below one of size src.
void span(ivec2 p, ivec2 dst, ivec2 src, out ivec2 lo, out ivec2 hi) {
  lo = 2 * p;
  hi = min(lo + 1, src - 1);
  if (p.x == dst.x - 1) hi.x = src.x - 1;
  if (p.y == dst.y - 1) hi.y = src.y - 1;
}

float source(ivec2 t) {
  if (u_from_depth) {
    float d = texelFetch(u_depth, t, 0).r;
    imageStore(u_level0, t, vec4(d, 0.0, 0.0, 0.0));
    return d;
  }
  return imageLoad(u_src, t).r;
}

// Min over the source texels under texel p of the level below the source.
float reduce1(ivec2 p) {
  ivec2 lo, hi;
  span(p, u_size1, u_size0, lo, hi);
  float m = uintBitsToFloat(0x7F800000u);  // +inf: min(inf, x) == x exactly
  for (int y = lo.y; y <= hi.y; ++y)
    for (int x = lo.x; x <= hi.x; ++x) m = min(m, source(ivec2(x, y)));
  return m;
}

void main() {
  ivec2 q = ivec2(gl_GlobalInvocationID.xy);
  ivec2 top = u_count == 0 ? u_size0 : (u_count == 1 ? u_size1 : u_size2);
  if (q.x >= top.x || q.y >= top.y) return;
  if (u_count == 0) {
    source(q);
    return;
  }
  if (u_count == 1) {
    imageStore(u_dst1, q, vec4(reduce1(q), 0.0, 0.0, 0.0));
    return;
  }
  ivec2 lo, hi;
  span(q, u_size2, u_size1, lo, hi);
  float m = uintBitsToFloat(0x7F800000u);
  for (int y = lo.y; y <= hi.y; ++y)
    for (int x = lo.x; x <= hi.x; ++x) {
      float v = reduce1(ivec2(x, y));
      imageStore(u_dst1, ivec2(x, y), vec4(v, 0.0, 0.0, 0.0));
      m = min(m, v);
    }
  imageStore(u_dst2, q, vec4(m, 0.0, 0.0, 0.0));
}
)";

GLuint buildProgram() {
  const std::string source = "#version 450\nlayout(local_size_x = " + std::to_string(kGroupSize) +
                             ", local_size_y = " + std::to_string(kGroupSize) + ") in;" +
                             kShaderBody;
  return buildGlProgram({{GL_COMPUTE_SHADER, source}}, "HzbBuilder: reduction");
}

int levelCountFor(int width, int height) {
  int count = 1;
  while (width > 1 || height > 1) {
    width = std::max(1, width / 2);
    height = std::max(1, height / 2);
    ++count;
  }
  return count;
}

GLuint groupsFor(int texels) { return GLuint((texels + kGroupSize - 1) / kGroupSize); }

}  // namespace

HzbBuilder::HzbBuilder() { program_ = buildProgram(); }

HzbBuilder::~HzbBuilder() {
  if (texture_) glDeleteTextures(1, &texture_);
  if (program_) glDeleteProgram(program_);
}

void HzbBuilder::build(unsigned depth_texture, int width, int height) {
  if (width < 1 || height < 1)
    throw std::invalid_argument("HzbBuilder::build: size " + std::to_string(width) + "x" +
                                std::to_string(height) + " is not positive");
  if (!texture_ || width != width_ || height != height_) {
    // Immutable storage cannot be resized: a new texture for a new size.
    if (texture_) glDeleteTextures(1, &texture_);
    texture_ = 0;
    const int levels = levelCountFor(width, height);
    glCreateTextures(GL_TEXTURE_2D, 1, &texture_);
    glTextureStorage2D(texture_, levels, GL_R32F, width, height);
    glTextureParameteri(texture_, GL_TEXTURE_MIN_FILTER, GL_NEAREST_MIPMAP_NEAREST);
    glTextureParameteri(texture_, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    width_ = width;
    height_ = height;
    levels_ = levels;
  }

  glUseProgram(program_);
  // The first pass reads the depth through texelFetch, which ignores filtering; a depth texture
  // with comparison on would return 0/1, so the caller's texture must keep
  // GL_TEXTURE_COMPARE_MODE = GL_NONE (the default, and what GlRenderer uses).
  glBindTextureUnit(0, depth_texture);
  glBindImageTexture(3, texture_, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_R32F);
  auto sizeOf = [&](int level) {
    return glm::ivec2(std::max(1, width >> level), std::max(1, height >> level));
  };
  for (int source = 0; source == 0 || source < levels_ - 1;) {
    const int count = std::min(2, levels_ - 1 - source);
    const glm::ivec2 s0 = sizeOf(source), s1 = sizeOf(source + std::min(count, 1)),
                     s2 = sizeOf(source + count);
    if (source > 0) {
      // The previous pass's image stores must land before this pass loads them.
      glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
      glBindImageTexture(0, texture_, source, GL_FALSE, 0, GL_READ_ONLY, GL_R32F);
    }
    // Units a pass does not write are unbound, so no stale binding aliases the source level.
    glBindImageTexture(1, count >= 1 ? texture_ : 0, source + 1, GL_FALSE, 0, GL_WRITE_ONLY,
                       GL_R32F);
    glBindImageTexture(2, count >= 2 ? texture_ : 0, source + 2, GL_FALSE, 0, GL_WRITE_ONLY,
                       GL_R32F);
    glUniform1i(0, source == 0 ? 1 : 0);
    glUniform1i(1, count);
    glUniform2i(2, s0.x, s0.y);
    glUniform2i(3, s1.x, s1.y);
    glUniform2i(4, s2.x, s2.y);
    const glm::ivec2 top = count == 0 ? s0 : (count == 1 ? s1 : s2);
    glDispatchCompute(groupsFor(top.x), groupsFor(top.y), 1);
    source += std::max(count, 1);
  }
  // Later users read the pyramid through texture fetches, image loads or glGetTextureImage.
  glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT |
                  GL_TEXTURE_UPDATE_BARRIER_BIT);
  for (GLuint unit = 0; unit < 4; ++unit)
    glBindImageTexture(unit, 0, 0, GL_FALSE, 0, GL_READ_ONLY, GL_R32F);
  glBindTextureUnit(0, 0);
  glUseProgram(0);
}

void HzbBuilder::readBack(HzbPyramid& out, int first_level) const {
  if (!texture_) throw std::logic_error("HzbBuilder::readBack: nothing was built");
  out.reset(width_, height_, std::clamp(first_level, 0, levels_ - 1));
  // Client memory, tightly packed: no pack buffer, default alignment (float rows are 4-byte
  // aligned anyway); the caller's settings come back afterwards.
  GLint pack_alignment = 4, pack_buffer = 0;
  glGetIntegerv(GL_PACK_ALIGNMENT, &pack_alignment);
  glGetIntegerv(GL_PIXEL_PACK_BUFFER_BINDING, &pack_buffer);
  glPixelStorei(GL_PACK_ALIGNMENT, 4);
  glBindBuffer(GL_PIXEL_PACK_BUFFER, 0);
  for (int level = out.firstLevel(); level < levels_; ++level) {
    std::span<float> data = out.mutableLevel(level);
    glGetTextureImage(texture_, level, GL_RED, GL_FLOAT, GLsizei(data.size_bytes()), data.data());
  }
  glPixelStorei(GL_PACK_ALIGNMENT, pack_alignment);
  glBindBuffer(GL_PIXEL_PACK_BUFFER, GLuint(pack_buffer));
}

unsigned HzbBuilder::texture() const { return texture_; }

}  // namespace tw
