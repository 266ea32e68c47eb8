// Camera paths: the small text format the viewer records and `render` / `view` replay, and the
// paths `render` can generate (an orbit around the model, a fly-through of it, a random walk).
//
// Format (docs/runtime.md is the spec), UTF-8 text, one key frame per line:
//   # terawalk camera path 1        <- required first line (the version)
//   # any other line starting with '#' is a comment; blank lines are ignored
//   t x y z yaw_deg pitch_deg fov_y_deg
// t in seconds, strictly increasing; x y z world metres (printed with enough digits to
// round-trip a double, e.g. %.17g or std::to_chars); angles in degrees. Readers reject anything
// else with FormatError naming the file, the line and the reason.
#pragma once

#include <cstdint>
#include <filesystem>
#include <vector>

#include "bounds.h"
#include "camera.h"

namespace tw {

struct CameraKey {
  double time_s = 0.0;
  Camera camera;  // position, yaw, pitch, fov (near/far are not stored)
};

struct CameraPath {
  std::vector<CameraKey> keys;  // time strictly increasing

  double durationS() const;  // last key time - first key time; 0 for <= 1 key
  // Camera at time t (clamped to the path): positions interpolated (Catmull-Rom or linear, in
  // double), yaw along the shorter arc, pitch and fov linearly. `base` supplies near/far.
  Camera sample(double time_s, const Camera& base = {}) const;
};

// Throws FormatError(file, line, reason) on bad input, std::runtime_error if unreadable.
CameraPath readCameraPath(const std::filesystem::path& path);
// Writes atomically enough for a recorder (temporary file + rename). Throws std::runtime_error.
void writeCameraPath(const CameraPath& path, const std::filesystem::path& file);

// A circle around `bounds` (world), looking at its centre from slightly above, `frames` keys
// spaced 1/fps apart; the radius frames the whole model at fov 60.
CameraPath generateOrbitPath(const Aabb& bounds, int frames, double fps = 30.0);
// A fly-through: enters the bounds from one end at about a third of its height, flies along the
// longest horizontal axis through the middle and out of the far end, looking ahead.
CameraPath generateFlythroughPath(const Aabb& bounds, int frames, double fps = 30.0);
// A random walk for soak runs: one key per frame, in segments drawn from `seed` (the same path on
// every machine): teleports to a random point of the bounds looking at another, fast flights to
// a random point (about the model's length a second), turns in place (a whole turn in one to two
// seconds) and walks ahead at 1.5 m/s, always inside the bounds grown by a tenth.
CameraPath generateRandomWalkPath(const Aabb& bounds, int frames, double fps = 30.0,
                                  uint64_t seed = 1);

// A steadier path along the same walk, for a film from a recorded one: control keys every
// `key_interval_s` (each the mean of the recorded keys within half an interval of it, so hand
// jitter averages out; the first and last keys kept as they are), then a Catmull-Rom spline
// through them for the position and for yaw (unwrapped), pitch and field of view, sampled `fps`
// times a second from the first key's time to the last's. Throws std::invalid_argument for an
// interval or rate not above 0, or more than 10^7 keys out.
CameraPath smoothCameraPath(const CameraPath& path, double key_interval_s, double fps);

}  // namespace tw
