// The viewer's layers, search, query and selection sets; see view_review.h.
#include "view_review.h"

#include <algorithm>
#include <cstdio>
#include <sstream>
#include <stdexcept>
#include <unordered_set>

#include <imgui.h>

#include "object_queries.h"

namespace tw {

ViewReview::ViewReview(const PackageView& view, ObjectStates& states, ViewSelection& selection,
                       const ProjectDatabase* db, std::filesystem::path sets_file)
    : view_(view), states_(states), selection_(selection), db_(db),
      sets_file_(std::move(sets_file)) {
  layer_objects_.resize(view_.layers().size());
  for (uint32_t o = 0; o < view_.objects().size(); ++o) {
    const pkg::ObjectRecord& r = view_.objects()[o];
    if (r.layer < layer_objects_.size()) layer_objects_[r.layer].push_back(o);
    object_of_id_.emplace(r.id, o);
  }
  recountLayers();
  try {
    sets_ = readSelectionSets(sets_file_);
  } catch (const std::exception& e) {
    sets_error_ = e.what();
    std::fprintf(stderr, "view: %s; saving sets is off until it is fixed or moved away\n",
                 e.what());
  }
}

void ViewReview::recountLayers() {
  layer_hidden_.assign(layer_objects_.size(), 0);
  for (size_t l = 0; l < layer_objects_.size(); ++l)
    for (uint32_t o : layer_objects_[l]) layer_hidden_[l] += (states_.flags(o) & kObjectHidden) != 0;
}

bool ViewReview::layerNamed(const std::string& name, uint32_t& layer) const {
  for (uint32_t l = 0; l < view_.layers().size(); ++l)
    if (view_.layerName(l) == name) {
      layer = l;
      return true;
    }
  std::printf("view: no layer named '%s'\n", name.c_str());
  std::fflush(stdout);
  return false;
}

void ViewReview::setLayerHidden(uint32_t layer, bool hidden) {
  if (layer >= layer_objects_.size()) return;
  for (uint32_t o : layer_objects_[layer]) states_.set(o, kObjectHidden, hidden);
  layer_hidden_[layer] = hidden ? uint32_t(layer_objects_[layer].size()) : 0;
  std::printf("view: layer '%s' %s (%zu objects)\n", std::string(view_.layerName(layer)).c_str(),
              hidden ? "hidden" : "shown", layer_objects_[layer].size());
  std::fflush(stdout);
}

void ViewReview::isolateLayer(uint32_t layer) {
  if (layer >= layer_objects_.size()) return;
  setAllBut(layer_objects_[layer], kObjectHidden);
  std::printf("view: layer '%s' isolated (%zu objects)\n",
              std::string(view_.layerName(layer)).c_str(), layer_objects_[layer].size());
  std::fflush(stdout);
}

void ViewReview::xrayOthers(uint32_t layer) {
  if (layer >= layer_objects_.size()) return;
  setAllBut(layer_objects_[layer], kObjectXray);
  std::printf("view: layer '%s' opaque, the others X-rayed\n",
              std::string(view_.layerName(layer)).c_str());
  std::fflush(stdout);
}

// Every object but `objects` takes `bit` (hidden or X-ray); the other of the two is cleared.
void ViewReview::setAllBut(const std::vector<uint32_t>& objects, uint32_t bit) {
  states_.setAll(kObjectHidden | kObjectXray, false);
  states_.setAll(bit, true);
  for (uint32_t o : objects) states_.set(o, bit, false);
  recountLayers();
}

void ViewReview::showAll() {
  states_.setAll(kObjectHidden, false);
  states_.setAll(kObjectXray, false);
  recountLayers();
  std::printf("view: everything shown\n");
  std::fflush(stdout);
}

namespace {

// Copies `text` into a panel field (cut to fit), so the panel shows what a script asked.
template <size_t N>
void showInField(char (&field)[N], const std::string& text) {
  const size_t n = std::min(text.size(), N - 1);
  std::copy_n(text.data(), n, field);
  field[n] = '\0';
}

}  // namespace

void ViewReview::search(const std::string& text) {
  showInField(search_text_, text);
  error_.clear();
  results_ = text.empty() ? std::vector<uint32_t>{} : objectsNamed(view_, text);
  results_label_ = std::to_string(results_.size()) + " objects named '" + text + "'";
  std::printf("view: search '%s': %zu objects\n", text.c_str(), results_.size());
  std::fflush(stdout);
}

void ViewReview::query(const std::string& where, const std::vector<std::string>& params) {
  showInField(query_text_, where);
  std::string joined;
  for (const std::string& p : params) joined += (joined.empty() ? "" : "; ") + p;
  showInField(query_params_, joined);
  results_.clear();
  error_.clear();
  results_label_.clear();
  if (!db_) {
    error_ = "no project database: give --db, or preprocess with --db";
  } else {
    try {
      const std::vector<std::string> keys = db_->findKeys(where, params);
      results_ = objectsWithKeys(view_, std::unordered_set<std::string>(keys.begin(), keys.end()));
      results_label_ = std::to_string(keys.size()) + " records, " +
                       std::to_string(results_.size()) + " objects";
    } catch (const std::exception& e) {
      error_ = e.what();
    }
  }
  if (error_.empty())
    std::printf("view: query '%s': %s\n", where.c_str(), results_label_.c_str());
  else
    std::printf("view: query '%s' failed: %s\n", where.c_str(), error_.c_str());
  std::fflush(stdout);
}

void ViewReview::selectResults() {
  selection_.select(results_);
  std::printf("view: selected %zu objects\n", results_.size());
  std::fflush(stdout);
}

void ViewReview::isolateResults() {
  setAllBut(results_, kObjectHidden);
  std::printf("view: isolated %zu objects\n", results_.size());
  std::fflush(stdout);
}

void ViewReview::zoomToResults() { zoom_requested_ = !results_.empty(); }

bool ViewReview::takeZoomRequest(glm::dvec3& lo, glm::dvec3& hi) {
  if (!zoom_requested_) return false;
  zoom_requested_ = false;
  return objectsBounds(view_, results_, lo, hi);
}

std::vector<uint32_t> ViewReview::sceneIds(std::vector<uint32_t> objects) const {
  for (uint32_t& o : objects) o = view_.objects()[o].id;
  return objects;
}

std::vector<uint32_t> ViewReview::objectsOf(const std::vector<uint32_t>& scene_ids) const {
  std::vector<uint32_t> objects;
  for (uint32_t id : scene_ids)
    if (auto it = object_of_id_.find(id); it != object_of_id_.end()) objects.push_back(it->second);
  return objects;
}

std::vector<uint32_t> ViewReview::objectsWith(uint32_t bits) const {
  std::vector<uint32_t> objects;
  for (uint32_t o = 0; o < states_.size(); ++o)
    if (states_.flags(o) & bits) objects.push_back(o);
  return objects;
}

void ViewReview::saveSelection(const std::string& name) {
  SelectionSet set;
  set.name = name;
  set.kind = SelectionSet::Kind::Selection;
  set.selected = sceneIds(selection_.selected());
  saveSet(std::move(set));
}

void ViewReview::saveVisibility(const std::string& name) {
  SelectionSet set;
  set.name = name;
  set.kind = SelectionSet::Kind::Visibility;
  set.hidden = sceneIds(objectsWith(kObjectHidden));
  set.xray = sceneIds(objectsWith(kObjectXray));
  saveSet(std::move(set));
}

// A set of the same name is replaced; the file is written at once.
void ViewReview::saveSet(SelectionSet set) {
  if (set.name.empty()) {
    error_ = "a set needs a name";
    return;
  }
  if (!sets_error_.empty()) {
    error_ = sets_error_ + " (not written over)";
    std::printf("view: set '%s' not saved: %s\n", set.name.c_str(), error_.c_str());
    std::fflush(stdout);
    return;
  }
  const size_t objects = set.selected.size() + set.hidden.size() + set.xray.size();
  auto same = std::find_if(sets_.begin(), sets_.end(),
                           [&](const SelectionSet& s) { return s.name == set.name; });
  const std::string name = set.name;
  if (same != sets_.end()) *same = std::move(set);
  else sets_.push_back(std::move(set));
  try {
    writeSelectionSets(sets_file_, sets_);
    std::printf("view: saved set '%s' (%zu objects) to %s\n", name.c_str(), objects,
                sets_file_.string().c_str());
  } catch (const std::exception& e) {
    error_ = e.what();
    std::printf("view: set '%s' not saved: %s\n", name.c_str(), e.what());
  }
  std::fflush(stdout);
}

bool ViewReview::restore(const std::string& name) {
  auto set = std::find_if(sets_.begin(), sets_.end(),
                          [&](const SelectionSet& s) { return s.name == name; });
  if (set == sets_.end()) {
    std::printf("view: no set named '%s'\n", name.c_str());
    std::fflush(stdout);
    return false;
  }
  if (set->kind == SelectionSet::Kind::Selection) {
    selection_.select(objectsOf(set->selected));
  } else {
    states_.setAll(kObjectHidden | kObjectXray, false);
    for (uint32_t o : objectsOf(set->hidden)) states_.set(o, kObjectHidden, true);
    for (uint32_t o : objectsOf(set->xray)) states_.set(o, kObjectXray, true);
    recountLayers();
  }
  std::printf("view: restored set '%s'\n", name.c_str());
  std::fflush(stdout);
  return true;
}

namespace {

// "a; b; c" as the values of ?1, ?2, ?3 (blank: none).
std::vector<std::string> splitParams(const char* text) {
  std::vector<std::string> params;
  std::stringstream in(text);
  for (std::string item; std::getline(in, item, ';');) {
    const size_t first = item.find_first_not_of(' '), last = item.find_last_not_of(' ');
    if (first != std::string::npos) params.push_back(item.substr(first, last - first + 1));
  }
  return params;
}

}  // namespace

void ViewReview::drawPanel(float x, float y, float height) {
  ImGui::SetNextWindowPos(ImVec2(x, y), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowSize(ImVec2(440.0f, height), ImGuiCond_FirstUseEver);
  ImGui::Begin("Review");
  if (ImGui::CollapsingHeader("Layers", ImGuiTreeNodeFlags_DefaultOpen)) {
    for (uint32_t l = 0; l < layer_objects_.size(); ++l) {
      ImGui::PushID(int(l));
      bool shown = layer_hidden_[l] < layer_objects_[l].size() || layer_objects_[l].empty();
      if (ImGui::Checkbox("##shown", &shown)) setLayerHidden(l, !shown);
      ImGui::SameLine();
      ImGui::Text("%-22s %7zu", std::string(view_.layerName(l)).c_str(), layer_objects_[l].size());
      ImGui::SameLine();
      if (ImGui::SmallButton("isolate")) isolateLayer(l);
      ImGui::SameLine();
      if (ImGui::SmallButton("x-ray others")) xrayOthers(l);
      ImGui::PopID();
    }
    if (ImGui::Button("show all")) showAll();
  }
  if (ImGui::CollapsingHeader("Search", ImGuiTreeNodeFlags_DefaultOpen)) {
    if (ImGui::InputText("name or key", search_text_, sizeof search_text_,
                         ImGuiInputTextFlags_EnterReturnsTrue))
      search(search_text_);
    ImGui::InputText("where", query_text_, sizeof query_text_);
    ImGui::InputText("values ?1; ?2", query_params_, sizeof query_params_);
    if (ImGui::Button("query")) query(query_text_, splitParams(query_params_));
    if (!error_.empty()) ImGui::TextColored(ImVec4(1.0f, 0.45f, 0.35f, 1.0f), "%s", error_.c_str());
    if (!results_label_.empty()) {
      ImGui::TextUnformatted(results_label_.c_str());
      if (ImGui::Button("select all")) selectResults();
      ImGui::SameLine();
      if (ImGui::Button("isolate")) isolateResults();
      ImGui::SameLine();
      if (ImGui::Button("zoom to")) zoomToResults();
      const size_t listed = std::min<size_t>(results_.size(), 8);
      for (size_t i = 0; i < listed; ++i)
        ImGui::Text("  %s  %s", std::string(view_.objectName(results_[i])).c_str(),
                    std::string(view_.objectDbKey(results_[i])).c_str());
      if (results_.size() > listed) ImGui::Text("  ... and %zu more", results_.size() - listed);
    }
  }
  if (ImGui::CollapsingHeader("Sets", ImGuiTreeNodeFlags_DefaultOpen)) {
    ImGui::InputText("set name", set_name_, sizeof set_name_);
    if (ImGui::Button("save selection")) saveSelection(set_name_);
    ImGui::SameLine();
    if (ImGui::Button("save visibility")) saveVisibility(set_name_);
    for (const SelectionSet& set : sets_) {
      ImGui::PushID(set.name.c_str());
      if (ImGui::SmallButton("restore")) restore(set.name);
      ImGui::SameLine();
      ImGui::Text("%s (%s)", set.name.c_str(),
                  set.kind == SelectionSet::Kind::Selection ? "selection" : "visibility");
      ImGui::PopID();
    }
  }
  ImGui::End();
}

}  // namespace tw
