// The headless GL context every rendering test depends on: GL 4.5 core through EGL surfaceless,
// able to render into an FBO and read the pixels back.
#include <gtest/gtest.h>

#define GL_GLEXT_PROTOTYPES 1
#include <GL/glcorearb.h>

#include "egl_context.h"

namespace tw {
namespace {

TEST(EglContext, CreatesCoreContextAtLeast45) {
  EglContext context;
  EXPECT_GT(context.majorVersion() * 10 + context.minorVersion(), 44) << context.version();
  EXPECT_FALSE(context.renderer().empty());
  // Extensions the runtime relies on are reachable through EGL.
  EXPECT_NE(context.procAddress("glMultiDrawElementsIndirectCountARB"), nullptr);
}

TEST(EglContext, ClearsAnFboAndReadsItBack) {
  EglContext context;
  GLuint fbo = 0, color = 0;
  glCreateFramebuffers(1, &fbo);
  glCreateRenderbuffers(1, &color);
  glNamedRenderbufferStorage(color, GL_RGBA8, 16, 8);
  glNamedFramebufferRenderbuffer(fbo, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, color);
  ASSERT_EQ(glCheckNamedFramebufferStatus(fbo, GL_FRAMEBUFFER), GLenum(GL_FRAMEBUFFER_COMPLETE));
  glBindFramebuffer(GL_FRAMEBUFFER, fbo);
  glViewport(0, 0, 16, 8);
  glClearColor(1.0f, 0.5f, 0.0f, 1.0f);
  glClear(GL_COLOR_BUFFER_BIT);
  unsigned char pixel[4] = {};
  glReadPixels(3, 5, 1, 1, GL_RGBA, GL_UNSIGNED_BYTE, pixel);
  EXPECT_EQ(pixel[0], 255);
  EXPECT_NEAR(pixel[1], 128, 1);
  EXPECT_EQ(pixel[2], 0);
  EXPECT_EQ(glGetError(), GLenum(GL_NO_ERROR));
  glDeleteRenderbuffers(1, &color);
  glDeleteFramebuffers(1, &fbo);
}

}  // namespace
}  // namespace tw
