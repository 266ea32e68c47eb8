// Instance records read as scene primitives. See instance_primitive.h.
#include "instance_primitive.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

namespace tw {

Primitive primitiveOf(const pkg::InstanceRecord& in, std::span<const glm::vec2> profile_points) {
  const float* p = in.params;
  const bool capped = (in.flags & pkg::kInstanceCapped) != 0;
  auto profile = [&] {
    std::vector<glm::vec2> points;
    if (in.profile_first <= profile_points.size() &&
        in.profile_count <= profile_points.size() - in.profile_first)
      points.assign(profile_points.begin() + in.profile_first,
                    profile_points.begin() + in.profile_first + in.profile_count);
    return points;
  };
  switch (static_cast<pkg::PrimitiveType>(in.type)) {
    case pkg::PrimitiveType::Cylinder: return Cylinder{p[0], p[1], capped};
    case pkg::PrimitiveType::Cone: return Cone{p[0], p[1], p[2], capped};
    case pkg::PrimitiveType::Sphere: return Sphere{p[0]};
    case pkg::PrimitiveType::TorusSegment: return TorusSegment{p[0], p[1], p[2]};
    case pkg::PrimitiveType::Box: return Box{glm::vec3(p[0], p[1], p[2])};
    case pkg::PrimitiveType::Extrusion: return Extrusion{profile(), p[0]};
    case pkg::PrimitiveType::Revolution: return Revolution{profile(), p[0]};
  }
  return Sphere{0.0f};  // unknown type (the view rejects it): tessellates to nothing
}

namespace {
bool positive(float v) { return std::isfinite(v) && v > 0.0f; }
}  // namespace

bool instanceLocalBox(const pkg::InstanceRecord& in, std::span<const glm::vec2> profile_points,
                      glm::vec3& lo, glm::vec3& hi) {
  const float* p = in.params;
  switch (static_cast<pkg::PrimitiveType>(in.type)) {
    case pkg::PrimitiveType::Cylinder:
      if (!positive(p[0]) || !positive(p[1])) return false;
      lo = {-p[0], -p[0], 0.0f};
      hi = {p[0], p[0], p[1]};
      return true;
    case pkg::PrimitiveType::Cone: {
      if (!(p[0] >= 0.0f) || !(p[1] >= 0.0f) || !positive(p[2]) || !positive(std::max(p[0], p[1])))
        return false;
      const float r = std::max(p[0], p[1]);
      lo = {-r, -r, 0.0f};
      hi = {r, r, p[2]};
      return true;
    }
    case pkg::PrimitiveType::Sphere:
      if (!positive(p[0])) return false;
      lo = glm::vec3(-p[0]);
      hi = glm::vec3(p[0]);
      return true;
    case pkg::PrimitiveType::TorusSegment: {
      const float major = p[0], minor = p[1], sweep = p[2];
      if (!positive(major) || !positive(minor) || minor >= major || !positive(sweep)) return false;
      // The annular sector's box: its end directions and the axis directions it sweeps over, at
      // both radii; the tube adds +-minor in z.
      glm::vec2 a(std::numeric_limits<float>::max()), b(-std::numeric_limits<float>::max());
      auto add = [&](double angle) {
        const glm::vec2 dir(static_cast<float>(std::cos(angle)), static_cast<float>(std::sin(angle)));
        for (float r : {major - minor, major + minor}) {
          a = glm::min(a, r * dir);
          b = glm::max(b, r * dir);
        }
      };
      const double s = std::min<double>(sweep, 2.0 * std::numbers::pi);
      add(0.0);
      add(s);
      for (int k = 1; k < 4; ++k)
        if (k * 0.5 * std::numbers::pi < s) add(k * 0.5 * std::numbers::pi);
      lo = {a.x, a.y, -minor};
      hi = {b.x, b.y, minor};
      return true;
    }
    case pkg::PrimitiveType::Box:
      if (!positive(p[0]) || !positive(p[1]) || !positive(p[2])) return false;
      lo = {-p[0], -p[1], -p[2]};
      hi = {p[0], p[1], p[2]};
      return true;
    case pkg::PrimitiveType::Extrusion:
    case pkg::PrimitiveType::Revolution: {
      if (in.profile_count < 2 || in.profile_first > profile_points.size() ||
          in.profile_count > profile_points.size() - in.profile_first || !positive(p[0]))
        return false;
      glm::vec2 a(std::numeric_limits<float>::max()), b(-std::numeric_limits<float>::max());
      for (const glm::vec2& q : profile_points.subspan(in.profile_first, in.profile_count)) {
        a = glm::min(a, q);
        b = glm::max(b, q);
      }
      if (!std::isfinite(a.x) || !std::isfinite(a.y) || !std::isfinite(b.x) || !std::isfinite(b.y))
        return false;
      if (in.type == static_cast<uint32_t>(pkg::PrimitiveType::Extrusion)) {
        lo = {a.x, a.y, 0.0f};  // the profile swept along +Z over the height
        hi = {b.x, b.y, p[0]};
      } else {
        const float r = std::max(std::fabs(a.x), std::fabs(b.x));  // (r, z) about +Z, any sweep
        lo = {-r, -r, a.y};
        hi = {r, r, b.y};
      }
      return true;
    }
    default:
      return false;
  }
}

}  // namespace tw
