// A sink that drops the objects of some layers by name and passes everything else on, so any
// reader can leave out a layer (`preprocess --exclude-layer hull`) without knowing of it. The
// layer table itself passes whole: indices, names and colours stay those of the file, and an
// excluded layer is simply empty.
#pragma once

#include <algorithm>
#include <string>
#include <vector>

#include "scene_sink.h"

namespace tw {

class LayerFilterSink : public SceneSink {
 public:
  LayerFilterSink(SceneSink& next, const std::vector<std::string>& excluded_names)
      : next_(next), excluded_names_(excluded_names) {}

  void onLayer(uint32_t index, const Layer& layer) override {
    if (excluded_.size() <= index) excluded_.resize(index + 1, false);
    excluded_[index] = std::find(excluded_names_.begin(), excluded_names_.end(), layer.name) !=
                       excluded_names_.end();
    next_.onLayer(index, layer);
  }

  void onObject(const SceneObject& object) override {
    if (object.info.layer < excluded_.size() && excluded_[object.info.layer]) return;
    next_.onObject(object);
  }

 private:
  SceneSink& next_;
  const std::vector<std::string>& excluded_names_;
  std::vector<bool> excluded_;
};

}  // namespace tw
