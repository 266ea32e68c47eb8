// Bounds of meshes, primitives and NURBS in local and world frames.
#include "bounds.h"

#include <algorithm>
#include <cmath>

namespace tw {
namespace {

void grow(LocalBox& box, const glm::vec3& p) {
  box.min = glm::min(box.min, p);
  box.max = glm::max(box.max, p);
}

}  // namespace

LocalBox primitiveBounds(const Primitive& primitive) {
  LocalBox box;
  std::visit(
      [&](const auto& p) {
        using T = std::decay_t<decltype(p)>;
        if constexpr (std::is_same_v<T, Cylinder>) {
          grow(box, {-p.radius, -p.radius, 0.0f});
          grow(box, {p.radius, p.radius, p.height});
        } else if constexpr (std::is_same_v<T, Cone>) {
          float r = std::max(p.radius_bottom, p.radius_top);
          grow(box, {-r, -r, 0.0f});
          grow(box, {r, r, p.height});
        } else if constexpr (std::is_same_v<T, Sphere>) {
          grow(box, glm::vec3(-p.radius));
          grow(box, glm::vec3(p.radius));
        } else if constexpr (std::is_same_v<T, TorusSegment>) {
          // Conservative: the full torus.
          float r = p.major_radius + p.minor_radius;
          grow(box, {-r, -r, -p.minor_radius});
          grow(box, {r, r, p.minor_radius});
        } else if constexpr (std::is_same_v<T, Box>) {
          grow(box, -p.half_extents);
          grow(box, p.half_extents);
        } else if constexpr (std::is_same_v<T, Extrusion>) {
          for (const glm::vec2& q : p.profile) {
            grow(box, {q.x, q.y, 0.0f});
            grow(box, {q.x, q.y, p.height});
          }
        } else if constexpr (std::is_same_v<T, Revolution>) {
          float r = 0.0f;
          for (const glm::vec2& q : p.profile) {
            r = std::max(r, std::fabs(q.x));
            grow(box, {0.0f, 0.0f, q.y});
          }
          if (!p.profile.empty()) {
            grow(box, {-r, -r, box.min.z});
            grow(box, {r, r, box.max.z});
          }
        }
      },
      primitive);
  return box;
}

LocalBox localBounds(const Geometry& geometry) {
  LocalBox box;
  if (const auto* mesh = std::get_if<TriangleMesh>(&geometry)) {
    for (const glm::vec3& p : mesh->positions) grow(box, p);
  } else if (const auto* primitive = std::get_if<Primitive>(&geometry)) {
    box = primitiveBounds(*primitive);
  } else if (const auto* nurbs = std::get_if<NurbsPatchSet>(&geometry)) {
    for (const NurbsPatch& patch : nurbs->patches)
      for (const glm::vec4& cp : patch.control_points) grow(box, glm::vec3(cp));
  }
  return box;
}

Aabb worldBounds(const SceneObject& object) {
  Aabb out;
  const Transform& t = object.info.transform;
  if (const auto* mesh = std::get_if<TriangleMesh>(&object.geometry)) {
    // Exact: transform every vertex, not the local box.
    for (const glm::vec3& p : mesh->positions) out.add(t.apply(p));
    return out;
  }
  return placedBox(localBounds(object.geometry), t);
}

Aabb placedBox(const LocalBox& box, const Transform& t) {
  Aabb out;
  if (box.min.x > box.max.x) return out;
  for (int i = 0; i < 8; ++i) {
    glm::vec3 corner{(i & 1) ? box.max.x : box.min.x, (i & 2) ? box.max.y : box.min.y,
                     (i & 4) ? box.max.z : box.min.z};
    out.add(t.apply(corner));
  }
  return out;
}

}  // namespace tw
