// Static equipment as parametrics: vessels and exchangers revolved from their outline (2:1
// elliptical heads), with skirts, saddles and flanged nozzles, and spherical air receivers.
#include <cmath>

#include "plant_parts.h"

namespace tw::plant {
namespace {

constexpr float kHalfPi = 1.5707963f;

// Outline of a vessel of radius r and tangent-to-tangent length `shell` along local +Z, from
// axis to axis, with 2:1 elliptical heads (depth r/2) at both ends. Local z = 0 is the bottom.
std::vector<glm::vec2> vesselOutline(float r, float shell) {
  constexpr int kHeadSteps = 6;
  const float head = r * 0.5f;
  std::vector<glm::vec2> p;
  for (int i = 0; i <= kHeadSteps; ++i) {
    float a = kHalfPi * static_cast<float>(i) / kHeadSteps;
    p.push_back({r * std::sin(a), head * (1.0f - std::cos(a))});
  }
  for (int i = kHeadSteps; i >= 0; --i) {
    float a = kHalfPi * static_cast<float>(i) / kHeadSteps;
    p.push_back({r * std::sin(a), head + shell + head * std::cos(a)});
  }
  return p;
}

ProjectRecord equipmentRecord(const std::string& key, const char* type, uint32_t service_index,
                              float diameter, std::string description) {
  const Service& s = service(service_index);
  ProjectRecord r;
  r.db_key = key;
  r.type = type;
  r.service = s.name;
  r.material = s.material;
  r.nominal_diameter_mm = diameter * 1000.0f;
  r.design_pressure_bar = s.pressure_bar * 1.1f;
  r.design_temperature_c = s.temperature_c + 25.0f;
  r.description = std::move(description);
  return r;
}

// A flanged nozzle stub of pipe size `size` from `from` along `dir`; returns its face.
glm::dvec3 emitNozzle(Emitter& out, const std::string& key, const std::string& owner, uint32_t n,
                      const glm::dvec3& from, const glm::vec3& dir, uint32_t size, float length) {
  float r = pipeSize(size).od_m * 0.5f;
  out.primitive(kLayerEquipment, key, format("%s nozzle N%u", owner.c_str(), n),
                alongAxis(from, dir), Cylinder{r, length, false});
  float ft = 0.03f + r * 0.25f;
  glm::dvec3 face = from + glm::dvec3(dir) * double(length);
  out.primitive(kLayerEquipment, key, format("%s nozzle N%u flange", owner.c_str(), n),
                alongAxis(face - glm::dvec3(dir) * double(ft), dir),
                Cylinder{r * 1.45f + 0.025f, ft, true});
  return face;
}

// Local Z along world +X, for horizontal equipment.
Transform horizontalFrame(const glm::dvec3& origin) {
  return basis(origin, glm::vec3(0, 1, 0), glm::vec3(0, 0, 1), glm::vec3(1, 0, 0));
}

}  // namespace

void emitVerticalVessel(Emitter& out, Random& rng, uint32_t area, uint32_t number,
                        const glm::dvec3& base, float diameter, float height, float rack_side_y,
                        std::vector<Nozzle>& nozzles) {
  std::string key = format("V-%u%02u", area, number);
  std::string owner = "vessel " + key;
  uint32_t svc = rng.below(serviceCount());
  out.record(equipmentRecord(key, "vessel", svc, diameter,
                             format("vertical %s scrubber, %.1f m x %.1f m", service(svc).name,
                                    diameter, height)));
  const float r = diameter * 0.5f;
  const float skirt = 1.2f;
  const float shell = std::max(0.5f, height - skirt - r);  // two heads of r/2 each
  out.primitive(kLayerEquipment, key, owner + " skirt", translation(base),
                Cylinder{r * 0.98f, skirt, false});
  glm::dvec3 bottom = base + glm::dvec3(0.0, 0.0, skirt);
  out.primitive(kLayerEquipment, key, owner + " shell", translation(bottom),
                Revolution{vesselOutline(r, shell), 6.2831853f});
  // Top nozzle, then side nozzles toward the rack.
  double top = skirt + shell + r;
  uint32_t n = 0;
  uint32_t top_size = 2 + rng.below(4);
  glm::dvec3 face = emitNozzle(out, key, owner, ++n, base + glm::dvec3(0, 0, top - 0.05),
                               glm::vec3(0, 0, 1), top_size, 0.45f);
  nozzles.push_back({face, glm::vec3(0, 0, 1), top_size});
  glm::vec3 side(0.0f, rack_side_y, 0.0f);
  for (float level : {0.85f, 0.55f, 0.25f}) {
    uint32_t size = 1 + rng.below(4);
    glm::dvec3 at = bottom + glm::dvec3(0.0, 0.0, r * 0.5 + shell * level) +
                    glm::dvec3(side) * double(r * 0.9f);
    face = emitNozzle(out, key, owner, ++n, at, side, size, 0.25f + r * 0.1f);
    nozzles.push_back({face, side, size});
  }
}

void emitHorizontalVessel(Emitter& out, Random& rng, uint32_t area, uint32_t number,
                          const glm::dvec3& base, float diameter, float length,
                          std::vector<Nozzle>& nozzles) {
  std::string key = format("V-%u%02u", area, number);
  std::string owner = "vessel " + key;
  uint32_t svc = rng.below(3);  // separators handle process fluids
  out.record(equipmentRecord(key, "vessel", svc, diameter,
                             format("horizontal three-phase separator, %.1f m x %.1f m",
                                    diameter, length)));
  const float r = diameter * 0.5f;
  const float shell = std::max(1.0f, length - r);
  const double axis_z = r + 0.6;
  glm::dvec3 start = base + glm::dvec3(-0.5 * length, 0.0, axis_z);
  out.primitive(kLayerEquipment, key, owner + " shell", horizontalFrame(start),
                Revolution{vesselOutline(r, shell), 6.2831853f});
  for (int s = 0; s < 2; ++s) {
    double x = (s == 0 ? -0.3 : 0.3) * length;
    glm::dvec3 c = base + glm::dvec3(x, 0.0, 0.5 * axis_z);
    glm::dvec3 half(0.25, r * 0.85, 0.5 * axis_z);
    out.primitive(kLayerEquipment, key, format("%s saddle %d", owner.c_str(), s + 1),
                  translation(c), Box{glm::vec3(half)});
  }
  uint32_t n = 0;
  for (float at : {-0.36f, -0.12f, 0.12f, 0.36f}) {
    uint32_t size = 2 + rng.below(5);
    glm::dvec3 from = base + glm::dvec3(at * length, 0.0, axis_z + r * 0.95);
    glm::dvec3 face = emitNozzle(out, key, owner, ++n, from, glm::vec3(0, 0, 1), size, 0.4f);
    nozzles.push_back({face, glm::vec3(0, 0, 1), size});
  }
}

void emitExchanger(Emitter& out, Random& rng, uint32_t area, uint32_t number,
                   const glm::dvec3& base, float diameter, float length,
                   std::vector<Nozzle>& nozzles) {
  std::string key = format("E-%u%02u", area, number);
  std::string owner = "exchanger " + key;
  uint32_t svc = rng.below(serviceCount());
  out.record(equipmentRecord(key, "heat exchanger", svc, diameter,
                             format("shell and tube cooler, %s side, %.1f m x %.1f m",
                                    service(svc).name, diameter, length)));
  const float r = diameter * 0.5f;
  const double axis_z = r + 0.5;
  const float channel = std::max(0.6f, diameter * 0.8f);
  const float transition = r * 0.4f;
  glm::dvec3 start = base + glm::dvec3(-0.5 * length, 0.0, axis_z);
  // Channel head (cylinder), cone transition, shell with one elliptical head.
  out.primitive(kLayerEquipment, key, owner + " channel", horizontalFrame(start),
                Cylinder{r * 1.12f, channel, true});
  out.primitive(kLayerEquipment, key, owner + " transition",
                horizontalFrame(start + glm::dvec3(channel, 0.0, 0.0)),
                Cone{r * 1.12f, r, transition, false});
  float shell = std::max(1.0f, length - channel - transition - r * 0.5f);
  std::vector<glm::vec2> outline = vesselOutline(r, shell);
  outline.erase(outline.begin(), outline.begin() + 6);  // flat end toward the channel
  outline.insert(outline.begin(), glm::vec2(0.0f, r * 0.5f));
  out.primitive(kLayerEquipment, key, owner + " shell",
                horizontalFrame(start + glm::dvec3(channel + transition - r * 0.5f, 0.0, 0.0)),
                Revolution{std::move(outline), 6.2831853f});
  for (int s = 0; s < 2; ++s) {
    double x = (s == 0 ? -0.25 : 0.3) * length;
    glm::dvec3 c = base + glm::dvec3(x, 0.0, 0.5 * axis_z);
    out.primitive(kLayerEquipment, key, format("%s saddle %d", owner.c_str(), s + 1),
                  translation(c), Box{glm::vec3(0.2f, r * 0.8f, 0.5f * float(axis_z))});
  }
  uint32_t n = 0;
  for (double at : {0.15 * channel, 0.65 * channel, 0.45 * length, 0.85 * length}) {
    uint32_t size = 2 + rng.below(4);
    glm::dvec3 from = start + glm::dvec3(at, 0.0, r * 0.95);
    glm::dvec3 face = emitNozzle(out, key, owner, ++n, from, glm::vec3(0, 0, 1), size, 0.35f);
    nozzles.push_back({face, glm::vec3(0, 0, 1), size});
  }
}

void emitAirReceiver(Emitter& out, uint32_t area, uint32_t number, const glm::dvec3& base,
                     float diameter, std::vector<Nozzle>& nozzles) {
  std::string key = format("V-%u%02u", area, number);
  std::string owner = "receiver " + key;
  out.record(equipmentRecord(key, "vessel", 6, diameter,
                             format("spherical instrument air receiver, %.1f m", diameter)));
  const float r = diameter * 0.5f;
  const double centre_z = r + 0.8;
  for (int leg = 0; leg < 4; ++leg) {
    double sx = (leg & 1) ? 1.0 : -1.0, sy = (leg & 2) ? 1.0 : -1.0;
    glm::dvec3 foot = base + glm::dvec3(sx * r * 0.65, sy * r * 0.65, 0.0);
    out.primitive(kLayerEquipment, key, format("%s leg %d", owner.c_str(), leg + 1),
                  translation(foot), Cylinder{0.05f, float(centre_z), true});
  }
  out.primitive(kLayerEquipment, key, owner + " sphere",
                translation(base + glm::dvec3(0.0, 0.0, centre_z)), Sphere{r});
  glm::dvec3 face = emitNozzle(out, key, owner, 1, base + glm::dvec3(0.0, 0.0, centre_z + r - 0.05),
                               glm::vec3(0, 0, 1), 1, 0.3f);
  nozzles.push_back({face, glm::vec3(0, 0, 1), 1});
}

}  // namespace tw::plant
