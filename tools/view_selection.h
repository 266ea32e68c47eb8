// What the reviewer has picked in the viewer: the selected objects, tinted through the
// walkthrough's object states, and the last pick (object, point, database record), which the
// properties panel shows.
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include <glm/glm.hpp>

#include "object_pick.h"
#include "object_states.h"
#include "package_view.h"
#include "project_database.h"

namespace tw {

class ViewSelection {
 public:
  // `db` may be null (no database given); both must outlive the selection.
  ViewSelection(const PackageView& view, ObjectStates& states, const ProjectDatabase* db);

  // A click: the picked object alone becomes the selection (nothing picked clears it); with
  // `toggle` (Ctrl), it is added, or removed when it was selected.
  void click(const std::optional<Pick>& pick, bool toggle);
  // These objects become the selection (search results, a restored set); no pick is shown.
  void select(const std::vector<uint32_t>& objects);
  void clear();
  bool empty() const { return selected_.empty(); }
  const std::vector<uint32_t>& selected() const { return selected_; }
  // World box of the selected objects' level-0 geometry; false when nothing is selected.
  bool bounds(glm::dvec3& lo, glm::dvec3& hi) const;

  // The properties panel (ImGui): the last pick's object, point and record.
  void drawPanel(float x, float y) const;

 private:
  const PackageView& view_;
  ObjectStates& states_;
  const ProjectDatabase* db_;
  std::vector<uint32_t> selected_;
  std::optional<Pick> last_;
  std::optional<ProjectRecord> record_;
  std::vector<ProjectProperty> properties_;
};

}  // namespace tw
