// Wavefront OBJ writer: one "o" group per object, world-space vertices, tessellating
// parametrics and NURBS at `tolerance`. Streams straight to disk.
//
// Output goes to PATH.tmp and finish() renames it to PATH; layer colours go to a companion .mtl
// (PATH with extension .mtl, referenced by "mtllib"), written at finish() when any layer is
// named. Destroying the writer without finish() removes the temporary files. I/O failures throw
// std::runtime_error naming the file. `tolerance` is the chordal tolerance in scene units.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>

#include "scene_sink.h"

namespace tw {

class ObjWriter : public SceneWriter {
 public:
  ObjWriter(const std::filesystem::path& path, float tolerance);
  ~ObjWriter() override;
  void onLayer(uint32_t index, const Layer& layer) override;
  void onObject(const SceneObject& object) override;
  void finish() override;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace tw
