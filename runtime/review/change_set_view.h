// A change set shown on a package: its moves as the moved-objects pass's meshes (each moved
// object's full-resolution geometry and its move, in the package frame), its hides and colours
// as object states. What `render --changes` and the viewer draw.
#pragma once

#include <string>
#include <vector>

#include "change_set.h"
#include "moved_objects_pass.h"
#include "object_distance.h"
#include "object_states.h"
#include "package_view.h"

namespace tw {

// Objects the change set's key names: by database key, else by name. Empty when none has it.
std::vector<uint32_t> objectsOfChangeKey(const PackageView& view, const std::string& key);

// The full-resolution geometry of `objects` for the moved-objects pass, one mesh each, with no
// move (parametrics tessellated at a thousandth of the object's size, at least a millimetre).
std::vector<MovedMesh> objectMeshes(const PackageView& view, const std::vector<uint32_t>& objects);

// The world move `world` as a move of the package frame (for MovedMesh::move).
glm::dmat4 packageMove(const PackageView& view, const glm::dmat4& world);

// The meshes of every moved object of `changes` (parametrics tessellated at a thousandth of the
// object's size, at least a millimetre), for Walkthrough::setMovedObjects. Throws
// std::runtime_error naming a key no object has.
std::vector<MovedMesh> movedMeshes(const ChangeSet& changes, const PackageView& view);

// Hides and colours of `changes` set on `states` (later changes win). Throws as movedMeshes.
void applyChangeStates(const ChangeSet& changes, const PackageView& view, ObjectStates& states);

// `shape` (package frame, measureShape) carried through the world move `world`: what a moved
// object is measured on.
MeasureShape movedShape(const PackageView& view, const MeasureShape& shape, const glm::dmat4& world);

// The world box of objects' level-0 geometry through a move (for pivots). False when none.
bool movedBounds(const PackageView& view, const std::vector<uint32_t>& objects,
                 const glm::dmat4& move, glm::dvec3& lo, glm::dvec3& hi);

}  // namespace tw
