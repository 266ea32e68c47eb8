// A headless OpenGL 4.5 core context through EGL, with no window and no X server.
//
// CI has no GPU: headless rendering (walkthrough renders, golden-image tests) runs on Mesa's
// llvmpipe through the surfaceless platform. The context renders into framebuffer objects only.
// On a machine with a GPU the same code picks the GPU driver.
#pragma once

#include <memory>
#include <string>

namespace tw {

class EglContext {
 public:
  // Creates a GL 4.5 core context and makes it current on the calling thread. Throws
  // std::runtime_error with the EGL error code and the step that failed.
  EglContext();
  ~EglContext();
  EglContext(const EglContext&) = delete;
  EglContext& operator=(const EglContext&) = delete;

  std::string renderer() const;  // GL_RENDERER, e.g. "llvmpipe (LLVM 15.0.6, 256 bits)"
  std::string version() const;   // GL_VERSION
  int majorVersion() const;
  int minorVersion() const;
  // Looks up an entry point (core or extension); nullptr when absent.
  void* procAddress(const char* name) const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace tw
