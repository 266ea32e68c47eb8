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

class TwsWriter : public SceneWriter {
 public:
  explicit TwsWriter(const std::filesystem::path& path);
  ~TwsWriter() override;  // without finish(), removes the temporary file
  void onLayer(uint32_t index, const Layer& layer) override;
  void onObject(const SceneObject& object) override;
  void finish() override;

  uint64_t bytesWritten() const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace tw
