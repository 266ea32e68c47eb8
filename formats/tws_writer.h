// Writer for TeraWalk's native scene format (.tws); see docs/scene-format.md.
//
// Each layer and each object becomes one chunk appended as soon as it arrives, so the writer
// holds at most one object in memory. Parametrics and NURBS are written exactly, untessellated.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>

#include "scene_sink.h"

namespace tw {

// Output goes to `path` + ".tmp" and is renamed to `path` by finish(). I/O failures throw
// std::runtime_error naming the file. Input the reader would reject (a layer declared out of
// order, an object on an undeclared layer, mesh indices out of range, non-finite values, invalid
// primitives or NURBS patches, names over 65,535 bytes) throws std::invalid_argument and writes
// nothing for that call. Meshes whose chunk would exceed 64 MiB are split into parts.
class TwsWriter : public SceneWriter {
 public:
  explicit TwsWriter(const std::filesystem::path& path);  // creates the temporary file
  ~TwsWriter() override;  // without finish(), removes the temporary file
  void onLayer(uint32_t index, const Layer& layer) override;
  void onObject(const SceneObject& object) override;
  void finish() override;  // writes the END chunk, closes, renames; no calls may follow

  uint64_t bytesWritten() const;  // bytes handed to the file so far, header included

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace tw
