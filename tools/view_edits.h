// The viewer's edits: moving, rotating and scaling the selection with a gizmo, hiding and
// colouring it and commenting on it, each step recorded in the change set (change_set.h) with
// undo and redo and saved next to the package (model.changes.json, reloaded when the viewer
// opens it); and the exploded view, which pushes each selected object away from the selection's
// common centre, animated, and is undone by collapsing (a view, not an edit: it is not recorded).
//
// The gizmo, switched on with G, sits on the selection's centre: an arrow per axis (X red, Y green, Z blue) moves
// along it, a square per plane moves in it, a ring per axis rotates about it; moves snap to
// kMoveStepM, rotations to kRotateStepDeg. It is drawn over the frame with ImGui's foreground
// list, and it takes the mouse while a handle is dragged (press, drag, release: one change).
// Scripts drive the same calls (view_script.h).
#pragma once

#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "camera.h"
#include "change_set.h"
#include "frame_loop.h"
#include "view_selection.h"

namespace tw {

class ViewEdits {
 public:
  static constexpr double kMoveStepM = 0.01;
  static constexpr double kRotateStepDeg = 5.0;

  // Reads the change set (a damaged one is reported and never written over) and shows it.
  ViewEdits(Walkthrough& walk, ViewSelection& selection, std::filesystem::path changes_file,
            std::string author);

  // Edits of the selection, snapped; each is one change per selected key (undone together).
  void moveSelection(const glm::dvec3& translation);
  void rotateSelection(const glm::dvec3& axis, double degrees);
  void scaleSelection(double factor);
  void hideSelection();
  void commentSelection(const std::string& text);
  bool undo();
  bool redo();
  bool save();  // false (and a message) when the file could not be read at start or written
  const ChangeSet& changes() const { return changes_; }
  // The world move of a key by the edits (identity when unmoved; the exploded view aside).
  glm::dmat4 placement(const std::string& key) const { return changes_.placement(key); }

  // The exploded view of the selection: factor 1 is where things stand; animated over
  // kExplodeSeconds from the current factor.
  void explode(double factor, double now_s);
  void collapse(double now_s) { explode(1.0, now_s); }
  bool exploding() const { return explode_to_ != 1.0 || explode_now_ != 1.0; }

  // Once a frame before rendering: the explode animation's step.
  void update(double now_s);

  // The gizmo, in window pixels of a `width` x `height` framebuffer seen by `camera`. press()
  // returns whether a handle was hit (then the mouse belongs to the gizmo until release()).
  bool press(const Camera& camera, int width, int height, double x, double y);
  void dragTo(double x, double y);
  void release();
  bool capturing() const { return drag_.has_value(); }
  // The gizmo shows (and takes presses) only while it is switched on: the G key, the Edit
  // section's checkbox, the script's `gizmo`.
  void toggleGizmo();
  bool gizmoShown() const { return show_gizmo_; }
  void drawGizmo(const Camera& camera, int width, int height) const;
  // The "Edit" section of the review window (drawn after it): undo, redo, save, explode, hide,
  // comment, the change count.
  void drawPanel(double now_s);

 private:
  struct Handle {
    enum class Kind { None, Arrow, Plane, Ring } kind = Kind::None;
    int axis = 0;  // arrow and ring: the axis; plane: the normal's axis
  };
  struct Gizmo {
    glm::dvec3 centre{0.0};
    double length_m = 1.0;  // the arrows' world length
  };
  struct Drag {
    Handle handle;
    Gizmo gizmo;
    Camera camera;
    int width = 0, height = 0;
    double x0 = 0.0, y0 = 0.0;
    size_t changes_before = 0;
  };

  std::vector<std::string> selectedKeys() const;
  void addPerKey(const std::vector<std::string>& keys, const std::function<Change(const std::string&, const glm::dvec3&)>& make);
  bool keyCentre(const std::string& key, glm::dvec3& centre) const;
  bool selectionCentre(glm::dvec3& centre, double& size) const;
  std::optional<Gizmo> gizmo(const Camera& camera, int height) const;
  Handle hit(const Gizmo& g, const Camera& camera, int width, int height, double x, double y) const;
  void refresh();  // the walkthrough's moved objects and states from the changes and explode

  Walkthrough& walk_;
  ViewSelection& selection_;
  std::filesystem::path file_;
  std::string author_;
  ChangeSet changes_;
  std::string load_error_;
  std::map<uint32_t, MovedMesh> geometry_;  // by object, move unset
  // Explode: each object's offset from the common centre (pushed to factor times it), animated.
  std::map<uint32_t, glm::dvec3> explode_offsets_;
  double explode_from_ = 1.0, explode_to_ = 1.0, explode_now_ = 1.0, explode_start_s_ = 0.0;
  std::optional<Drag> drag_;
  bool show_gizmo_ = false;
  std::vector<uint32_t> hidden_by_edits_;
};

}  // namespace tw
