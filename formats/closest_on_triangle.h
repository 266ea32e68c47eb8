// The point of a triangle (its inside included) closest to a point: the region walk over the
// triangle's vertices, edges and face (Ericson, "Real-Time Collision Detection", 5.1.5), for
// glm's float and double vectors alike. Used by the far proxies' distance checks (float) and by
// measuring (double).
#pragma once

#include <cmath>

#include <glm/glm.hpp>

namespace tw {

template <typename Vec>
Vec closestOnTriangle(const Vec& p, const Vec& a, const Vec& b, const Vec& c) {
  using Scalar = typename Vec::value_type;
  const Vec ab = b - a, ac = c - a, ap = p - a;
  const Scalar d1 = glm::dot(ab, ap), d2 = glm::dot(ac, ap);
  if (d1 <= Scalar(0) && d2 <= Scalar(0)) return a;
  const Vec bp = p - b;
  const Scalar d3 = glm::dot(ab, bp), d4 = glm::dot(ac, bp);
  if (d3 >= Scalar(0) && d4 <= d3) return b;
  const Scalar vc = d1 * d4 - d3 * d2;
  if (vc <= Scalar(0) && d1 >= Scalar(0) && d3 <= Scalar(0)) return a + ab * (d1 / (d1 - d3));
  const Vec cp = p - c;
  const Scalar d5 = glm::dot(ab, cp), d6 = glm::dot(ac, cp);
  if (d6 >= Scalar(0) && d5 <= d6) return c;
  const Scalar vb = d5 * d2 - d1 * d6;
  if (vb <= Scalar(0) && d2 >= Scalar(0) && d6 <= Scalar(0)) return a + ac * (d2 / (d2 - d6));
  const Scalar va = d3 * d6 - d5 * d4;
  if (va <= Scalar(0) && (d4 - d3) >= Scalar(0) && (d5 - d6) >= Scalar(0))
    return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
  const Scalar denom = va + vb + vc;
  if (!(std::abs(denom) > Scalar(0))) {  // degenerate triangle: the nearest of its corners
    const Scalar da = glm::dot(p - a, p - a), db = glm::dot(p - b, p - b),
                 dc = glm::dot(p - c, p - c);
    return da <= db && da <= dc ? a : (db <= dc ? b : c);
  }
  return a + ab * (vb / denom) + ac * (vc / denom);
}

}  // namespace tw
