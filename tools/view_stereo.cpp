// The viewer's stereo frames (view_stereo.h).
#include "view_stereo.h"

#define GL_GLEXT_PROTOTYPES 1
#include <GL/glcorearb.h>

namespace tw {

ViewStereo::ViewStereo() { glCreateFramebuffers(1, &framebuffer_); }

ViewStereo::~ViewStereo() {
  glDeleteFramebuffers(1, &framebuffer_);
  glDeleteTextures(1, &texture_);
}

FrameStats ViewStereo::render(Walkthrough& walk, const Camera& camera, double time_s,
                              const StereoOptions& stereo) {
  const FrameStats stats = walk.renderStereoFrame(camera, time_s, stereo, left_, right_);
  const int eye_width = walk.renderer().width(), eye_height = walk.renderer().height();
  mode_ = stereo.mode;
  if (mode_ == StereoMode::QuadBuffered) {
    width_ = eye_width;
    height_ = eye_height;
    return stats;
  }
  composeStereo(stereo.mode, eye_width, eye_height, left_, right_, frame_);
  width_ = stereo.mode == StereoMode::SideBySide ? 2 * eye_width : eye_width;
  height_ = stereo.mode == StereoMode::TopBottom ? 2 * eye_height : eye_height;
  return stats;
}

void ViewStereo::upload(const std::vector<uint8_t>& rgba, int width, int height) {
  if (width != texture_width_ || height != texture_height_) {
    glDeleteTextures(1, &texture_);
    glCreateTextures(GL_TEXTURE_2D, 1, &texture_);
    glTextureStorage2D(texture_, 1, GL_RGBA8, width, height);
    glNamedFramebufferTexture(framebuffer_, GL_COLOR_ATTACHMENT0, texture_, 0);
    texture_width_ = width;
    texture_height_ = height;
  }
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glTextureSubImage2D(texture_, 0, 0, 0, width, height, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
}

// The frame's rows are top-down, GL's bottom-up: blit upside down.
void ViewStereo::blitTo(unsigned draw_buffer, int screen_width, int screen_height) {
  glNamedFramebufferDrawBuffer(0, draw_buffer);
  glBlitNamedFramebuffer(framebuffer_, 0, 0, 0, texture_width_, texture_height_, 0, screen_height, screen_width,
                         0, GL_COLOR_BUFFER_BIT, GL_NEAREST);
}

void ViewStereo::present(int screen_width, int screen_height) {
  if (mode_ == StereoMode::QuadBuffered) {
    upload(left_, width_, height_);
    blitTo(GL_BACK_LEFT, screen_width, screen_height);
    upload(right_, width_, height_);
    blitTo(GL_BACK_RIGHT, screen_width, screen_height);
    glNamedFramebufferDrawBuffer(0, GL_BACK);  // the overlays go to both eyes
  } else {
    upload(frame_, width_, height_);
    blitTo(GL_BACK, screen_width, screen_height);
  }
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  glViewport(0, 0, screen_width, screen_height);
}

}  // namespace tw
