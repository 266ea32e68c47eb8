// Objects a reviewer moved, rotated or scaled, drawn at their new placement.
//
// Why a pass of its own: a package's coarse clusters merge many objects into shared vertices, so
// an object cannot be moved inside them. A moved object carries kObjectMoved (object_states.h),
// which makes every cluster pass leave its triangles out at every level of detail, and this pass
// draws its full-resolution geometry (level-0 triangles and its parametrics tessellated, given by
// the caller) through the object's move, in the opaque surface pass: lit and coloured as the
// other passes do (object colour, selection tint, recolouring), writing depth and its object id
// (so it picks at its new place), clipped and capped by the section planes. It costs its
// full-resolution triangles every frame, whatever its distance, and is never culled.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "gl_renderer.h"

namespace tw {

struct MovedMesh {
  uint32_t object = 0;                // object index
  glm::dvec3 anchor{0.0};             // package frame
  std::vector<glm::vec3> triangles;   // three positions a triangle, relative to anchor
  glm::dmat4 move{1.0};               // package frame to package frame
};

class MovedObjectsPass {
 public:
  MovedObjectsPass();  // needs a current GL 4.5 context; throws std::runtime_error
  ~MovedObjectsPass();
  MovedObjectsPass(const MovedObjectsPass&) = delete;
  MovedObjectsPass& operator=(const MovedObjectsPass&) = delete;

  // Replaces what is drawn. The same objects as before (same order, anchors and triangle counts:
  // the same geometry) only take their new moves; otherwise the triangles are uploaded again.
  void set(std::vector<MovedMesh> meshes);
  bool empty() const { return meshes_.empty(); }
  uint64_t triangles() const { return triangle_count_; }

  // Draws into the renderer's targets in its current surface pass (opaque), seen from `eye`
  // (package frame) with projection * view rotation.
  void draw(const GlRenderer& renderer, const glm::dvec3& eye, const glm::mat4& view_projection) const;

 private:
  struct Upload {
    uint32_t first = 0, count = 0;  // vertices
  };
  std::vector<MovedMesh> meshes_;
  std::vector<Upload> ranges_;
  uint64_t triangle_count_ = 0;
  unsigned program_ = 0, vao_ = 0, buffer_ = 0;
};

}  // namespace tw
