// Vertices that lie within a tolerance of a vertex of another group without being the same
// vertex: the places where two parts of neighbouring groups touch without sharing vertices
// (CAD parts meeting with a gap below the package's quantization, a fitting's rim on its pipe's).
//
// Why: the package stores positions on a per-cluster grid, and `terawalk verify` (and the eye)
// joins vertices that decode within that grid's error. Such a pair is a border between the two
// groups as much as a shared vertex is, so the DAG builder holds these vertices like shared ones
// when it may move a group's rims (vertex clustering, dropping and sloppy simplification of free
// parts); otherwise one side moves and a crack opens against the other.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

namespace tw {

// How far apart two vertices may be and still decode as one: twice the package's quantization
// error at the grid a cluster of this extent is stored on (grid_weld.h, clusterPositionShift).
float packageGridTolerance(const glm::vec3& extent, double position_step_m);

// For each vertex in `vertices` (indices into positions, each once) whose group (owner[v]) is a
// single group, sets near[v] = 1 when a vertex of another group, or a shared one (owner
// `multi`), lies within `tolerance` on every axis. Shared vertices are not marked themselves
// (they are held anyway). tolerance <= 0: nothing is marked.
void markVerticesNearOtherGroups(std::span<const glm::vec3> positions,
                                 std::span<const uint32_t> vertices,
                                 std::span<const uint32_t> owner, uint32_t multi,
                                 float tolerance, std::vector<uint8_t>& near);

}  // namespace tw
