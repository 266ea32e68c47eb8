// Which way is up in a scene file, and the turn that makes it Z up.
//
// Inside TeraWalk the scene is Z up: the camera's orbits and fly-throughs turn about Z, walking
// keeps Z vertical, the generated plant is built that way. Files disagree: glTF is Y up by its
// specification, STEP, IFC and our .tws are Z up, and OBJ, PLY and STL say nothing, so the user
// says (`--up y|z`; Z when not said). A Y-up file is turned by +90 degrees about X as it is read,
// (x, y, z) -> (x, -z, y): its Y becomes Z and handedness is kept. Only the objects' placements
// turn (UpAxisSink): meshes, primitives and patches keep their local frames.
#pragma once

#include <string_view>

#include <glm/glm.hpp>

#include "scene_sink.h"

namespace tw {

enum class UpAxis { Auto, Y, Z };  // Auto: the format's own rule

// "auto", "y", "z"; throws std::invalid_argument naming the value otherwise.
UpAxis parseUpAxis(std::string_view name);
const char* upAxisName(UpAxis up);

// The rotation taking Y-up coordinates to Z-up ones.
glm::dmat3 yUpToZUp();

// Passes everything on with each object's placement turned from Y up to Z up.
class UpAxisSink : public SceneSink {
 public:
  explicit UpAxisSink(SceneSink& next) : next_(next) {}
  void onLayer(uint32_t index, const Layer& layer) override { next_.onLayer(index, layer); }
  void onObject(const SceneObject& object) override;

 private:
  SceneSink& next_;
  SceneObject turned_;
};

}  // namespace tw
