// Numbering, counting and streaming of generated objects; see plant_emitter.h.
#include "plant_emitter.h"

#include <cstdarg>
#include <cstdio>

#include "nurbs_conforming.h"

namespace tw::plant {

Layer layerDefinition(uint32_t index) {
  // Colours are 0xAABBGGRR, chosen to read like a plant model: grey steel, yellow process
  // piping, green water, blue utilities, red fire water, orange grating.
  static const Layer kLayers[kLayerCount] = {
      {"hull", 0xff5a4a3cu},
      {"decks and walls", 0xff9aa0a4u},
      {"structure", 0xff3c78b4u},
      {"grating", 0xff2a8ce0u},
      {"stairs and handrails", 0xff20c8f0u},
      {"piping process", 0xff30d0e8u},
      {"piping water", 0xff40b040u},
      {"piping utility", 0xffd08040u},
      {"piping fire", 0xff2020d0u},
      {"valves", 0xffc040c0u},
      {"equipment", 0xff80c0a0u},
      {"electrical", 0xff6060f0u},
  };
  return kLayers[index < kLayerCount ? index : 0];
}

std::string format(const char* fmt, ...) {
  char buffer[256];
  va_list args;
  va_start(args, fmt);
  int n = std::vsnprintf(buffer, sizeof buffer, fmt, args);
  va_end(args);
  if (n < 0) return {};
  return std::string(buffer, static_cast<size_t>(n) < sizeof buffer ? static_cast<size_t>(n)
                                                                      : sizeof buffer - 1);
}

Emitter::Emitter(SceneSink* sink, ProjectDatabase* db, float tolerance)
    : sink_(sink), db_(db), tolerance_(tolerance) {}

void Emitter::declareLayers() {
  for (uint32_t i = 0; i < kLayerCount; ++i)
    if (sink_) sink_->onLayer(i, layerDefinition(i));
  summary_.layers = kLayerCount;
}

void Emitter::record(const ProjectRecord& record) {
  ++summary_.db_records;
  if (db_ && sink_) db_->put(record);
}

void Emitter::primitive(uint32_t layer, const std::string& key, std::string name,
                        const Transform& transform, const Primitive& primitive) {
  ++summary_.objects;
  ++summary_.primitive_objects;
  const uint64_t triangles = primitiveTriangleCount(primitive, tolerance_);
  summary_.triangles += triangles;
  summary_.budget_triangles += triangles;
  uint32_t id = next_id_++;
  if (!sink_) return;
  scratch_.info.id = id;
  scratch_.info.name = std::move(name);
  scratch_.info.layer = layer;
  scratch_.info.db_key = key;
  scratch_.info.color_rgba = 0;
  scratch_.info.transform = transform;
  scratch_.geometry = primitive;
  sink_->onObject(scratch_);
}

void Emitter::emit(SceneObject& object) {
  ++summary_.objects;
  object.info.id = next_id_++;
  if (const auto* mesh = std::get_if<TriangleMesh>(&object.geometry)) {
    ++summary_.mesh_objects;
    summary_.mesh_triangles += mesh->triangleCount();
    summary_.triangles += mesh->triangleCount();
    summary_.budget_triangles += mesh->triangleCount();
  } else if (const auto* p = std::get_if<Primitive>(&object.geometry)) {
    ++summary_.primitive_objects;
    const uint64_t triangles = primitiveTriangleCount(*p, tolerance_);
    summary_.triangles += triangles;
    summary_.budget_triangles += triangles;
  } else if (const auto* nurbs = std::get_if<NurbsPatchSet>(&object.geometry)) {
    ++summary_.nurbs_objects;
    summary_.nurbs_patches += nurbs->patches.size();
    summary_.budget_triangles += nurbsTriangleCount(*nurbs, tolerance_);
    summary_.triangles += nurbsConformingTriangleCount(*nurbs, tolerance_);
  }
  if (sink_) sink_->onObject(object);
}

}  // namespace tw::plant
