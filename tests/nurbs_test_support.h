// NURBS patches for tests: clamped uniform knot vectors and a patch from its degrees, counts and
// control points (x, y, z, w), shared by the NURBS evaluation and tessellation tests.
#pragma once

#include <cstdint>
#include <utility>
#include <vector>

#include <glm/glm.hpp>

#include "scene.h"

namespace tw::test {

// degree + 1 copies of a, the interior knots evenly spaced, degree + 1 copies of b.
inline std::vector<float> clampedKnots(uint32_t degree, uint32_t count, float a = 0.0f,
                                       float b = 1.0f) {
  std::vector<float> k;
  const uint32_t interior = count - degree - 1;
  for (uint32_t i = 0; i <= degree; ++i) k.push_back(a);
  for (uint32_t i = 1; i <= interior; ++i)
    k.push_back(a + (b - a) * static_cast<float>(i) / static_cast<float>(interior + 1));
  for (uint32_t i = 0; i <= degree; ++i) k.push_back(b);
  return k;
}

inline NurbsPatch makePatch(uint32_t du, uint32_t dv, uint32_t cu, uint32_t cv,
                            std::vector<glm::vec4> points) {
  NurbsPatch p;
  p.degree_u = du;
  p.degree_v = dv;
  p.count_u = cu;
  p.count_v = cv;
  p.knots_u = clampedKnots(du, cu);
  p.knots_v = clampedKnots(dv, cv);
  p.control_points = std::move(points);
  return p;
}

}  // namespace tw::test
