// Per-object run-time state and its hidden-object counts; see object_states.h.
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
  if ((before ^ flags) & kObjectHidden) counted_ = false;
}

void ObjectStates::setAll(uint32_t bits, bool on) {
  for (GpuObjectState& s : states_) s.flags = on ? s.flags | bits : s.flags & ~bits;
  changed_ = true;
  if (bits & kObjectHidden) counted_ = false;
}

void ObjectStates::setColor(uint32_t object, uint32_t rgba) {
  if (object >= states_.size()) return;
  states_[object].color_rgba = rgba;
  states_[object].flags |= kObjectRecolored;
  changed_ = true;
}

void ObjectStates::clearColor(uint32_t object) { set(object, kObjectRecolored, false); }

void ObjectStates::countHidden() const {
  if (counted_) return;
  visible_before_.resize(states_.size() + 1);
  uint32_t visible = 0;
  for (size_t i = 0; i < states_.size(); ++i) {
    visible_before_[i] = visible;
    visible += !(states_[i].flags & kObjectHidden);
  }
  visible_before_[states_.size()] = visible;
  counted_ = true;
}

uint32_t ObjectStates::hiddenCount() const {
  countHidden();
  return uint32_t(states_.size()) - visible_before_.back();
}

bool ObjectStates::allHidden(uint32_t first, uint32_t last) const {
  if (states_.empty() || first > last || first >= states_.size()) return false;
  countHidden();
  last = std::min<uint32_t>(last, uint32_t(states_.size() - 1));
  return visible_before_[last + 1] == visible_before_[first];
}

bool ObjectStates::anyHidden(uint32_t first, uint32_t last) const {
  if (states_.empty() || first > last || first >= states_.size()) return false;
  countHidden();
  last = std::min<uint32_t>(last, uint32_t(states_.size() - 1));
  return visible_before_[last + 1] - visible_before_[first] < last + 1 - first;
}

}  // namespace tw
