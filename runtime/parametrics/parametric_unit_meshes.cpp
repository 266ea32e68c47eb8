// The unit meshes of tessellated parametrics. See parametric_unit_meshes.h.
#include "parametric_unit_meshes.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace tw {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

}  // namespace

float ringSwell(uint32_t n) {
  return static_cast<float>(2.0 / (1.0 + std::cos(std::numbers::pi / std::max(n, 3u))));
}

UnitMesh UnitMeshBuilder::tube(uint32_t n) {
  UnitMesh m = begin();
  const std::vector<glm::vec2> ring = straddlingCircle(n);
  // Side rims, then the caps' own rims (flat normals), then the cap centres.
  for (float rim : {1.0f, 2.0f})
    for (float z : {0.0f, 1.0f})
      for (const glm::vec2& cs : ring) shapes.push_back({cs.x, cs.y, z, rim});
  shapes.push_back({0.0f, 0.0f, 0.0f, 0.0f});  // bottom cap centre
  shapes.push_back({0.0f, 0.0f, 1.0f, 0.0f});  // top cap centre
  for (uint32_t i = 0; i < n; ++i) {
    const uint32_t i1 = (i + 1) % n;
    quad(i, i1, n + i1, n + i);
  }
  m.side_indices = count(m);
  for (uint32_t i = 0; i < n; ++i) {
    const uint32_t i1 = (i + 1) % n;
    triangle(4 * n, 2 * n + i1, 2 * n + i);
    triangle(4 * n + 1, 3 * n + i, 3 * n + i1);
  }
  m.all_indices = count(m);
  return m;
}

UnitMesh UnitMeshBuilder::sphere(uint32_t n, uint32_t m) {
  UnitMesh mesh = begin();
  const std::vector<glm::vec2> ring = circle(n);
  shapes.push_back({1.0f, 0.0f, 0.0f, -1.0f});  // south pole
  for (uint32_t j = 1; j < m; ++j) {
    const double phi = -0.5 * std::numbers::pi + std::numbers::pi * j / m;
    const float c = static_cast<float>(std::cos(phi)), s = static_cast<float>(std::sin(phi));
    for (const glm::vec2& cs : ring) shapes.push_back({cs.x, cs.y, c, s});
  }
  const uint32_t north = 1 + (m - 1) * n;
  shapes.push_back({1.0f, 0.0f, 0.0f, 1.0f});
  auto at = [n](uint32_t row, uint32_t i) { return 1 + (row - 1) * n + i % n; };
  for (uint32_t i = 0; i < n; ++i) {
    triangle(0, at(1, i + 1), at(1, i));
    for (uint32_t row = 1; row + 1 < m; ++row) quad(at(row, i), at(row, i + 1), at(row + 1, i + 1), at(row + 1, i));
    triangle(at(m - 1, i), at(m - 1, i + 1), north);
  }
  mesh.side_indices = mesh.all_indices = count(mesh);
  return mesh;
}

UnitMesh UnitMeshBuilder::torus(uint32_t nu, uint32_t nv) {
  UnitMesh m = begin();
  const std::vector<glm::vec2> ring = straddlingCircle(nv);
  for (const glm::vec2& cs : ring)
    for (uint32_t i = 0; i <= nu; ++i) shapes.push_back({float(i) / float(nu), cs.x, cs.y, 0.0f});
  auto at = [nu](uint32_t row, uint32_t i) { return row * (nu + 1) + i; };
  for (uint32_t k = 0; k < nv; ++k) {
    const uint32_t k1 = (k + 1) % nv;
    for (uint32_t i = 0; i < nu; ++i) quad(at(k, i), at(k, i + 1), at(k1, i + 1), at(k1, i));
  }
  m.side_indices = m.all_indices = count(m);
  return m;
}

UnitMesh UnitMeshBuilder::box() {
  UnitMesh m = begin();
  for (uint32_t c = 0; c < 8; ++c)
    shapes.push_back({(c & 1) ? 1.0f : -1.0f, (c & 2) ? 1.0f : -1.0f, (c & 4) ? 1.0f : -1.0f, 0.0f});
  // Corners by bit (0: x, 1: y, 2: z), two triangles per face: -X, +X, -Y, +Y, -Z, +Z.
  constexpr uint32_t kCorners[36] = {0, 6, 2, 0, 4, 6, 1, 7, 5, 1, 3, 7, 0, 5, 4, 0, 1, 5,
                                     2, 7, 3, 2, 6, 7, 0, 3, 1, 0, 2, 3, 4, 7, 6, 4, 5, 7};
  for (uint32_t i = 0; i < 36; i += 3) triangle(kCorners[i], kCorners[i + 1], kCorners[i + 2]);
  m.side_indices = m.all_indices = count(m);
  return m;
}

UnitMesh UnitMeshBuilder::begin() const {
  UnitMesh m;
  m.base_vertex = static_cast<uint32_t>(shapes.size());
  m.first_index = static_cast<uint32_t>(indices.size());
  return m;
}

void UnitMeshBuilder::quad(uint32_t a, uint32_t b, uint32_t c, uint32_t d) {
  triangle(a, b, c);
  triangle(a, c, d);
}

std::vector<glm::vec2> UnitMeshBuilder::circle(uint32_t n) {
  std::vector<glm::vec2> ring(n);
  for (uint32_t i = 0; i < n; ++i) {
    const double a = kTwoPi * i / n;
    ring[i] = {static_cast<float>(std::cos(a)), static_cast<float>(std::sin(a))};
  }
  return ring;
}

std::vector<glm::vec2> UnitMeshBuilder::straddlingCircle(uint32_t n) {
  std::vector<glm::vec2> ring = circle(n);
  const float out = ringSwell(n);
  for (glm::vec2& p : ring) p *= out;
  return ring;
}

}  // namespace tw
