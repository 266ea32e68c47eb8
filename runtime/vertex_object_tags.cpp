// Per-vertex object tags for the mesh shaders. See vertex_object_tags.h.
#include "vertex_object_tags.h"

#include <algorithm>
#include <cstring>
#include <vector>

namespace tw {

namespace {

constexpr uint32_t kUntagged = UINT32_MAX;

void storeTag(pkg::EncodedVertex& vertex, uint16_t tag) {
  static_assert(sizeof(vertex.oct) == sizeof(tag));
  std::memcpy(vertex.oct, &tag, sizeof tag);
}

}  // namespace

uint16_t vertexObjectTag(const pkg::EncodedVertex& vertex) {
  uint16_t tag = 0;
  std::memcpy(&tag, vertex.oct, sizeof tag);
  return tag;
}

uint32_t tagVertexObjects(std::span<pkg::EncodedVertex> vertices, std::span<uint16_t> indices,
                          std::span<const uint32_t> triangle_objects) {
  const size_t triangles = std::min(triangle_objects.size(), indices.size() / 3);
  // First triangle of each vertex, or kSharedVertexTag once two objects meet there.
  std::vector<uint32_t> owner(vertices.size(), kUntagged);
  for (size_t t = 0; t < triangles; ++t) {
    for (size_t k = 0; k < 3; ++k) {
      const uint16_t v = indices[3 * t + k];
      if (v >= vertices.size()) continue;
      uint32_t& o = owner[v];
      if (o == kUntagged)
        o = static_cast<uint32_t>(t);
      else if (o != kSharedVertexTag && triangle_objects[o] != triangle_objects[t])
        o = kSharedVertexTag;
    }
  }
  for (size_t v = 0; v < vertices.size(); ++v)
    storeTag(vertices[v], owner[v] == kUntagged || owner[v] > kSharedVertexTag
                              ? kSharedVertexTag
                              : static_cast<uint16_t>(owner[v]));
  uint32_t unresolved = 0;
  for (size_t t = 0; t < triangles; ++t) {
    uint16_t* tri = &indices[3 * t];
    auto own = [&](uint16_t v) { return v < vertices.size() && owner[v] != kSharedVertexTag; };
    if (own(tri[2])) continue;
    if (own(tri[0]))
      std::rotate(tri, tri + 1, tri + 3);  // (a, b, c) -> (b, c, a): a last
    else if (own(tri[1]))
      std::rotate(tri, tri + 2, tri + 3);  // (a, b, c) -> (c, a, b): b last
    else
      ++unresolved;
  }
  return unresolved;
}

}  // namespace tw
