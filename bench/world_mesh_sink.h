// WorldMeshSink: gathers every triangle mesh a reader streams into one indexed mesh in world
// coordinates (primitives and NURBS are ignored). The benchmarks that start from a model file
// (the bunny) use it to get plain buffers.
#pragma once

#include <cstdint>
#include <variant>
#include <vector>

#include <glm/glm.hpp>

#include "scene_sink.h"

namespace tw {

class WorldMeshSink : public SceneSink {
 public:
  void onLayer(uint32_t, const Layer&) override {}
  void onObject(const SceneObject& object) override {
    const auto* mesh = std::get_if<TriangleMesh>(&object.geometry);
    if (!mesh) return;
    const auto base = static_cast<uint32_t>(positions.size());
    for (const glm::vec3& p : mesh->positions)
      positions.push_back(glm::vec3(object.info.transform.apply(p)));
    for (uint32_t i : mesh->indices) indices.push_back(base + i);
  }
  std::vector<glm::vec3> positions;
  std::vector<uint32_t> indices;
};

}  // namespace tw
