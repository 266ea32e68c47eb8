// Global vertex index -> index in the part being built, for readers that hand a large mesh to
// the sink in parts (each part carries only the vertices it uses).
//
// Why: a table with one slot per global vertex costs 4 to 8 bytes per vertex of the whole file
// (400 MB for the 100M-triangle plant PLY) when a part only ever holds a few hundred thousand.
// This is an open-addressing hash sized for one part, emptied slot by slot when the part ends.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace tw {

class PartVertexMap {
 public:
  static constexpr uint32_t kNone = 0xffffffffu;

  // Room for at most max_vertices distinct vertices per part (the table stays under half full).
  explicit PartVertexMap(size_t max_vertices = 0) {
    size_t slots = 16;
    while (slots < 2 * max_vertices) slots *= 2;
    slots_.assign(slots, Slot{kNone, 0});
  }

  // The local index of global vertex g: found, or made by make() (called once per new vertex)
  // and remembered. g must not be kNone.
  template <typename Make>
  uint32_t localOf(uint32_t g, Make&& make) {
    size_t at = slotOf(g);
    if (slots_[at].global != kNone) return slots_[at].local;
    if (2 * (used_.size() + 1) > slots_.size()) {
      grow();
      at = slotOf(g);
    }
    const uint32_t local = make();
    slots_[at] = Slot{g, local};
    used_.push_back(at);
    return local;
  }

  // The local index of g, or kNone.
  uint32_t find(uint32_t g) const {
    const Slot& slot = slots_[slotOf(g)];
    return slot.global == kNone ? kNone : slot.local;
  }

  // Forgets every vertex of the part (all slots emptied together: no probe chain breaks).
  void clear() {
    for (size_t at : used_) slots_[at].global = kNone;
    used_.clear();
  }

 private:
  struct Slot {
    uint32_t global, local;
  };

  size_t slotOf(uint32_t g) const {
    const size_t mask = slots_.size() - 1;
    size_t i = (size_t{g} * 0x9E3779B1u) & mask;
    while (slots_[i].global != kNone && slots_[i].global != g) i = (i + 1) & mask;
    return i;
  }

  // Doubles the table when a part holds more vertices than it was sized for.
  void grow() {
    std::vector<Slot> old;
    old.swap(slots_);
    slots_.assign(old.size() * 2, Slot{kNone, 0});
    used_.clear();
    for (const Slot& s : old)
      if (s.global != kNone) {
        const size_t at = slotOf(s.global);
        slots_[at] = s;
        used_.push_back(at);
      }
  }

  std::vector<Slot> slots_;
  std::vector<size_t> used_;  // the slots holding this part's vertices
};

}  // namespace tw
