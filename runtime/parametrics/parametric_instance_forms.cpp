// Tessellated parametrics: the per-instance bounds and the form each instance takes. See
// parametric_instance_forms.h.
#include "parametric_instance_forms.h"

#include <algorithm>
#include <cmath>
#include <functional>

#include "covered_box_faces.h"
#include "parametric_meshes.h"
#include "parametric_unit_meshes.h"

namespace tw::instance_forms {

namespace {

const float kMaxRingSwell = ringSwell(3);

// The middle one of three sizes.
float secondLargest(const std::array<float, 3>& v) {
  return std::max(std::min(v[0], v[1]), std::min(std::max(v[0], v[1]), v[2]));
}

}  // namespace

uint32_t levelIndex(uint32_t segments) {
  const auto it = std::lower_bound(kLevels.begin(), kLevels.end(), segments);
  return it == kLevels.end() ? uint32_t(kLevels.size() - 1) : uint32_t(it - kLevels.begin());
}

Shape surfaceOf(uint32_t type) {
  switch (static_cast<pkg::PrimitiveType>(type)) {
    case pkg::PrimitiveType::Sphere: return Shape::Sphere;
    case pkg::PrimitiveType::TorusSegment: return Shape::Torus;
    case pkg::PrimitiveType::Box: return Shape::Box;
    case pkg::PrimitiveType::Extrusion:
    case pkg::PrimitiveType::Revolution: return Shape::Profile;
    default: return Shape::Tube;
  }
}

bool tubeInsideHidden(const InstanceBounds& b, const glm::vec3& eye, float margin) {
  if (!(b.flags & kOrthogonalAxes)) return false;
  const glm::vec3 to_eye = eye - b.origin;
  const float length2 = glm::dot(b.axis, b.axis);
  if (!(length2 > 0.0f)) return false;
  const float t = glm::dot(to_eye, b.axis) / length2;
  if (t < 0.0f || t > 1.0f) return false;
  return glm::length(to_eye - t * b.axis) > kMaxRingSwell * b.size[0] + margin;
}

bool eyeOutsideSolid(const InstanceBounds& b, const glm::vec3& eye, float margin) {
  const glm::vec3 from_centre = eye - b.centre;
  if (glm::length(from_centre) > b.radius + margin) return true;
  const glm::vec3 d = glm::abs(from_centre) - b.extent;
  if (std::max({d.x, d.y, d.z}) > margin) return true;
  if (surfaceOf(b.type) != Shape::Tube || !(b.flags & kOrthogonalAxes)) return false;
  const float length = glm::length(b.axis);
  if (!(length > 0.0f)) return false;
  const glm::vec3 to_eye = eye - b.origin;
  const float along = glm::dot(to_eye, b.axis) / length;  // metres from the base plane
  if (along < -margin || along > length + margin) return true;
  return glm::length(to_eye - (along / length) * b.axis) > kMaxRingSwell * b.size[0] + margin;
}

InstanceBounds boundsOf(const pkg::InstanceRecord& in, std::span<const glm::vec2> profile_points,
                        const glm::dvec3& anchor) {
  InstanceBounds b;
  glm::vec3 lo, hi;
  if (in.type >= kTypes || !instanceLocalBox(in, profile_points, lo, hi)) return b;
  // Straddling rings reach out past the true circle: the bounds take in the most they may.
  const float* p = in.params;
  const float swell = kMaxRingSwell - 1.0f;
  glm::vec3 grow(0.0f);
  switch (static_cast<pkg::PrimitiveType>(in.type)) {
    case pkg::PrimitiveType::Cylinder: grow = {swell * p[0], swell * p[0], 0.0f}; break;
    case pkg::PrimitiveType::Cone:
      grow = {swell * std::max(p[0], p[1]), swell * std::max(p[0], p[1]), 0.0f};
      break;
    case pkg::PrimitiveType::TorusSegment: grow = glm::vec3(swell * p[1]); break;
    default: break;
  }
  lo -= grow;
  hi += grow;
  const glm::mat3 linear = instanceLinear(in);
  const glm::vec3 scale(glm::length(linear[0]), glm::length(linear[1]), glm::length(linear[2]));
  const float largest = std::max({scale.x, scale.y, scale.z});
  // Chordal error scales with the largest stretch of the circle's plane (all axes for spheres).
  const float cross = std::max(scale.x, scale.y);
  const glm::dvec3 origin(in.origin[0], in.origin[1], in.origin[2]);
  b.centre = glm::vec3(origin - anchor) + linear * (0.5f * (lo + hi));
  b.radius = glm::dot(scale, 0.5f * (hi - lo));  // conservative for any linear map
  const glm::vec3 half = 0.5f * (hi - lo);
  for (int axis = 0; axis < 3; ++axis)  // |linear| times the half sizes, row by row
    b.extent[axis] = std::abs(linear[0][axis]) * half.x + std::abs(linear[1][axis]) * half.y +
                     std::abs(linear[2][axis]) * half.z;
  switch (static_cast<pkg::PrimitiveType>(in.type)) {
    case pkg::PrimitiveType::Cylinder: b.size = {p[0] * cross, p[1] * scale.z, 0.0f}; break;
    case pkg::PrimitiveType::Cone: b.size = {std::max(p[0], p[1]) * cross, p[2] * scale.z, 0.0f}; break;
    case pkg::PrimitiveType::Sphere: b.size = {p[0] * largest, 0.0f, 0.0f}; break;
    case pkg::PrimitiveType::TorusSegment: b.size = {(p[0] + p[1]) * cross, p[1] * largest, p[2]}; break;
    case pkg::PrimitiveType::Box: b.size = {p[0] * scale.x, p[1] * scale.y, p[2] * scale.z}; break;
    default: {  // extrusion, revolution: their box
      const glm::vec3 world_half = half * scale;
      b.size = {world_half.x, world_half.y, world_half.z};
      break;
    }
  }
  const bool finite = std::isfinite(b.radius) && std::isfinite(b.centre.x) &&
                      std::isfinite(b.centre.y) && std::isfinite(b.centre.z);
  b.origin = glm::vec3(origin - anchor);
  if (in.type == static_cast<uint32_t>(pkg::PrimitiveType::Box)) b.covered_faces = coveredFaces(in.flags);
  if (in.type == static_cast<uint32_t>(pkg::PrimitiveType::Cylinder) ||
      in.type == static_cast<uint32_t>(pkg::PrimitiveType::Cone))
    b.axis = linear[2] * b.size[1] / std::max(scale.z, 1e-30f);
  b.type = static_cast<uint8_t>(in.type);
  b.flags = (finite ? kValid : 0) | ((in.flags & pkg::kInstanceCapped) ? kCapped : 0) |
            (glm::determinant(linear) < 0.0f ? kMirrored : 0);
  auto perpendicular = [](const glm::vec3& u, const glm::vec3& v) {
    return std::abs(glm::dot(u, v)) <= 1e-5f * glm::length(u) * glm::length(v);
  };
  if (perpendicular(linear[0], linear[1]) && perpendicular(linear[0], linear[2]) &&
      perpendicular(linear[1], linear[2]))
    b.flags |= kOrthogonalAxes;
  if (in.type == static_cast<uint32_t>(pkg::PrimitiveType::Extrusion)) {
    // Shoelace area against the box's: equal (to float rounding) for a rectangle.
    const auto profile = profile_points.subspan(in.profile_first, in.profile_count);
    const double area2 = profileSignedArea2(profile);
    const double box_area = double(hi.x - lo.x) * double(hi.y - lo.y);
    if (std::abs(0.5 * std::abs(area2) - box_area) <= 1e-5 * box_area) b.flags |= kRectangleProfile;
    if (extrusionEnclosesSolid(profile)) b.flags |= kClosedProfile;
  }
  return b;
}

Form chooseForm(const InstanceBounds& b, float tolerance, float thin, float min_thin) {
  Form f;
  f.capped = (b.flags & kCapped) != 0;
  float across = 0.0f;  // thin forms: the width the ribbon, box or point stands for
  // Cross-section rings (tubes, tori, spheres) at half the tolerance: a ring's error shows on
  // both sides of a pipe, so its width is what tau bounds (docs/parametrics.md, "Rings").
  const float ring_tolerance = 0.5f * tolerance;
  switch (surfaceOf(b.type)) {
    case Shape::Tube:
      if (2.0f * b.size[0] < thin) {
        f.shape = b.size[1] < thin ? Shape::Point : Shape::Ribbon;
        across = 2.0f * b.size[0];
        break;
      }
      f.shape = Shape::Tube;
      f.a = levelIndex(arcSegments(b.size[0], float(kTwoPi), ring_tolerance));
      break;
    case Shape::Sphere:
      if (2.0f * b.size[0] < thin) {
        f.shape = Shape::Point;
        across = 2.0f * b.size[0];
        break;
      }
      f.shape = Shape::Sphere;
      f.a = levelIndex(arcSegments(b.size[0], float(kTwoPi), ring_tolerance));
      f.b = levelIndex(std::max(2u, arcSegments(b.size[0], float(std::numbers::pi), ring_tolerance)));
      break;
    case Shape::Torus: {
      f.a = levelIndex(arcSegments(b.size[0], std::min(b.size[2], float(kTwoPi)), tolerance));
      if (2.0f * b.size[1] < thin) {
        // The ribbon is narrower than its chords' sag could be at the tolerance: a quarter of it,
        // and straddling chords (appendTubeRibbon), keep it within an eighth of the true centre
        // circle.
        f.shape = Shape::Ribbon;
        f.a = levelIndex(arcSegments(b.size[0], std::min(b.size[2], float(kTwoPi)), 0.25f * tolerance));
        across = 2.0f * b.size[1];
        break;
      }
      f.shape = Shape::Torus;
      f.b = levelIndex(arcSegments(b.size[1], float(kTwoPi), ring_tolerance));
      break;
    }
    default: {  // box and profiles: thin in two directions, the box; in all three, a point
      int thin_axes = 0, longest = 0, thinnest = 0;
      for (int axis = 0; axis < 3; ++axis) {
        thin_axes += 2.0f * b.size[axis] < thin;
        if (b.size[axis] > b.size[longest]) longest = axis;
        if (b.size[axis] < b.size[thinnest]) thinnest = axis;
      }
      f.shape = thin_axes == 3 ? Shape::Point : surfaceOf(b.type);
      if (thin_axes == 2) {
        // A beam thinner than a pixel both ways across: a ribbon along its longest axis, as
        // wide as its cross-section seen from the eye (appendBeamRibbon), the silhouette its box
        // would show, in two triangles instead of six to twelve, each fragment shaded with the
        // face under it.
        for (int axis = 0; axis < 3; ++axis)
          if (axis != longest) across = std::max(across, 2.0f * b.size[axis]);
        f.shape = Shape::Ribbon;
        f.box_frame = true;
        f.long_axis = static_cast<uint8_t>(longest);
      } else if (f.shape == Shape::Point) {
        // Its second largest size, as for a ribbon: what it covers of a pixel is at most its
        // largest times that, so a rail post far below a pixel across is left out at every
        // scale, not drawn as a pixel from afar and left out nearer.
        across = 2.0f * secondLargest(b.size);
      }
      // An extrusion is drawn as its box when the profile lies within `tolerance` of the box's
      // sides (at most half its smaller width away), or is the box.
      if (f.shape == Shape::Profile && b.type == static_cast<uint8_t>(pkg::PrimitiveType::Extrusion) &&
          ((b.flags & kRectangleProfile) || std::min(b.size[0], b.size[1]) <= tolerance)) {
        f.shape = Shape::Box;
        f.box_frame = true;
      }
      // A plate's rims are as wide as the plate is thick: under min_thin they go as a ribbon that
      // narrow would, and the plate is its two large faces.
      if (f.shape == Shape::Box && thin_axes == 1 && 2.0f * b.size[thinnest] < min_thin) {
        const uint32_t all = 0x3f, large = 3u << (2 * thinnest);
        f.thin_faces = static_cast<uint8_t>(all & ~large);
      }
      // A revolution: half the tolerance for the angle, half for the profile (appendLathe).
      if (f.shape == Shape::Profile && b.type == static_cast<uint8_t>(pkg::PrimitiveType::Revolution)) {
        f.shape = Shape::Lathe;
        f.a = levelIndex(arcSegments(std::max(b.size[0], b.size[1]), float(kTwoPi), 0.5f * tolerance));
      }
      break;
    }
  }
  if (across > 0.0f && across < min_thin) f.shape = Shape::None;
  if (f.shape != Shape::Tube) f.capped = false;
  if (f.shape == Shape::Point) f.batch = kPoints;  // a ribbon faces the eye: two-sided
  return f;
}

// Derived from chooseForm's rules with k the scale, thin = thin_px / k, min_thin = min_thin_px / k
// (mt = min_thin_px <= thin_px): every thin form (ribbon or point) is as wide as the instance's
// second largest size M, and anything wider than a pixel there is a surface, so an instance
// shows from mt / M on: a tube's diameter, a sphere's, a torus's tube; a box's (extrusion's,
// revolution's) middle size. Nothing shows below min_feature_px / (2 r) either, r the bounding
// sphere's radius.
double shownFrom(const InstanceBounds& b, double thin_px, double min_thin_px,
                 double min_feature_px) {
  if (!(b.flags & kValid)) return INFINITY;
  const double mt = std::min(min_thin_px, thin_px);
  double across = 0.0;  // M, in metres
  switch (surfaceOf(b.type)) {
    case Shape::Tube: across = 2.0 * double(b.size[0]); break;
    case Shape::Sphere: across = 2.0 * double(b.size[0]); break;
    case Shape::Torus: across = 2.0 * double(b.size[1]); break;
    default: across = 2.0 * double(secondLargest(b.size)); break;
  }
  // A thin form of zero width is never left out (chooseForm leaves out only widths above zero).
  const double from = across > 0.0 ? mt / across : 0.0;
  const double diameter = 2.0 * double(b.radius);
  const double feature =
      min_feature_px > 0.0 ? (diameter > 0.0 ? min_feature_px / diameter : INFINITY) : 0.0;
  return std::max(from, feature);
}

void cullBackFaces(Form& f, const InstanceBounds& b, bool eye_outside, bool inside_hidden) {
  if (f.shape == Shape::Point || f.shape == Shape::Ribbon || f.shape == Shape::None) return;
  bool closed = true;
  if (f.shape == Shape::Tube) closed = f.capped || inside_hidden;
  if (f.shape == Shape::Torus)
    closed = inside_hidden || b.size[2] >= float(kTwoPi);  // a full torus has no open ends
  if (closed && (eye_outside || inside_hidden))  // back faces hidden by the front faces
    f.batch = (b.flags & kMirrored) ? kCullCw : kCullCcw;
}

}  // namespace tw::instance_forms
