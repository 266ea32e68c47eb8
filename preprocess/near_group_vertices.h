// Vertices that lie within a tolerance of a vertex of another group without being the same
// vertex: the places where two parts of neighbouring groups touch without sharing vertices
// (CAD parts meeting with a gap below the package's quantization, a fitting's rim on its pipe's).
//
// Why: the package stores positions on a per-cluster grid, and `terawalk verify` (and the eye)
// joins vertices that decode within that grid's error. Such a pair is a border between the two
// groups as much as a shared vertex is, so the DAG builder holds these vertices like shared ones
// when it may move a group's rims (vertex clustering, dropping and sloppy simplification of free
// parts); otherwise one side moves and a crack opens against the other.
//
// The DAG builder retries a level with larger groups when it does not shrink enough; the
// vertices and the tolerance stay the same, only the groups change. So the spatial index is a
// value built once per level and tolerance, and each attempt only marks against its owners.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "vertex_cell_grid.h"

namespace tw {

// How far apart two vertices may be and still decode as one: twice the package's quantization
// error at the grid a cluster of this extent is stored on (grid_weld.h, clusterPositionShift).
float packageGridTolerance(const glm::vec3& extent, double position_step_m);

// The vertex pairs within a tolerance over a set of vertices, kept for the attempts of a level.
class NearVertexIndex {
 public:
  NearVertexIndex() = default;
  // `vertices`: indices into positions, each once. Non-finite positions are left out.
  // tolerance <= 0 gives an index that marks nothing. Positions must outlive the index.
  NearVertexIndex(std::span<const glm::vec3> positions, std::span<const uint32_t> vertices,
                  float tolerance);

  float tolerance() const { return tolerance_; }
  // Whether vertex v (an index into positions) has another indexed vertex within the tolerance.
  bool hasNeighbour(uint32_t v) const { return v < near_any_.size() && near_any_[v] != 0; }

  // For each indexed vertex whose group (owner[v]) is a single group, sets near[v] = 1 when a
  // vertex of another group, or a shared one (owner `multi`), lies within the tolerance on every
  // axis. Shared vertices are not marked themselves (they are held anyway).
  void markNearOtherGroups(std::span<const glm::vec3> positions, std::span<const uint32_t> owner,
                           uint32_t multi, std::vector<uint8_t>& near) const;

 private:
  float tolerance_ = 0.0f;
  VertexCellGrid grid_;
  // Every (vertex, vertex within the tolerance) pair, both ways round. Few on real models (the
  // tolerance is below the quantization step); when they would be many (thousands of vertices
  // on one spot) the list is left empty and each marking searches the grid again.
  std::vector<std::pair<uint32_t, uint32_t>> pairs_;
  bool search_each_time_ = false;
  std::vector<uint8_t> near_any_;  // per vertex of positions: has a neighbour within tolerance
};

// One-shot form of the index: build it and mark.
void markVerticesNearOtherGroups(std::span<const glm::vec3> positions,
                                 std::span<const uint32_t> vertices,
                                 std::span<const uint32_t> owner, uint32_t multi,
                                 float tolerance, std::vector<uint8_t>& near);

}  // namespace tw
