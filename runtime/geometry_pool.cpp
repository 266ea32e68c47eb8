// The GPU geometry pool: three immutable-storage buffers and the vertex array that reads them.
// The pager decides every offset within the layout's capacities, so the GPU budget is a hard
// limit. Storage grows on demand up to those capacities (a larger buffer, the old contents copied
// on the GPU, the vertex array re-pointed): allocating the whole budget up front costs time and
// memory at start-up (llvmpipe touches every byte: about 0.5 s and 1 GiB of RSS for the default
// budget), while the pager places pages lowest address first, so the used part stays compact.
#include "geometry_pool.h"

#define GL_GLEXT_PROTOTYPES 1
#include <GL/glcorearb.h>

#include <algorithm>
#include <cstddef>
#include <cstdio>
#include <stdexcept>
#include <string>

namespace tw {
namespace {

constexpr GLuint kVertexBinding = 0;    // the one vertex buffer binding of the VAO
constexpr GLuint kPositionAttrib = 0;   // uvec3 q, 16-bit grid units
constexpr GLuint kTagAttrib = 1;        // uint: a triangle of the vertex's object (vertex_object_tags.h)

// First storage of each buffer, in elements (a few MiB), before any growth.
constexpr uint64_t kInitialElements = 1u << 18;

GLuint makeBuffer(uint64_t bytes, const char* what) {
  GLuint buffer = 0;
  glCreateBuffers(1, &buffer);
  // A zero-size store is an error in GL; keep one element so an empty pool is still valid.
  glNamedBufferStorage(buffer, static_cast<GLsizeiptr>(std::max<uint64_t>(bytes, 16)), nullptr,
                       GL_DYNAMIC_STORAGE_BIT);
  if (GLenum error = glGetError(); error != GL_NO_ERROR) {
    glDeleteBuffers(1, &buffer);
    char message[160];
    std::snprintf(message, sizeof message,
                  "GeometryPool: cannot allocate %llu bytes for the %s buffer (GL error 0x%04x)",
                  static_cast<unsigned long long>(bytes), what, error);
    throw std::runtime_error(message);
  }
  return buffer;
}

void checkRange(uint64_t first, uint64_t count, uint64_t capacity, const char* what,
                uint32_t page) {
  if (first > capacity || count > capacity - first) {
    throw std::out_of_range("GeometryPool::upload: page " + std::to_string(page) + " " + what +
                            " [" + std::to_string(first) + ", +" + std::to_string(count) +
                            ") exceeds the pool capacity " + std::to_string(capacity));
  }
}

}  // namespace

GeometryPool::GeometryPool(const PoolLayout& layout) : layout_(layout) {
  while (glGetError() != GL_NO_ERROR) {
  }  // errors left by others must not be blamed on us
  allocated_ = {std::min(layout.vertices, kInitialElements), std::min(layout.indices, kInitialElements),
                std::min(layout.triangles, kInitialElements)};
  try {
    vertices_ = makeBuffer(allocated_.vertices * sizeof(pkg::EncodedVertex), "vertex");
    indices_ = makeBuffer(allocated_.indices * sizeof(uint16_t), "index");
    objects_ = makeBuffer(allocated_.triangles * sizeof(uint32_t), "triangle-object");
  } catch (...) {
    glDeleteBuffers(1, &vertices_);
    glDeleteBuffers(1, &indices_);
    throw;
  }
  glCreateVertexArrays(1, &vao_);
  glVertexArrayVertexBuffer(vao_, kVertexBinding, vertices_, 0, sizeof(pkg::EncodedVertex));
  glEnableVertexArrayAttrib(vao_, kPositionAttrib);
  glVertexArrayAttribIFormat(vao_, kPositionAttrib, 3, GL_UNSIGNED_SHORT,
                             offsetof(pkg::EncodedVertex, q));
  glVertexArrayAttribBinding(vao_, kPositionAttrib, kVertexBinding);
  glEnableVertexArrayAttrib(vao_, kTagAttrib);  // the normal's two bytes, as one 16-bit word
  glVertexArrayAttribIFormat(vao_, kTagAttrib, 1, GL_UNSIGNED_SHORT,
                             offsetof(pkg::EncodedVertex, oct));
  glVertexArrayAttribBinding(vao_, kTagAttrib, kVertexBinding);
  glVertexArrayElementBuffer(vao_, indices_);
}

GeometryPool::~GeometryPool() {
  glDeleteVertexArrays(1, &vao_);
  glDeleteBuffers(1, &vertices_);
  glDeleteBuffers(1, &indices_);
  glDeleteBuffers(1, &objects_);
}

void GeometryPool::grow(unsigned& buffer, uint64_t& allocated, uint64_t needed, uint64_t capacity,
                        uint64_t element_bytes, const char* what) {
  if (needed <= allocated) return;
  // Doubling keeps the number of copies logarithmic in the final size.
  const uint64_t elements = std::min(capacity, std::max(needed, 2 * allocated));
  const GLuint bigger = makeBuffer(elements * element_bytes, what);
  glCopyNamedBufferSubData(buffer, bigger, 0, 0, static_cast<GLsizeiptr>(allocated * element_bytes));
  glDeleteBuffers(1, &buffer);
  buffer = bigger;
  allocated = elements;
  glVertexArrayVertexBuffer(vao_, kVertexBinding, vertices_, 0, sizeof(pkg::EncodedVertex));
  glVertexArrayElementBuffer(vao_, indices_);
}

uint64_t GeometryPool::upload(const PageUpload& upload) {
  // Check all three ranges before writing any, so a bad upload leaves the pool untouched.
  checkRange(upload.first_vertex, upload.vertices.size(), layout_.vertices, "vertices",
             upload.page);
  checkRange(upload.first_index, upload.indices.size(), layout_.indices, "indices", upload.page);
  checkRange(upload.first_triangle, upload.triangle_objects.size(), layout_.triangles,
             "triangles", upload.page);
  grow(vertices_, allocated_.vertices, upload.first_vertex + upload.vertices.size(),
       layout_.vertices, sizeof(pkg::EncodedVertex), "vertex");
  grow(indices_, allocated_.indices, upload.first_index + upload.indices.size(), layout_.indices,
       sizeof(uint16_t), "index");
  grow(objects_, allocated_.triangles, upload.first_triangle + upload.triangle_objects.size(),
       layout_.triangles, sizeof(uint32_t), "triangle-object");
  if (!upload.vertices.empty()) {
    glNamedBufferSubData(vertices_,
                         static_cast<GLintptr>(upload.first_vertex * sizeof(pkg::EncodedVertex)),
                         static_cast<GLsizeiptr>(upload.vertices.size() * sizeof(pkg::EncodedVertex)),
                         upload.vertices.data());
  }
  if (!upload.indices.empty()) {
    glNamedBufferSubData(indices_, static_cast<GLintptr>(upload.first_index * sizeof(uint16_t)),
                         static_cast<GLsizeiptr>(upload.indices.size() * sizeof(uint16_t)),
                         upload.indices.data());
  }
  if (!upload.triangle_objects.empty()) {
    glNamedBufferSubData(objects_,
                         static_cast<GLintptr>(upload.first_triangle * sizeof(uint32_t)),
                         static_cast<GLsizeiptr>(upload.triangle_objects.size() * sizeof(uint32_t)),
                         upload.triangle_objects.data());
  }
  return upload.bytes();
}

}  // namespace tw
