// The snapshot camera: a pinhole in world coordinates, and the automatic "outside" view that
// frames a whole model.
#pragma once

#include <string_view>

#include <glm/glm.hpp>

#include "bounds.h"
#include "embree_scene.h"

namespace tw {

struct SnapshotCamera {
  glm::dvec3 eye{0.0, -10.0, 5.0};  // world coordinates, scene units
  glm::dvec3 target{0.0};           // the point at the image centre
  glm::dvec3 up{0.0, 0.0, 1.0};     // need not be unit or orthogonal to the view direction
  double fov_y_deg = 45.0;          // vertical field of view
};

// Orthonormal camera frame: forward (eye to target), right, and up in the image. Degenerate
// input (eye == target, up parallel to the view) falls back to a usable frame, never NaN.
struct CameraFrame {
  glm::dvec3 forward, right, up;
};
CameraFrame cameraFrame(const SnapshotCamera& camera);

// A conventional front direction for an up axis: -Y for Z-up (CAD, plants), +Z for Y-up
// (OBJ scans, glTF). The auto view and the sun are placed relative to it.
glm::dvec3 frontFor(const glm::dvec3& up);

// The whole model in frame, seen from `azimuth_deg` (0 = straight from the front, positive
// turns to the right) and `elevation_deg` above the horizon. The eye is the closest, and the
// target the most central, that keep all eight box corners inside the frustum (plus an 8%
// margin) for the given aspect (width / height). Empty bounds give a unit view of the origin.
SnapshotCamera autoOutsideCamera(const Aabb& bounds, double aspect, const glm::dvec3& up,
                                 double fov_y_deg = 45.0, double azimuth_deg = 35.0,
                                 double elevation_deg = 30.0);

// Tightens an automatic camera on the geometry itself: box corners overestimate what a slanted
// or hollow model covers on screen. Casts a coarse probe grid (about 24K rays) through
// `camera`, then moves the target to the middle of what was hit and the eye along the same
// direction to the smallest distance that keeps every hit point in frame (8% margin). Returns
// `camera` unchanged when the probe hits nothing. `scene` must be committed.
SnapshotCamera fitCameraToScene(const EmbreeScene& scene, const SnapshotCamera& camera, double aspect);

// Parses "x,y,z" (spaces allowed around the numbers). Throws std::invalid_argument naming the
// text when it is not three finite numbers.
glm::dvec3 parseVec3(std::string_view text);

}  // namespace tw
