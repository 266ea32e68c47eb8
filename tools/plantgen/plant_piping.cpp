// Pipe runs: straight parametric cylinders, torus elbows joined exactly at the bends, flanges
// and in-line valves (revolved body, cone bonnet, stem, handwheel torus or box actuator).
#include <algorithm>
#include <cmath>

#include "plant_parts.h"

namespace tw::plant {
namespace {

constexpr float kMaxSpoolM = 12.0f;  // straight pipe comes in spools of at most this length
constexpr float kPi = 3.14159265358979f;

float flangeRadius(float pipe_radius) { return pipe_radius * 1.45f + 0.025f; }
float flangeThickness(float pipe_radius) { return 0.03f + pipe_radius * 0.25f; }

void emitFlange(Emitter& out, const PipeLine& line, const glm::dvec3& at, const glm::vec3& dir,
                uint32_t& flange_number) {
  float h = flangeThickness(line.radius_m);
  out.primitive(pipeLayer(line), line.key, format("flange %s #%u", line.key.c_str(), ++flange_number),
                alongAxis(at - glm::dvec3(dir) * (0.5 * h), dir),
                Cylinder{flangeRadius(line.radius_m), h, true});
}

}  // namespace

uint32_t pipeLayer(const PipeLine& line) { return service(line.service).layer; }

Transform alongAxis(const glm::dvec3& origin, const glm::vec3& dir) {
  glm::vec3 z = glm::normalize(dir);
  glm::vec3 helper = std::fabs(z.z) < 0.9f ? glm::vec3(0, 0, 1) : glm::vec3(1, 0, 0);
  glm::vec3 x = glm::normalize(glm::cross(helper, z));
  glm::vec3 y = glm::cross(z, x);
  return basis(origin, x, y, z);
}

namespace {

// One straight stretch between two bends: spools, and possibly a valve in its middle.
struct Straight {
  glm::dvec3 from;
  glm::vec3 dir;
  float length;
};

void emitPipe(Emitter& out, const PipeLine& line, const glm::dvec3& from, const glm::vec3& dir,
              float length, uint32_t& segment) {
  float done = 0.0f;
  while (length - done > 1e-3f) {
    float piece = std::min(kMaxSpoolM, length - done);
    // Avoid a stub spool at the end: split the last two evenly.
    if (length - done - piece > 0.0f && length - done - piece < 1.0f)
      piece = (length - done) * 0.5f;
    out.primitive(pipeLayer(line), line.key, format("pipe %s seg %u", line.key.c_str(), ++segment),
                  alongAxis(from + glm::dvec3(dir) * double(done), dir),
                  Cylinder{line.radius_m, piece, false});
    done += piece;
  }
}

void emitValve(Emitter& out, Random& rng, const PipeLine& line, const glm::dvec3& start,
               const glm::vec3& dir, float length, uint32_t& flange_number) {
  const float r = line.radius_m;
  const float h = flangeThickness(r);
  bool actuated = rng.chance(0.3f);
  uint32_t number = out.next_valve_number++;
  std::string key = format("%s-%05u", actuated ? "XV" : "HV", number);
  ProjectRecord rec;
  rec.db_key = key;
  rec.type = "valve";
  rec.line_number = std::to_string(line.number);
  rec.service = service(line.service).name;
  rec.material = service(line.service).material;
  rec.nominal_diameter_mm = pipeSize(line.size).nominal_mm;
  rec.design_pressure_bar = service(line.service).pressure_bar;
  rec.design_temperature_c = service(line.service).temperature_c;
  rec.description = format("%s valve on line %s", actuated ? "actuated ball" : "manual gate",
                           line.key.c_str());
  out.record(rec);

  emitFlange(out, line, start + glm::dvec3(dir) * double(h * 0.5f), dir, flange_number);
  emitFlange(out, line, start + glm::dvec3(dir) * double(length - h * 0.5f), dir, flange_number);
  // Globe-shaped body between the flanges, revolved about the pipe axis.
  float body = length - 2.0f * h;
  float rb = r * 1.25f, rw = r * 1.8f;
  Revolution shell;
  shell.profile = {{0.0f, 0.0f},           {rb, 0.0f},           {rb, 0.15f * body},
                   {rw, 0.35f * body},     {rw, 0.65f * body},   {rb, 0.85f * body},
                   {rb, body},             {0.0f, body}};
  glm::dvec3 body_start = start + glm::dvec3(dir) * double(h);
  out.primitive(kLayerValves, key, format("valve %s body", key.c_str()),
                alongAxis(body_start, dir), shell);
  // Stem up (or sideways on a vertical pipe), with a bonnet cone.
  glm::vec3 up = std::fabs(dir.z) < 0.7f ? glm::vec3(0, 0, 1)
                                         : glm::normalize(glm::cross(dir, glm::vec3(1, 0, 0)));
  glm::dvec3 mid = start + glm::dvec3(dir) * double(length * 0.5f);
  glm::dvec3 bonnet_base = mid + glm::dvec3(up) * double(rw * 0.8f);
  float bonnet_h = 0.05f + r * 1.2f;
  out.primitive(kLayerValves, key, format("valve %s bonnet", key.c_str()),
                alongAxis(bonnet_base, up), Cone{rw * 0.75f, rw * 0.35f, bonnet_h, true});
  float stem_r = std::max(0.012f, r * 0.15f);
  float stem_h = 0.15f + r * 2.5f;
  glm::dvec3 stem_base = bonnet_base + glm::dvec3(up) * double(bonnet_h);
  out.primitive(kLayerValves, key, format("valve %s stem", key.c_str()),
                alongAxis(stem_base, up), Cylinder{stem_r, stem_h, true});
  glm::dvec3 top = stem_base + glm::dvec3(up) * double(stem_h);
  if (actuated) {
    float a = 0.12f + r * 1.2f;
    Transform t = alongAxis(top + glm::dvec3(up) * double(a * 0.5f), up);
    out.primitive(kLayerValves, key, format("valve %s actuator", key.c_str()), t,
                  Box{glm::vec3(a * 0.7f, a * 0.5f, a * 0.5f)});
  } else {
    float wheel = std::clamp(r * 2.0f, 0.09f, 0.35f);
    out.primitive(kLayerValves, key, format("valve %s handwheel", key.c_str()),
                  alongAxis(top, up), TorusSegment{wheel, 0.012f + r * 0.04f, 2.0f * kPi});
  }
}

}  // namespace

bool emitRun(Emitter& out, Random& rng, PipeLine& line, const std::vector<glm::dvec3>& points,
             const RunStyle& style) {
  const size_t n = points.size();
  if (n < 2) return false;
  const float r = line.radius_m;
  const float bend_r = std::max(1.5f * pipeSize(line.size).nominal_mm * 0.001f, r * 1.3f);
  // Trim at every corner (0 where the run goes straight on), checked before emitting anything.
  std::vector<float> trim(n, 0.0f), sweep(n, 0.0f);
  for (size_t i = 1; i + 1 < n; ++i) {
    glm::dvec3 a = glm::normalize(points[i] - points[i - 1]);
    glm::dvec3 b = glm::normalize(points[i + 1] - points[i]);
    double c = std::clamp(glm::dot(a, b), -1.0, 1.0);
    double angle = std::acos(c);
    if (angle > 2.7) return false;  // a U-turn cannot be one elbow
    sweep[i] = static_cast<float>(angle);
    trim[i] = angle < 1e-4 ? 0.0f : bend_r * static_cast<float>(std::tan(angle * 0.5));
  }
  for (size_t i = 0; i + 1 < n; ++i) {
    double length = glm::length(points[i + 1] - points[i]);
    if (length < trim[i] + trim[i + 1] + 0.02) return false;
  }

  recordLine(out, line);
  uint32_t segment = 0, elbow = 0, flange = 0, valves = 0;
  const float fh = flangeThickness(r);
  for (size_t i = 0; i + 1 < n; ++i) {
    glm::vec3 dir = glm::vec3(glm::normalize(points[i + 1] - points[i]));
    float length = static_cast<float>(glm::length(points[i + 1] - points[i]));
    glm::dvec3 from = points[i] + glm::dvec3(dir) * double(trim[i]);
    float straight = length - trim[i] - trim[i + 1];
    if (i == 0 && style.flange_start) emitFlange(out, line, points[0] + glm::dvec3(dir) * double(fh * 0.5f), dir, flange);
    float valve_len = std::max(0.25f, 3.2f * r + 0.12f);
    if (valves < style.max_valves && straight > valve_len + 1.0f && rng.chance(style.valve_chance)) {
      float before = (straight - valve_len) * rng.uniform(0.3f, 0.7f);
      emitPipe(out, line, from, dir, before, segment);
      glm::dvec3 vstart = from + glm::dvec3(dir) * double(before);
      emitValve(out, rng, line, vstart, dir, valve_len, flange);
      emitPipe(out, line, vstart + glm::dvec3(dir) * double(valve_len), dir,
               straight - before - valve_len, segment);
      ++valves;
    } else {
      emitPipe(out, line, from, dir, straight, segment);
    }
    if (i + 2 == n && style.flange_end)
      emitFlange(out, line, points[n - 1] - glm::dvec3(dir) * double(fh * 0.5f), dir, flange);
    // Elbow at the far corner. Torus frame: arc in local XY from +X turning CCW about +Z, so
    // local X points from the bend centre to the elbow start, local Y along the incoming pipe.
    size_t c = i + 1;
    if (c + 1 < n && trim[c] > 0.0f) {
      glm::dvec3 a = glm::dvec3(dir);
      glm::dvec3 b = glm::normalize(points[c + 1] - points[c]);
      glm::dvec3 nrm = glm::normalize(b - a * glm::dot(a, b));
      glm::dvec3 start = points[c] - a * double(trim[c]);
      glm::dvec3 centre = start + nrm * double(bend_r);
      glm::vec3 x = glm::vec3(-nrm), y = glm::vec3(a);
      out.primitive(pipeLayer(line), line.key, format("elbow %s #%u", line.key.c_str(), ++elbow),
                    basis(centre, x, y, glm::cross(x, y)), TorusSegment{bend_r, r, sweep[c]});
    }
  }
  return true;
}

}  // namespace tw::plant
