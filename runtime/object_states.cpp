// Per-object run-time state and its counts by look; see object_states.h.
#include "object_states.h"

#include <algorithm>

namespace tw {

ObjectStates::ObjectStates(size_t object_count) : states_(object_count) {}

void ObjectStates::set(uint32_t object, uint32_t bits, bool on) {
  if (object >= states_.size()) return;
  uint32_t& flags = states_[object].flags;
  const uint32_t before = flags;
  flags = on ? flags | bits : flags & ~bits;
  if (flags == before) return;
  changed_ = true;
  counted_ = false;
}

void ObjectStates::setAll(uint32_t bits, bool on) {
  for (GpuObjectState& s : states_) s.flags = on ? s.flags | bits : s.flags & ~bits;
  changed_ = true;
  counted_ = false;
}

void ObjectStates::setColor(uint32_t object, uint32_t rgba) {
  if (object >= states_.size()) return;
  states_[object].color_rgba = rgba;
  states_[object].flags |= kObjectRecolored;
  changed_ = true;
}

void ObjectStates::clearColor(uint32_t object) { set(object, kObjectRecolored, false); }

void ObjectStates::countLooks() const {
  if (counted_) return;
  opaque_before_.resize(states_.size() + 1);
  ghosted_before_.resize(states_.size() + 1);
  uint32_t opaque = 0, ghosted = 0;
  selected_shown_ = 0;
  for (size_t i = 0; i < states_.size(); ++i) {
    opaque_before_[i] = opaque;
    ghosted_before_[i] = ghosted;
    const ObjectLook look = objectLook(states_[i].flags);
    opaque += look == ObjectLook::Opaque;
    ghosted += look == ObjectLook::Ghosted;
    selected_shown_ += look != ObjectLook::Hidden && (states_[i].flags & kObjectSelected);
  }
  opaque_before_[states_.size()] = opaque;
  ghosted_before_[states_.size()] = ghosted;
  counted_ = true;
}

uint32_t ObjectStates::countIn(const std::vector<uint32_t>& before, uint32_t first,
                               uint32_t last, uint32_t* range_size) const {
  if (range_size) *range_size = 0;
  if (states_.empty() || first > last || first >= states_.size()) return 0;
  last = std::min<uint32_t>(last, uint32_t(states_.size() - 1));
  if (range_size) *range_size = last + 1 - first;
  return before[last + 1] - before[first];
}

bool ObjectStates::anyOpaque(uint32_t first, uint32_t last) const {
  countLooks();
  return countIn(opaque_before_, first, last) > 0;
}

bool ObjectStates::allOpaque(uint32_t first, uint32_t last) const {
  countLooks();
  uint32_t range = 0;
  const uint32_t opaque = countIn(opaque_before_, first, last, &range);
  return opaque == range;
}

bool ObjectStates::anyGhosted(uint32_t first, uint32_t last) const {
  countLooks();
  return countIn(ghosted_before_, first, last) > 0;
}

bool ObjectStates::everyObjectOpaque() const {
  countLooks();
  return opaque_before_.back() == states_.size();
}

bool ObjectStates::anyGhosted() const {
  countLooks();
  return ghosted_before_.back() > 0;
}

bool ObjectStates::anySelected() const {
  countLooks();
  return selected_shown_ > 0;
}

}  // namespace tw
