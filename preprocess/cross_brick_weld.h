// Rim vertices of different bricks that lie closer than the package's base step, moved onto one
// position before the bricks' DAGs are built.
//
// Why: CAD tessellators write the two ends of parts that abut (a pipe and its elbow) with their
// own copies of the shared ring, and those copies differ by float noise (one ulp of the 10M
// plant's coordinates). Inside a brick the package-grid weld (grid_weld.h) joins them, so the
// parts become one surface. Across a brick border nothing did: the ring's edges were not
// bit-identical, so they were no seam and were not locked; each brick then snapped its copy to its
// own grid, and the package's snapping later made some copies coincide and not others. Parts
// glued at some vertices and split at others look like a new hole to `terawalk verify` (a bricked
// 10M plant failed so at level 4) and can open one in the runtime. Welding the copies first makes
// them bit-identical, so the ring becomes an ordinary seam: locked in both bricks, welded exactly
// by the merge of their roots.
//
// The rule is the grid weld's first step with a tolerance that also covers the input's float
// noise (the preprocessor passes the base step plus two ulps of the largest coordinate the
// readers stored: on the 100M plant, copies one ulp apart at x = 288.75 m lie two base steps
// apart): a position within the tolerance on every axis of an earlier position of another brick
// (earlier in position order) takes that position; a position that moved is never a target, so
// moves are at most the tolerance and never chain. Deterministic: the result depends only on the
// set of (position, brick) candidates and the tolerance.
#pragma once

#include <cstdint>
#include <span>
#include <unordered_map>
#include <vector>

#include <glm/glm.hpp>

#include "byte_packing.h"
#include "position_key.h"

namespace tw {

class CrossBrickWeld {
 public:
  struct Candidate {
    glm::vec3 position;
    uint32_t brick;
  };

  CrossBrickWeld() = default;
  // `candidates`: rim vertices of every brick (repeats allowed); `tolerance` > 0, per axis.
  // Non-finite positions are left out.
  static CrossBrickWeld build(std::vector<Candidate> candidates, float tolerance);

  // Moves every position of a brick that the weld moves.
  void apply(std::span<glm::vec3> positions) const;
  // The bricks holding a moved position, ascending.
  const std::vector<uint32_t>& bricksWithMoves() const { return bricks_; }
  size_t movedPositions() const { return moved_.size(); }

  // Into a blob and back (the plan of a scale-out run keeps it for the brick jobs); the moves in
  // position order, so equal welds give equal bytes.
  void write(ByteWriter& out) const;
  static CrossBrickWeld read(ByteReader& in);

 private:
  std::unordered_map<PositionKey, glm::vec3, PositionHash> moved_;
  std::vector<uint32_t> bricks_;
};

}  // namespace tw
