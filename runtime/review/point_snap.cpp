// Snapping a picked point (point_snap.h).
#include "point_snap.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <tuple>
#include <vector>
#include <limits>
#include <optional>

namespace tw {
namespace {

// The shape's feature edges: on one triangle only (a border), or between triangles whose normals
// differ by more than 20 degrees (a crease); the diagonals of flat faces are no edges to a user.
std::vector<std::pair<glm::dvec3, glm::dvec3>> featureEdges(const MeasureShape& shape) {
  using Key = std::array<double, 6>;
  std::map<Key, std::vector<glm::dvec3>> normals;
  for (const Triangle3d& t : shape.triangles) {
    const glm::dvec3 n = glm::cross(t[1] - t[0], t[2] - t[0]);
    const double len = glm::length(n);
    if (len <= 0.0) continue;
    for (int e = 0; e < 3; ++e) {
      glm::dvec3 a = t[size_t(e)], b = t[size_t((e + 1) % 3)];
      if (std::tie(b.x, b.y, b.z) < std::tie(a.x, a.y, a.z)) std::swap(a, b);
      normals[{a.x, a.y, a.z, b.x, b.y, b.z}].push_back(n / len);
    }
  }
  const double crease = std::cos(20.0 * 3.14159265358979323846 / 180.0);
  std::vector<std::pair<glm::dvec3, glm::dvec3>> edges;
  for (const auto& [k, ns] : normals) {
    bool feature = ns.size() != 2;
    for (size_t i = 1; i < ns.size() && !feature; ++i) feature = std::abs(glm::dot(ns[0], ns[i])) < crease;
    if (feature) edges.push_back({{k[0], k[1], k[2]}, {k[3], k[4], k[5]}});
  }
  return edges;
}

}  // namespace

const char* snapKindName(SnappedPoint::Kind kind) {
  switch (kind) {
    case SnappedPoint::Kind::AxisEnd: return "axis end";
    case SnappedPoint::Kind::Vertex: return "vertex";
    case SnappedPoint::Kind::Edge: return "edge";
    case SnappedPoint::Kind::Surface: return "surface";
  }
  return "?";
}

SnappedPoint snapPoint(const PackageView& view, const MeasureShape& shape, const glm::dvec3& picked,
                       double radius_m) {
  const glm::dvec3 p = picked - view.origin();  // the shape's frame
  auto nearest = [&](auto&& candidates) {
    double best = radius_m;
    std::optional<glm::dvec3> found;
    candidates([&](const glm::dvec3& q) {
      const double d = glm::length(q - p);
      if (d <= best) {
        best = d;
        found = q;
      }
    });
    return found;
  };
  if (auto q = nearest([&](auto&& offer) {
        for (const CylinderAxis& c : shape.cylinders) {
          offer(c.base);
          offer(c.top);
        }
      }))
    return {SnappedPoint::Kind::AxisEnd, *q + view.origin()};
  if (auto q = nearest([&](auto&& offer) {
        for (const Triangle3d& t : shape.triangles)
          for (const glm::dvec3& v : t) offer(v);
      }))
    return {SnappedPoint::Kind::Vertex, *q + view.origin()};
  if (auto q = nearest([&](auto&& offer) {
        for (const auto& [a, b] : featureEdges(shape)) {
          const glm::dvec3 ab = b - a;
          offer(a + std::clamp(glm::dot(p - a, ab) / glm::dot(ab, ab), 0.0, 1.0) * ab);
        }
      }))
    return {SnappedPoint::Kind::Edge, *q + view.origin()};
  return {SnappedPoint::Kind::Surface, picked};
}

}  // namespace tw
