// The viewer's measure tool: points picked on surfaces and snapped (point_snap.h: a cylinder's
// end centre, a vertex, a feature edge, within 10 pixels), showing the distance and its X, Y, Z
// parts for two points and the angle at the middle one for three; and the minimum distance
// between the two selected objects on their full-resolution geometry, or between their centre
// lines (object_distance.h), with the two closest points drawn. Switched on with M (or the
// panel); while on, clicks measure instead of selecting. Scripts: measure-at X Y,
// measure-between, measure-clear.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "camera.h"
#include "frame_loop.h"
#include "point_snap.h"
#include "view_selection.h"

namespace tw {

class ViewMeasure {
 public:
  // `placement`: the world move of a database key (the viewer's edits; identity when unmoved),
  // so moved objects are measured where they are drawn.
  ViewMeasure(Walkthrough& walk, const ViewSelection& selection,
              std::function<glm::dmat4(const std::string&)> placement);

  void toggle();
  bool on() const { return on_; }
  // A point under framebuffer pixel x, y of the frame just drawn with `camera`, snapped.
  bool addPoint(const Camera& camera, int x, int y);
  // The minimum distance between the selection's two objects (by database key).
  bool between(bool centre_lines);
  void clear();

  // Points, lines and labels over the frame (ImGui's foreground list).
  void draw(const Camera& camera, int width, int height) const;
  // The "Measure" part of the review window.
  void drawPanel();

 private:
  std::string keyOf(uint32_t object) const;

  Walkthrough& walk_;
  const ViewSelection& selection_;
  std::function<glm::dmat4(const std::string&)> placement_;
  bool on_ = false;
  std::vector<SnappedPoint> points_;
  std::optional<std::pair<glm::dvec3, glm::dvec3>> closest_;
  std::string result_;
};

}  // namespace tw
