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

namespace tw {

// How far apart two vertices may be and still decode as one: twice the package's quantization
// error at the grid a cluster of this extent is stored on (grid_weld.h, clusterPositionShift).
float packageGridTolerance(const glm::vec3& extent, double position_step_m);

// A hashed grid of tolerance-sized cells over a set of vertices.
class NearVertexIndex {
 public:
  NearVertexIndex() = default;
  // `vertices`: indices into positions, each once. Non-finite positions are left out.
  // tolerance <= 0 gives an index that marks nothing.
  NearVertexIndex(std::span<const glm::vec3> positions, std::span<const uint32_t> vertices,
                  float tolerance);

  float tolerance() const { return tolerance_; }

  // For each indexed vertex whose group (owner[v]) is a single group, sets near[v] = 1 when a
  // vertex of another group, or a shared one (owner `multi`), lies within the tolerance on every
  // axis. Shared vertices are not marked themselves (they are held anyway). Runs on TBB.
  void markNearOtherGroups(std::span<const glm::vec3> positions, std::span<const uint32_t> owner,
                           uint32_t multi, std::vector<uint8_t>& near) const;

 private:
  struct Entry {
    int64_t x, y, z;
    uint32_t vertex;
    int8_t side[3];  // per axis, the neighbouring cell a vertex within tolerance may lie in
    bool operator<(const Entry& o) const {
      return x != o.x ? x < o.x : y != o.y ? y < o.y : z != o.z ? z < o.z : vertex < o.vertex;
    }
  };
  size_t slotOf(int64_t x, int64_t y, int64_t z) const;
  // Calls visit(w) for each other indexed vertex w within the tolerance of entry e's vertex,
  // until visit returns false.
  template <typename Visit>
  void forEachNear(const Entry& e, std::span<const glm::vec3> positions, Visit&& visit) const;
  void listPairs(std::span<const glm::vec3> positions);

  float tolerance_ = 0.0f;
  std::vector<Entry> entries_;   // sorted by cell, so a cell's vertices are one run
  std::vector<uint32_t> first_;  // open addressing: a cell's first entry, or kEmpty
  // Every (vertex, vertex within the tolerance) pair, both ways round. Few on real models (the
  // tolerance is below the quantization step); when they would be many (thousands of vertices
  // on one spot) the list is left empty and each marking searches the cells again.
  std::vector<std::pair<uint32_t, uint32_t>> pairs_;
  bool search_each_time_ = false;
};

// One-shot form of the index: build it and mark.
void markVerticesNearOtherGroups(std::span<const glm::vec3> positions,
                                 std::span<const uint32_t> vertices,
                                 std::span<const uint32_t> owner, uint32_t multi,
                                 float tolerance, std::vector<uint8_t>& near);

}  // namespace tw
