// The range of coordinates and sizes a scene may hold, checked as objects are read.
//
// Downstream code trusts its bounds: Embree asserts on rays with coordinates past about 1e18, a
// bound of 1e308 overflows the package's grid arithmetic, and a NaN makes every comparison
// false. So each object a reader delivers is checked once, at the boundary, against documented
// limits far beyond any plant or ship (and beyond the Earth), and one that falls outside is a
// FormatError naming the file, the object and the reason, before anything is built from it.
#pragma once

#include <string>

#include "scene_sink.h"

namespace tw {

// No world coordinate beyond this many metres from the scene's zero (georeferenced models sit
// a few thousand kilometres out).
constexpr double kMaxSceneCoordinateM = 1e9;
// No object larger than this along any axis.
constexpr double kMaxObjectExtentM = 1e7;

// Passes objects on to `inner` after checking them; layers pass unchanged. Throws FormatError
// naming `file_name`.
class RangeCheckedSink : public SceneSink {
 public:
  RangeCheckedSink(std::string file_name, SceneSink& inner)
      : file_name_(std::move(file_name)), inner_(inner) {}
  void onLayer(uint32_t index, const Layer& layer) override { inner_.onLayer(index, layer); }
  void onObject(const SceneObject& object) override;

 private:
  std::string file_name_;
  SceneSink& inner_;
};

}  // namespace tw
