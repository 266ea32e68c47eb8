// The walkthrough camera: orientation vectors, the reversed-Z projection and the culling frustum.
// Everything is double; only eye-relative results ever reach floats (see camera.h).
#include "camera.h"

#include <cmath>

namespace tw {

glm::dvec3 Camera::forward() const {
  double cp = std::cos(pitch_rad);
  return {cp * std::cos(yaw_rad), cp * std::sin(yaw_rad), std::sin(pitch_rad)};
}

// forward x Z, normalised: depends on yaw only, so it stays defined looking straight up or down.
glm::dvec3 Camera::right() const { return {std::sin(yaw_rad), -std::cos(yaw_rad), 0.0}; }

glm::dvec3 Camera::up() const { return glm::cross(right(), forward()); }

glm::dmat4 Camera::viewRotation() const {
  glm::dvec3 r = right(), u = up(), f = forward();
  glm::dmat4 m(1.0);  // column-major: m[column][row]; rows are right, up, -forward
  for (int i = 0; i < 3; ++i) {
    m[i][0] = r[i];
    m[i][1] = u[i];
    m[i][2] = -f[i];
  }
  return m;
}

// Clip z = A * z_eye + B with w = -z_eye gives depth = -A + B / distance; depth(near) = 1 and
// depth(far) = 0 give A = n / (f - n), B = n f / (f - n).
glm::dmat4 Camera::projection(double aspect) const {
  double t = std::tan(fov_y_rad * 0.5);
  double n = near_m, f = far_m;
  glm::dmat4 m(0.0);
  m[0][0] = 1.0 / (aspect * t);
  m[1][1] = 1.0 / t;
  m[2][2] = n / (f - n);
  m[2][3] = -1.0;
  m[3][2] = n * f / (f - n);
  return m;
}

double Camera::pixelScale(double viewport_height_px) const {
  return viewport_height_px / (2.0 * std::tan(fov_y_rad * 0.5));
}

double nearPlaneReach(double near_m, double half_width, double half_height) {
  return near_m * std::sqrt(1.0 + half_width * half_width + half_height * half_height);
}

double Camera::nearPlaneReach(double aspect) const {
  const double t = std::tan(fov_y_rad * 0.5);
  return tw::nearPlaneReach(near_m, t * aspect, t);
}

void Camera::lookAt(const glm::dvec3& target) {
  glm::dvec3 d = target - position;
  double horizontal = std::hypot(d.x, d.y);
  if (horizontal == 0.0 && d.z == 0.0) return;  // no direction: keep the current one
  if (horizontal > 0.0) yaw_rad = std::atan2(d.y, d.x);  // straight up/down: keep the yaw
  pitch_rad = std::atan2(d.z, horizontal);
}

bool Frustum::intersectsSphere(const glm::dvec3& center, double radius) const {
  for (const glm::dvec4& p : planes)
    if (p.x * center.x + p.y * center.y + p.z * center.z + p.w < -radius) return false;
  return true;
}

bool Frustum::intersectsBox(const glm::dvec3& box_min, const glm::dvec3& box_max) const {
  for (const glm::dvec4& p : planes) {
    // The corner furthest along the normal: if even it is outside, the whole box is.
    double x = p.x >= 0.0 ? box_max.x : box_min.x;
    double y = p.y >= 0.0 ? box_max.y : box_min.y;
    double z = p.z >= 0.0 ? box_max.z : box_min.z;
    if (p.x * x + p.y * y + p.z * z + p.w < 0.0) return false;
  }
  return true;
}

Frustum makeFrustum(const Camera& camera, const glm::dvec3& eye, double aspect) {
  glm::dvec3 f = camera.forward(), r = camera.right(), u = camera.up();
  double ty = std::tan(camera.fov_y_rad * 0.5);
  double tx = ty * aspect;
  auto through = [&](glm::dvec3 n, const glm::dvec3& point) {
    n = glm::normalize(n);
    return glm::dvec4(n, -glm::dot(n, point));
  };
  Frustum frustum;
  frustum.planes[0] = through(f, eye + f * camera.near_m);   // near
  frustum.planes[1] = through(-f, eye + f * camera.far_m);   // far
  // Side planes pass through the eye; each normal is orthogonal to the edge direction it
  // contains (e.g. left: f - tx r) and points inward.
  frustum.planes[2] = through(r + f * tx, eye);   // left
  frustum.planes[3] = through(-r + f * tx, eye);  // right
  frustum.planes[4] = through(u + f * ty, eye);   // bottom
  frustum.planes[5] = through(-u + f * ty, eye);  // top
  return frustum;
}

std::optional<glm::dvec2> imagePoint(const Camera& camera, int width, int height,
                                     const glm::dvec3& world) {
  const glm::dmat4 m = camera.projection(double(width) / height) * camera.viewRotation();
  const glm::dvec4 c = m * glm::dvec4(world - camera.position, 1.0);
  if (c.w <= 1e-9) return std::nullopt;
  return glm::dvec2((c.x / c.w * 0.5 + 0.5) * width, (0.5 - c.y / c.w * 0.5) * height);
}

}  // namespace tw
