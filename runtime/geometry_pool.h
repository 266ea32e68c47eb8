// The GPU geometry pool: three GL buffers (vertices, 16-bit indices, per-triangle objects) with
// capacities from a PoolLayout, filled at offsets the pager chose; storage grows on demand up to
// the capacities. One pool means one vertex array object and one glMultiDrawElementsIndirect per
// frame for all mesh clusters.
// Needs a current GL 4.5 context for its whole life.
#pragma once

#include <cstdint>

#include "pager.h"

namespace tw {

class GeometryPool {
 public:
  explicit GeometryPool(const PoolLayout& layout);  // throws std::runtime_error on GL failure
  ~GeometryPool();
  GeometryPool(const GeometryPool&) = delete;
  GeometryPool& operator=(const GeometryPool&) = delete;

  // Copies the page's data to its offsets (glNamedBufferSubData); returns bytes copied. Throws
  // std::out_of_range, writing nothing, when a range does not fit the layout.
  uint64_t upload(const PageUpload& upload);

  unsigned vertexArray() const { return vao_; }          // vertex buffer + index buffer bound
  unsigned triangleObjectBuffer() const { return objects_; }  // SSBO of uint object indices
  const PoolLayout& layout() const { return layout_; }      // capacities (the budget)
  const PoolLayout& allocated() const { return allocated_; }  // storage allocated so far

 private:
  void grow(unsigned& buffer, uint64_t& allocated, uint64_t needed, uint64_t capacity,
            uint64_t element_bytes, const char* what);

  PoolLayout layout_;
  PoolLayout allocated_;
  unsigned vao_ = 0, vertices_ = 0, indices_ = 0, objects_ = 0;
};

}  // namespace tw
