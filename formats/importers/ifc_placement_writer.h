// A copy of an IFC file with moved products placed anew: the way a review's moves go back to an
// IFC model (`terawalk changes apply model.ifc changes.json -o moved.ifc`).
//
// Each product whose GlobalId a move names gets a new, absolute IfcLocalPlacement (no
// PlacementRelTo) whose IfcAxis2Placement3D is the move composed with the product's old world
// placement (ifc_frames.h), in the file's length unit; the new instances are appended to the DATA
// section with ids past the file's largest, and the product's ObjectPlacement argument is
// rewritten to name the new placement. Every other byte is copied as it was. Products placed
// relative to a moved one (their PlacementRelTo chains) move with it, as in the CAD tool. A move
// with a scale has no IFC placement (IfcAxis2Placement3D is rigid): it is refused, naming the
// product.
#pragma once

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include <glm/glm.hpp>

namespace tw {

struct IfcMoveReport {
  size_t moved = 0;                  // products given a new placement
  std::vector<std::string> missing;  // GlobalIds no product of the file has
};

// `moves`: GlobalId and world move (metres, Z up as the file is). Throws FormatError for a file
// that does not read, std::invalid_argument for a move that is not rigid, std::runtime_error
// naming `out` when it cannot be written (written to a temporary file renamed over it).
IfcMoveReport writeMovedIfc(const std::filesystem::path& in, const std::filesystem::path& out,
                            const std::vector<std::pair<std::string, glm::dmat4>>& moves);

}  // namespace tw
