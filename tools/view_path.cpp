// The viewer's path player (view_path.h).
#include "view_path.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <imgui.h>

#include "view_log.h"

namespace tw {

void ViewPath::load(CameraPath path, const std::string& name) {
  path_ = std::move(path);
  name_ = name;
  time_s_ = 0.0;
  following_ = !path_.keys.empty();
  playing_ = following_;
}

void ViewPath::play() {
  following_ = playing_ = !path_.keys.empty();
}

void ViewPath::pause() {
  playing_ = false;
  following_ = !path_.keys.empty();
}

void ViewPath::stop() { playing_ = following_ = false; }

void ViewPath::seek(double seconds_from_start) {
  time_s_ = std::clamp(seconds_from_start, 0.0, path_.durationS());
  following_ = !path_.keys.empty();
  viewSay("path at %.2f s of %.2f s", time_s_, path_.durationS());
}

void ViewPath::smooth(double interval_s) {
  if (path_.keys.size() < 2) return;
  const size_t before = path_.keys.size();
  path_ = smoothCameraPath(path_, std::max(0.05, interval_s), 30.0);
  viewSay("path smoothed: %zu keys to %zu, control keys every %.2f s", before, path_.keys.size(), interval_s);
}

bool ViewPath::save(const std::string& file) {
  try {
    writeCameraPath(path_, file);
    viewSay("path written: %s (%zu keys)", file.c_str(), path_.keys.size());
    return true;
  } catch (const std::runtime_error& e) {
    viewSay("path not written: %s", e.what());
    return false;
  }
}

void ViewPath::update(double dt, Camera& camera) {
  if (!following()) return;
  const double span = path_.durationS();
  if (playing_ && span > 0.0) time_s_ = std::fmod(time_s_ + dt, span);
  camera = path_.sample(path_.keys.front().time_s + time_s_, camera);
}

void ViewPath::drawPanel(const CameraPath& recorded) {
  ImGui::Begin("Review");
  if (!ImGui::CollapsingHeader("Path")) {
    ImGui::End();
    return;
  }
  if (path_.keys.empty()) {
    ImGui::TextUnformatted("no path: give --path, or record one with R");
  } else {
    ImGui::Text("%s: %zu keys, %.1f s", name_.c_str(), path_.keys.size(), path_.durationS());
    if (ImGui::Button(playing_ ? "Pause" : "Play")) playing_ ? pause() : play();
    ImGui::SameLine();
    if (ImGui::Button("Stop")) stop();
    float t = float(time_s_);
    if (ImGui::SliderFloat("time (s)", &t, 0.0f, float(path_.durationS()), "%.2f")) {
      pause();
      seek(t);
    }
    ImGui::SliderFloat("control keys every (s)", &interval_s_, 0.1f, 10.0f, "%.1f", ImGuiSliderFlags_Logarithmic);
    if (ImGui::Button("Smooth")) smooth(interval_s_);
    ImGui::InputText("##save", save_name_, sizeof save_name_);
    ImGui::SameLine();
    if (ImGui::Button("Save path")) save(save_name_);
  }
  if (!recorded.keys.empty() && ImGui::Button("Play the recorded path")) load(recorded, "recorded");
  ImGui::End();
}

}  // namespace tw
