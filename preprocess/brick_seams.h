// The seams between spatial bricks: the edges that are open (used by one triangle) in two bricks
// at once, because bricking sent the two triangles of an edge to different bricks.
//
// Why: each brick's LOD DAG must keep its seams exactly (DagOptions::lock_open_boundaries), or
// neighbouring bricks crack. But CAD models are full of open edges of their own (pipes without
// caps, sheets, plates), and locking those too pins every such part for good: the DAG can then
// neither simplify nor drop them, and its levels stall (a 10M-triangle tessellated plant in four
// bricks shrank 4.19M -> 3.78M -> 3.68M -> 3.66M). Locking only the true seams leaves the model's
// own open parts free, as in a single-brick build.
//
// Edges are compared by the exact bits of their two end positions (the DAG welds the same way),
// through a 64-bit hash of those bits: a collision (about one in 10^19 per pair) can only lock
// an edge that needed no lock, never miss a seam. Finding the set reads every brick once and
// keeps only edges lying inside another brick's bounds (8 bytes each): seams are among them, and
// the model's own edges far from brick borders are not. Brick bounds overlap more than one
// would think (a long plate or pipe stretches its brick's bounds), so on the 100M plant these
// are a good share of all edges: the hash keeps them at a third of the keys' size. An edge in two bricks is locked in both,
// whatever its count in each (a non-manifold edge used three times in one brick and once in the
// other is still where they meet).
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "cross_brick_weld.h"
#include "progress.h"
#include "scene_bricking.h"

namespace tw {

// An undirected edge by the float bits of its end positions, smaller end first.
using SeamEdgeKey = std::array<uint32_t, 6>;
SeamEdgeKey seamEdgeKey(const glm::vec3& a, const glm::vec3& b);
uint64_t seamEdgeHash(const SeamEdgeKey& key);

// Sorted, unique open-edge keys of one triangle soup (after exact welding; degenerate and
// non-finite triangles are skipped, as the DAG skips them).
std::vector<SeamEdgeKey> openEdgeKeys(std::span<const glm::vec3> positions,
                                      std::span<const uint32_t> indices);

// Sorted, unique keys of every edge of a triangle soup (same skipping rules).
std::vector<SeamEdgeKey> edgeKeys(std::span<const glm::vec3> positions,
                                  std::span<const uint32_t> indices);

class BrickSeams {
 public:
  // The edges found in at least two bricks (the brick DAGs consult it for their open edges),
  // after welding the rim vertices of different bricks that lie within `weld_tolerance` of each
  // other on every axis (cross_brick_weld.h; 0: no weld). Reads every brick whose bounds overlap
  // another's once (loadBrick), and the bricks the weld moves a second time; with one brick
  // there are no seams and nothing is read. A brick's DAG must be built from
  // weldAcrossBricks(mesh).
  static BrickSeams find(const BrickedScene& scene, float weld_tolerance,
                         Progress* progress = nullptr);
  // From per-brick unique edge lists directly (tests).
  static BrickSeams fromOpenEdges(std::vector<std::vector<SeamEdgeKey>> per_brick);

  bool contains(const glm::vec3& a, const glm::vec3& b) const;
  size_t size() const { return hashes_.size(); }
  // A brick's positions as the seams were found on: near-coincident rims of different bricks
  // made one.
  void weldAcrossBricks(std::span<glm::vec3> positions) const { weld_.apply(positions); }
  size_t weldedPositions() const { return weld_.movedPositions(); }

  // Into a blob and back: the plan step finds the seams once and every brick job reads them.
  // Reading throws FormatError naming `source` for a short or damaged blob.
  std::vector<uint8_t> serialize() const;
  static BrickSeams deserialize(std::span<const uint8_t> bytes, const std::string& source);

 private:
  static BrickSeams fromSortedHashes(const std::vector<std::vector<uint64_t>>& per_brick);

  std::vector<uint64_t> hashes_;  // of the seam edges' keys, sorted, unique
  CrossBrickWeld weld_;
};

}  // namespace tw
