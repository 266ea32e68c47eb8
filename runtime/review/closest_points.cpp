// Closest points of segments, triangles and cylinders. See closest_points.h.
//
// The segment case follows the classic region analysis (Ericson, "Real-Time Collision
// Detection", 5.1.9) in double precision; the point-triangle case is formats/closest_on_triangle.h.
#include "closest_points.h"

#include <algorithm>
#include <cmath>

#include "closest_on_triangle.h"

namespace tw {
namespace {

PointPair pair(const glm::dvec3& a, const glm::dvec3& b) { return {a, b, glm::length(b - a)}; }

// Where segment p-q crosses triangle t (its inside included), if it does.
std::optional<glm::dvec3> segmentCrossing(const glm::dvec3& p, const glm::dvec3& q,
                                          const Triangle3d& t) {
  const glm::dvec3 e1 = t[1] - t[0], e2 = t[2] - t[0], d = q - p;
  const glm::dvec3 n = glm::cross(e1, e2);
  const double denom = -glm::dot(d, n);
  if (std::abs(denom) <= 1e-300) return std::nullopt;  // parallel: the edge tests see it
  const glm::dvec3 ap = p - t[0];
  const double along = glm::dot(ap, n) / denom;
  if (along < 0.0 || along > 1.0) return std::nullopt;
  const glm::dvec3 e = glm::cross(-d, ap);
  const double v = glm::dot(e2, e) / denom, w = -glm::dot(e1, e) / denom;
  if (v < 0.0 || w < 0.0 || v + w > 1.0) return std::nullopt;
  return p + d * along;
}

}  // namespace

SegmentClosest closestOnSegments(const glm::dvec3& p0, const glm::dvec3& p1, const glm::dvec3& q0,
                                 const glm::dvec3& q1) {
  const glm::dvec3 d1 = p1 - p0, d2 = q1 - q0, r = p0 - q0;
  const double a = glm::dot(d1, d1), e = glm::dot(d2, d2), f = glm::dot(d2, r);
  double s = 0.0, t = 0.0;
  if (a <= 0.0 && e <= 0.0) {
    // Both points.
  } else if (a <= 0.0) {
    t = std::clamp(f / e, 0.0, 1.0);
  } else {
    const double c = glm::dot(d1, r);
    if (e <= 0.0) {
      s = std::clamp(-c / a, 0.0, 1.0);
    } else {
      const double b = glm::dot(d1, d2), denom = a * e - b * b;
      // Parallel segments (denom 0): any s works; start from 0 and let t and s settle.
      s = denom > 0.0 ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
      t = (b * s + f) / e;
      if (t < 0.0) {
        t = 0.0;
        s = std::clamp(-c / a, 0.0, 1.0);
      } else if (t > 1.0) {
        t = 1.0;
        s = std::clamp((b - c) / a, 0.0, 1.0);
      }
    }
  }
  return {pair(p0 + d1 * s, q0 + d2 * t), s, t};
}

glm::dvec3 closestOnTriangle(const glm::dvec3& p, const Triangle3d& t) {
  return closestOnTriangle(p, t[0], t[1], t[2]);
}

PointPair closestBetweenTriangles(const Triangle3d& s, const Triangle3d& t) {
  // Crossing: an edge of one through the other.
  for (int i = 0; i < 3; ++i) {
    if (auto hit = segmentCrossing(s[i], s[(i + 1) % 3], t)) return pair(*hit, *hit);
    if (auto hit = segmentCrossing(t[i], t[(i + 1) % 3], s)) return pair(*hit, *hit);
  }
  // Otherwise the closest pair is a vertex against the other's face or an edge against an edge.
  PointPair best{glm::dvec3(0.0), glm::dvec3(0.0), INFINITY};
  auto consider = [&](const PointPair& p) {
    if (p.distance < best.distance) best = p;
  };
  for (int i = 0; i < 3; ++i) {
    consider(pair(s[i], closestOnTriangle(s[i], t)));
    consider(pair(closestOnTriangle(t[i], s), t[i]));
    for (int j = 0; j < 3; ++j)
      consider(closestOnSegments(s[i], s[(i + 1) % 3], t[j], t[(j + 1) % 3]).points);
  }
  return best;
}

std::optional<PointPair> closestBetweenCylinders(const CylinderAxis& a, const CylinderAxis& b) {
  const glm::dvec3 da = a.top - a.base, db = b.top - b.base;
  const double la = glm::length(da), lb = glm::length(db);
  if (!(la > 0.0 && lb > 0.0 && a.radius > 0.0 && b.radius > 0.0)) return std::nullopt;
  const glm::dvec3 ua = da / la, ub = db / lb;
  glm::dvec3 on_a, on_b;
  const double sine = glm::length(glm::cross(ua, ub));
  if (sine < 1e-12) {
    // Parallel: the stretch of a's axis beside b's, and its middle.
    const double t0 = glm::dot(b.base - a.base, ua), t1 = glm::dot(b.top - a.base, ua);
    const double lo = std::max(0.0, std::min(t0, t1)), hi = std::min(la, std::max(t0, t1));
    if (!(lo < hi)) return std::nullopt;  // end to end: a cap is closest
    on_a = a.base + ua * (0.5 * (lo + hi));
    on_b = b.base + ub * glm::dot(on_a - b.base, ub);
  } else {
    const SegmentClosest axes = closestOnSegments(a.base, a.top, b.base, b.top);
    const double eps = 1e-12;
    if (axes.s <= eps || axes.s >= 1.0 - eps || axes.t <= eps || axes.t >= 1.0 - eps)
      return std::nullopt;  // at an end of an axis: a cap or a rim is closest
    on_a = axes.points.a;
    on_b = axes.points.b;
  }
  const glm::dvec3 between = on_b - on_a;
  const double axis_distance = glm::length(between);
  if (!(axis_distance > a.radius + b.radius)) return std::nullopt;  // touching or overlapping
  const glm::dvec3 n = between / axis_distance;
  return pair(on_a + n * a.radius, on_b - n * b.radius);
}

}  // namespace tw
