// Rows of equal boxes laid end to end, each object the next one's predecessor: a deck's plates
// along a frame line, a wall's panels; and rows of equal extrusions end to end, a frame line's
// beams. The runtime draws a row as one long box (or, thin, as one band) whose fragments tell
// which member they fall on, so the pixels and ids are those of the members drawn one by one, in
// a fraction of the triangles.
//
// Why: from outside the 50M plant the deck plates were 7,192 boxes a frame, ten times the 5M
// plant's, each a few pixels across and two triangles at least; a row of four is two triangles
// for its top (docs/parametrics.md, "Rows of boxes").
// What makes a row: Box instances of parametric clusters with the same half sizes, the same
// transform columns and the same flags apart from their covered faces; member k + 1's object is
// member k's plus one, and its centre lies one box length along a canonical axis from member
// k's, the face between them marked covered on both sides (covered_box_faces.h: the same layer,
// the same rectangle). Extrusions: the same transform columns, height, flags and profile point
// for point, and member k + 1 starts where member k ends. Positions agree within
// kFaceToleranceM. The members may lie in other clusters than the first: the first member's
// cluster draws the row when it is among the frame's clusters, and a member whose row's cluster
// is not draws itself.
// Who runs it: ParametricInstanceMeshes, once, when it opens a package that marks covered faces.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include <glm/vec2.hpp>

#include "package_format.h"

namespace tw {

// The most members a row has (a longer chain is split): the count fits a byte.
inline constexpr uint32_t kMaxBoxRowMembers = 255;

struct BoxRow {
  uint32_t cluster = 0;             // the first member's cluster, which draws the row
  uint8_t axis = 0;                 // the canonical axis the members follow each other along
  std::vector<uint32_t> instances;  // the members' instance indices, first to last (at least 2)
  std::vector<uint32_t> member_clusters;  // and their clusters
  // The row as one instance: the first member's record made `instances.size()` times as long
  // along `axis`. A box's is centred on the row, its covered faces the row's own (the first
  // member's start face, the last one's end face, and a side face where every member's is
  // covered); an extrusion's starts where the first member does.
  pkg::InstanceRecord record{};
};

// The rows among the instances of the parametric clusters of `clusters` (profiles in
// `profile_points`), ordered by their first member; each instance is in at most one. Clusters
// whose instance range lies outside `instances`, and extrusions whose profile lies outside
// `profile_points`, are passed over.
std::vector<BoxRow> findBoxRows(std::span<const pkg::InstanceRecord> instances,
                                std::span<const pkg::ClusterRecord> clusters,
                                std::span<const glm::vec2> profile_points);

}  // namespace tw
