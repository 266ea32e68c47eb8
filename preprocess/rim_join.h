// Rims of one group that almost meet, joined before the group is simplified.
//
// Why: two parts' rims a little open (too far apart for the full-resolution weld, within the
// coarse grid's error), or a seam an earlier level left a hair open, are one place in the
// package, which decodes both onto one grid point, and in `terawalk verify` and the eye. Left as
// two sets of vertices, vertex clustering may move one side and not the other and open a gap
// the fine level did not show (docs/preprocess.md, "Rims that almost meet inside one group").
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

namespace tw {

// Joins the rim vertices of `tris` (on an edge not used exactly twice) marked in `candidate`
// (one flag per position) that lie within `tolerance` of each other on every axis onto the
// smallest of them, and drops the triangles that collapse with their entries of `ids` (one per
// triangle). Returns the farthest a point of the surface moved (0 when nothing was joined).
float joinNearRims(std::span<const glm::vec3> positions, std::vector<uint32_t>& tris,
                   std::vector<uint32_t>& ids, std::span<const uint8_t> candidate,
                   float tolerance);

}  // namespace tw
