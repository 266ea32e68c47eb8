// GL program building with logs and clean-up. See gl_program.h.
#include "gl_program.h"

#define GL_GLEXT_PROTOTYPES 1
#include <GL/glcorearb.h>

#include <algorithm>
#include <stdexcept>
#include <vector>

namespace tw {
namespace {

const char* stageName(unsigned stage) {
  switch (stage) {
    case GL_VERTEX_SHADER: return "vertex";
    case GL_FRAGMENT_SHADER: return "fragment";
    case GL_COMPUTE_SHADER: return "compute";
    case GL_GEOMETRY_SHADER: return "geometry";
    default: return "unknown";
  }
}

std::string shaderLog(GLuint shader) {
  GLint length = 0;
  glGetShaderiv(shader, GL_INFO_LOG_LENGTH, &length);
  std::string log(static_cast<size_t>(std::max(length, 1)), '\0');
  glGetShaderInfoLog(shader, length, nullptr, log.data());
  return log.c_str();
}

std::string programLog(GLuint program) {
  GLint length = 0;
  glGetProgramiv(program, GL_INFO_LOG_LENGTH, &length);
  std::string log(static_cast<size_t>(std::max(length, 1)), '\0');
  glGetProgramInfoLog(program, length, nullptr, log.data());
  return log.c_str();
}

}  // namespace

unsigned buildGlProgram(std::initializer_list<ShaderSource> stages, const std::string& name) {
  std::vector<GLuint> shaders;
  auto release = [&shaders] {
    for (GLuint s : shaders) glDeleteShader(s);
  };
  for (const ShaderSource& stage : stages) {
    GLuint shader = glCreateShader(stage.stage);
    shaders.push_back(shader);
    const char* text = stage.text.c_str();
    glShaderSource(shader, 1, &text, nullptr);
    glCompileShader(shader);
    GLint ok = GL_FALSE;
    glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
    if (!ok) {
      const std::string log = shaderLog(shader);
      release();
      throw std::runtime_error(name + ": cannot compile the " + stageName(stage.stage) +
                               " shader: " + log);
    }
  }
  GLuint program = glCreateProgram();
  for (GLuint s : shaders) glAttachShader(program, s);
  glLinkProgram(program);
  for (GLuint s : shaders) glDetachShader(program, s);
  release();
  GLint ok = GL_FALSE;
  glGetProgramiv(program, GL_LINK_STATUS, &ok);
  if (!ok) {
    const std::string log = programLog(program);
    glDeleteProgram(program);
    throw std::runtime_error(name + ": cannot link the program: " + log);
  }
  return program;
}

}  // namespace tw
