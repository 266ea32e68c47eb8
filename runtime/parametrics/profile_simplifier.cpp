// Ramer-Douglas-Peucker profile simplification (profile_simplifier.h).
#include "profile_simplifier.h"

#include <algorithm>

#include <glm/geometric.hpp>

namespace tw {

// Marks in keep_ the points of profile[first..last] (indices modulo its size) that lie farther
// than `tolerance` from the chord of their span, splitting spans until none does.
void ProfileSimplifier::mark(std::span<const glm::vec2> profile, size_t first, size_t last,
                             float tolerance) {
  const size_t n = profile.size();
  spans_.assign(1, {first, last});
  while (!spans_.empty()) {
    const auto [a_index, b_index] = spans_.back();
    spans_.pop_back();
    if (b_index <= a_index + 1) continue;
    const glm::vec2 a = profile[a_index % n], ab = profile[b_index % n] - a;
    const float length2 = glm::dot(ab, ab);
    size_t farthest = a_index;
    float worst = -1.0f;
    for (size_t k = a_index + 1; k < b_index; ++k) {
      const glm::vec2 ap = profile[k % n] - a;
      const float t = length2 > 0.0f ? std::clamp(glm::dot(ap, ab) / length2, 0.0f, 1.0f) : 0.0f;
      const float distance = glm::length(ap - t * ab);
      if (distance > worst) {
        worst = distance;
        farthest = k;
      }
    }
    if (worst > tolerance) {
      keep_[farthest % n] = 1;
      spans_.push_back({a_index, farthest});
      spans_.push_back({farthest, b_index});
    }
  }
}

// Appends the marked points to `kept` in order, leaving out consecutive duplicates.
void ProfileSimplifier::collect(std::span<const glm::vec2> profile,
                                std::vector<glm::vec2>& kept) const {
  for (size_t k = 0; k < profile.size(); ++k)
    if (keep_[k] && (kept.empty() || kept.back() != profile[k])) kept.push_back(profile[k]);
}

void ProfileSimplifier::simplify(std::span<const glm::vec2> profile, float tolerance,
                                 std::vector<glm::vec2>& kept) {
  kept.clear();
  const size_t n = profile.size();
  if (n == 0) return;
  keep_.assign(n, 0);
  keep_[0] = keep_[n - 1] = 1;
  mark(profile, 0, n - 1, tolerance);
  collect(profile, kept);
}

void ProfileSimplifier::simplifyClosed(std::span<const glm::vec2> profile, float tolerance,
                                       std::vector<glm::vec2>& kept) {
  kept.clear();
  const size_t n = profile.size();
  if (n < 3) {
    kept.assign(profile.begin(), profile.end());
    return;
  }
  size_t far = 0;
  float far_distance = -1.0f;
  for (size_t k = 1; k < n; ++k) {
    const float d = glm::length(profile[k] - profile[0]);
    if (d > far_distance) {
      far_distance = d;
      far = k;
    }
  }
  keep_.assign(n, 0);
  keep_[0] = keep_[far] = 1;
  mark(profile, 0, far, tolerance);
  mark(profile, far, n, tolerance);  // back round to the first point
  collect(profile, kept);
  while (kept.size() > 1 && kept.back() == kept.front()) kept.pop_back();
}

}  // namespace tw
