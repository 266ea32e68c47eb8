// A thin owner of an Embree 3 device and scene: triangles in, ray hits out.
//
// Plant coordinates can be kilometres from the datum, where float loses millimetres. The scene
// therefore has a double-precision origin and stores every vertex as a float offset from it;
// rays are expressed in the same origin-relative frame. The class knows nothing of images or
// shading so the occlusion preprocess (rays cast from view cells) and CPU snapshots share it.
#pragma once

#include <cstdint>
#include <limits>
#include <memory>
#include <span>
#include <vector>

#include <glm/glm.hpp>

namespace tw {

// A ray in the scene's origin-relative frame. `direction` need not be unit length; t is measured
// in multiples of it. Hits are reported for t in [t_near, t_far].
struct Ray {
  glm::vec3 origin{0.0f};
  glm::vec3 direction{0.0f, 0.0f, 1.0f};
  float t_near = 0.0f;
  float t_far = std::numeric_limits<float>::infinity();
};

class EmbreeScene {
 public:
  struct Hit {
    bool hit = false;
    float t = std::numeric_limits<float>::infinity();
    glm::vec3 normal{0.0f};  // unit geometric normal, following the triangle's winding
    float u = 0.0f, v = 0.0f;  // barycentrics of the hit point: p = (1-u-v)*p0 + u*p1 + v*p2
    uint32_t user_id = 0;    // as given to addMesh
    uint32_t geometry = 0;   // as returned by addMesh
    uint32_t primitive = 0;  // triangle index within that mesh
  };

  // Creates the device and an empty scene. Throws std::runtime_error if Embree cannot start.
  explicit EmbreeScene(const glm::dvec3& origin);
  ~EmbreeScene();
  EmbreeScene(const EmbreeScene&) = delete;
  EmbreeScene& operator=(const EmbreeScene&) = delete;

  const glm::dvec3& origin() const { return origin_; }
  // World (double) to the scene frame (float) and back.
  glm::vec3 toScene(const glm::dvec3& world) const { return glm::vec3(world - origin_); }
  glm::dvec3 toWorld(const glm::vec3& scene) const { return origin_ + glm::dvec3(scene); }

  // Adds a triangle mesh whose positions are already relative to origin(). Returns its geometry
  // id (0, 1, 2... in call order). The copying overload leaves the caller's buffers alone; the
  // moving overload takes ownership and lets Embree read the vectors in place (no second copy,
  // which matters at 10M+ triangles). Throws std::invalid_argument when indices.size() is not a
  // multiple of 3 or an index is out of range, std::runtime_error on an Embree error. Must be
  // called before commit(). Empty meshes are accepted and never hit.
  uint32_t addMesh(std::span<const glm::vec3> positions_rel, std::span<const uint32_t> indices,
                   uint32_t user_id);
  uint32_t addMesh(std::vector<glm::vec3>&& positions_rel, std::vector<uint32_t>&& indices,
                   uint32_t user_id);

  // Builds the BVH. Call once, after the last addMesh and before any query.
  void commit();
  bool committed() const { return committed_; }

  uint32_t geometryCount() const { return static_cast<uint32_t>(user_ids_.size()); }
  uint64_t triangleCount() const { return triangles_; }

  // Nearest hit along one ray. Thread-safe after commit().
  Hit intersect(const Ray& ray) const;
  // True if anything lies on the ray within [t_near, t_far] (cheaper than intersect).
  bool occluded(const Ray& ray) const;

  // Batches, spread over all cores. `hits` / `blocked` must be as long as `rays`. `coherent`
  // hints that neighbouring rays travel together (camera rays); leave it false for random rays.
  void intersect(std::span<const Ray> rays, std::span<Hit> hits, bool coherent = false) const;
  void occluded(std::span<const Ray> rays, std::span<uint8_t> blocked, bool coherent = false) const;

  // Single-ray queries with the coherent hint, for callers that run their own parallel loop
  // over neighbouring rays (image rows).
  Hit intersectCoherent(const Ray& ray) const;

 private:
  struct Impl;
  uint32_t attach(void* geometry, uint64_t triangle_count, uint32_t user_id);
  void throwIfError(const char* what) const;

  glm::dvec3 origin_;
  std::unique_ptr<Impl> impl_;
  std::vector<uint32_t> user_ids_;  // by geometry id
  uint64_t triangles_ = 0;
  bool committed_ = false;
};

}  // namespace tw
