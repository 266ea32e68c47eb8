// Internal interface between the plant generator's driver and its part builders.
//
// Builders place objects in world coordinates (metres, Z up) and hand them to an Emitter. Each
// file builds one family of parts: piping (runs, elbows, flanges, valves), equipment (vessels,
// mesh pumps and compressors), structure (steel, decks, walls), outfitting (grating, stairs,
// handrails, cable trays), the NURBS hull, and the module that arranges them all.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "plant_emitter.h"
#include "plant_random.h"

namespace tw::plant {

// ---- Frames -------------------------------------------------------------------------------
inline Transform translation(const glm::dvec3& origin) {
  Transform t;
  t.origin = origin;
  return t;
}
// Local axes x, y, z (orthonormal, right-handed) placed at `origin`.
inline Transform basis(const glm::dvec3& origin, const glm::vec3& x, const glm::vec3& y,
                       const glm::vec3& z) {
  Transform t;
  t.origin = origin;
  t.linear = glm::mat3(x, y, z);
  return t;
}
// Local +Z along the unit vector `dir`; the roll about it is arbitrary but deterministic.
Transform alongAxis(const glm::dvec3& origin, const glm::vec3& dir);

// ---- Tags and engineering data ----------------------------------------------------------------
struct Service {
  const char* code;  // line-number service code ("HC")
  const char* name;
  uint32_t layer;
  float pressure_bar;
  float temperature_c;
  const char* spec;  // piping class ("A1")
  const char* material;
};
const Service& service(uint32_t index);
uint32_t serviceCount();

struct PipeSize {
  const char* inch;  // nominal size as written in line numbers
  float nominal_mm;
  float od_m;  // outside diameter
};
const PipeSize& pipeSize(uint32_t index);  // 0 = 2" ... pipeSizeCount()-1 = 24"
uint32_t pipeSizeCount();

// One piping line: every segment, elbow and flange of its runs carries `key`.
struct PipeLine {
  std::string key;  // 12"-HC-1001-A1
  uint32_t service = 0;
  uint32_t size = 0;
  uint32_t number = 0;
  float radius_m = 0.0f;
  const char* where = "";  // for the record's description
  bool recorded = false;   // its record is stored with its first run
};
// Numbers a new line; its record is stored when a run of it is first emitted.
PipeLine openLine(Emitter& out, uint32_t service_index, uint32_t size_index, const char* where);
void recordLine(Emitter& out, PipeLine& line);
uint32_t pipeLayer(const PipeLine& line);

// ---- Piping ------------------------------------------------------------------------------------
struct RunStyle {
  bool flange_start = true;
  bool flange_end = true;
  float valve_chance = 0.3f;  // per straight long enough to hold a valve
  uint32_t max_valves = 2;
};
// Emits the run through `points` (world, consecutive distinct points): straight cylinders cut
// where the run bends, torus elbows that join them exactly, flanges and in-line valves.
// Returns false (emitting nothing) when the route is too tight to bend this pipe.
bool emitRun(Emitter& out, Random& rng, PipeLine& line, const std::vector<glm::dvec3>& points,
             const RunStyle& style);

// ---- Equipment ---------------------------------------------------------------------------------
// A connection point on a piece of equipment: where a pipe run starts, pointing away from it.
struct Nozzle {
  glm::dvec3 position;
  glm::vec3 direction;
  uint32_t size;
};

// Triangle-mesh equipment built once per plant and re-emitted with new transforms and tags.
class EquipmentTemplates {
 public:
  EquipmentTemplates();
  SceneObject pump;        // local frame: base at z = 0, shaft along +X, suction at the +X end
  SceneObject compressor;  // local frame: base at z = 0, shaft along +X
};

// Equipment builders. `base` is the centre of the footprint on the deck; side nozzles point
// toward `rack_side_y` (+1 or -1: the pipe rack's side in Y). Nozzles are appended.
void emitPumpPair(Emitter& out, EquipmentTemplates& templates, uint32_t area, uint32_t number,
                  const glm::dvec3& base, std::vector<Nozzle>& nozzles);
void emitCompressor(Emitter& out, EquipmentTemplates& templates, uint32_t area, uint32_t number,
                    const glm::dvec3& base, std::vector<Nozzle>& nozzles);
void emitVerticalVessel(Emitter& out, Random& rng, uint32_t area, uint32_t number,
                        const glm::dvec3& base, float diameter, float height, float rack_side_y,
                        std::vector<Nozzle>& nozzles);
void emitHorizontalVessel(Emitter& out, Random& rng, uint32_t area, uint32_t number,
                          const glm::dvec3& base, float diameter, float length,
                          std::vector<Nozzle>& nozzles);
void emitExchanger(Emitter& out, Random& rng, uint32_t area, uint32_t number,
                   const glm::dvec3& base, float diameter, float length,
                   std::vector<Nozzle>& nozzles);
void emitAirReceiver(Emitter& out, uint32_t area, uint32_t number, const glm::dvec3& base,
                     float diameter, std::vector<Nozzle>& nozzles);

// ---- Structure and outfitting ---------------------------------------------------------------
// I-profile (12-point polygon) of the given depth and flange width, centred on the origin.
std::vector<glm::vec2> iProfile(float depth, float width);

void emitColumn(Emitter& out, const std::string& key, std::string name, const glm::dvec3& base,
                float height, const std::vector<glm::vec2>& profile);
// Horizontal beam along X or Y from `start` (centre of its section) over `length` (signed).
void emitBeam(Emitter& out, const std::string& key, std::string name, const glm::dvec3& start,
              bool along_x, float length, const std::vector<glm::vec2>& profile);
void emitTube(Emitter& out, uint32_t layer, const std::string& key, std::string name,
              const glm::dvec3& from, const glm::dvec3& to, float radius, bool capped);
void emitBox(Emitter& out, uint32_t layer, const std::string& key, std::string name,
             const glm::dvec3& min, const glm::dvec3& max);

// Handrail along a straight edge at deck level z: posts, top and knee rails, toe plates.
void emitHandrail(Emitter& out, const std::string& key, const glm::dvec3& from,
                  const glm::dvec3& to);
// Grating panels (about 1 m wide, separate objects) covering the rectangle at height z.
void emitGrating(Emitter& out, const std::string& key, const glm::dvec3& min, double x1,
                 double y1);
// A straight stair flight climbing by `rise` from `bottom` along +X (dir_x = 1) or -X (-1);
// treads span `width` toward +Y. Returns the horizontal run.
float emitStairFlight(Emitter& out, const std::string& key, const glm::dvec3& bottom, float rise,
                      float width, float dir_x);
// Cable tray (U extrusion) sections along +X from `start` over `length`, with its record.
void emitCableTray(Emitter& out, const glm::dvec3& start, float length, float width);
void emitLight(Emitter& out, const std::string& key, const glm::dvec3& ceiling_point);

// ---- Hull --------------------------------------------------------------------------------------
// A ship-like hull: closed bicubic Bezier patch set sharing borders, deck at z = 0 of `origin`
// (the hull hangs below), bow toward +X. `smooth` gives a ship-like curved hull; otherwise a
// faceted hard-chine barge, much cheaper to tessellate (for small plants). Builds the object
// without emitting it.
SceneObject buildHull(uint32_t hull_index, const glm::dvec3& deck_origin, float length,
                      float beam, float depth, bool smooth);
ProjectRecord hullRecord(uint32_t hull_index, float length, float beam, float depth);

// ---- Modules -----------------------------------------------------------------------------------
constexpr float kModuleLengthM = 32.0f;  // along X
constexpr float kModuleWidthM = 22.0f;   // along Y
constexpr float kStoreyHeightM = 9.0f;
constexpr float kCorridorWidthM = 10.0f;  // main pipe rack between the two module rows

struct ModuleSite {
  uint32_t index = 0;  // global module number (areas and tags derive from it)
  uint32_t row = 0;    // 0: port row (also builds the main rack segment), 1: starboard
  glm::dvec3 origin;   // module corner (min x, min y) at the top of its lowest deck
};
// Emits one module; `fill` in (0, 1] scales equipment, piping and outfitting (1 = full).
void emitModule(Emitter& out, EquipmentTemplates& templates, uint64_t seed,
                const ModuleSite& site, float fill);

}  // namespace tw::plant
