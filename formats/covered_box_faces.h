// Which faces of box instances are covered by a face of another box of the same layer: the two
// faces are the same rectangle and face each other, as where a deck's plates, one per bay, or a
// wall's panels meet.
//
// Why: such a face can only be reached by a ray that first crosses the other box, so the renderer
// may leave it out whenever the other box is drawn. A deck of twelve plates shows up to two side
// faces of each plate from outside; most of them meet the next plate. From outside the 50M plant
// the deck plates are a seventh of the frame's instances and, at up to six triangles each, the
// largest share of its triangles (docs/parametrics.md, "Faces between boxes").
// How: the six faces of every Box instance whose transform's columns are perpendicular are
// indexed by their centre's grid cell (kFaceToleranceM cells, sorted keys). Two faces pair when
// their centres agree within the tolerance, their normals are opposite, their edges agree as
// vectors (up to sign and order) and their objects share a layer; both are then covered.
// Positions are the package frame's (InstanceRecord::origin), where neighbouring boxes' faces
// agree to float rounding.
// Who runs it: the preprocessor, once, storing the faces as instance flags
// (pkg::kInstanceCoveredFaces; preprocess/parametrics/instance_flag_marking.h); `terawalk verify` again, to
// check them.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "package_format.h"

namespace tw {

// Faces whose centres and edges agree this closely (metres) count as one: float rounding of the
// package frame, far below a pixel of anything a walkthrough shows.
inline constexpr double kFaceToleranceM = 2e-4;

struct CoveredFaceStats {
  uint64_t boxes = 0;          // Box instances with perpendicular columns
  uint64_t covered_faces = 0;  // faces marked
  uint64_t boxes_with_covered_faces = 0;
};

// Per instance, a mask of its covered faces: bit f for face f of its canonical box, in the order
// -X, +X, -Y, +Y, -Z, +Z (0 for anything but a box). `object_layers` holds each object's layer;
// instances whose object is beyond it pair with nothing.
std::vector<uint8_t> findCoveredBoxFaces(std::span<const pkg::InstanceRecord> instances,
                                         std::span<const uint32_t> object_layers,
                                         CoveredFaceStats* stats = nullptr);

// A face mask as instance flags (pkg::kInstanceCoveredFaces), and back.
inline uint32_t coveredFaceInstanceFlags(uint8_t faces) {
  return (uint32_t(faces) & 0x3fu) << pkg::kInstanceCoveredFaceShift;
}
inline uint8_t coveredFaces(uint32_t instance_flags) {
  return uint8_t((instance_flags & pkg::kInstanceCoveredFaces) >> pkg::kInstanceCoveredFaceShift);
}

}  // namespace tw
