// Cuts an indexed triangle mesh into spatially compact clusters: the unit the LOD DAG groups and
// simplifies, and the unit the runtime draws, culls and pages.
//
// Why our own splitter rather than meshopt_buildMeshlets: meshoptimizer 0.18 caps a meshlet at
// 255 vertices and 512 triangles, while TeraWalk wants GL draws of up to 1024 triangles (bigger
// multi-draw entries are cheaper on llvmpipe). Recursive median bisection of the triangle
// centroids along the longest axis of their bounds gives balanced, compact clusters whatever the
// connectivity: thousands of disconnected CAD parts are gathered by proximity, where a
// connectivity-driven meshlet builder would emit one tiny meshlet per part. It is deterministic
// and costs O(n log(n / max_triangles)).
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

namespace tw {

// Clusters as ranges of one permutation of the input triangles.
struct TriangleClusters {
  std::vector<uint32_t> triangles;  // input triangle indices, cluster after cluster
  std::vector<uint32_t> offsets;    // cluster i is triangles[offsets[i], offsets[i + 1])

  size_t clusterCount() const { return offsets.empty() ? 0 : offsets.size() - 1; }
};

// Splits the triangles (three indices each into `positions`) into ceil(n / max_triangles)
// clusters whose sizes differ by at most one triangle, so every cluster holds at most
// max_triangles and, when there are more than max_triangles triangles, at least about half of it.
// Clusters come out in spatial (depth-first bisection) order. Zero triangles give zero clusters.
// Throws std::invalid_argument if indices.size() is not a multiple of 3, an index is out of
// range, or max_triangles is 0. Non-finite positions are tolerated (treated as the origin).
TriangleClusters clusterizeTriangles(std::span<const glm::vec3> positions,
                                     std::span<const uint32_t> indices, uint32_t max_triangles);

// As clusterizeTriangles, but no cluster mixes a large object (at least max_triangles / 2
// triangles here) with any other object: each large object is split alone, and the triangles of
// all smaller objects together. Why: a group's error is its worst part's, so a hull whose
// clusters also hold small parts inherits the error of dropping them and stays fine far longer
// than its own surface needs. Sizes differ by at most one triangle within each of those sets.
// Same errors as clusterizeTriangles, and std::invalid_argument when triangle_objects does not
// hold one id per triangle.
TriangleClusters clusterizeTrianglesByObject(std::span<const glm::vec3> positions,
                                             std::span<const uint32_t> indices,
                                             std::span<const uint32_t> triangle_objects,
                                             uint32_t max_triangles);

}  // namespace tw
