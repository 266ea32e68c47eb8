// The viewer's path player: plays a camera path (--path, or the one just recorded with R) with a
// time slider, pauses on a moment, smooths it (camera_path.h, smoothCameraPath) and writes it
// again. While it plays or holds a moment the camera follows the path; Stop hands it back to the
// keyboard and mouse.
#pragma once

#include <string>

#include "camera_path.h"

namespace tw {

class ViewPath {
 public:
  void load(CameraPath path, const std::string& name);
  bool following() const { return following_ && !path_.keys.empty(); }

  void play();
  void pause();
  void stop();
  void seek(double seconds_from_start);
  // A steadier copy replaces the path (control keys every `interval_s`, 30 keys a second).
  void smooth(double interval_s);
  // Writes the path; false (said in the log) when it cannot.
  bool save(const std::string& file);

  // Advances the time by `dt` when playing (looping at the end) and, while following, puts the
  // camera where the path is (keeping its near and far planes).
  void update(double dt, Camera& camera);
  // The "Path" panel; `recorded` is offered for playing when it has keys.
  void drawPanel(const CameraPath& recorded);

 private:
  CameraPath path_;
  std::string name_;
  double time_s_ = 0.0;  // from the path's first key
  bool playing_ = false, following_ = false;
  float interval_s_ = 1.0f;
  char save_name_[256] = "smoothed.path";
};

}  // namespace tw
