// Binary little-endian PLY writer for triangle soups in world coordinates, for other tools.
//
// Every object is tessellated (parametrics and NURBS at `tolerance`), transformed to world space
// and appended: positions as float x, y, z (relative to no origin: world coordinates rounded to
// float), an RGB colour per vertex from the object's or its layer's colour, and triangles. Memory
// stays bounded: faces are spooled to a side file and appended on finish().
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>

#include "scene_sink.h"

namespace tw {

class PlyWriter : public SceneWriter {
 public:
  PlyWriter(const std::filesystem::path& path, float tolerance);
  ~PlyWriter() override;
  void onLayer(uint32_t index, const Layer& layer) override;
  void onObject(const SceneObject& object) override;
  void finish() override;

  uint64_t vertexCount() const;
  uint64_t triangleCount() const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace tw
