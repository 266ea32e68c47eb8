// Recursive median bisection of triangle centroids into balanced clusters, with large objects
// kept apart (see clusterize.h).
#include "clusterize.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <unordered_map>

#include "object_sets.h"

namespace tw {

namespace {

struct Splitter {
  const std::vector<glm::vec3>& centroids;
  std::vector<uint32_t>& order;
  std::vector<uint32_t>& offsets;
  size_t max_triangles;

  // Depth-first, left before right, so clusters are emitted in spatial order.
  void split(size_t begin, size_t end) {
    size_t count = end - begin;
    if (count <= max_triangles) {
      offsets.push_back(static_cast<uint32_t>(end));
      return;
    }
    // Give each side a whole number of final clusters so sizes stay balanced to one triangle.
    size_t clusters = (count + max_triangles - 1) / max_triangles;
    size_t left_clusters = clusters / 2;
    size_t mid = begin + count * left_clusters / clusters;

    glm::vec3 lo(INFINITY), hi(-INFINITY);
    for (size_t i = begin; i < end; ++i) {
      lo = glm::min(lo, centroids[order[i]]);
      hi = glm::max(hi, centroids[order[i]]);
    }
    glm::vec3 extent = hi - lo;
    int axis = extent.x >= extent.y && extent.x >= extent.z ? 0 : (extent.y >= extent.z ? 1 : 2);
    // Ties broken by triangle index: the result does not depend on the library's nth_element.
    std::nth_element(order.begin() + static_cast<ptrdiff_t>(begin),
                     order.begin() + static_cast<ptrdiff_t>(mid),
                     order.begin() + static_cast<ptrdiff_t>(end), [&](uint32_t a, uint32_t b) {
                       float ca = centroids[a][axis], cb = centroids[b][axis];
                       return ca < cb || (ca == cb && a < b);
                     });
    split(begin, mid);
    split(mid, end);
  }
};

// Median bisection of one point per triangle.
TriangleClusters splitPoints(const std::vector<glm::vec3>& points, uint32_t max_triangles) {
  TriangleClusters result;
  result.triangles.resize(points.size());
  std::iota(result.triangles.begin(), result.triangles.end(), 0u);
  if (points.empty()) return result;
  result.offsets.reserve(points.size() / max_triangles + 2);
  result.offsets.push_back(0);
  Splitter splitter{points, result.triangles, result.offsets, max_triangles};
  splitter.split(0, points.size());
  return result;
}

// The small objects' set: each triangle sorted by its object's centre, pulled a millionth of the
// way toward its own centroid (so an object's triangles stay in spatial order among themselves).
// A split then cuts through at most one object, where sorting by triangle centroid cut through
// every part it crossed: a part whose triangles sit in two groups has every vertex on a group
// border and cannot simplify (the KiCad connector's groups were locked that way).
TriangleClusters clusterizeSmallObjects(std::span<const glm::vec3> positions,
                                        std::span<const uint32_t> indices,
                                        std::span<const uint32_t> objects,
                                        uint32_t max_triangles) {
  const size_t triangle_count = indices.size() / 3;
  std::vector<glm::vec3> centroids(triangle_count);
  std::unordered_map<uint32_t, std::pair<glm::vec3, glm::vec3>> bounds;
  for (size_t t = 0; t < triangle_count; ++t) {
    glm::vec3 sum(0.0f);
    for (int k = 0; k < 3; ++k) sum += positions[indices[3 * t + k]];
    glm::vec3 c = sum / 3.0f;
    for (int a = 0; a < 3; ++a)
      if (!std::isfinite(c[a])) c[a] = 0.0f;
    centroids[t] = c;
    auto [it, fresh] = bounds.try_emplace(objects[t], c, c);
    if (!fresh) {
      it->second.first = glm::min(it->second.first, c);
      it->second.second = glm::max(it->second.second, c);
    }
  }
  for (size_t t = 0; t < triangle_count; ++t) {
    const auto& [lo, hi] = bounds[objects[t]];
    const glm::vec3 centre = 0.5f * (lo + hi);
    centroids[t] = centre + 1e-6f * (centroids[t] - centre);
  }
  return splitPoints(centroids, max_triangles);
}

}  // namespace

TriangleClusters clusterizeTriangles(std::span<const glm::vec3> positions,
                                     std::span<const uint32_t> indices, uint32_t max_triangles) {
  if (indices.size() % 3 != 0)
    throw std::invalid_argument("clusterizeTriangles: index count is not a multiple of 3");
  if (max_triangles == 0) throw std::invalid_argument("clusterizeTriangles: max_triangles is 0");
  size_t triangle_count = indices.size() / 3;

  std::vector<glm::vec3> centroids(triangle_count);
  for (size_t t = 0; t < triangle_count; ++t) {
    glm::vec3 sum(0.0f);
    for (int k = 0; k < 3; ++k) {
      uint32_t v = indices[3 * t + k];
      if (v >= positions.size())
        throw std::invalid_argument("clusterizeTriangles: index out of range");
      sum += positions[v];
    }
    glm::vec3 c = sum / 3.0f;
    // Non-finite centroids would break the comparator's strict weak ordering.
    for (int a = 0; a < 3; ++a)
      if (!std::isfinite(c[a])) c[a] = 0.0f;
    centroids[t] = c;
  }

  return splitPoints(centroids, max_triangles);
}

TriangleClusters clusterizeTrianglesByObject(std::span<const glm::vec3> positions,
                                             std::span<const uint32_t> indices,
                                             std::span<const uint32_t> triangle_objects,
                                             uint32_t max_triangles) {
  const size_t triangle_count = indices.size() / 3;
  if (triangle_objects.size() != triangle_count)
    throw std::invalid_argument("clusterizeTrianglesByObject: one object id per triangle needed");
  // Triangles per object, then the sets: each large object alone, every other triangle in one
  // shared set.
  std::unordered_map<uint32_t, uint32_t> per_object;
  for (uint32_t object : triangle_objects) ++per_object[object];
  const uint32_t large = std::max<uint32_t>(1, max_triangles / 2);
  const std::vector<std::vector<uint32_t>> sets = setsByLargeObject(
      triangle_count, [&](size_t t) { return triangle_objects[t]; },
      [&](uint32_t object) { return per_object[object] >= large; });
  if (sets.empty() || (sets.size() == 1 && per_object[triangle_objects[0]] >= large))
    return clusterizeTriangles(positions, indices, max_triangles);

  TriangleClusters result;
  result.triangles.reserve(triangle_count);
  result.offsets.push_back(0);
  std::vector<uint32_t> set_indices, set_objects;
  for (const std::vector<uint32_t>& set : sets) {
    set_indices.clear();
    set_objects.clear();
    for (uint32_t t : set) {
      set_indices.insert(set_indices.end(), indices.begin() + 3 * t, indices.begin() + 3 * t + 3);
      set_objects.push_back(triangle_objects[t]);
    }
    const bool small_objects = per_object[set_objects.front()] < large;
    TriangleClusters part =
        small_objects ? clusterizeSmallObjects(positions, set_indices, set_objects, max_triangles)
                      : clusterizeTriangles(positions, set_indices, max_triangles);
    for (size_t c = 0; c < part.clusterCount(); ++c) {
      for (uint32_t i = part.offsets[c]; i < part.offsets[c + 1]; ++i)
        result.triangles.push_back(set[part.triangles[i]]);
      result.offsets.push_back(uint32_t(result.triangles.size()));
    }
  }
  return result;
}

}  // namespace tw
