// Indexed triangles welded by exact position, and the directed use of each welded edge: the
// common first step of the topology checks (watertight_check, patch_mesh_check), which judge a
// surface by its shape, not by how its vertices were split for normals.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <unordered_map>
#include <vector>

#include <glm/glm.hpp>

#include "scene.h"

namespace tw {

struct WeldedTriangles {
  std::vector<glm::vec3> points;                   // distinct positions (bitwise, -0 == +0) used
                                                   // by faces, in order of first use
  std::vector<std::array<uint32_t, 3>> triangles;  // indices into points
  std::vector<uint32_t> sources;  // for each of `triangles`, its index in the mesh (indices / 3)
  uint64_t skipped = 0;  // triangles with an index out of range or a repeated welded vertex
};

// Welds `mesh`'s positions by exact bits (formats/position_key.h); normals are ignored.
WeldedTriangles weldExactly(const TriangleMesh& mesh);

// How often an undirected edge is used from its lower to its higher welded index (forward) and
// the other way (backward); keyed by (lower << 32) | higher.
struct EdgeUse {
  uint32_t forward = 0, backward = 0;
};
std::unordered_map<uint64_t, EdgeUse> countEdgeUses(
    std::span<const std::array<uint32_t, 3>> triangles);

}  // namespace tw
