// One process module: a steel deck stack with its decks, walls, stairs, handrails, internal pipe
// rack, equipment and the piping that connects them; module rows of the port side also carry
// the FPSO's main pipe rack segment in the corridor beside them.
//
// Module frame (before `site.origin`): X along the hull, Y across, Z up from the top of the
// lowest deck; footprint kModuleLengthM x kModuleWidthM, storeys kStoreyHeightM high.
#include <algorithm>
#include <cmath>

#include "plant_parts.h"

namespace tw::plant {
namespace {

const double kXs[] = {0.0, 8.0, 16.0, 24.0, 32.0};
const double kYs[] = {0.0, 7.0, 15.0, 22.0};
constexpr int kBaysX = 4, kBaysY = 3;
constexpr double kPlate = 0.15;      // deck plate thickness
constexpr double kRackY0 = 8.3, kRackY1 = 13.7;  // internal rack band
constexpr double kTier0 = 6.0, kTier1 = 7.3;     // rack beam tops above the storey's deck
constexpr double kStoolM = 3.0;      // module stools above the hull deck

struct Context {
  Emitter& out;
  EquipmentTemplates& templates;
  Random rng;
  const ModuleSite& site;
  float fill;
  uint32_t area;
  uint32_t storeys;
  std::vector<glm::vec2> column_profile, beam_profile, secondary_profile, rack_profile;
  std::vector<Nozzle> nozzles;
  std::vector<glm::dvec3> route;
  uint32_t equipment_number = 0;

  glm::dvec3 at(double x, double y, double z) const { return site.origin + glm::dvec3(x, y, z); }
  bool take() { return rng.uniform() < fill; }
  std::string tag(const char* prefix, uint32_t level, const char* type, const char* what) {
    std::string key = format("%s-%u-L%u", prefix, area, level);
    ProjectRecord r;
    r.db_key = key;
    r.type = type;
    r.material = "S355 steel";
    r.description = format("%s, module M%u level %u", what, area, level);
    out.record(r);
    return key;
  }
};

// ---- Structure ------------------------------------------------------------------------------

void emitSteel(Context& c) {
  // Stools carry the module above the hull deck.
  std::string stool_key = c.tag("ST", 0, "stool", "module stools");
  for (double x : {0.0, 16.0, 32.0})
    for (double y : {0.0, 22.0})
      emitColumn(c.out, stool_key, format("stool M%u x%.0f y%.0f", c.area, x, y),
                 c.at(x, y, -kStoolM), float(kStoolM - 0.8), c.column_profile);
  for (uint32_t level = 0; level <= c.storeys; ++level) {
    double z = level * kStoreyHeightM;
    std::string key = c.tag("ST", level + 1, "steel", "primary steel");
    double beam_z = z - kPlate - 0.35;
    for (int iy = 0; iy <= kBaysY; ++iy)
      for (int ix = 0; ix < kBaysX; ++ix)
        emitBeam(c.out, key, format("beam M%u L%u y%d b%d", c.area, level, iy, ix),
                 c.at(kXs[ix], kYs[iy], beam_z), true, 8.0f, c.beam_profile);
    for (int ix = 0; ix <= kBaysX; ++ix)
      for (int iy = 0; iy < kBaysY; ++iy)
        emitBeam(c.out, key, format("beam M%u L%u x%d b%d", c.area, level, ix, iy),
                 c.at(kXs[ix], kYs[iy], beam_z), false, float(kYs[iy + 1] - kYs[iy]),
                 c.beam_profile);
    for (int iy = 0; iy < kBaysY; ++iy)
      for (int ix = 0; ix < kBaysX; ++ix)
        emitBeam(c.out, key, format("joist M%u L%u y%d b%d", c.area, level, iy, ix),
                 c.at(kXs[ix], 0.5 * (kYs[iy] + kYs[iy + 1]), z - kPlate - 0.2), true, 8.0f,
                 c.secondary_profile);
    if (level == c.storeys) break;
    for (double x : kXs)
      for (double y : kYs)
        emitColumn(c.out, key, format("column M%u L%u x%.0f y%.0f", c.area, level, x, y),
                   c.at(x, y, z), float(kStoreyHeightM - kPlate - 0.7), c.column_profile);
    // X-bracing in the end bays of the long faces and the middle bay of the short faces.
    double top = z + kStoreyHeightM - kPlate - 0.7;
    auto brace = [&](glm::dvec3 a, glm::dvec3 b, const char* face, int n) {
      emitTube(c.out, kLayerStructure, key, format("brace M%u L%u %s %d", c.area, level, face, n),
               c.at(a.x, a.y, a.z), c.at(b.x, b.y, b.z), 0.11f, true);
    };
    for (double y : {0.0, 22.0})
      for (int ix : {0, 3}) {
        brace({kXs[ix], y, z}, {kXs[ix + 1], y, top}, y == 0.0 ? "south" : "north", 2 * ix);
        brace({kXs[ix + 1], y, z}, {kXs[ix], y, top}, y == 0.0 ? "south" : "north", 2 * ix + 1);
      }
    for (double x : {0.0, 32.0}) {
      brace({x, kYs[1], z}, {x, kYs[2], top}, x == 0.0 ? "west" : "east", 0);
      brace({x, kYs[2], z}, {x, kYs[1], top}, x == 0.0 ? "west" : "east", 1);
    }
    // Internal rack: cross beams at two tiers on every frame line.
    for (int ix = 0; ix <= kBaysX; ++ix)
      for (double tier : {kTier0, kTier1})
        emitBeam(c.out, key, format("rack beam M%u L%u x%d t%.0f", c.area, level, ix, tier),
                 c.at(kXs[ix], kYs[1], z + tier - 0.15), false, float(kYs[2] - kYs[1]),
                 c.rack_profile);
  }
}

void emitDecksWallsAccess(Context& c) {
  const bool outboard_low_y = c.site.row == 0;
  for (uint32_t level = 0; level <= c.storeys; ++level) {
    double z = level * kStoreyHeightM;
    std::string deck_key = c.tag("DK", level + 1, "deck", "deck plating");
    for (int iy = 0; iy < kBaysY; ++iy)
      for (int ix = 0; ix < kBaysX; ++ix) {
        if (level > 0 && ix == 0 && iy == 0) continue;  // stair well
        // The roof is a laydown strip along the outboard edge only; the rest stays open, as on
        // real topsides, so the top storey's equipment and piping show from above.
        if (level == c.storeys && level > 0 && iy != (outboard_low_y ? 0 : kBaysY - 1)) continue;
        emitBox(c.out, kLayerDecks, deck_key, format("deck M%u L%u bay %d.%d", c.area, level, ix, iy),
                c.at(kXs[ix], kYs[iy], z - kPlate), c.at(kXs[ix + 1], kYs[iy + 1], z));
      }
    if (level > 0) {
      std::string grating_key = c.tag("GR", level + 1, "grating", "stair landing grating");
      emitGrating(c.out, grating_key, c.at(0.0, 3.0, z), c.site.origin.x + 8.0, c.site.origin.y + 7.0);
      emitHandrail(c.out, grating_key, c.at(0.3, 3.0, z), c.at(7.7, 3.0, z));
    }
    // Handrails where a deck edge is open: the roof all round, the corridor side below it.
    double open_y = outboard_low_y ? 22.0 : 0.0;
    std::string rail_key =
        level > 0 ? c.tag("HR", level + 1, "handrail", "deck edge handrails") : std::string();
    if (level == c.storeys && level > 0) {
      for (double y : {0.0, 22.0}) emitHandrail(c.out, rail_key, c.at(0.2, y, z), c.at(31.8, y, z));
      for (double x : {0.0, 32.0}) emitHandrail(c.out, rail_key, c.at(x, 0.2, z), c.at(x, 21.8, z));
    } else if (level > 0) {
      emitHandrail(c.out, rail_key, c.at(0.2, open_y, z), c.at(31.8, open_y, z));
    }
    if (level == c.storeys) break;
    // Walls: blast walls on the outboard face and the west end of the lowest storey only;
    // upper storeys are open frames, so the plant reads as a plant from outside while decks
    // and the low walls still occlude views from inside.
    if (level == 0) {
      std::string wall_key = c.tag("WL", level + 1, "wall", "blast and weather walls");
      double wall_y = outboard_low_y ? -0.12 : 22.0;
      double wall_top = z + kStoreyHeightM - kPlate - 0.7;
      for (int ix = 0; ix < kBaysX; ++ix) {
        // Louvred openings, but never a wall record without a panel.
        if (c.rng.chance(0.2f) && ix != 1) continue;
        emitBox(c.out, kLayerDecks, wall_key, format("wall M%u L%u bay %d", c.area, level, ix),
                c.at(kXs[ix], wall_y, z), c.at(kXs[ix + 1], wall_y + 0.12, wall_top));
      }
      for (int iy = 1; iy < kBaysY; ++iy)
        emitBox(c.out, kLayerDecks, wall_key, format("wall M%u L%u end %d", c.area, level, iy),
                c.at(-0.12, kYs[iy], z), c.at(0.0, kYs[iy + 1], wall_top));
    }
    // Stairs in the well bay: two flights and a landing per storey.
    std::string stair_key = c.tag("SR", level + 1, "stair", "stair tower flights");
    float half = float(kStoreyHeightM) * 0.5f;
    float run = emitStairFlight(c.out, stair_key, c.at(0.9, 0.4, z), half, 1.0f, 1.0f);
    emitGrating(c.out, stair_key, c.at(0.9 + run, 0.4, z + half), c.site.origin.x + 0.9 + run + 1.2,
                c.site.origin.y + 2.8);
    emitStairFlight(c.out, stair_key, c.at(0.9 + run, 1.7, z + half), half, 1.0f, -1.0f);
    // Lights under the ceiling and the cable tray along the rack.
    std::string light_key = c.tag("LT", level + 1, "lighting", "area lighting");
    for (int ix = 0; ix < kBaysX; ++ix)
      for (double y : {4.0, 18.0})
        emitLight(c.out, light_key, c.at(kXs[ix] + 4.0, y, z + kStoreyHeightM - kPlate - 0.75));
    emitCableTray(c.out, c.at(0.0, 14.4, z + 8.0), 32.0f, 0.6f);
    emitCableTray(c.out, c.at(0.0, 7.8, z + 8.0), 32.0f, 0.45f);
  }
}

// ---- Piping ---------------------------------------------------------------------------------

uint32_t randomSize(Random& rng, uint32_t min_size, uint32_t max_size) {
  // Small bore dominates real plants: bias toward the low end.
  float u = rng.uniform();
  return min_size + std::min(max_size - min_size, static_cast<uint32_t>(u * u * (max_size - min_size + 1)));
}

// Straight headers across the module with tie-in flanges at both ends; some top-tier lines get
// an up-and-over expansion loop.
void emitHeaders(Context& c, double z_top_of_beam, double y0, double y1, uint32_t max_size,
                 bool loops, const char* where) {
  double y = y0;
  RunStyle style;
  style.valve_chance = 0.12f;
  style.max_valves = 1;
  while (true) {
    uint32_t size = randomSize(c.rng, 0, max_size);
    uint32_t svc = c.rng.below(serviceCount());
    bool wanted = c.take();
    bool loop = loops && c.rng.chance(0.5f);
    float r = pipeSize(size).od_m * 0.5f;
    double pitch = 2.0 * (r * 1.45 + 0.025) + 0.08;
    if (y + pitch > y1) break;
    double py = y + 0.5 * pitch;
    y += pitch;
    if (!wanted) continue;
    PipeLine line = openLine(c.out, svc, size, where);
    double pz = z_top_of_beam + r + 0.02;
    c.route.clear();
    c.route.push_back(c.at(0.05, py, pz));
    if (loop) {
      double bend = 1.5 * pipeSize(size).nominal_mm * 0.001;
      double h = 2.0 * bend + 0.8, xa = c.rng.uniform(6.0f, 12.0f), w = 3.0 + 2.0 * bend;
      c.route.push_back(c.at(xa, py, pz));
      c.route.push_back(c.at(xa, py, pz + h));
      c.route.push_back(c.at(xa + w, py, pz + h));
      c.route.push_back(c.at(xa + w, py, pz));
    }
    c.route.push_back(c.at(kModuleLengthM - 0.05, py, pz));
    emitRun(c.out, c.rng, line, c.route, style);
  }
}

// Connects each equipment nozzle to the rack: out of the nozzle, up to a branch elevation,
// across to a lane under the rack, along it, and up into the header above.
void emitBranches(Context& c, double z) {
  uint32_t lane = 0;
  RunStyle style;
  style.valve_chance = 0.35f;
  style.max_valves = 1;
  for (const Nozzle& n : c.nozzles) {
    PipeLine line = openLine(c.out, c.rng.below(serviceCount()), n.size, "equipment connection");
    double bend = std::max(1.5 * pipeSize(n.size).nominal_mm * 0.001, pipeSize(n.size).od_m * 0.65);
    double clear = 2.0 * bend + 0.3;
    double zb = z + (lane % 2 == 0 ? 4.4 : 5.0);
    double y_lane = kRackY0 + 0.5 + 0.45 * (lane % 10);
    ++lane;
    glm::dvec3 local = n.position - c.site.origin;
    c.route.clear();
    c.route.push_back(n.position);
    glm::dvec3 p = local;
    if (std::fabs(n.direction.z) < 0.5f) {
      p += glm::dvec3(n.direction) * clear;
      c.route.push_back(c.site.origin + p);
    }
    zb = std::max(zb, p.z + clear);
    if (zb > z + kTier0 - 0.6) continue;
    p.z = zb;
    c.route.push_back(c.site.origin + p);
    if (std::fabs(y_lane - p.y) < clear) y_lane = p.y + (y_lane > p.y ? clear : -clear);
    p.y = y_lane;
    c.route.push_back(c.site.origin + p);
    double dx = c.rng.uniform(2.5f, 6.0f) * (p.x > 16.0 ? -1.0 : 1.0);
    p.x = std::clamp(p.x + dx, 0.5, kModuleLengthM - 0.5);
    c.route.push_back(c.site.origin + p);
    p.z = z + kTier0 - 0.25;
    c.route.push_back(c.site.origin + p);
    emitRun(c.out, c.rng, line, c.route, style);
  }
}

// Utility stations: small-bore drops from the rack to hose valves at working height.
void emitUtilityDrops(Context& c, double z) {
  RunStyle style;
  style.valve_chance = 0.5f;
  style.max_valves = 1;
  style.flange_start = false;
  for (int i = 0; i < 12; ++i) {
    bool wanted = c.take();
    double x = 1.0 + 2.6 * i + c.rng.uniform(0.0f, 1.0f);
    bool south = c.rng.chance(0.5f);
    if (!wanted) continue;
    PipeLine line = openLine(c.out, 6 + c.rng.below(3), 0, "utility station drop");
    double y_rack = south ? kRackY0 + 0.3 : kRackY1 - 0.3;
    double y_station = south ? kRackY0 - 1.2 : kRackY1 + 1.2;
    c.route.clear();
    c.route.push_back(c.at(x, y_rack, z + kTier0 - 0.1));
    c.route.push_back(c.at(x, y_rack, z + 3.0));
    c.route.push_back(c.at(x, y_station, z + 3.0));
    c.route.push_back(c.at(x, y_station, z + 1.1));
    emitRun(c.out, c.rng, line, c.route, style);
  }
}

// ---- Equipment --------------------------------------------------------------------------------

void emitEquipment(Context& c, uint32_t storey) {
  double z = storey * kStoreyHeightM;
  struct Slot {
    double x, y;
    float rack_side;
  };
  const Slot slots[] = {{12.0, 3.8, 1.0f},  {20.0, 3.8, 1.0f},  {28.0, 3.8, 1.0f},
                        {4.0, 18.3, -1.0f}, {12.0, 18.3, -1.0f}, {20.0, 18.3, -1.0f},
                        {28.0, 18.3, -1.0f}};
  for (const Slot& s : slots) {
    bool wanted = c.take();
    float kind = c.rng.uniform();
    float size = c.rng.uniform();
    if (!wanted) continue;
    uint32_t number = ++c.equipment_number;
    glm::dvec3 base = c.at(s.x, s.y, z);
    if (kind < 0.32f) {
      emitPumpPair(c.out, c.templates, c.area, number, base, c.nozzles);
    } else if (kind < 0.5f) {
      emitVerticalVessel(c.out, c.rng, c.area, number, base, 1.2f + 1.4f * size, 3.5f + 1.3f * size,
                         s.rack_side, c.nozzles);
    } else if (kind < 0.66f) {
      emitHorizontalVessel(c.out, c.rng, c.area, number, base, 1.6f + 1.2f * size, 5.0f + 1.6f * size,
                           c.nozzles);
    } else if (kind < 0.82f) {
      emitExchanger(c.out, c.rng, c.area, number, base, 0.7f + 0.6f * size, 5.0f + 1.5f * size,
                    c.nozzles);
    } else if (kind < 0.92f && storey == 0) {
      emitCompressor(c.out, c.templates, c.area, number, base, c.nozzles);
    } else {
      emitAirReceiver(c.out, c.area, number, base, 1.4f + 0.8f * size, c.nozzles);
    }
  }
}

// ---- Main rack ------------------------------------------------------------------------------

void emitMainRack(Context& c) {
  const double y0 = kModuleWidthM + 0.5, y1 = kModuleWidthM + kCorridorWidthM - 0.5;
  std::string key = format("MR-%u", c.area);
  ProjectRecord r;
  r.db_key = key;
  r.type = "pipe rack";
  r.material = "S355 steel";
  r.description = format("main pipe rack segment beside module M%u", c.area);
  c.out.record(r);
  const double tiers[] = {-kStoolM + 3.5, -kStoolM + 7.0, -kStoolM + 10.5};
  for (double x : {0.0, 8.0, 16.0, 24.0}) {
    for (double y : {y0, y1})
      emitColumn(c.out, key, format("main rack M%u column x%.0f y%.1f", c.area, x, y),
                 c.at(x + 0.4, y, -kStoolM), float(tiers[2] + kStoolM + 0.2), c.column_profile);
    for (double t : tiers)
      emitBeam(c.out, key, format("main rack M%u beam x%.0f z%.1f", c.area, x, t),
               c.at(x + 0.4, y0, t - 0.25), false, float(y1 - y0), c.beam_profile);
  }
  for (int t = 0; t < 3; ++t)
    emitHeaders(c, tiers[t], y0 + 0.4, y1 - 0.4, 9, t == 2, "main pipe rack");
  for (int t = 0; t < 2; ++t) emitCableTray(c.out, c.at(0.0, y1 - 0.8, tiers[t] + 1.6), 32.0f, 0.6f);
}

}  // namespace

void emitModule(Emitter& out, EquipmentTemplates& templates, uint64_t seed,
                const ModuleSite& site, float fill) {
  Context c{out, templates, Random::derive(seed, 0x6d6f64756c65ull + site.index), site, fill,
            10u + site.index, 0, {}, {}, {}, {}, {}, {}, 0};
  c.storeys = fill >= 0.35f ? 3 : (fill >= 0.12f ? 2 : 1);
  c.column_profile = iProfile(0.5f, 0.4f);
  c.beam_profile = iProfile(0.7f, 0.3f);
  c.secondary_profile = iProfile(0.4f, 0.18f);
  c.rack_profile = iProfile(0.3f, 0.15f);
  emitSteel(c);
  emitDecksWallsAccess(c);
  for (uint32_t storey = 0; storey < c.storeys; ++storey) {
    double z = storey * kStoreyHeightM;
    c.nozzles.clear();
    emitEquipment(c, storey);
    emitHeaders(c, z + kTier0, kRackY0, kRackY1, 7, false, "module rack");
    emitHeaders(c, z + kTier1, kRackY0, kRackY1, 7, false, "module rack");
    emitBranches(c, z);
    emitUtilityDrops(c, z);
  }
  if (site.row == 0) emitMainRack(c);
}

}  // namespace tw::plant
