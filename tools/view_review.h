// The viewer's review tools besides picking: the layers (each with its object count: show,
// hide, isolate, X-ray the others, show all), a search over names and keys, a query over the
// project database (a WHERE clause over its records and properties, values bound), what they
// find (select all, isolate, zoom to), and named selection sets saved next to the package
// (selection_sets.h). Every action changes the walkthrough's object states, so it shows at every
// level of detail from the next frame; the panel's buttons and the viewer's script
// (view_script.h) call the same actions, and each says what it did on stdout.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <unordered_map>
#include <vector>

#include <glm/glm.hpp>

#include "object_states.h"
#include "package_view.h"
#include "project_database.h"
#include "selection_sets.h"
#include "view_selection.h"

namespace tw {

class ViewReview {
 public:
  // `db` may be null; everything given must outlive the review. The sets are read from
  // `sets_file` now (a damaged file is reported, and not written over).
  ViewReview(const PackageView& view, ObjectStates& states, ViewSelection& selection,
             const ProjectDatabase* db, std::filesystem::path sets_file);

  // Layers, by index or name (an unknown name is reported, and nothing changes).
  void setLayerHidden(uint32_t layer, bool hidden);
  void isolateLayer(uint32_t layer);  // only this layer shows; nothing is X-rayed
  void xrayOthers(uint32_t layer);    // this layer opaque, every other ghosted; nothing hidden
  void showAll();                     // nothing hidden or X-rayed
  bool layerNamed(const std::string& name, uint32_t& layer) const;

  // Search and query; results replace the previous ones.
  void search(const std::string& text);
  // `params`: the values for ?1, ?2, ... A bad query leaves no results and SQLite's message.
  void query(const std::string& where, const std::vector<std::string>& params);
  const std::vector<uint32_t>& results() const { return results_; }
  const std::string& error() const { return error_; }
  void selectResults();
  void isolateResults();
  // Asks the viewer to frame the results (it takes the box with takeZoomRequest).
  void zoomToResults();
  bool takeZoomRequest(glm::dvec3& lo, glm::dvec3& hi);

  // Selection sets.
  void saveSelection(const std::string& name);
  void saveVisibility(const std::string& name);
  bool restore(const std::string& name);
  const std::vector<SelectionSet>& sets() const { return sets_; }
  const std::filesystem::path& setsFile() const { return sets_file_; }

  // The "Review" window (ImGui) at x, y, `height` pixels tall at first (it scrolls).
  void drawPanel(float x, float y, float height);

 private:
  void recountLayers();
  void setAllBut(const std::vector<uint32_t>& objects, uint32_t bit);
  void saveSet(SelectionSet set);
  std::vector<uint32_t> sceneIds(std::vector<uint32_t> objects) const;
  std::vector<uint32_t> objectsOf(const std::vector<uint32_t>& scene_ids) const;
  std::vector<uint32_t> objectsWith(uint32_t bits) const;

  const PackageView& view_;
  ObjectStates& states_;
  ViewSelection& selection_;
  const ProjectDatabase* db_;
  std::filesystem::path sets_file_;
  std::vector<std::vector<uint32_t>> layer_objects_;  // object indices by layer
  std::vector<uint32_t> layer_hidden_;                // hidden objects by layer
  std::unordered_map<uint32_t, uint32_t> object_of_id_;  // scene id -> object index
  std::vector<uint32_t> results_;
  std::string results_label_, error_;
  std::vector<SelectionSet> sets_;
  std::string sets_error_;  // the sets file could not be read: it is not written over
  bool zoom_requested_ = false;
  // The panel's text fields.
  char search_text_[128] = {};
  char query_text_[512] = {};
  char query_params_[256] = {};
  char set_name_[64] = {};
};

}  // namespace tw
