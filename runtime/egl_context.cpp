// EGL surfaceless context creation. Each step is checked, because a headless machine without the
// right Mesa packages fails here first and the message must say which step and why.
#include "egl_context.h"

#include <EGL/egl.h>
#include <EGL/eglext.h>
#define GL_GLEXT_PROTOTYPES 1
#include <GL/glcorearb.h>

#include <cstdio>
#include <stdexcept>

namespace tw {
namespace {

[[noreturn]] void failEgl(const char* step) {
  char buf[128];
  std::snprintf(buf, sizeof buf, "EGL: %s failed (error 0x%04x)", step, eglGetError());
  throw std::runtime_error(buf);
}

}  // namespace

struct EglContext::State {
  EGLDisplay display = EGL_NO_DISPLAY;
  EGLContext context = EGL_NO_CONTEXT;
};

EglContext::EglContext() : state_(std::make_unique<State>()) {
  // 1. The surfaceless platform needs no window system at all.
  state_->display = eglGetPlatformDisplay(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY,
                                          nullptr);
  if (state_->display == EGL_NO_DISPLAY) failEgl("eglGetPlatformDisplay(surfaceless)");
  EGLint major = 0, minor = 0;
  if (!eglInitialize(state_->display, &major, &minor)) failEgl("eglInitialize");
  // 2. Desktop OpenGL rather than GLES.
  if (!eglBindAPI(EGL_OPENGL_API)) failEgl("eglBindAPI(EGL_OPENGL_API)");
  // 3. Any config will do: we render to our own FBOs, never to an EGL surface.
  const EGLint config_attribs[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_NONE};
  EGLConfig config = nullptr;
  EGLint configs = 0;
  if (!eglChooseConfig(state_->display, config_attribs, &config, 1, &configs)) {
    failEgl("eglChooseConfig");
  }
  // 4. GL 4.5 core: llvmpipe refuses 4.6, and 4.5 plus ARB extensions covers what we use.
  const EGLint context_attribs[] = {EGL_CONTEXT_MAJOR_VERSION, 4,
                                    EGL_CONTEXT_MINOR_VERSION, 5,
                                    EGL_CONTEXT_OPENGL_PROFILE_MASK,
                                    EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                                    EGL_NONE};
  state_->context = eglCreateContext(state_->display, configs > 0 ? config : EGL_NO_CONFIG_KHR,
                                     EGL_NO_CONTEXT, context_attribs);
  if (state_->context == EGL_NO_CONTEXT) {
    eglTerminate(state_->display);
    failEgl("eglCreateContext(OpenGL 4.5 core)");
  }
  // 5. Current with no surface (EGL_KHR_surfaceless_context).
  if (!eglMakeCurrent(state_->display, EGL_NO_SURFACE, EGL_NO_SURFACE, state_->context)) {
    eglDestroyContext(state_->display, state_->context);
    eglTerminate(state_->display);
    failEgl("eglMakeCurrent(surfaceless)");
  }
}

EglContext::~EglContext() {
  eglMakeCurrent(state_->display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
  eglDestroyContext(state_->display, state_->context);
  eglTerminate(state_->display);
}

std::string EglContext::renderer() const {
  const auto* s = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  return s ? s : "";
}

std::string EglContext::version() const {
  const auto* s = reinterpret_cast<const char*>(glGetString(GL_VERSION));
  return s ? s : "";
}

int EglContext::majorVersion() const {
  GLint v = 0;
  glGetIntegerv(GL_MAJOR_VERSION, &v);
  return v;
}

int EglContext::minorVersion() const {
  GLint v = 0;
  glGetIntegerv(GL_MINOR_VERSION, &v);
  return v;
}

void* EglContext::procAddress(const char* name) const {
  return reinterpret_cast<void*>(eglGetProcAddress(name));
}

}  // namespace tw
