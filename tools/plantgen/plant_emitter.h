// The plant generator's single output path: ids, layers, records, and equivalent-triangle counts.
//
// Every part builder hands its objects to an Emitter, which numbers them, counts their
// equivalent triangles (exactly as tw::SceneStats does, and as the size target does: NURBS per
// patch) and streams them to the sink. An Emitter without a sink is a dry run: it only counts,
// which is how the driver sizes the last module.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

#include "plant_generator.h"

namespace tw::plant {

// Layer indices, in declaration order.
enum LayerId : uint32_t {
  kLayerHull,
  kLayerDecks,  // solid deck plates and walls: the big occluders
  kLayerStructure,
  kLayerGrating,
  kLayerAccess,  // stairs and handrails
  kLayerPipingProcess,
  kLayerPipingWater,
  kLayerPipingUtility,
  kLayerPipingFire,
  kLayerValves,
  kLayerEquipment,
  kLayerElectrical,
  kLayerCount
};
Layer layerDefinition(uint32_t index);

class Emitter {
 public:
  // `sink` and `db` may be nullptr: a dry run counts but writes nothing.
  Emitter(SceneSink* sink, ProjectDatabase* db, float tolerance);

  float tolerance() const { return tolerance_; }
  bool dryRun() const { return sink_ == nullptr; }

  // Declares all layers (call once, first).
  void declareLayers();
  // Stores the record of a new key. Callers make each key once (tags come from counters), so
  // this never needs to remember keys.
  void record(const ProjectRecord& record);

  // Emits one parametric object; the Emitter assigns the id.
  void primitive(uint32_t layer, const std::string& key, std::string name,
                 const Transform& transform, const Primitive& primitive);
  // Emits a prepared object (meshes, NURBS, reused templates); sets its id.
  void emit(SceneObject& object);

  const PlantSummary& summary() const { return summary_; }
  PlantSummary& summary() { return summary_; }
  // As the size target counts them (PlantOptions::target_triangles).
  uint64_t triangles() const { return summary_.budget_triangles; }

  // Tag counters live here so that names stay unique across modules and hulls.
  uint32_t next_line_number = 1001;
  uint32_t next_valve_number = 1;
  uint32_t next_tray_number = 1;

 private:
  SceneSink* sink_;
  ProjectDatabase* db_;
  float tolerance_;
  uint32_t next_id_ = 1;
  SceneObject scratch_;  // reused for primitives so names and keys keep their capacity
  PlantSummary summary_;
};

// printf-style formatting into a std::string (names and tags are short).
std::string format(const char* fmt, ...) __attribute__((format(printf, 1, 2)));

}  // namespace tw::plant
