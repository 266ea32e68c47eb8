// The viewer's ocean and sky panel (view_environment.h).
#include "view_environment.h"

#include <stdexcept>

#include <imgui.h>

#include "view_log.h"

namespace tw {

ViewEnvironment::ViewEnvironment(Walkthrough& walk, const std::optional<EnvironmentOptions>& initial,
                                 const glm::dvec3& model_centre)
    : walk_(walk) {
  if (initial) {
    options_ = *initial;
  } else {
    options_.grid.center = glm::dvec2(model_centre);
  }
  apply();
}

void ViewEnvironment::setOcean(bool on) {
  options_.ocean = on;
  apply();
  viewSay("ocean %s (waterline %.2f m, %zu waves)", on ? "on" : "off", options_.grid.waterline_m,
          options_.waves.waves.size());
}

void ViewEnvironment::setSky(bool on) {
  options_.sky = on;
  apply();
  viewSay("sky %s", on ? "on" : "off");
}

void ViewEnvironment::apply() {
  try {
    validateEnvironment(options_);
    walk_.setEnvironment(options_);
    error_.clear();
  } catch (const std::invalid_argument& e) {
    error_ = e.what();
  }
}

void ViewEnvironment::drawPanel() {
  ImGui::Begin("Review");
  if (!ImGui::CollapsingHeader("Ocean and sky")) {
    ImGui::End();
    return;
  }
  bool changed = ImGui::Checkbox("ocean", &options_.ocean);
  ImGui::SameLine();
  changed |= ImGui::Checkbox("sky", &options_.sky);
  float waterline = float(options_.grid.waterline_m);
  if (ImGui::DragFloat("waterline (m)", &waterline, 0.1f, -1000.0f, 1000.0f, "%.1f")) {
    options_.grid.waterline_m = waterline;
    changed = true;
  }
  float elevation = float(options_.sun.sun_elevation_deg), azimuth = float(options_.sun.sun_azimuth_deg);
  if (ImGui::SliderFloat("sun elevation", &elevation, -10.0f, 90.0f, "%.0f deg")) {
    options_.sun.sun_elevation_deg = elevation;
    changed = true;
  }
  if (ImGui::SliderFloat("sun azimuth", &azimuth, 0.0f, 360.0f, "%.0f deg")) {
    options_.sun.sun_azimuth_deg = azimuth;
    changed = true;
  }
  // The wind makes a new set of waves; the steepness applies to whatever set there is.
  float wind = float(options_.waves.wind_speed_mps), wind_direction = float(options_.waves.wind_direction_deg);
  int count = int(options_.waves.waves.size());
  bool new_sea = ImGui::SliderFloat("wind (m/s)", &wind, 0.5f, 40.0f, "%.1f");
  new_sea |= ImGui::SliderFloat("wind direction", &wind_direction, -180.0f, 180.0f, "%.0f deg");
  new_sea |= ImGui::SliderInt("waves", &count, 1, kMaxOceanWaves);
  if (new_sea) {
    const double steepness = options_.waves.steepness;
    options_.waves = wavesForWind(wind, wind_direction, count);
    options_.waves.steepness = steepness;
    changed = true;
  }
  float steepness = float(options_.waves.steepness);
  if (ImGui::SliderFloat("steepness", &steepness, 0.0f, 1.0f, "%.2f")) {
    options_.waves.steepness = steepness;
    changed = true;
  }
  if (ImGui::TreeNode("each wave")) {
    for (size_t i = 0; i < options_.waves.waves.size(); ++i) {
      GerstnerWave& w = options_.waves.waves[i];
      ImGui::PushID(int(i));
      float amplitude = float(w.amplitude_m), wavelength = float(w.wavelength_m), direction = float(w.direction_deg);
      ImGui::Text("wave %zu", i + 1);
      if (ImGui::SliderFloat("amplitude (m)", &amplitude, 0.0f, 10.0f, "%.2f", ImGuiSliderFlags_Logarithmic)) {
        w.amplitude_m = amplitude;
        changed = true;
      }
      if (ImGui::SliderFloat("wavelength (m)", &wavelength, 0.5f, 1000.0f, "%.1f", ImGuiSliderFlags_Logarithmic)) {
        w.wavelength_m = wavelength;
        changed = true;
      }
      if (ImGui::SliderFloat("direction", &direction, -180.0f, 180.0f, "%.0f deg")) {
        w.direction_deg = direction;
        changed = true;
      }
      ImGui::PopID();
    }
    ImGui::TreePop();
  }
  if (changed) apply();
  if (!error_.empty()) ImGui::TextColored(ImVec4(1, 0.4f, 0.3f, 1), "%s", error_.c_str());
  ImGui::End();
}

}  // namespace tw
