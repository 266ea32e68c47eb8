// The viewer's section planes: up to six, each placed on a surface (a click, or the script's
// `section-at X Y`: through the picked point, its normal the surface's, turned toward the eye, so
// what lies in front of the surface is cut away and its inside shows) or typed in, then dragged
// along its normal; and a section box around the selection. They go to the walkthrough
// (Walkthrough::setSections), so every draw path clips and caps (section_planes.h).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "camera.h"
#include "frame_loop.h"
#include "section_planes.h"
#include "view_selection.h"

namespace tw {

class ViewSections {
 public:
  ViewSections(Walkthrough& walk, const ViewSelection& selection);

  // A plane on the surface under framebuffer pixel x, y of the frame just drawn with `camera`;
  // false when nothing is there (or six planes are placed already).
  bool placeAt(const Camera& camera, int x, int y);
  bool add(const SectionPlane& plane);
  // Moves the last plane along its normal by `metres` (toward the removed side when positive).
  void offsetLast(double metres);
  // A box around the selection, `margin` metres larger on every side; false with no selection.
  bool boxAroundSelection(double margin);
  void clear();
  const std::vector<SectionPlane>& planes() const { return planes_; }
  const std::optional<std::pair<glm::dvec3, glm::dvec3>>& box() const { return box_; }
  // Planes and box as a viewpoint keeps them (box last, six planes facing out).
  std::vector<SectionPlane> all() const;
  void set(std::vector<SectionPlane> planes);

  // Whether the next click places a plane (the panel's button; the viewer asks before picking).
  bool placingOnClick() const { return placing_; }
  void stopPlacing() { placing_ = false; }
  // The "Sections" part of the review window.
  void drawPanel();

 private:
  void apply();

  Walkthrough& walk_;
  const ViewSelection& selection_;
  std::vector<SectionPlane> planes_;
  std::optional<std::pair<glm::dvec3, glm::dvec3>> box_;
  bool placing_ = false;
  float drag_m_ = 0.0f;  // the panel's slider: the last plane's offset from where it was placed
  char typed_[128] = {};  // the panel's field for a typed-in plane
};

}  // namespace tw
