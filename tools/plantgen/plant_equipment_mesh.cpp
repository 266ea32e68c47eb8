// Pumps and compressors as detailed triangle meshes, built once and re-emitted per tag.
//
// Rotating equipment comes from vendors as meshes, so the generator models it that way: a lathe
// and box builder assembles casing, motor with fins, coupling guard, base plate and nozzles into
// one TriangleMesh. Each instance reuses the template's buffers and only changes its transform,
// id and tag, so a 100M-triangle plant costs no per-pump mesh building.
#include <cmath>

#include "plant_parts.h"

namespace tw::plant {
namespace {

constexpr float kTwoPi = 6.2831853f;

// Appends geometry to one mesh in the template's frame. `place` maps a part's local frame
// (lathe axis +Z) into the template frame.
class MeshBuilder {
 public:
  explicit MeshBuilder(TriangleMesh& mesh) : mesh_(mesh) {}

  // Surface of revolution of (radius, z) points about local +Z; radius 0 closes on the axis.
  void lathe(const glm::mat4& place, const std::vector<glm::vec2>& profile, uint32_t segments) {
    std::vector<uint32_t> ring_start(profile.size());
    for (size_t j = 0; j < profile.size(); ++j) {
      ring_start[j] = static_cast<uint32_t>(mesh_.positions.size());
      float r = profile[j].x, z = profile[j].y;
      uint32_t count = r > 0.0f ? segments : 1;
      for (uint32_t k = 0; k < count; ++k) {
        float a = kTwoPi * static_cast<float>(k) / static_cast<float>(segments);
        add(place, glm::vec3(r * std::cos(a), r * std::sin(a), z));
      }
    }
    for (size_t j = 0; j + 1 < profile.size(); ++j) {
      bool lo_point = profile[j].x <= 0.0f, hi_point = profile[j + 1].x <= 0.0f;
      if (lo_point && hi_point) continue;
      uint32_t lo = ring_start[j], hi = ring_start[j + 1];
      for (uint32_t k = 0; k < segments; ++k) {
        uint32_t k1 = (k + 1) % segments;
        if (lo_point) {  // a disc facing down the axis, as the side faces away from it
          tri(lo, hi + k1, hi + k);
        } else if (hi_point) {
          tri(lo + k, lo + k1, hi);
        } else {
          tri(lo + k, lo + k1, hi + k1);
          tri(lo + k, hi + k1, hi + k);
        }
      }
    }
  }

  // Tube ring of a torus: circle of `minor` at distance `major` from the axis.
  void torus(const glm::mat4& place, float major, float minor, uint32_t around, uint32_t tube) {
    std::vector<glm::vec2> profile;
    for (uint32_t i = 0; i <= tube; ++i) {
      float a = kTwoPi * static_cast<float>(i) / static_cast<float>(tube);
      profile.push_back({major + minor * std::cos(a), minor * std::sin(a)});
    }
    lathe(place, profile, around);
  }

  void box(const glm::mat4& place, const glm::vec3& half) {
    uint32_t base = static_cast<uint32_t>(mesh_.positions.size());
    for (int i = 0; i < 8; ++i)
      add(place, glm::vec3((i & 1) ? half.x : -half.x, (i & 2) ? half.y : -half.y,
                           (i & 4) ? half.z : -half.z));
    static const uint32_t kFaces[12][3] = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6},
                                           {0, 1, 4}, {1, 5, 4}, {2, 6, 3}, {3, 6, 7},
                                           {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
    for (const auto& f : kFaces) tri(base + f[0], base + f[1], base + f[2]);
  }

 private:
  void add(const glm::mat4& place, const glm::vec3& p) {
    mesh_.positions.push_back(glm::vec3(place * glm::vec4(p, 1.0f)));
  }
  void tri(uint32_t a, uint32_t b, uint32_t c) {
    mesh_.indices.insert(mesh_.indices.end(), {a, b, c});
  }
  TriangleMesh& mesh_;
};

glm::mat4 at(float x, float y, float z) { return glm::mat4(1.0f, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, x, y, z, 1); }
// Lathe axis (+Z) along +X, starting at (x, y, z).
glm::mat4 alongX(float x, float y, float z) {
  return glm::mat4(0, 1, 0, 0, 0, 0, 1, 0, 1, 0, 0, 0, x, y, z, 1);
}

// A nozzle: pipe stub of radius r and length len along the lathe frame, with a flange.
void nozzle(MeshBuilder& b, const glm::mat4& place, float r, float len, uint32_t segments) {
  float fr = r * 1.6f + 0.02f, ft = 0.03f + r * 0.2f;
  b.lathe(place, {{0.0f, 0.0f}, {r, 0.0f}, {r, len - ft}, {fr, len - ft}, {fr, len}, {0.0f, len}},
          segments);
}

void finishTemplate(SceneObject& object, const char* name) {
  object.info.name = name;
  object.info.layer = kLayerEquipment;
}

TriangleMesh buildPump() {
  TriangleMesh m;
  MeshBuilder b(m);
  constexpr uint32_t kSeg = 40;
  const float axis_z = 0.48f;
  b.box(at(0.0f, 0.0f, 0.06f), {1.15f, 0.38f, 0.06f});  // base plate
  // Motor with fan cowl, along +X ending at the coupling.
  b.lathe(alongX(-1.05f, 0.0f, axis_z),
          {{0.0f, 0.0f}, {0.2f, 0.0f}, {0.25f, 0.05f}, {0.25f, 0.16f}, {0.27f, 0.16f},
           {0.27f, 0.9f}, {0.2f, 0.9f}, {0.2f, 0.98f}, {0.04f, 0.98f}, {0.04f, 1.12f}, {0.0f, 1.12f}},
          kSeg);
  for (int i = 0; i < 10; ++i) {  // cooling fins
    float a = kTwoPi * (static_cast<float>(i) + 0.5f) / 10.0f;
    glm::mat4 fin = alongX(-0.85f, 0.0f, axis_z);
    fin = fin * at(0.28f * std::cos(a), 0.28f * std::sin(a), 0.36f);
    b.box(fin, {0.012f + 0.018f * std::fabs(std::cos(a)), 0.012f + 0.018f * std::fabs(std::sin(a)), 0.34f});
  }
  b.box(at(-0.55f, 0.0f, 0.18f), {0.36f, 0.24f, 0.06f});  // motor feet
  b.box(at(-0.55f, 0.0f, axis_z + 0.32f), {0.12f, 0.1f, 0.07f});  // terminal box
  b.box(at(0.2f, 0.0f, axis_z), {0.13f, 0.14f, 0.14f});  // coupling guard
  b.lathe(alongX(0.33f, 0.0f, axis_z),  // bearing housing
          {{0.0f, 0.0f}, {0.1f, 0.0f}, {0.11f, 0.05f}, {0.11f, 0.25f}, {0.14f, 0.28f},
           {0.14f, 0.32f}, {0.0f, 0.32f}},
          kSeg);
  b.box(at(0.5f, 0.0f, 0.22f), {0.16f, 0.14f, 0.1f});  // bearing pedestal
  // Volute: a disc with a torus rim around the impeller.
  b.lathe(alongX(0.65f, 0.0f, axis_z),
          {{0.0f, 0.0f}, {0.24f, 0.0f}, {0.3f, 0.04f}, {0.3f, 0.2f}, {0.22f, 0.24f},
           {0.1f, 0.24f}, {0.1f, 0.3f}, {0.0f, 0.3f}},
          kSeg);
  b.torus(alongX(0.77f, 0.0f, axis_z), 0.27f, 0.09f, kSeg, 16);
  b.box(at(0.77f, 0.0f, 0.16f), {0.15f, 0.2f, 0.06f});  // casing foot
  nozzle(b, alongX(0.95f, 0.0f, axis_z), 0.08f, 0.3f, 32);                  // suction, +X
  nozzle(b, at(0.77f, 0.0f, axis_z + 0.33f), 0.06f, 0.35f, 32);             // discharge, +Z
  return m;
}

TriangleMesh buildCompressor() {
  TriangleMesh m;
  MeshBuilder b(m);
  constexpr uint32_t kSeg = 64;
  const float axis_z = 1.35f;
  b.box(at(0.0f, 0.0f, 0.2f), {4.2f, 1.4f, 0.2f});  // skid
  b.box(at(-2.2f, 0.0f, 0.7f), {1.2f, 0.8f, 0.3f});  // motor pedestal
  b.lathe(alongX(-3.6f, 0.0f, axis_z),  // motor with end shields
          {{0.0f, 0.0f}, {0.55f, 0.0f}, {0.7f, 0.15f}, {0.75f, 0.15f}, {0.75f, 2.45f},
           {0.7f, 2.45f}, {0.55f, 2.6f}, {0.12f, 2.6f}, {0.12f, 2.85f}, {0.0f, 2.85f}},
          kSeg);
  for (int i = 0; i < 16; ++i) {  // cooling fins
    float a = kTwoPi * (static_cast<float>(i) + 0.5f) / 16.0f;
    glm::mat4 fin = alongX(-3.4f, 0.0f, axis_z) * at(0.78f * std::cos(a), 0.78f * std::sin(a), 1.1f);
    b.box(fin, {0.03f + 0.04f * std::fabs(std::cos(a)), 0.03f + 0.04f * std::fabs(std::sin(a)), 0.95f});
  }
  b.box(at(-2.2f, 0.0f, axis_z + 0.95f), {0.3f, 0.25f, 0.2f});  // terminal box
  b.box(at(-0.4f, 0.0f, 1.0f), {0.55f, 0.7f, 0.6f});            // gearbox
  b.box(at(-0.4f, 0.0f, 1.75f), {0.45f, 0.6f, 0.15f});          // gearbox cover
  b.lathe(alongX(0.15f, 0.0f, axis_z), {{0.0f, 0.0f}, {0.25f, 0.0f}, {0.25f, 0.5f}, {0.0f, 0.5f}},
          kSeg);  // coupling housing
  b.box(at(1.9f, 0.0f, 0.7f), {1.3f, 0.7f, 0.3f});  // barrel pedestal
  b.lathe(alongX(0.65f, 0.0f, axis_z),  // barrel casing with bolted end covers
          {{0.0f, 0.0f}, {0.45f, 0.0f}, {0.45f, 0.12f}, {0.8f, 0.12f}, {0.8f, 0.3f},
           {0.7f, 0.3f}, {0.7f, 2.2f}, {0.8f, 2.2f}, {0.8f, 2.38f}, {0.45f, 2.38f},
           {0.45f, 2.5f}, {0.0f, 2.5f}},
          kSeg);
  b.torus(alongX(1.2f, 0.0f, axis_z), 0.72f, 0.08f, kSeg, 12);  // suction volute
  b.torus(alongX(2.3f, 0.0f, axis_z), 0.72f, 0.08f, kSeg, 12);  // discharge volute
  nozzle(b, at(1.2f, 0.0f, axis_z + 0.7f), 0.2f, 0.9f, 48);     // suction, +Z
  nozzle(b, at(2.3f, 0.0f, axis_z + 0.7f), 0.16f, 0.9f, 48);    // discharge, +Z
  b.box(at(3.6f, 0.9f, 0.9f), {0.5f, 0.35f, 0.5f});             // lube oil console
  b.box(at(3.6f, -0.9f, 0.9f), {0.5f, 0.35f, 0.5f});            // seal gas panel
  return m;
}

}  // namespace

EquipmentTemplates::EquipmentTemplates() {
  pump.geometry = buildPump();
  finishTemplate(pump, "pump");
  compressor.geometry = buildCompressor();
  finishTemplate(compressor, "compressor");
}

void emitPumpPair(Emitter& out, EquipmentTemplates& templates, uint32_t area, uint32_t number,
                  const glm::dvec3& base, std::vector<Nozzle>& nozzles) {
  for (int side = 0; side < 2; ++side) {
    char suffix = side == 0 ? 'A' : 'B';
    std::string key = format("P-%u%02u-%c", area, number, suffix);
    ProjectRecord r;
    r.db_key = key;
    r.type = "pump";
    r.service = service(area + number).name;
    r.material = "DSS 22Cr casing";
    r.nominal_diameter_mm = 150.0;
    r.design_pressure_bar = service(area + number).pressure_bar;
    r.design_temperature_c = service(area + number).temperature_c;
    r.description = format("centrifugal pump %c (%s), area %u", suffix,
                           side == 0 ? "duty" : "standby", area);
    out.record(r);
    glm::dvec3 origin = base + glm::dvec3(0.0, side == 0 ? -0.9 : 0.9, 0.0);
    SceneObject& pump = templates.pump;
    pump.info.name = "pump " + key;
    pump.info.db_key = key;
    pump.info.transform = translation(origin);
    out.emit(pump);
    nozzles.push_back({origin + glm::dvec3(1.25, 0.0, 0.48), glm::vec3(1, 0, 0), 3});
    nozzles.push_back({origin + glm::dvec3(0.77, 0.0, 1.16), glm::vec3(0, 0, 1), 2});
  }
}

void emitCompressor(Emitter& out, EquipmentTemplates& templates, uint32_t area, uint32_t number,
                    const glm::dvec3& base, std::vector<Nozzle>& nozzles) {
  std::string key = format("K-%u%02u", area, number);
  ProjectRecord r;
  r.db_key = key;
  r.type = "compressor";
  r.service = "process gas";
  r.material = "CS casing";
  r.nominal_diameter_mm = 400.0;
  r.design_pressure_bar = 98.0;
  r.design_temperature_c = 140.0;
  r.description = format("motor-driven centrifugal gas compressor, area %u", area);
  out.record(r);
  SceneObject& k = templates.compressor;
  k.info.name = "compressor " + key;
  k.info.db_key = key;
  k.info.transform = translation(base);
  out.emit(k);
  nozzles.push_back({base + glm::dvec3(1.2, 0.0, 2.95), glm::vec3(0, 0, 1), 7});
  nozzles.push_back({base + glm::dvec3(2.3, 0.0, 2.95), glm::vec3(0, 0, 1), 6});
}

}  // namespace tw::plant
