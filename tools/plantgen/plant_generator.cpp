// The plant generator's driver: site layout and the triangle budget.
//
// A site is a row of FPSOs side by side; each carries two rows of process modules along its
// hull. The driver measures what a full module costs with a dry run, plans how many modules
// and hulls the target needs, then streams hull after hull and module after module. The last
// module is filled partly, its fill found by dry runs, so the total lands close to the target.
#include "plant_generator.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "plant_parts.h"

namespace tw {
namespace {

using plant::EquipmentTemplates;
using plant::Emitter;
using plant::ModuleSite;

constexpr uint32_t kMaxModulesAlong = 10;  // per row: a 400 m hull
constexpr float kHullEndsM = 40.0f;        // bow and stern beyond the module rows
constexpr float kHullDepthM = 26.0f;
constexpr float kHullBeamM = 2.0f * (plant::kModuleWidthM + 2.0f) + plant::kCorridorWidthM;
constexpr double kFpsoSpacingM = 110.0;

struct Layout {
  uint32_t fpsos = 1;
  uint32_t modules_along = 1;  // per row, per FPSO
  bool smooth_hull = true;      // ship-like; a faceted barge when that would cost too much
  uint64_t hull_triangles = 0;  // one hull
};
// Hulls may take at most this share of the target before they fall back to barges.
constexpr double kMaxHullShare = 0.15;

float hullLength(uint32_t modules_along) {
  return static_cast<float>(modules_along) * plant::kModuleLengthM + 2.0f * kHullEndsM;
}

SceneObject makeHull(uint32_t index, const Layout& layout) {
  glm::dvec3 origin(0.0, kFpsoSpacingM * index, 0.0);
  return plant::buildHull(index, origin, hullLength(layout.modules_along), kHullBeamM, kHullDepthM,
                          layout.smooth_hull);
}

Layout planLayout(uint64_t modules, uint64_t target, float tolerance) {
  uint64_t slots = modules + std::max<uint64_t>(1, modules / 16);  // spare: module costs vary
  Layout layout;
  layout.fpsos = static_cast<uint32_t>((slots + 2 * kMaxModulesAlong - 1) / (2 * kMaxModulesAlong));
  uint64_t per_fpso = (slots + layout.fpsos - 1) / layout.fpsos;
  layout.modules_along = static_cast<uint32_t>((per_fpso + 1) / 2);
  for (bool smooth : {true, false}) {
    layout.smooth_hull = smooth;
    SceneObject hull = makeHull(0, layout);
    layout.hull_triangles = nurbsTriangleCount(std::get<NurbsPatchSet>(hull.geometry), tolerance);
    if (double(layout.hull_triangles) * layout.fpsos <= kMaxHullShare * double(target)) break;
  }
  return layout;
}

ModuleSite moduleSite(uint32_t index, const Layout& layout) {
  uint32_t per_fpso = 2 * layout.modules_along;
  uint32_t fpso = index / per_fpso, j = index % per_fpso;
  ModuleSite site;
  site.index = index;
  site.row = j % 2;
  double x = kHullEndsM + plant::kModuleLengthM * (j / 2);
  double y = site.row == 0 ? -0.5 * plant::kCorridorWidthM - plant::kModuleWidthM
                           : 0.5 * plant::kCorridorWidthM;
  site.origin = glm::dvec3(x, kFpsoSpacingM * fpso + y, 3.0);
  return site;
}

uint64_t dryRunModule(EquipmentTemplates& templates, const PlantOptions& options,
                      const ModuleSite& site, float fill) {
  Emitter dry(nullptr, nullptr, options.tolerance);
  plant::emitModule(dry, templates, options.seed, site, fill);
  return dry.triangles();
}

// The fill whose module cost is closest to `budget` (0 when even the smallest overshoots more
// than an empty slot undershoots). Costs grow with fill, so bisection converges.
float fitFill(EquipmentTemplates& templates, const PlantOptions& options, const ModuleSite& site,
              uint64_t budget) {
  float lo = 0.0f, hi = 1.0f, best = 0.0f;
  uint64_t best_error = budget;  // error of leaving the slot empty
  for (int i = 0; i < 14; ++i) {
    float mid = 0.5f * (lo + hi);
    uint64_t cost = dryRunModule(templates, options, site, mid);
    uint64_t error = cost > budget ? cost - budget : budget - cost;
    if (error < best_error) {
      best_error = error;
      best = mid;
    }
    if (cost > budget) hi = mid; else lo = mid;
  }
  return best;
}

void checkCancelled(Progress* progress) {
  if (progress && progress->cancelled()) throw std::runtime_error("cancelled");
}

}  // namespace

PlantSummary generatePlant(const PlantOptions& options, SceneSink& sink, ProjectDatabase* db,
                           Progress* progress) {
  if (options.target_triangles == 0) throw std::invalid_argument("target triangle count is zero");
  if (!(options.tolerance > 0.0f)) throw std::invalid_argument("tolerance must be positive");
  const uint64_t target = options.target_triangles;

  EquipmentTemplates templates;
  // What a full module costs, on average over both rows (row 0 also builds the main rack).
  Layout layout;
  uint64_t module_cost = (dryRunModule(templates, options, moduleSite(0, layout), 1.0f) +
                          dryRunModule(templates, options, moduleSite(1, layout), 1.0f)) / 2;
  module_cost = std::max<uint64_t>(module_cost, 1);
  // The hulls depend on the module count and take budget from it: iterate to a fixed point.
  uint64_t modules = 1;
  for (int i = 0; i < 4; ++i) {
    uint64_t hulls = uint64_t(layout.fpsos) * layout.hull_triangles;
    uint64_t left = target > hulls ? target - hulls : 0;
    modules = std::max<uint64_t>(1, (left + module_cost - 1) / module_cost);
    layout = planLayout(modules, target, options.tolerance);
  }

  Emitter out(&sink, db, options.tolerance);
  out.declareLayers();
  beginStage(progress, "generating plant", target);
  const uint32_t slots_per_fpso = 2 * layout.modules_along;
  uint32_t module_index = 0;
  uint64_t modules_done = 0, hulls_done = 0;
  bool budget_spent = false;
  for (uint32_t f = 0; f < layout.fpsos; ++f) {
    // Every planned hull is emitted, even past the last module: the budget reserved it.
    SceneObject hull = makeHull(f, layout);
    out.record(plant::hullRecord(f, hullLength(layout.modules_along), kHullBeamM, kHullDepthM));
    out.emit(hull);
    ++hulls_done;
    uint64_t reserve = uint64_t(layout.fpsos - f - 1) * layout.hull_triangles;
    for (uint32_t j = 0; j < slots_per_fpso && !budget_spent; ++j, ++module_index) {
      checkCancelled(progress);
      uint64_t spent = out.triangles() + reserve;
      if (spent >= target) {
        budget_spent = true;
        break;
      }
      uint64_t remaining = target - spent;
      ModuleSite site = moduleSite(module_index, layout);
      float fill = 1.0f;
      // Far from the end a full module always fits; near it, measure before committing.
      if (remaining < module_cost * 2 &&
          dryRunModule(templates, options, site, 1.0f) > remaining) {
        fill = fitFill(templates, options, site, remaining);
        budget_spent = true;
      }
      if (fill > 0.0f) {
        plant::emitModule(out, templates, options.seed, site, fill);
        ++modules_done;
      }
      updateProgress(progress, std::min(out.triangles(), target));
      if (budget_spent) break;
    }
  }
  endStage(progress);
  PlantSummary summary = out.summary();
  summary.modules = modules_done;
  summary.hulls = hulls_done;
  return summary;
}

}  // namespace tw
