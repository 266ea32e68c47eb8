// Which clusters of a DAG level are simplified together: groups of about group_size neighbouring
// clusters, from METIS_PartGraphKway on the cluster adjacency graph (edge weight = vertices two
// clusters share, a proxy for their border's length; vertex weight = triangles), plus weak edges
// between clusters that neighbour each other in Morton order of their centres, so disconnected
// CAD parts still group by proximity. Kept apart from the DAG builder (cluster_dag.h) because it
// is the one place that talks to METIS.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

namespace tw {

// cluster_tris[c]: cluster c's triangles as vertex indices (< vertex_count), three per triangle;
// centers[c]: its centre. A level of <= group_size clusters is one group (METIS is not called);
// if METIS fails, runs of group_size clusters in Morton order. Members of a group are in
// ascending order and groups in part order; deterministic (METIS runs serially, fixed seed).
std::vector<std::vector<uint32_t>> groupClusters(
    std::span<const std::span<const uint32_t>> cluster_tris, std::span<const glm::vec3> centers,
    uint32_t group_size, size_t vertex_count);

// As groupClusters, but a large object's clusters are grouped among themselves: the clusters
// holding only object O form a set of their own when they hold at least large_triangles
// triangles together, and every other cluster goes to one shared set; each set is grouped
// apart (sets in order of their first cluster). Why: a group's error is its worst part's, so a
// hull grouped with small parts takes the error of dropping or merging them and is kept fine
// far longer than its surface needs (docs/preprocess.md, "Large objects apart"). Once an object
// has shrunk below large_triangles it joins the shared set, which is how it merges with its
// neighbours toward the root. cluster_ids[c]: cluster c's object id per triangle.
std::vector<std::vector<uint32_t>> groupClustersByObject(
    std::span<const std::span<const uint32_t>> cluster_tris,
    std::span<const std::span<const uint32_t>> cluster_ids, std::span<const glm::vec3> centers,
    uint32_t group_size, uint32_t large_triangles, size_t vertex_count);

}  // namespace tw
