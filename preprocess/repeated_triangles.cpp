// Finding exact repeats of triangles by a sort of their rotated vertex triples (see
// repeated_triangles.h).
#include "repeated_triangles.h"

#include <algorithm>
#include <array>

#include <tbb/parallel_sort.h>

#include "exact_weld.h"

namespace tw {

namespace {

struct RotatedTriangle {
  std::array<uint32_t, 3> v;  // smallest vertex first, cyclic order kept
  uint32_t triangle;
  auto operator<=>(const RotatedTriangle&) const = default;
};

RotatedTriangle rotated(uint32_t a, uint32_t b, uint32_t c, uint32_t triangle) {
  if (b < a && b < c) return {{b, c, a}, triangle};
  if (c < a && c < b) return {{c, a, b}, triangle};
  return {{a, b, c}, triangle};
}

// The triangles of `keys` whose vertex triple equals an earlier one's, increasing.
std::vector<uint32_t> repeatsOf(std::vector<RotatedTriangle>& keys) {
  tbb::parallel_sort(keys.begin(), keys.end());
  std::vector<uint32_t> repeats;
  for (size_t i = 1; i < keys.size(); ++i)
    if (keys[i].v == keys[i - 1].v) repeats.push_back(keys[i].triangle);
  std::sort(repeats.begin(), repeats.end());
  return repeats;
}

}  // namespace

std::vector<uint32_t> repeatedTriangles(const TriangleMesh& mesh) {
  const WeldedTriangles welded = weldExactly(mesh);
  std::vector<RotatedTriangle> keys;
  keys.reserve(welded.triangles.size());
  for (size_t t = 0; t < welded.triangles.size(); ++t) {
    const auto& [a, b, c] = welded.triangles[t];
    keys.push_back(rotated(a, b, c, welded.sources[t]));
  }
  return repeatsOf(keys);
}

uint64_t dropRepeatedTriangles(std::vector<uint32_t>& tris, std::vector<uint32_t>& ids) {
  std::vector<RotatedTriangle> keys(ids.size());
  for (uint32_t t = 0; t < keys.size(); ++t)
    keys[t] = rotated(tris[3 * t], tris[3 * t + 1], tris[3 * t + 2], t);
  const std::vector<uint32_t> repeats = repeatsOf(keys);
  if (repeats.empty()) return 0;
  size_t kept = 0, next = 0;
  for (size_t t = 0; t < ids.size(); ++t) {
    if (next < repeats.size() && repeats[next] == t) {
      ++next;
      continue;
    }
    for (int k = 0; k < 3; ++k) tris[3 * kept + k] = tris[3 * t + k];
    ids[kept++] = ids[t];
  }
  tris.resize(3 * kept);
  ids.resize(kept);
  return repeats.size();
}

TriangleMesh withoutTriangles(const TriangleMesh& mesh, const std::vector<uint32_t>& triangles) {
  TriangleMesh out;
  out.positions = mesh.positions;
  out.normals = mesh.normals;
  out.colors = mesh.colors;
  out.indices.reserve(mesh.indices.size() - 3 * triangles.size());
  size_t next = 0;
  for (uint32_t t = 0; 3 * size_t(t) + 2 < mesh.indices.size(); ++t) {
    if (next < triangles.size() && triangles[next] == t) {
      ++next;
      continue;
    }
    out.indices.insert(out.indices.end(), mesh.indices.begin() + 3 * t,
                       mesh.indices.begin() + 3 * t + 3);
  }
  return out;
}

}  // namespace tw
