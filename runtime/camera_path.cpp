// Camera paths: the text reader and writer, interpolation between key frames, and the generated
// orbit, fly-through and random-walk paths `render` uses when it is given no path file.
#include "camera_path.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>
#include <string_view>
#include <system_error>

#include "file_reader.h"
#include "format_error.h"
#include "text_scan.h"

namespace tw {
namespace {

constexpr std::string_view kHeaderPrefix = "# terawalk camera path";
constexpr int kVersion = 1;
constexpr int kFields = 7;  // t x y z yaw_deg pitch_deg fov_y_deg
constexpr double kDegToRad = std::numbers::pi / 180.0;
constexpr double kRadToDeg = 180.0 / std::numbers::pi;

std::string_view trimmed(std::string_view s) {
  text::skipBlanks(s);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
  return s;
}

// Shown in messages; keeps a corrupted line from flooding the terminal.
std::string quoted(std::string_view token) {
  std::string out = "'";
  for (char c : token.substr(0, 32)) out += (c >= 32 && c < 127) ? c : '?';
  if (token.size() > 32) out += "...";
  return out + "'";
}

bool looksNonFinite(std::string_view token) {
  if (!token.empty() && (token[0] == '+' || token[0] == '-')) token.remove_prefix(1);
  if (token.size() < 3) return false;
  auto lower = [](char c) { return static_cast<char>(c >= 'A' && c <= 'Z' ? c + 32 : c); };
  std::string head{lower(token[0]), lower(token[1]), lower(token[2])};
  return head == "inf" || head == "nan";
}

// Parses one key frame line into `key`; throws FormatError at `line_number`.
CameraKey parseKey(std::string_view line, const std::string& file, uint64_t line_number) {
  static constexpr const char* kNames[kFields] = {"time",    "x",         "y",        "z",
                                                  "yaw_deg", "pitch_deg", "fov_y_deg"};
  double values[kFields];
  int count = 0;
  for (std::string_view token = text::nextToken(line); !token.empty();
       token = text::nextToken(line)) {
    if (count == kFields)
      throw FormatError::atLine(file, line_number,
                                "expected 7 fields (t x y z yaw_deg pitch_deg fov_y_deg), found more");
    if (looksNonFinite(token))
      throw FormatError::atLine(file, line_number,
                                std::string("non-finite ") + kNames[count] + " " + quoted(token));
    std::string_view rest = token;
    double value = 0.0;
    if (!text::parseDouble(rest, value) || !rest.empty())
      throw FormatError::atLine(file, line_number,
                                std::string(kNames[count]) + " is not a number: " + quoted(token));
    if (!std::isfinite(value))
      throw FormatError::atLine(file, line_number,
                                std::string("non-finite ") + kNames[count] + " " + quoted(token));
    values[count++] = value;
  }
  if (count != kFields)
    throw FormatError::atLine(file, line_number,
                              "expected 7 fields (t x y z yaw_deg pitch_deg fov_y_deg), found " +
                                  std::to_string(count));
  if (values[5] < -90.0 || values[5] > 90.0)
    throw FormatError::atLine(file, line_number, "pitch_deg outside [-90, 90]");
  if (!(values[6] > 0.0 && values[6] < 180.0))
    throw FormatError::atLine(file, line_number, "fov_y_deg outside (0, 180)");
  CameraKey key;
  key.time_s = values[0];
  key.camera.position = {values[1], values[2], values[3]};
  key.camera.yaw_rad = values[4] * kDegToRad;
  key.camera.pitch_rad = values[5] * kDegToRad;
  key.camera.fov_y_rad = values[6] * kDegToRad;
  return key;
}

void checkHeader(std::string_view line, const std::string& file) {
  constexpr std::string_view kBom = "\xEF\xBB\xBF";  // some editors start UTF-8 files with it
  if (line.substr(0, kBom.size()) == kBom) line.remove_prefix(kBom.size());
  line = trimmed(line);
  if (line.substr(0, kHeaderPrefix.size()) != kHeaderPrefix)
    throw FormatError::atLine(file, 1,
                              "not a camera path: the first line must be '# terawalk camera path 1'");
  std::string_view version = trimmed(line.substr(kHeaderPrefix.size()));
  int64_t value = 0;
  std::string_view rest = version;
  if (version.empty() || !text::parseInt64(rest, value) || !rest.empty())
    throw FormatError::atLine(file, 1, "camera path header has no version number");
  if (value != kVersion)
    throw FormatError::atLine(file, 1,
                              "unsupported camera path version " + std::string(version) +
                                  " (this build reads version 1)");
}

void appendNumber(std::string& out, double value) {
  char buffer[64];
  // Shortest form that reads back as the same double.
  auto result = std::to_chars(buffer, buffer + sizeof(buffer), value);
  out.append(buffer, result.ptr);
}

// Hermite basis on one segment; positions are offset from p0 so plant coordinates keep their
// precision (the curve is computed in metres from the segment start).
glm::dvec3 hermite(const glm::dvec3& p0, const glm::dvec3& p1, const glm::dvec3& m0,
                   const glm::dvec3& m1, double dt, double s) {
  double s2 = s * s, s3 = s2 * s;
  double h10 = s3 - 2.0 * s2 + s;
  double h01 = -2.0 * s3 + 3.0 * s2;
  double h11 = s3 - s2;
  return p0 + (p1 - p0) * h01 + m0 * (h10 * dt) + m1 * (h11 * dt);
}

// Catmull-Rom tangent at key i for non-uniform times (one-sided at the ends), metres/second.
glm::dvec3 tangent(const std::vector<CameraKey>& keys, size_t i) {
  size_t a = i == 0 ? 0 : i - 1;
  size_t b = std::min(i + 1, keys.size() - 1);
  double dt = keys[b].time_s - keys[a].time_s;
  if (dt <= 0.0) return glm::dvec3(0.0);
  return (keys[b].camera.position - keys[a].camera.position) / dt;
}

void checkBoundsAndFrames(const Aabb& bounds, int frames, double fps) {
  if (bounds.empty()) throw std::invalid_argument("camera path: empty bounds");
  if (frames < 1) throw std::invalid_argument("camera path: frames must be >= 1");
  if (!(fps > 0.0) || !std::isfinite(fps)) throw std::invalid_argument("camera path: fps must be > 0");
}

}  // namespace

double CameraPath::durationS() const {
  return keys.size() <= 1 ? 0.0 : keys.back().time_s - keys.front().time_s;
}

Camera CameraPath::sample(double time_s, const Camera& base) const {
  Camera camera = base;
  if (keys.empty()) return camera;
  auto take = [&](const CameraKey& key) {
    camera.position = key.camera.position;
    camera.yaw_rad = key.camera.yaw_rad;
    camera.pitch_rad = key.camera.pitch_rad;
    camera.fov_y_rad = key.camera.fov_y_rad;
    return camera;
  };
  // Clamped to the path (NaN lands on the first key).
  if (!(time_s > keys.front().time_s)) return take(keys.front());
  if (time_s >= keys.back().time_s) return take(keys.back());
  auto next = std::upper_bound(keys.begin(), keys.end(), time_s,
                               [](double t, const CameraKey& k) { return t < k.time_s; });
  size_t i1 = static_cast<size_t>(next - keys.begin());
  size_t i0 = i1 - 1;
  const Camera& c0 = keys[i0].camera;
  const Camera& c1 = keys[i1].camera;
  double dt = keys[i1].time_s - keys[i0].time_s;
  double s = (time_s - keys[i0].time_s) / dt;
  camera.position = hermite(c0.position, c1.position, tangent(keys, i0), tangent(keys, i1), dt, s);
  double yaw_delta = std::remainder(c1.yaw_rad - c0.yaw_rad, 2.0 * std::numbers::pi);
  camera.yaw_rad = c0.yaw_rad + yaw_delta * s;
  camera.pitch_rad = c0.pitch_rad + (c1.pitch_rad - c0.pitch_rad) * s;
  camera.fov_y_rad = c0.fov_y_rad + (c1.fov_y_rad - c0.fov_y_rad) * s;
  return camera;
}

CameraPath readCameraPath(const std::filesystem::path& path) {
  FileReader reader(path);  // throws FormatError (a std::runtime_error) when unreadable
  const std::string& file = reader.name();
  CameraPath result;
  std::string_view line;
  if (!reader.readLine(line))
    throw FormatError::atLine(file, 1, "empty file: expected '# terawalk camera path 1'");
  checkHeader(line, file);
  while (reader.readLine(line)) {
    std::string_view content = trimmed(line);
    if (content.empty() || content.front() == '#') continue;
    CameraKey key = parseKey(content, file, reader.line());
    if (!result.keys.empty() && !(key.time_s > result.keys.back().time_s))
      throw FormatError::atLine(file, reader.line(),
                                "time does not increase (previous key is at " +
                                    std::to_string(result.keys.back().time_s) + " s)");
    result.keys.push_back(key);
  }
  if (result.keys.empty())
    throw FormatError::atLine(file, reader.line(), "camera path has no key frames");
  return result;
}

void writeCameraPath(const CameraPath& path, const std::filesystem::path& file) {
  std::string text = "# terawalk camera path 1\n# t x y z yaw_deg pitch_deg fov_y_deg\n";
  for (const CameraKey& key : path.keys) {
    const double values[kFields] = {key.time_s,
                                    key.camera.position.x,
                                    key.camera.position.y,
                                    key.camera.position.z,
                                    key.camera.yaw_rad * kRadToDeg,
                                    key.camera.pitch_rad * kRadToDeg,
                                    key.camera.fov_y_rad * kRadToDeg};
    for (int i = 0; i < kFields; ++i) {
      if (i) text += ' ';
      appendNumber(text, values[i]);
    }
    text += '\n';
  }
  // A recorder killed mid-write must not leave half a path under the final name.
  std::filesystem::path temporary = file;
  temporary += ".tmp";
  {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    out.write(text.data(), static_cast<std::streamsize>(text.size()));
    out.close();
    if (!out) throw std::runtime_error("cannot write camera path " + temporary.string());
  }
  std::error_code ec;
  std::filesystem::rename(temporary, file, ec);
  if (ec) {
    std::filesystem::remove(temporary, ec);
    throw std::runtime_error("cannot write camera path " + file.string() + ": " + ec.message());
  }
}

CameraPath generateOrbitPath(const Aabb& bounds, int frames, double fps) {
  checkBoundsAndFrames(bounds, frames, fps);
  constexpr double kFovY = 60.0 * kDegToRad;
  constexpr double kElevation = 20.0 * kDegToRad;  // "slightly above"
  constexpr double kMargin = 1.1;
  glm::dvec3 center = bounds.center();
  double radius = std::max(glm::length(bounds.extent()) * 0.5, 1e-3);
  // The bounding sphere fills the vertical field of view (the narrower one for aspect >= 1).
  double distance = kMargin * radius / std::sin(kFovY * 0.5);
  CameraPath path;
  path.keys.reserve(static_cast<size_t>(frames));
  for (int i = 0; i < frames; ++i) {
    double angle = 2.0 * std::numbers::pi * i / frames;
    CameraKey key;
    key.time_s = i / fps;
    key.camera.fov_y_rad = kFovY;
    key.camera.position = center + distance * glm::dvec3(std::cos(kElevation) * std::cos(angle),
                                                          std::cos(kElevation) * std::sin(angle),
                                                          std::sin(kElevation));
    key.camera.lookAt(center);
    path.keys.push_back(key);
  }
  return path;
}

CameraPath generateFlythroughPath(const Aabb& bounds, int frames, double fps) {
  checkBoundsAndFrames(bounds, frames, fps);
  glm::dvec3 extent = bounds.extent();
  glm::dvec3 center = bounds.center();
  int axis = extent.x >= extent.y ? 0 : 1;
  double margin = std::max(extent[axis] * 0.05, 1.0);
  glm::dvec3 start = center, end = center;
  start[axis] = bounds.min[axis] - margin;
  end[axis] = bounds.max[axis] + margin;
  start.z = end.z = bounds.min.z + extent.z / 3.0;
  double yaw = axis == 0 ? 0.0 : std::numbers::pi / 2.0;
  CameraPath path;
  path.keys.reserve(static_cast<size_t>(frames));
  for (int i = 0; i < frames; ++i) {
    double s = frames == 1 ? 0.0 : static_cast<double>(i) / (frames - 1);
    CameraKey key;
    key.time_s = i / fps;
    key.camera.position = start + (end - start) * s;
    key.camera.yaw_rad = yaw;
    key.camera.pitch_rad = 0.0;
    key.camera.fov_y_rad = 60.0 * kDegToRad;
    path.keys.push_back(key);
  }
  return path;
}

namespace {

// Uniform doubles in [0, 1) from a 64-bit Mersenne twister, mapped by hand: the standard's
// distributions differ between library versions, and a soak path must be the same everywhere.
class WalkRandom {
 public:
  explicit WalkRandom(uint64_t seed) : engine_(seed) {}
  double unit() { return double(engine_() >> 11) * 0x1.0p-53; }
  double between(double lo, double hi) { return lo + (hi - lo) * unit(); }
  int frames(int lo, int hi) { return lo + int(unit() * (hi - lo + 1)); }

 private:
  std::mt19937_64 engine_;
};

}  // namespace

CameraPath generateRandomWalkPath(const Aabb& bounds, int frames, double fps, uint64_t seed) {
  checkBoundsAndFrames(bounds, frames, fps);
  const glm::dvec3 extent = bounds.extent();
  const glm::dvec3 lo = bounds.min - extent * 0.1, hi = bounds.max + extent * 0.1;
  const double length = std::max({extent.x, extent.y, extent.z, 1.0});
  WalkRandom random(seed);
  auto randomPoint = [&] {
    return glm::dvec3(random.between(bounds.min.x, bounds.max.x),
                      random.between(bounds.min.y, bounds.max.y),
                      random.between(bounds.min.z, bounds.max.z));
  };
  auto lookAt = [](Camera& c, const glm::dvec3& target) {
    const glm::dvec3 d = target - c.position;
    if (glm::length(glm::dvec2(d)) > 0.0) c.yaw_rad = std::atan2(d.y, d.x);
    c.pitch_rad = std::clamp(std::atan2(d.z, glm::length(glm::dvec2(d))), -0.6, 0.6);
  };

  Camera camera;
  camera.position = bounds.center();
  camera.fov_y_rad = 60.0 * kDegToRad;
  CameraPath path;
  path.keys.reserve(size_t(frames));
  auto key = [&] {
    camera.position = glm::clamp(camera.position, lo, hi);
    path.keys.push_back(CameraKey{double(path.keys.size()) / fps, camera});
  };
  while (int(path.keys.size()) < frames) {
    const double pick = random.unit();
    if (pick < 0.2) {  // teleport, looking at another point of the model, then look around
      camera.position = randomPoint();
      lookAt(camera, randomPoint());
      const int hold = random.frames(10, 30);
      const double drift = random.between(-0.5, 0.5) / fps;
      for (int i = 0; i < hold; ++i, camera.yaw_rad += drift) key();
    } else if (pick < 0.5) {  // fast flight to a random point, looking where it goes
      const glm::dvec3 from = camera.position, to = randomPoint();
      const int steps = std::max(1, int(glm::length(to - from) / length * fps));
      const glm::dvec3 d = to - from;
      lookAt(camera, to);
      for (int i = 1; i <= steps; ++i) {
        camera.position = from + d * (double(i) / steps);
        key();
      }
    } else if (pick < 0.75) {  // a whole turn in place, either way
      const int steps = random.frames(int(fps), int(2 * fps));
      const double turn = (random.unit() < 0.5 ? -2.0 : 2.0) * std::numbers::pi / steps;
      for (int i = 0; i < steps; ++i, camera.yaw_rad += turn) key();
    } else {  // a walk straight ahead, level
      camera.pitch_rad = 0.0;
      const glm::dvec3 step(std::cos(camera.yaw_rad) * 1.5 / fps,
                            std::sin(camera.yaw_rad) * 1.5 / fps, 0.0);
      const int steps = random.frames(int(fps), int(3 * fps));
      for (int i = 0; i < steps; ++i, camera.position += step) key();
    }
    camera.yaw_rad = std::remainder(camera.yaw_rad, 2.0 * std::numbers::pi);
  }
  path.keys.resize(size_t(frames));
  return path;
}

namespace {

// A camera's angles as numbers a spline can pass through: yaw unwrapped against the previous key.
struct SmoothKey {
  double time_s;
  glm::dvec3 position;
  double yaw, pitch, fov;
};

// The mean of the keys within [t - half, t + half], yaw unwrapped around `near_yaw`.
SmoothKey meanAround(const CameraPath& path, double t, double half, double near_yaw) {
  SmoothKey mean{t, glm::dvec3(0.0), 0.0, 0.0, 0.0};
  int n = 0;
  const glm::dvec3 anchor = path.keys.front().camera.position;  // keeps plant coordinates exact
  for (const CameraKey& k : path.keys) {
    if (k.time_s < t - half || k.time_s > t + half) continue;
    mean.position += k.camera.position - anchor;
    mean.yaw += near_yaw + std::remainder(k.camera.yaw_rad - near_yaw, 2.0 * std::numbers::pi);
    mean.pitch += k.camera.pitch_rad;
    mean.fov += k.camera.fov_y_rad;
    ++n;
  }
  if (n == 0) {  // a gap in the recording: the path's own interpolation
    const Camera c = path.sample(t);
    return {t, c.position, near_yaw + std::remainder(c.yaw_rad - near_yaw, 2.0 * std::numbers::pi), c.pitch_rad,
            c.fov_y_rad};
  }
  mean.position = anchor + mean.position / double(n);
  mean.yaw /= n;
  mean.pitch /= n;
  mean.fov /= n;
  return mean;
}

// Uniform Catmull-Rom through p1..p2 with neighbours p0, p3, at s in [0, 1].
double catmullRom(double p0, double p1, double p2, double p3, double s) {
  return 0.5 * ((2.0 * p1) + (-p0 + p2) * s + (2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3) * s * s +
                (-p0 + 3.0 * p1 - 3.0 * p2 + p3) * s * s * s);
}

}  // namespace

CameraPath smoothCameraPath(const CameraPath& path, double key_interval_s, double fps) {
  if (!(key_interval_s > 0.0) || !(fps > 0.0) || !std::isfinite(key_interval_s) || !std::isfinite(fps))
    throw std::invalid_argument("smoothing a path needs an interval and a rate above 0");
  if (path.keys.size() < 2) return path;
  const double t0 = path.keys.front().time_s, t1 = path.keys.back().time_s;
  if ((t1 - t0) * fps > 1e7) throw std::invalid_argument("the smoothed path would have more than 10^7 keys");
  // Control keys: the ends as recorded, the mean of the walk every interval between them.
  std::vector<SmoothKey> control;
  auto exact = [](const CameraKey& k, double near_yaw) {
    return SmoothKey{k.time_s, k.camera.position,
                     near_yaw + std::remainder(k.camera.yaw_rad - near_yaw, 2.0 * std::numbers::pi),
                     k.camera.pitch_rad, k.camera.fov_y_rad};
  };
  control.push_back(exact(path.keys.front(), path.keys.front().camera.yaw_rad));
  const int inner = std::max(0, int(std::ceil((t1 - t0) / key_interval_s)) - 1);
  const double step = (t1 - t0) / (inner + 1);
  for (int i = 1; i <= inner; ++i) control.push_back(meanAround(path, t0 + i * step, 0.5 * step, control.back().yaw));
  control.push_back(exact(path.keys.back(), control.back().yaw));

  CameraPath out;
  const int frames = int(std::floor((t1 - t0) * fps + 1e-9)) + 1;
  out.keys.reserve(size_t(frames));
  const glm::dvec3 anchor = control.front().position;
  for (int f = 0; f < frames; ++f) {
    const double t = std::min(t1, t0 + f / fps);
    const size_t i = std::min(size_t((t - t0) / step), control.size() - 2);
    const double s = std::clamp((t - control[i].time_s) / (control[i + 1].time_s - control[i].time_s), 0.0, 1.0);
    const SmoothKey& p0 = control[i == 0 ? 0 : i - 1];
    const SmoothKey& p1 = control[i];
    const SmoothKey& p2 = control[i + 1];
    const SmoothKey& p3 = control[std::min(i + 2, control.size() - 1)];
    auto along = [&](auto get) { return catmullRom(get(p0), get(p1), get(p2), get(p3), s); };
    CameraKey key;
    key.time_s = t;
    key.camera.position = anchor + glm::dvec3(along([&](const SmoothKey& k) { return k.position.x - anchor.x; }),
                                              along([&](const SmoothKey& k) { return k.position.y - anchor.y; }),
                                              along([&](const SmoothKey& k) { return k.position.z - anchor.z; }));
    key.camera.yaw_rad = std::remainder(along([](const SmoothKey& k) { return k.yaw; }), 2.0 * std::numbers::pi);
    key.camera.pitch_rad = std::clamp(along([](const SmoothKey& k) { return k.pitch; }), -1.55, 1.55);
    key.camera.fov_y_rad = std::clamp(along([](const SmoothKey& k) { return k.fov; }), 0.01, 3.1);
    if (!out.keys.empty() && key.time_s <= out.keys.back().time_s) continue;  // times strictly increase
    out.keys.push_back(key);
  }
  return out;
}

}  // namespace tw
