// Compiling and linking GL shader programs, with the driver's log in the exception when a step
// fails. Shared by the GL code of the runtime (the renderer) and of occlusion (the HZB builder),
// so the error handling and the clean-up after a failure live in one place.
#pragma once

#include <initializer_list>
#include <string>
#include <utility>

namespace tw {

// One shader stage's source: a GL stage enum (GL_VERTEX_SHADER, GL_COMPUTE_SHADER, ...) and its
// GLSL text.
struct ShaderSource {
  unsigned stage;
  std::string text;
};

// Compiles every stage and links them into a program (a current GL context is needed). Throws
// std::runtime_error("<name>: cannot compile the <stage> shader: <log>" or "...cannot link...")
// and leaves no shader or program behind when a step fails. The shaders are deleted once linked.
unsigned buildGlProgram(std::initializer_list<ShaderSource> stages, const std::string& name);

}  // namespace tw
