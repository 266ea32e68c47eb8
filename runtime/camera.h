// The walkthrough camera: a double-precision eye in world metres, yaw/pitch orientation (Z up),
// and a reversed-Z perspective projection.
//
// Why double and eye-relative: plant coordinates reach (500000, 7000000, 0) m, where float steps
// are 0.5 m. The CPU keeps the eye in double; the renderer only ever sees positions relative to
// the eye (view rotation without translation, offsets computed in double), so nothing jitters.
// Why reversed Z: near planes of centimetres and far planes of kilometres; with
// glClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE), a float depth buffer cleared to 0 and
// glDepthFunc(GL_GREATER), depth precision is nearly uniform in log distance.
#pragma once

#include <optional>

#include <glm/glm.hpp>

namespace tw {

// Distance from the eye to the corners of a near plane at near_m whose half width and half
// height at unit distance are given: surfaces closer than that may be clipped open. Camera's
// own, and the parametric passes' from their projection matrix, are this one formula.
double nearPlaneReach(double near_m, double half_width, double half_height);

struct Camera {
  glm::dvec3 position{0.0};  // world metres (package users subtract PackageHeader::origin)
  double yaw_rad = 0.0;      // about +Z; 0 looks along +X, pi/2 along +Y
  double pitch_rad = 0.0;    // up from the XY plane, clamped to (-pi/2, pi/2) by users
  double fov_y_rad = 1.0471975511965976;  // 60 degrees, vertical
  double near_m = 0.05;
  double far_m = 20000.0;

  glm::dvec3 forward() const;  // unit
  glm::dvec3 right() const;    // unit, horizontal
  glm::dvec3 up() const;       // unit, right x forward... i.e. image up
  // World -> eye rotation only (no translation): eye space is x right, y up, -z forward.
  glm::dmat4 viewRotation() const;
  // Reversed-Z perspective for glClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE): depth 1 at near_m,
  // 0 at far_m. aspect = width / height.
  glm::dmat4 projection(double aspect) const;
  // Pixels per unit of (size / distance) at the image centre: viewport_height / (2 tan(fov_y/2)).
  // A sphere of radius r at distance d spans about 2 * r * pixelScale / d pixels.
  double pixelScale(double viewport_height_px) const;
  // Distance from the eye to the near plane's corners at aspect width / height: surfaces closer
  // than that may be clipped open, showing what lies behind their front faces.
  double nearPlaneReach(double aspect) const;
  // Points the camera from its position at `target` (world), keeping Z up.
  void lookAt(const glm::dvec3& target);
};

// Where a world point lands on a `width` x `height` image seen by `camera` (pixels, top left,
// y down); nullopt behind the eye. For what is drawn over a frame (the viewer's gizmo, measures).
std::optional<glm::dvec2> imagePoint(const Camera& camera, int width, int height,
                                     const glm::dvec3& world);

// Six planes (near, far, left, right, bottom, top) with inward unit normals, in the frame the
// eye was given in (world, or package frame = world - origin): dot(n, p) + d >= 0 inside.
struct Frustum {
  glm::dvec4 planes[6];

  // Conservative: false only when the sphere lies wholly outside one plane.
  bool intersectsSphere(const glm::dvec3& center, double radius) const;
  // Conservative box test (the p-vertex test against each plane).
  bool intersectsBox(const glm::dvec3& box_min, const glm::dvec3& box_max) const;
};

// The frustum of `camera` at aspect width / height, with its eye placed at `eye` (pass
// camera.position - origin to get it in the package frame).
Frustum makeFrustum(const Camera& camera, const glm::dvec3& eye, double aspect);

}  // namespace tw
