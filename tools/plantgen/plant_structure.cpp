// Steel and access: I-beam extrusions, tubular bracing, plates and walls as boxes, and the many
// small parts real models are full of (grating panels, stair treads, handrail posts and rails,
// cable tray sections, light fittings), each a separate object.
#include <algorithm>
#include <cmath>

#include "plant_parts.h"

namespace tw::plant {

std::vector<glm::vec2> iProfile(float depth, float width) {
  const float h = depth * 0.5f, b = width * 0.5f;
  const float tf = std::max(0.008f, depth * 0.06f);  // flange thickness
  const float tw = std::max(0.006f, depth * 0.035f) * 0.5f;  // half web thickness
  // Counter-clockwise from the bottom-left corner.
  return {{-b, -h},     {b, -h},     {b, -h + tf},  {tw, -h + tf}, {tw, h - tf},  {b, h - tf},
          {b, h},       {-b, h},     {-b, h - tf},  {-tw, h - tf}, {-tw, -h + tf}, {-b, -h + tf}};
}

void emitColumn(Emitter& out, const std::string& key, std::string name, const glm::dvec3& base,
                float height, const std::vector<glm::vec2>& profile) {
  out.primitive(kLayerStructure, key, std::move(name), translation(base),
                Extrusion{profile, height});
}

void emitBeam(Emitter& out, const std::string& key, std::string name, const glm::dvec3& start,
              bool along_x, float length, const std::vector<glm::vec2>& profile) {
  // The profile's web runs along local Y, which must stay vertical.
  glm::vec3 dir = along_x ? glm::vec3(length > 0 ? 1 : -1, 0, 0) : glm::vec3(0, length > 0 ? 1 : -1, 0);
  glm::vec3 y(0, 0, 1);
  glm::vec3 x = glm::cross(y, dir);
  out.primitive(kLayerStructure, key, std::move(name), basis(start, x, y, dir),
                Extrusion{profile, std::fabs(length)});
}

void emitTube(Emitter& out, uint32_t layer, const std::string& key, std::string name,
              const glm::dvec3& from, const glm::dvec3& to, float radius, bool capped) {
  glm::dvec3 d = to - from;
  double len = glm::length(d);
  if (len < 1e-4) return;
  out.primitive(layer, key, std::move(name), alongAxis(from, glm::vec3(d / len)),
                Cylinder{radius, static_cast<float>(len), capped});
}

void emitBox(Emitter& out, uint32_t layer, const std::string& key, std::string name,
             const glm::dvec3& min, const glm::dvec3& max) {
  out.primitive(layer, key, std::move(name), translation((min + max) * 0.5),
                Box{glm::vec3((max - min) * 0.5)});
}

void emitHandrail(Emitter& out, const std::string& key, const glm::dvec3& from,
                  const glm::dvec3& to) {
  constexpr float kPostSpacing = 1.6f, kHeight = 1.1f;
  glm::dvec3 d = to - from;
  double len = glm::length(d);
  if (len < 0.3) return;
  glm::dvec3 dir = d / len;
  uint32_t spans = std::max<uint32_t>(1, static_cast<uint32_t>(std::ceil(len / kPostSpacing)));
  for (uint32_t i = 0; i <= spans; ++i) {
    glm::dvec3 p = from + d * (double(i) / spans);
    out.primitive(kLayerAccess, key, format("handrail %s post %u", key.c_str(), i + 1),
                  translation(p), Cylinder{0.024f, kHeight, true});
  }
  for (uint32_t i = 0; i < spans; ++i) {
    glm::dvec3 a = from + d * (double(i) / spans), b = from + d * (double(i + 1) / spans);
    emitTube(out, kLayerAccess, key, format("handrail %s top rail %u", key.c_str(), i + 1),
             a + glm::dvec3(0, 0, kHeight), b + glm::dvec3(0, 0, kHeight), 0.021f, false);
    emitTube(out, kLayerAccess, key, format("handrail %s knee rail %u", key.c_str(), i + 1),
             a + glm::dvec3(0, 0, 0.55), b + glm::dvec3(0, 0, 0.55), 0.017f, false);
    // Toe plate: thin box along the span.
    glm::dvec3 side = glm::normalize(glm::cross(glm::dvec3(0, 0, 1), dir)) * 0.004;
    glm::dvec3 mid = (a + b) * 0.5 + glm::dvec3(0, 0, 0.05);
    Transform t = basis(mid, glm::vec3(dir), glm::vec3(glm::normalize(side)), glm::vec3(0, 0, 1));
    out.primitive(kLayerAccess, key, format("handrail %s toe plate %u", key.c_str(), i + 1), t,
                  Box{glm::vec3(float(glm::length(b - a) * 0.5), 0.004f, 0.05f)});
  }
}

void emitGrating(Emitter& out, const std::string& key, const glm::dvec3& min, double x1,
                 double y1) {
  constexpr double kPanel = 1.0, kThick = 0.04;
  uint32_t n = std::max<uint32_t>(1, static_cast<uint32_t>(std::round((x1 - min.x) / kPanel)));
  double w = (x1 - min.x) / n;
  for (uint32_t i = 0; i < n; ++i) {
    glm::dvec3 a(min.x + w * i + 0.005, min.y, min.z - kThick);
    glm::dvec3 b(min.x + w * (i + 1) - 0.005, y1, min.z);
    emitBox(out, kLayerGrating, key, format("grating %s panel %u", key.c_str(), i + 1), a, b);
  }
}

float emitStairFlight(Emitter& out, const std::string& key, const glm::dvec3& bottom, float rise,
                      float width, float dir_x) {
  constexpr float kStep = 0.2f, kGoing = 0.25f;
  const double sx = dir_x < 0.0f ? -1.0 : 1.0;
  uint32_t steps = std::max<uint32_t>(2, static_cast<uint32_t>(std::round(rise / kStep)));
  float step = rise / static_cast<float>(steps);
  float run = kGoing * static_cast<float>(steps);
  for (uint32_t i = 0; i < steps; ++i) {
    glm::dvec3 c = bottom + glm::dvec3(sx * kGoing * (i + 0.5), width * 0.5, step * (i + 1) - 0.015);
    out.primitive(kLayerAccess, key, format("stair %s tread %u", key.c_str(), i + 1),
                  translation(c), Box{glm::vec3(kGoing * 0.5f + 0.01f, width * 0.5f, 0.015f)});
  }
  // Stringers and sloped handrails on both sides.
  glm::vec3 slope = glm::normalize(glm::vec3(float(sx) * run, 0.0f, rise));
  float len = std::sqrt(run * run + rise * rise);
  for (int s = 0; s < 2; ++s) {
    double y = s == 0 ? -0.01 : width + 0.01;
    glm::dvec3 mid = bottom + glm::dvec3(sx * run * 0.5, y, rise * 0.5 - 0.1);
    Transform t = basis(mid, slope, glm::vec3(0, 1, 0), glm::cross(slope, glm::vec3(0, 1, 0)));
    out.primitive(kLayerAccess, key, format("stair %s stringer %d", key.c_str(), s + 1), t,
                  Box{glm::vec3(len * 0.5f, 0.01f, 0.12f)});
    glm::dvec3 a = bottom + glm::dvec3(0.0, y, 1.0), b = a + glm::dvec3(sx * run, 0.0, rise);
    emitTube(out, kLayerAccess, key, format("stair %s rail %d", key.c_str(), s + 1), a, b,
             0.021f, true);
    for (int p = 0; p < 3; ++p) {
      glm::dvec3 foot = bottom + glm::dvec3(sx * run * (0.1 + 0.4 * p), y, rise * (0.1 + 0.4 * p));
      out.primitive(kLayerAccess, key, format("stair %s post %d.%d", key.c_str(), s + 1, p + 1),
                    translation(foot), Cylinder{0.024f, 1.0f, true});
    }
  }
  return run;
}

void emitCableTray(Emitter& out, const glm::dvec3& start, float length, float width) {
  constexpr float kSection = 6.0f, kDepth = 0.1f, kWall = 0.004f;
  uint32_t number = out.next_tray_number++;
  std::string key = format("CT-%05u", number);
  ProjectRecord r;
  r.db_key = key;
  r.type = "cable tray";
  r.material = "HDG steel";
  r.nominal_diameter_mm = width * 1000.0f;
  r.description = format("ladder cable tray %.0f mm, %.1f m", width * 1000.0f, length);
  out.record(r);
  const float w = width * 0.5f;
  // U section, counter-clockwise, extruded along +X (local Z).
  std::vector<glm::vec2> u = {{-w, 0.0f},          {w, 0.0f},           {w, kDepth},
                              {w - kWall, kDepth}, {w - kWall, kWall},  {-w + kWall, kWall},
                              {-w + kWall, kDepth}, {-w, kDepth}};
  uint32_t sections = std::max<uint32_t>(1, static_cast<uint32_t>(std::ceil(length / kSection)));
  float piece = length / static_cast<float>(sections);
  for (uint32_t i = 0; i < sections; ++i) {
    glm::dvec3 at = start + glm::dvec3(piece * i, 0.0, 0.0);
    // Local X -> world Y, local Y -> world Z (the U opens upward), local Z -> world X.
    out.primitive(kLayerElectrical, key, format("cable tray %s section %u", key.c_str(), i + 1),
                  basis(at, glm::vec3(0, 1, 0), glm::vec3(0, 0, 1), glm::vec3(1, 0, 0)),
                  Extrusion{u, piece - 0.01f});
  }
}

void emitLight(Emitter& out, const std::string& key, const glm::dvec3& ceiling_point) {
  out.primitive(kLayerElectrical, key, "light " + key + " pendant",
                translation(ceiling_point - glm::dvec3(0, 0, 0.5)), Cylinder{0.02f, 0.5f, true});
  out.primitive(kLayerElectrical, key, "light " + key + " globe",
                translation(ceiling_point - glm::dvec3(0, 0, 0.62)), Sphere{0.12f});
}

}  // namespace tw::plant
