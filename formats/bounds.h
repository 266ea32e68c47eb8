// Axis-aligned bounds in world coordinates (double precision) and the bounds of scene objects.
#pragma once

#include <limits>

#include <glm/glm.hpp>

#include "scene.h"

namespace tw {

struct Aabb {
  glm::dvec3 min{std::numeric_limits<double>::infinity()};
  glm::dvec3 max{-std::numeric_limits<double>::infinity()};

  bool empty() const { return min.x > max.x; }
  void add(const glm::dvec3& p) {
    min = glm::min(min, p);
    max = glm::max(max, p);
  }
  void add(const Aabb& b) {
    if (b.empty()) return;
    add(b.min);
    add(b.max);
  }
  glm::dvec3 center() const { return (min + max) * 0.5; }
  glm::dvec3 extent() const { return empty() ? glm::dvec3(0.0) : max - min; }
};

// Conservative world-space bounds of an object's geometry: exact for meshes, the transformed
// local box for primitives, and the control-point hull for NURBS (a rational B-spline with
// positive weights lies inside the convex hull of its control points).
Aabb worldBounds(const SceneObject& object);

// Bounds of the geometry in its own local frame.
struct LocalBox {
  glm::vec3 min{std::numeric_limits<float>::infinity()};
  glm::vec3 max{-std::numeric_limits<float>::infinity()};
};
LocalBox localBounds(const Geometry& geometry);
// The same for one primitive in its canonical frame (a torus segment's is its whole torus's).
LocalBox primitiveBounds(const Primitive& primitive);
// World bounds of a local box carried by `t`: its eight corners placed.
Aabb placedBox(const LocalBox& box, const Transform& t);

}  // namespace tw
