// The viewer's selection and properties panel; see view_selection.h.
#include "view_selection.h"

#include <algorithm>
#include <cstdio>
#include <string>

#include <imgui.h>

#include "object_queries.h"

namespace tw {

ViewSelection::ViewSelection(const PackageView& view, ObjectStates& states,
                             const ProjectDatabase* db)
    : view_(view), states_(states), db_(db) {}

void ViewSelection::click(const std::optional<Pick>& pick, bool toggle) {
  if (!toggle) clear();
  last_ = pick;
  record_.reset();
  properties_.clear();
  if (!pick) return;
  const uint32_t object = pick->object;
  auto it = std::find(selected_.begin(), selected_.end(), object);
  if (toggle && it != selected_.end()) {
    selected_.erase(it);
    states_.set(object, kObjectSelected, false);
  } else if (it == selected_.end()) {
    selected_.push_back(object);
    states_.set(object, kObjectSelected, true);
  }
  const std::string key(view_.objectDbKey(object));
  if (db_ && !key.empty()) {
    record_ = db_->find(key);
    properties_ = db_->properties(key);
  }
  std::printf("view: picked object %u (%s) key %s at %.17g %.17g %.17g%s\n", object,
              std::string(view_.objectName(object)).c_str(), key.c_str(), pick->world.x,
              pick->world.y, pick->world.z, record_ ? ", record found" : "");
  std::fflush(stdout);
}

void ViewSelection::select(const std::vector<uint32_t>& objects) {
  clear();
  for (uint32_t o : objects) {
    if (o >= view_.objects().size() || (states_.flags(o) & kObjectSelected)) continue;
    selected_.push_back(o);
    states_.set(o, kObjectSelected, true);
  }
}

void ViewSelection::clear() {
  for (uint32_t o : selected_) states_.set(o, kObjectSelected, false);
  selected_.clear();
  last_.reset();
  record_.reset();
  properties_.clear();
}

bool ViewSelection::bounds(glm::dvec3& lo, glm::dvec3& hi) const {
  return objectsBounds(view_, selected_, lo, hi);
}

void ViewSelection::drawPanel(float x, float y) const {
  ImGui::SetNextWindowPos(ImVec2(x, y), ImGuiCond_FirstUseEver, ImVec2(1.0f, 0.0f));
  ImGui::Begin("Properties", nullptr, ImGuiWindowFlags_AlwaysAutoResize);
  if (!last_) {
    ImGui::TextUnformatted(selected_.empty() ? "click an object to select it"
                                             : "selection changed");
  } else {
    const uint32_t object = last_->object;
    const pkg::ObjectRecord& r = view_.objects()[object];
    ImGui::Text("object   %u (id %u)", object, r.id);
    ImGui::Text("name     %s", std::string(view_.objectName(object)).c_str());
    ImGui::Text("layer    %s", std::string(view_.layerName(r.layer)).c_str());
    ImGui::Text("db key   %s", std::string(view_.objectDbKey(object)).c_str());
    ImGui::Text("point    %.6f %.6f %.6f", last_->world.x, last_->world.y, last_->world.z);
    ImGui::Text("distance %.3f m", last_->distance_m);
    ImGui::Separator();
    if (!db_) {
      ImGui::TextUnformatted("no project database (--db)");
    } else if (!record_) {
      ImGui::TextUnformatted("no record for this key");
    } else {
      ImGui::Text("type          %s", record_->type.c_str());
      ImGui::Text("line number   %s", record_->line_number.c_str());
      ImGui::Text("service       %s", record_->service.c_str());
      ImGui::Text("material      %s", record_->material.c_str());
      ImGui::Text("diameter      %.1f mm", record_->nominal_diameter_mm);
      ImGui::Text("pressure      %.2f bar", record_->design_pressure_bar);
      ImGui::Text("temperature   %.1f C", record_->design_temperature_c);
      ImGui::TextWrapped("%s", record_->description.c_str());
      for (const ProjectProperty& p : properties_)
        ImGui::Text("%s / %s  %s %s", p.set.c_str(), p.name.c_str(), p.value.c_str(),
                    p.unit.c_str());
    }
  }
  ImGui::Text("%zu selected   [click] select  [Ctrl] add  [dbl] frame  [Esc] clear",
              selected_.size());
  ImGui::End();
}

}  // namespace tw
