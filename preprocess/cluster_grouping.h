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

}  // namespace tw
