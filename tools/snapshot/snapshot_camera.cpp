// Camera frames, automatic framing and vector parsing for snapshots.
#include "snapshot_camera.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <stdexcept>
#include <limits>
#include <string>
#include <vector>

namespace tw {

namespace {

bool finite(const glm::dvec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

constexpr double kPi = 3.14159265358979323846;
// Frustum narrowing for automatic framing: 8% keeps a visible border around the model.
constexpr double kFitMargin = 1.08;

double radians(double deg) { return deg * kPi / 180.0; }

glm::dvec3 safeNormalize(const glm::dvec3& v, const glm::dvec3& fallback) {
  double len = glm::length(v);
  return (len > 1e-300 && std::isfinite(len)) ? v / len : fallback;
}

// The tightest eye position, for a fixed view frame, that sees every point (given relative to
// some reference point on the view axis). In frame coordinates (x right, y up, z towards the
// eye) a point is inside the right plane when x + z*tan_x <= ex + ez*tan_x, and inside the
// left one when -x + z*tan_x <= ez*tan_x - ex; the extreme points along each plane's normal
// fix both planes, whose intersection gives ex and ez. Likewise for y. The eye takes the
// larger ez, so the model is centred and fills the tighter axis. The margin narrows the
// frustum so nothing touches the border. Returns false when there are no points.
bool fitPoints(const std::vector<glm::dvec3>& points, const CameraFrame& frame, double tan_x, double tan_y,
               double margin, SnapshotCamera& camera) {
  if (points.empty()) return false;
  tan_x /= margin;
  tan_y /= margin;
  constexpr double kLow = -std::numeric_limits<double>::infinity();
  double a = kLow, b = kLow, c = kLow, d = kLow;
  for (const glm::dvec3& p : points) {
    double x = glm::dot(p, frame.right), y = glm::dot(p, frame.up), z = -glm::dot(p, frame.forward);
    a = std::max(a, x + z * tan_x);
    b = std::max(b, -x + z * tan_x);
    c = std::max(c, y + z * tan_y);
    d = std::max(d, -y + z * tan_y);
  }
  const double ez = std::max((a + b) / (2.0 * tan_x), (c + d) / (2.0 * tan_y));
  double ex = (a - b) * 0.5, ey = (c - d) * 0.5;
  if (!std::isfinite(ez) || !std::isfinite(ex) || !std::isfinite(ey)) return false;
  // On the axis that did not set ez the model has room to spare; centre its projection there
  // (perspective makes the plane intersection above slightly off-centre). The sum of the
  // extreme projected offsets falls monotonically as the eye moves, so bisect for zero.
  auto centre = [&](const glm::dvec3& axis, double guess) {
    double span = 0.0;
    for (const glm::dvec3& p : points) span = std::max(span, std::abs(glm::dot(p, axis) - guess));
    double lo = guess - span, hi = guess + span;
    for (int i = 0; i < 60 && hi > lo; ++i) {
      double mid = 0.5 * (lo + hi), low = std::numeric_limits<double>::infinity(), high = -low;
      for (const glm::dvec3& p : points) {
        double depth = ez + glm::dot(p, frame.forward);  // ez - z, positive for points in front
        if (depth <= 0.0) continue;
        double offset = (glm::dot(p, axis) - mid) / depth;
        low = std::min(low, offset);
        high = std::max(high, offset);
      }
      if (low + high > 0.0) lo = mid; else hi = mid;
    }
    return 0.5 * (lo + hi);
  };
  ex = centre(frame.right, ex);
  ey = centre(frame.up, ey);
  const glm::dvec3 reference = camera.target;
  camera.target = reference + ex * frame.right + ey * frame.up;
  camera.eye = camera.target - frame.forward * ez;
  return true;
}

}  // namespace

glm::dvec3 frontFor(const glm::dvec3& up_in) {
  glm::dvec3 up = safeNormalize(up_in, {0.0, 0.0, 1.0});
  glm::dvec3 candidate = std::abs(up.z) > 0.7 ? glm::dvec3(0.0, -1.0, 0.0) : glm::dvec3(0.0, 0.0, 1.0);
  return safeNormalize(candidate - glm::dot(candidate, up) * up, {1.0, 0.0, 0.0});
}

CameraFrame cameraFrame(const SnapshotCamera& camera) {
  CameraFrame f;
  glm::dvec3 up = safeNormalize(camera.up, {0.0, 0.0, 1.0});
  f.forward = safeNormalize(camera.target - camera.eye, -frontFor(up));
  // Looking straight along the up axis: any horizontal direction will do as image-up; take the
  // conventional front so top views come out north-up.
  if (std::abs(glm::dot(f.forward, up)) > 0.9999) up = -frontFor(up) * (glm::dot(f.forward, up) > 0 ? -1.0 : 1.0);
  f.right = safeNormalize(glm::cross(f.forward, up), {1.0, 0.0, 0.0});
  f.up = glm::cross(f.right, f.forward);
  return f;
}

SnapshotCamera autoOutsideCamera(const Aabb& bounds, double aspect, const glm::dvec3& up_in, double fov_y_deg,
                                 double azimuth_deg, double elevation_deg) {
  SnapshotCamera cam;
  cam.fov_y_deg = std::clamp(fov_y_deg, 1.0, 170.0);
  cam.up = safeNormalize(up_in, {0.0, 0.0, 1.0});
  Aabb box = bounds;
  if (box.empty() || !finite(box.min) || !finite(box.max)) {
    box = Aabb{};
    box.add(glm::dvec3(-0.5));
    box.add(glm::dvec3(0.5));
  }
  cam.target = box.center();

  // Direction from the target towards the eye.
  const glm::dvec3 front = frontFor(cam.up);
  const glm::dvec3 right = glm::cross(cam.up, front);
  const double az = radians(azimuth_deg), el = radians(std::clamp(elevation_deg, -89.9, 89.9));
  const glm::dvec3 back = std::cos(el) * (std::cos(az) * front + std::sin(az) * right) + std::sin(el) * cam.up;

  // Fit the eight box corners, then make sure a flat or point-like model keeps some distance.
  SnapshotCamera probe = cam;
  probe.eye = cam.target + back;
  const CameraFrame frame = cameraFrame(probe);
  const double tan_y = std::tan(radians(cam.fov_y_deg) * 0.5);
  const double tan_x = tan_y * std::clamp(aspect, 1e-3, 1e3);
  const glm::dvec3 extent = box.extent();
  std::vector<glm::dvec3> corners;
  for (int i = 0; i < 8; ++i)
    corners.push_back(box.min - cam.target +
                      glm::dvec3(i & 1 ? extent.x : 0.0, i & 2 ? extent.y : 0.0, i & 4 ? extent.z : 0.0));
  if (!fitPoints(corners, frame, tan_x, tan_y, kFitMargin, cam)) cam.eye = cam.target + back;
  const double min_distance = std::max(glm::length(extent), 1e-6) * 0.5;
  if (glm::length(cam.eye - cam.target) < min_distance) cam.eye = cam.target + back * min_distance;
  return cam;
}

SnapshotCamera fitCameraToScene(const EmbreeScene& scene, const SnapshotCamera& camera, double aspect) {
  aspect = std::clamp(aspect, 1e-3, 1e3);
  const CameraFrame frame = cameraFrame(camera);
  const double tan_y = std::tan(radians(std::clamp(camera.fov_y_deg, 1.0, 170.0)) * 0.5);
  const double tan_x = tan_y * aspect;

  // 1. Probe: a grid with the image's aspect, about 24K rays.
  const int rows = std::clamp(static_cast<int>(std::sqrt(24000.0 / aspect)), 8, 1024);
  const int cols = std::clamp(static_cast<int>(rows * aspect), 8, 4096);
  std::vector<Ray> rays(size_t(rows) * cols);
  const glm::vec3 eye = scene.toScene(camera.eye);
  for (int y = 0; y < rows; ++y) {
    for (int x = 0; x < cols; ++x) {
      double px = (x + 0.5) / cols * 2.0 - 1.0, py = 1.0 - (y + 0.5) / rows * 2.0;
      Ray& r = rays[size_t(y) * cols + x];
      r.origin = eye;
      r.direction = glm::vec3(glm::normalize(frame.forward + px * tan_x * frame.right + py * tan_y * frame.up));
    }
  }
  std::vector<EmbreeScene::Hit> hits(rays.size());
  scene.intersect(rays, hits, true);

  // 2. Hit points relative to the current target, fitted like the box corners.
  std::vector<glm::dvec3> points;
  for (size_t i = 0; i < rays.size(); ++i)
    if (hits[i].hit)
      points.push_back(camera.eye + glm::dvec3(rays[i].direction) * double(hits[i].t) - camera.target);
  SnapshotCamera out = camera;
  if (!fitPoints(points, frame, tan_x, tan_y, kFitMargin, out)) return camera;
  return out;
}

glm::dvec3 parseVec3(std::string_view text) {
  glm::dvec3 v(0.0);
  size_t pos = 0;
  for (int axis = 0; axis < 3; ++axis) {
    while (pos < text.size() && text[pos] == ' ') ++pos;
    const char* begin = text.data() + pos;
    const char* end = text.data() + text.size();
    if (pos < text.size() && text[pos] == '+') ++begin;  // from_chars refuses a leading '+'
    double value = 0.0;
    auto [ptr, ec] = std::from_chars(begin, end, value);
    if (ec != std::errc() || !std::isfinite(value))
      throw std::invalid_argument("expected three numbers x,y,z but got '" + std::string(text) + "'");
    v[axis] = value;
    pos = static_cast<size_t>(ptr - text.data());
    while (pos < text.size() && text[pos] == ' ') ++pos;
    if (axis < 2) {
      if (pos >= text.size() || text[pos] != ',')
        throw std::invalid_argument("expected three numbers x,y,z but got '" + std::string(text) + "'");
      ++pos;
    }
  }
  if (pos != text.size())
    throw std::invalid_argument("expected three numbers x,y,z but got '" + std::string(text) + "'");
  return v;
}

}  // namespace tw
