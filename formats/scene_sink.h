// The streaming hand-off between readers (and the generator) and whatever consumes a scene.
//
// Readers never build a whole scene in memory; they push layers and objects to a sink as soon as
// each is complete, so memory stays bounded by the largest single object part.
#pragma once

#include <cstdint>

#include "scene.h"

namespace tw {

class SceneSink {
 public:
  virtual ~SceneSink() = default;

  // Declares layer `index`. Indices count up from 0 without gaps, and each layer is declared
  // before the first object that uses it.
  virtual void onLayer(uint32_t index, const Layer& layer) = 0;

  // One object, or one part of an object: a reader may split a large mesh into several parts
  // that carry the same ObjectInfo and arrive one after another. The sink must copy what it keeps.
  virtual void onObject(const SceneObject& object) = 0;
};

}  // namespace tw

namespace tw {

// A sink that writes a file. Output goes to a temporary name and only finish() renames it into
// place, so a failed or interrupted run never leaves a truncated file under the final name.
class SceneWriter : public SceneSink {
 public:
  // Flushes, closes and renames the file into place. Throws std::runtime_error on I/O failure.
  virtual void finish() = 0;
};

// Passes everything to several sinks, in order (for example a .tws writer and a PLY writer).
class FanOutSink : public SceneSink {
 public:
  void add(SceneSink& sink) { sinks_.push_back(&sink); }
  void onLayer(uint32_t index, const Layer& layer) override {
    for (SceneSink* s : sinks_) s->onLayer(index, layer);
  }
  void onObject(const SceneObject& object) override {
    for (SceneSink* s : sinks_) s->onObject(object);
  }

 private:
  std::vector<SceneSink*> sinks_;
};

}  // namespace tw
