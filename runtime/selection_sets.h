// Named selection sets, saved in a small JSON file next to the package (model.twk:
// model.sets.json), so a reviewer's "all fire-water valves" or "hull hidden, piping X-rayed" can
// be restored in a later session, or handed to a colleague with the package.
//
// A set holds either a selection or a visibility state (the hidden and the X-rayed objects).
// Objects are stored by their scene ids (ObjectRecord::id), which a rebuild of the same scene
// keeps, not by their index in one package:
//
//   {"terawalk_selection_sets": 1,
//    "sets": [{"name": "fire valves", "kind": "selection", "selected": [812, 813]},
//             {"name": "no hull", "kind": "visibility", "hidden": [1], "xray": []}]}
//
// A file that cannot be read is reported (file and reason) and never overwritten: saving into
// it fails until it is fixed or moved away, so nothing written before is lost.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace tw {

struct SelectionSet {
  enum class Kind { Selection, Visibility };
  std::string name;
  Kind kind = Kind::Selection;
  std::vector<uint32_t> selected;  // scene object ids (Selection)
  std::vector<uint32_t> hidden;    // (Visibility)
  std::vector<uint32_t> xray;      // (Visibility)
};

// The sets file of a package: its path with the extension replaced by ".sets.json".
std::filesystem::path selectionSetsPathFor(const std::filesystem::path& package);

// Reads the file; a missing file is no sets. Throws std::runtime_error naming the file and what
// is wrong (not JSON, a field of the wrong type, an unknown kind).
std::vector<SelectionSet> readSelectionSets(const std::filesystem::path& path);

// Writes all the sets, replacing the file atomically (a temporary file renamed over it).
// Throws std::runtime_error when it cannot.
void writeSelectionSets(const std::filesystem::path& path, const std::vector<SelectionSet>& sets);

}  // namespace tw
