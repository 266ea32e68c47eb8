// The viewer's stereo: both eyes drawn (Walkthrough::renderStereoFrame), put together on the CPU
// (composeStereo) and shown through a texture the size of the composed frame, so side by side,
// top and bottom and anaglyph all reach the window the same way. Quad-buffered stereo (asked for
// at start, `--stereo quad-buffered`, where the display offers a stereo context) sends each eye to
// its own back buffer instead.
#pragma once

#include <cstdint>
#include <vector>

#include "frame_loop.h"
#include "stereo.h"

namespace tw {

class ViewStereo {
 public:
  ViewStereo();  // needs the window's GL context
  ~ViewStereo();
  ViewStereo(const ViewStereo&) = delete;
  ViewStereo& operator=(const ViewStereo&) = delete;

  // Draws both eyes of `camera` (the renderer at the eye's size) and keeps the composed frame.
  FrameStats render(Walkthrough& walk, const Camera& camera, double time_s, const StereoOptions& stereo);
  // Shows the composed frame over the whole window and leaves the window's framebuffer bound with
  // its viewport, for the overlays (as GlRenderer::blitToScreen does).
  void present(int screen_width, int screen_height);

 private:
  void upload(const std::vector<uint8_t>& rgba, int width, int height);
  void blitTo(unsigned draw_buffer, int screen_width, int screen_height);
  StereoMode mode_ = StereoMode::Off;
  std::vector<uint8_t> left_, right_, frame_;
  int width_ = 0, height_ = 0;  // of frame_
  unsigned texture_ = 0, framebuffer_ = 0;
  int texture_width_ = 0, texture_height_ = 0;
};

}  // namespace tw
