// Splitting a DAG level's items (triangles, or clusters) into the sets that are clustered or
// grouped apart: one set per large object, one shared set for everything else.
//
// Why: a group's error is its worst part's, so a large surface that shares clusters or groups
// with small parts takes the error of dropping or merging them (docs/preprocess.md, "Large
// objects apart"). clusterize and cluster_grouping both keep large objects apart the same way.
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <unordered_map>
#include <vector>

namespace tw {

constexpr uint32_t kNoObject = std::numeric_limits<uint32_t>::max();

// Items 0..count-1 into sets: the items whose owner(item) is an object that is_large(object)
// accepts form one set per object; the rest (owner kNoObject, or a small object) one shared set.
// Sets come in the order of their first item, items in ascending order: deterministic.
template <typename Owner, typename IsLarge>
std::vector<std::vector<uint32_t>> setsByLargeObject(size_t count, Owner owner, IsLarge is_large) {
  std::unordered_map<uint32_t, uint32_t> set_of_object;
  std::vector<std::vector<uint32_t>> sets;
  uint32_t shared_set = kNoObject;
  for (size_t item = 0; item < count; ++item) {
    const uint32_t object = owner(item);
    uint32_t set;
    if (object != kNoObject && is_large(object)) {
      auto [it, fresh] = set_of_object.try_emplace(object, uint32_t(sets.size()));
      if (fresh) sets.emplace_back();
      set = it->second;
    } else {
      if (shared_set == kNoObject) {
        shared_set = uint32_t(sets.size());
        sets.emplace_back();
      }
      set = shared_set;
    }
    sets[set].push_back(uint32_t(item));
  }
  return sets;
}

}  // namespace tw
