// Objects of a package found by what a reviewer names them by: a layer's name, database keys.
// What the render and view commands hide, isolate and select (object_states.h).
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <unordered_set>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "package_view.h"

namespace tw {

// The layer's index, or throws std::invalid_argument naming the layer and the package's layers.
uint32_t layerIndex(const PackageView& view, std::string_view name);

// Object indices (ascending) of the layer, or whose database key is one of `keys`.
std::vector<uint32_t> objectsOfLayer(const PackageView& view, uint32_t layer);
std::vector<uint32_t> objectsWithKeys(const PackageView& view,
                                      const std::unordered_set<std::string>& keys);
// Object indices (ascending) whose name or database key contains `text` (case-sensitive).
std::vector<uint32_t> objectsNamed(const PackageView& view, std::string_view text);

// World box of the objects' level-0 geometry; false (lo, hi untouched) when there are none.
bool objectsBounds(const PackageView& view, std::span<const uint32_t> objects, glm::dvec3& lo,
                   glm::dvec3& hi);

// Keys from `text`: the lines of that file when it names one (blank lines and # comments
// skipped), else a comma-separated list. Throws std::runtime_error for an empty result.
std::unordered_set<std::string> parseKeyList(const std::string& text);

}  // namespace tw
