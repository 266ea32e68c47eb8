// Circular arcs sampled into points. See plane_arcs.h.
#include "plane_arcs.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace tw {

std::vector<glm::dvec2> arcPoints(const glm::dvec2& centre, double r, double t0, double sweep,
                                  int min_steps) {
  const int steps = std::max(min_steps, int(std::ceil(std::abs(sweep) / kArcStepRad)));
  std::vector<glm::dvec2> out;
  out.reserve(size_t(steps) + 1);
  for (int i = 0; i <= steps; ++i) {
    const double t = t0 + sweep * double(i) / double(steps);
    out.push_back(centre + r * glm::dvec2(std::cos(t), std::sin(t)));
  }
  return out;
}

std::vector<glm::dvec2> arcThrough(const glm::dvec2& a, const glm::dvec2& b, const glm::dvec2& c) {
  const double d = 2.0 * (a.x * (b.y - c.y) + b.x * (c.y - a.y) + c.x * (a.y - b.y));
  const double scale = std::max({glm::length(b - a), glm::length(c - b), 1e-300});
  if (std::abs(d) <= 1e-12 * scale * scale) return {a, b, c};
  auto sq = [](const glm::dvec2& p) { return glm::dot(p, p); };
  const glm::dvec2 centre((sq(a) * (b.y - c.y) + sq(b) * (c.y - a.y) + sq(c) * (a.y - b.y)) / d,
                          (sq(a) * (c.x - b.x) + sq(b) * (a.x - c.x) + sq(c) * (b.x - a.x)) / d);
  const double two_pi = 2.0 * std::numbers::pi;
  auto angle = [&](const glm::dvec2& p) { return std::atan2(p.y - centre.y, p.x - centre.x); };
  auto ccw = [&](double from, double to) { return std::fmod(std::fmod(to - from, two_pi) + two_pi, two_pi); };
  const double t0 = angle(a);
  const double to_c = ccw(t0, angle(c)), to_b = ccw(t0, angle(b));
  const double sweep = to_b < to_c ? to_c : to_c - two_pi;  // the way that passes b
  std::vector<glm::dvec2> out = arcPoints(centre, glm::length(a - centre), t0, sweep, 2);
  out.front() = a;
  out.back() = c;
  return out;
}

}  // namespace tw
