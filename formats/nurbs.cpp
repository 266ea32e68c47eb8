// Validation and evaluation of rational B-spline patches.
//
// Evaluation uses the Cox-de Boor recurrence for the basis functions of the knot span and their
// exact first derivatives (from the degree p-1 basis), in double precision; the normal is the
// normalised cross product of the exact rational partial derivatives.
#include <algorithm>
#include <array>
#include <cmath>
#include <string>

#include "nurbs.h"

namespace tw {
namespace {

// Degree and count limits: a degree beyond 10 is not CAD data, and the work of one evaluation
// grows with (degree + 1)^2.
constexpr uint32_t kMaxNurbsDegree = 10;
constexpr uint32_t kMaxNurbsCount = 1u << 16;

std::string checkKnots(const std::vector<float>& knots, uint32_t degree, uint32_t count, const char* dir) {
  const std::string d(dir);
  if (knots.size() != static_cast<size_t>(count) + degree + 1)
    return "knot vector " + d + " has " + std::to_string(knots.size()) + " entries, expected " +
           std::to_string(static_cast<size_t>(count) + degree + 1);
  uint32_t multiplicity = 1;
  for (size_t i = 0; i < knots.size(); ++i) {
    if (!std::isfinite(knots[i])) return "knot vector " + d + " has a non-finite value";
    if (i == 0) continue;
    if (knots[i] < knots[i - 1]) return "knot vector " + d + " is decreasing at index " + std::to_string(i);
    multiplicity = knots[i] == knots[i - 1] ? multiplicity + 1 : 1;
    if (multiplicity > degree + 1)
      return "knot vector " + d + " has a knot of multiplicity above degree + 1";
  }
  if (!(knots[degree] < knots[count])) return "knot vector " + d + " has an empty domain";
  return {};
}

// Knot span s in [p, n - 1] with knots[s] <= t < knots[s + 1]; at the domain end, the last
// non-empty span. `t` must already lie in the domain.
uint32_t findSpan(const std::vector<float>& k, uint32_t p, uint32_t n, double t) {
  if (t >= k[n]) {
    uint32_t s = n - 1;
    while (s > p && !(k[s] < k[n])) --s;
    return s;
  }
  uint32_t lo = p, hi = n;  // k[lo] <= t < k[hi]
  while (hi - lo > 1) {
    const uint32_t mid = lo + (hi - lo) / 2;
    if (t < k[mid])
      hi = mid;
    else
      lo = mid;
  }
  return lo;
}

// The p + 1 non-zero basis functions of span s at t (n[r] = N_{s-p+r,p}) and their first
// derivatives (d[r]).
struct Basis {
  std::array<double, kMaxNurbsDegree + 1> n{}, d{};
};

void basisFunctions(const std::vector<float>& k, uint32_t p, uint32_t s, double t, Basis& b) {
  std::array<double, kMaxNurbsDegree + 1> left{}, right{}, lower{};
  b.n[0] = 1.0;
  if (p == 1) lower[0] = 1.0;
  for (uint32_t j = 1; j <= p; ++j) {
    left[j] = t - k[s + 1 - j];
    right[j] = static_cast<double>(k[s + j]) - t;
    double saved = 0.0;
    for (uint32_t r = 0; r < j; ++r) {
      const double denom = right[r + 1] + left[j - r];
      const double temp = denom != 0.0 ? b.n[r] / denom : 0.0;
      b.n[r] = saved + right[r + 1] * temp;
      saved = left[j - r] * temp;
    }
    b.n[j] = saved;
    if (j + 1 == p)
      for (uint32_t r = 0; r < p; ++r) lower[r] = b.n[r];
  }
  // N'_{i,p} = p N_{i,p-1} / (k[i+p] - k[i]) - p N_{i+1,p-1} / (k[i+p+1] - k[i+1]), i = s-p+r,
  // where lower[r'] = N_{s-p+1+r', p-1}.
  for (uint32_t r = 0; r <= p; ++r) {
    const uint32_t i = s - p + r;
    double v = 0.0;
    if (r >= 1) {
      const double den = static_cast<double>(k[i + p]) - k[i];
      if (den != 0.0) v += p * lower[r - 1] / den;
    }
    if (r < p) {
      const double den = static_cast<double>(k[i + p + 1]) - k[i + 1];
      if (den != 0.0) v -= p * lower[r] / den;
    }
    b.d[r] = v;
  }
}

struct SurfacePoint {
  glm::dvec3 p, du, dv;
};

SurfacePoint evaluateDerivatives(const NurbsPatch& patch, double u, double v) {
  const uint32_t pu = patch.degree_u, pv = patch.degree_v;
  const uint32_t su = findSpan(patch.knots_u, pu, patch.count_u, u);
  const uint32_t sv = findSpan(patch.knots_v, pv, patch.count_v, v);
  Basis bu, bv;
  basisFunctions(patch.knots_u, pu, su, u, bu);
  basisFunctions(patch.knots_v, pv, sv, v, bv);
  // Homogeneous sums: A = sum N M w P, W = sum N M w, and their u and v derivatives.
  glm::dvec3 a(0.0), a_u(0.0), a_v(0.0);
  double w = 0.0, w_u = 0.0, w_v = 0.0;
  for (uint32_t r = 0; r <= pv; ++r) {
    const size_t row = static_cast<size_t>(sv - pv + r) * patch.count_u;
    for (uint32_t c = 0; c <= pu; ++c) {
      const glm::vec4& cp = patch.control_points[row + su - pu + c];
      const double weight = cp.w;
      const glm::dvec3 wp = glm::dvec3(cp.x, cp.y, cp.z) * weight;
      const double nm = bu.n[c] * bv.n[r], dnm_u = bu.d[c] * bv.n[r], dnm_v = bu.n[c] * bv.d[r];
      a += nm * wp;
      a_u += dnm_u * wp;
      a_v += dnm_v * wp;
      w += nm * weight;
      w_u += dnm_u * weight;
      w_v += dnm_v * weight;
    }
  }
  SurfacePoint sp;
  sp.p = a / w;
  sp.du = (a_u - w_u * sp.p) / w;
  sp.dv = (a_v - w_v * sp.p) / w;
  return sp;
}

bool unitNormal(const SurfacePoint& sp, glm::dvec3& n) {
  const glm::dvec3 c = glm::cross(sp.du, sp.dv);
  const double len = glm::length(c);
  const double scale = glm::length(sp.du) * glm::length(sp.dv);
  if (!(len > 1e-12 * scale) || !(len > 0.0) || !std::isfinite(len)) return false;
  n = c / len;
  return true;
}

}  // namespace

std::string validateNurbsPatch(const NurbsPatch& patch) {
  if (patch.degree_u < 1 || patch.degree_v < 1) return "degree must be at least 1";
  if (patch.degree_u > kMaxNurbsDegree || patch.degree_v > kMaxNurbsDegree)
    return "degree above " + std::to_string(kMaxNurbsDegree);
  if (patch.count_u <= patch.degree_u || patch.count_v <= patch.degree_v)
    return "control point count must exceed the degree";
  if (patch.count_u > kMaxNurbsCount || patch.count_v > kMaxNurbsCount)
    return "control point count above " + std::to_string(kMaxNurbsCount);
  const uint64_t points = uint64_t{patch.count_u} * patch.count_v;
  if (patch.control_points.size() != points)
    return "has " + std::to_string(patch.control_points.size()) + " control points, expected " +
           std::to_string(points);
  if (std::string e = checkKnots(patch.knots_u, patch.degree_u, patch.count_u, "u"); !e.empty()) return e;
  if (std::string e = checkKnots(patch.knots_v, patch.degree_v, patch.count_v, "v"); !e.empty()) return e;
  for (const glm::vec4& cp : patch.control_points) {
    if (!std::isfinite(cp.x) || !std::isfinite(cp.y) || !std::isfinite(cp.z) || !std::isfinite(cp.w))
      return "control point with a non-finite coordinate or weight";
    if (!(cp.w > 0.0f)) return "control point weight must be positive";
  }
  return {};
}

NurbsDomain nurbsDomain(const NurbsPatch& patch) {
  return {patch.knots_u[patch.degree_u], patch.knots_u[patch.count_u], patch.knots_v[patch.degree_v],
          patch.knots_v[patch.count_v]};
}

glm::vec3 evaluateNurbs(const NurbsPatch& patch, float u, float v, glm::vec3* normal) {
  const NurbsDomain dom = nurbsDomain(patch);
  const double uu = std::clamp(static_cast<double>(u), static_cast<double>(dom.u0), static_cast<double>(dom.u1));
  const double vv = std::clamp(static_cast<double>(v), static_cast<double>(dom.v0), static_cast<double>(dom.v1));
  const SurfacePoint sp = evaluateDerivatives(patch, std::isnan(u) ? dom.u0 : uu, std::isnan(v) ? dom.v0 : vv);
  if (normal) {
    glm::dvec3 n(0.0, 0.0, 1.0);
    if (!unitNormal(sp, n)) {
      // Degenerate point (a collapsed edge, a pole): take the normal a little way inside the
      // domain, which is the limit of the normals around it.
      const double cu = 0.5 * (static_cast<double>(dom.u0) + dom.u1), cv = 0.5 * (static_cast<double>(dom.v0) + dom.v1);
      const SurfacePoint near = evaluateDerivatives(patch, uu + (cu - uu) * 2e-4, vv + (cv - vv) * 2e-4);
      if (!unitNormal(near, n)) n = glm::dvec3(0.0, 0.0, 1.0);
    }
    *normal = glm::vec3(n);
  }
  return glm::vec3(sp.p);
}

}  // namespace tw
