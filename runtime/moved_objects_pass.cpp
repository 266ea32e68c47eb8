// The moved objects' pass (moved_objects_pass.h).
#include "moved_objects_pass.h"

#define GL_GLEXT_PROTOTYPES 1
#include <GL/glcorearb.h>

#include <stdexcept>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/type_ptr.hpp>

#include "gl_program.h"
#include "gl_shaders.h"

namespace tw {
namespace {

constexpr int kModelEyeLocation = 2;  // mat4: anchor-relative to eye-relative, moved
constexpr int kObjectLocation = 3;    // uint: the object index

std::string vertexShader() {
  return R"(#version 450 core
layout(location = 0) in vec3 position;
layout(location = 0) uniform mat4 view_projection;
layout(location = 2) uniform mat4 model_eye;
out vec3 pos_eye;
void main() {
  pos_eye = (model_eye * vec4(position, 1.0)).xyz;
  gl_Position = view_projection * vec4(pos_eye, 1.0);
}
)";
}

std::string fragmentShader() {
  return std::string(R"(#version 450 core
in vec3 pos_eye;
layout(location = 3) uniform uint object;
layout(location = 0) out vec4 out_color;
layout(location = 1) out uint out_id;
)") + gl::shadingGlsl() + R"(
void main() {
  // Drawn here precisely because it is moved: only hiding, and the X-ray pass, leave it out.
  if ((objectFlags(object) & kObjectHidden) != 0u || surface_pass != 0u) discard;
  if (sectionClipped(pos_eye)) discard;
  vec3 n = facetNormal(pos_eye);
  out_color = sectionCap(!gl_FrontFacing) ? kSectionCap : shadeSurface(objectBaseColor(object), n, pos_eye);
  out_id = object + 1u;
}
)";
}

}  // namespace

MovedObjectsPass::MovedObjectsPass() {
  program_ = buildGlProgram({{GL_VERTEX_SHADER, vertexShader()}, {GL_FRAGMENT_SHADER, fragmentShader()}},
                            "moved objects");
  glCreateVertexArrays(1, &vao_);
  glEnableVertexArrayAttrib(vao_, 0);
  glVertexArrayAttribFormat(vao_, 0, 3, GL_FLOAT, GL_FALSE, 0);
  glVertexArrayAttribBinding(vao_, 0, 0);
}

MovedObjectsPass::~MovedObjectsPass() {
  if (buffer_) glDeleteBuffers(1, &buffer_);
  if (vao_) glDeleteVertexArrays(1, &vao_);
  if (program_) glDeleteProgram(program_);
}

void MovedObjectsPass::set(std::vector<MovedMesh> meshes) {
  // The same objects with new moves (a drag, the explode animation): only the moves change, the
  // uploaded triangles stay.
  bool same = meshes.size() == meshes_.size();
  for (size_t i = 0; same && i < meshes.size(); ++i)
    same = meshes[i].object == meshes_[i].object && meshes[i].anchor == meshes_[i].anchor &&
           meshes[i].triangles.size() == meshes_[i].triangles.size();
  if (same) {
    for (size_t i = 0; i < meshes.size(); ++i) meshes_[i].move = meshes[i].move;
    return;
  }
  meshes_ = std::move(meshes);
  ranges_.clear();
  triangle_count_ = 0;
  std::vector<glm::vec3> all;
  for (const MovedMesh& m : meshes_) {
    ranges_.push_back({static_cast<uint32_t>(all.size()), static_cast<uint32_t>(m.triangles.size())});
    all.insert(all.end(), m.triangles.begin(), m.triangles.end());
    triangle_count_ += m.triangles.size() / 3;
  }
  if (buffer_) glDeleteBuffers(1, &buffer_);
  buffer_ = 0;
  if (all.empty()) return;
  glCreateBuffers(1, &buffer_);
  glNamedBufferStorage(buffer_, static_cast<GLsizeiptr>(all.size() * sizeof(glm::vec3)), all.data(), 0);
  glVertexArrayVertexBuffer(vao_, 0, buffer_, 0, sizeof(glm::vec3));
}

void MovedObjectsPass::draw(const GlRenderer& renderer, const glm::dvec3& eye,
                            const glm::mat4& view_projection) const {
  if (meshes_.empty() || renderer.surfacePass() != SurfacePass::Opaque) return;
  renderer.bindSurfaceState();
  glDisable(GL_CULL_FACE);
  glUseProgram(program_);
  glBindVertexArray(vao_);
  glUniformMatrix4fv(gl::kViewProjectionLocation, 1, GL_FALSE, glm::value_ptr(view_projection));
  glUniform1ui(gl::kObjectColorCountLocation, renderer.objectColorCount());
  for (size_t i = 0; i < meshes_.size(); ++i) {
    const MovedMesh& m = meshes_[i];
    // In double: the anchor's offset after the move, relative to the eye; then float.
    const glm::dmat4 model_eye =
        glm::translate(glm::dmat4(1.0), -eye) * m.move * glm::translate(glm::dmat4(1.0), m.anchor);
    const glm::mat4 model(model_eye);
    glUniformMatrix4fv(kModelEyeLocation, 1, GL_FALSE, glm::value_ptr(model));
    glUniform1ui(kObjectLocation, m.object);
    glDrawArrays(GL_TRIANGLES, static_cast<GLint>(ranges_[i].first), static_cast<GLsizei>(ranges_[i].count));
  }
  glBindVertexArray(0);
}

}  // namespace tw
