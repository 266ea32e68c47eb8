// A change set: the edits made in a review (move, rotate, scale, hide, colour, a comment on an
// object), in a documented JSON file next to the package (model.twk: model.changes.json), so
// they can be reloaded with the package and carried back to the scene (`terawalk changes apply`).
//
//   {"terawalk_changes": 1,
//    "changes": [
//      {"kind": "move", "key": "P-101", "author": "ana", "date": "2026-12-06T14:00:00Z",
//       "old_pivot": [x, y, z], "new_pivot": [x, y, z],
//       "transform": [16 numbers, column-major 4x4, world to world]},
//      {"kind": "hide", "key": "...", "hidden": true, ...},
//      {"kind": "colour", "key": "...", "rgba": "FF8000FF", ...},
//      {"kind": "comment", "key": "...", "text": "...", ...}]}
//
// An object is named by its database key (an IFC GlobalId for IFC models), else its name. A
// move's transform maps the object's world positions before the move to after it (rotation and
// scale about its pivot, then the translation), in double precision; the pivots are where the
// object's centre was and is. Moves of one object compose in order.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <glm/glm.hpp>

namespace tw {

struct Change {
  enum class Kind { Move, Hide, Colour, Comment };
  Kind kind = Kind::Move;
  std::string key;
  std::string author, date;
  glm::dmat4 transform{1.0};  // Move
  glm::dvec3 old_pivot{0.0}, new_pivot{0.0};  // Move
  bool hidden = true;          // Hide
  uint32_t rgba = 0xffffffffu;  // Colour, 0xAABBGGRR as the renderer takes it
  std::string text;            // Comment
};

// A move about `pivot` (world): scale, then rotate (radians about the unit axis), then
// translate. The transform maps world positions before to after.
glm::dmat4 moveTransform(const glm::dvec3& pivot, const glm::dvec3& translation,
                         const glm::dvec3& rotation_axis = {0.0, 0.0, 1.0}, double angle_rad = 0.0,
                         double scale = 1.0);

class ChangeSet {
 public:
  const std::vector<Change>& changes() const { return changes_; }
  bool empty() const { return changes_.empty(); }

  // Adds a change; what was undone before it is gone (as in any editor).
  void add(Change change);
  // Takes back the last change, or puts the last one taken back again; false when there is none.
  bool undo();
  bool redo();
  size_t undoable() const { return changes_.size(); }
  size_t redoable() const { return undone_.size(); }

  // Every move of `key`, composed in order (identity when none).
  glm::dmat4 placement(const std::string& key) const;
  // The keys moved, each once, in the order first moved.
  std::vector<std::string> movedKeys() const;

 private:
  std::vector<Change> changes_;
  std::vector<Change> undone_;
};

std::filesystem::path changeSetPathFor(const std::filesystem::path& package);

// Throws std::runtime_error naming the file and what is wrong (not JSON, a field missing or of
// the wrong type, a transform that is not 16 finite numbers, an unknown kind). A missing file is
// an empty change set.
ChangeSet readChangeSet(const std::filesystem::path& path);
// Replaces the file atomically (a temporary file renamed over it).
void writeChangeSet(const std::filesystem::path& path, const ChangeSet& changes);

}  // namespace tw
