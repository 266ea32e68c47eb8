// The procedural offshore plant generator behind `terawalk gen plant`: our benchmark input.
//
// It streams a plant that looks like FPSO topsides: ship-like NURBS hulls carrying rows of
// process modules (solid decks, walls, I-beam steel, gratings, stairs, handrails), pipe racks
// with thousands of parametric pipe runs (cylinders, torus elbows, flanges, valves), vessels of
// revolution, pumps and compressors as triangle meshes, and cable trays. Every object has a
// plant-tag database key with one record in the project database.
//
// Deterministic: the same options give a byte-identical object stream. Units: metres, Z up.
// Memory stays bounded whatever the size: objects go to the sink as soon as they exist.
#pragma once

#include <cstdint>

#include "progress.h"
#include "project_database.h"
#include "scene_sink.h"
#include "tessellate.h"

namespace tw {

struct PlantOptions {
  // Size of the plant in equivalent triangles: meshes count their triangles, parametrics
  // tw::primitiveTriangleCount and NURBS tw::nurbsTriangleCount (per patch) at `tolerance`. The
  // generated total (PlantSummary::budget_triangles) lands within a few percent of this from
  // about 50,000 up (less is one small module). Counting NURBS per patch, not as the preprocessor
  // tessellates them, keeps the plants of each seed and size what they were.
  uint64_t target_triangles = 1'000'000;
  uint64_t seed = 1;
  float tolerance = kDefaultChordalTolerance;  // metres
};

struct PlantSummary {
  uint64_t objects = 0;
  uint64_t layers = 0;
  uint64_t triangles = 0;  // equivalent triangles, counted exactly like tw::SceneStats does
  uint64_t budget_triangles = 0;  // as the size target counts them: NURBS per patch
  uint64_t mesh_triangles = 0;
  uint64_t primitive_objects = 0;
  uint64_t mesh_objects = 0;
  uint64_t nurbs_objects = 0;
  uint64_t nurbs_patches = 0;
  uint64_t db_records = 0;  // distinct database keys, each put once
  uint64_t modules = 0;     // process modules (a partly filled last one counts)
  uint64_t hulls = 0;
};

// Streams the plant to `sink` (layers first) and its records to `db` (may be nullptr; the caller
// commits). Reports equivalent triangles to `progress` (may be nullptr) and throws
// std::runtime_error("cancelled") when it asks to stop. Throws std::invalid_argument for a zero
// target or a non-positive tolerance.
PlantSummary generatePlant(const PlantOptions& options, SceneSink& sink, ProjectDatabase* db,
                           Progress* progress);

}  // namespace tw
