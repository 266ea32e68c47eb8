// Builds the hierarchical-Z pyramid of a depth texture on the GPU with a compute shader (GL 4.5
// core, runs on Mesa llvmpipe), and reads back the levels the CPU test uses. Same pyramid as
// HzbPyramid::fromDepth (hzb_pyramid.h), bit for bit on the levels read back.
//
// GL code: lives in the tw_occlusion_gl library, which only the runtime links.
#pragma once

#include "hzb_pyramid.h"

namespace tw {

class HzbBuilder {
 public:
  // Compiles the shader. A GL 4.5 context must be current for the builder's whole life. Throws
  // std::runtime_error when the shader does not compile or link.
  HzbBuilder();
  ~HzbBuilder();
  HzbBuilder(const HzbBuilder&) = delete;
  HzbBuilder& operator=(const HzbBuilder&) = delete;

  // Builds the pyramid of `depth_texture` (GL_DEPTH_COMPONENT32F, width x height, reversed Z)
  // into an R32F texture with mipmaps (reallocated when the size changes). Throws
  // std::invalid_argument for a size < 1.
  void build(unsigned depth_texture, int width, int height);
  // Reads levels [first_level, levelCount) of the last build into `out` (blocks on the GPU).
  // first_level is clamped to the last level.
  void readBack(HzbPyramid& out, int first_level) const;
  unsigned texture() const;  // the R32F pyramid (level 0 = full resolution)

 private:
  unsigned program_ = 0, texture_ = 0;
  int width_ = 0, height_ = 0, levels_ = 0;
};

}  // namespace tw
