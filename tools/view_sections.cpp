// The viewer's section planes (view_sections.h).
#include "view_sections.h"

#include <cstdio>

#include <imgui.h>

#include "object_pick.h"
#include "view_log.h"

namespace tw {
ViewSections::ViewSections(Walkthrough& walk, const ViewSelection& selection)
    : walk_(walk), selection_(selection) {}

bool ViewSections::placeAt(const Camera& camera, int x, int y) {
  const GlRenderer& r = walk_.renderer();
  auto at = [&](int px, int py) -> std::optional<Pick> {
    if (px < 0 || py < 0 || px >= r.width() || py >= r.height()) return std::nullopt;
    return pickPixel(r, camera, px, py);
  };
  const std::optional<Pick> centre = at(x, y);
  if (!centre) {
    viewSay("sections: nothing under %d,%d\n", x, y);
    return false;
  }
  // The surface's normal from two neighbouring points on the same object.
  glm::dvec3 normal = -camera.forward();
  const std::optional<Pick> right = at(x + 2, y), down = at(x, y + 2);
  if (right && down && right->object == centre->object && down->object == centre->object) {
    const glm::dvec3 n = glm::cross(right->world - centre->world, down->world - centre->world);
    if (glm::length(n) > 1e-12) normal = glm::normalize(n);
  }
  if (glm::dot(normal, camera.position - centre->world) < 0.0) normal = -normal;
  placing_ = false;
  return add({centre->world, normal});
}

bool ViewSections::add(const SectionPlane& plane) {
  if (planes_.size() >= kMaxUserSectionPlanes) {
    viewSay("sections: %zu planes already, at most %zu\n", planes_.size(), kMaxUserSectionPlanes);
    return false;
  }
  planes_.push_back(plane);
  drag_m_ = 0.0f;
  apply();
  viewSay("sections: plane %zu at (%.3f, %.3f, %.3f), normal (%.3f, %.3f, %.3f)\n", planes_.size(),
      plane.point.x, plane.point.y, plane.point.z, plane.normal.x, plane.normal.y, plane.normal.z);
  return true;
}

void ViewSections::offsetLast(double metres) {
  if (planes_.empty()) return;
  planes_.back().point += planes_.back().normal * metres;
  apply();
  viewSay("sections: plane %zu moved %.3f m along its normal\n", planes_.size(), metres);
}

bool ViewSections::boxAroundSelection(double margin) {
  glm::dvec3 lo, hi;
  if (!selection_.bounds(lo, hi)) return false;
  box_ = std::make_pair(lo - glm::dvec3(margin), hi + glm::dvec3(margin));
  apply();
  viewSay("sections: box around the selection\n");
  return true;
}

void ViewSections::clear() {
  planes_.clear();
  box_.reset();
  drag_m_ = 0.0f;
  apply();
  viewSay("sections: cleared\n");
}

std::vector<SectionPlane> ViewSections::all() const {
  std::vector<SectionPlane> out = planes_;
  if (box_)
    for (const SectionPlane& p : sectionBoxPlanes(box_->first, box_->second)) out.push_back(p);
  return out;
}

void ViewSections::set(std::vector<SectionPlane> planes) {
  if (planes.size() > kMaxUserSectionPlanes) planes.resize(kMaxUserSectionPlanes);
  planes_ = std::move(planes);
  box_.reset();
  apply();
}

void ViewSections::apply() { walk_.setSections(all()); }

void ViewSections::drawPanel() {
  ImGui::Begin("Review");
  if (!ImGui::CollapsingHeader("Sections")) {
    ImGui::End();
    return;
  }
  ImGui::Text("%zu planes%s", planes_.size(), box_ ? " and a box" : "");
  if (ImGui::Button(placing_ ? "click a surface..." : "Plane at click")) placing_ = !placing_;
  ImGui::SameLine();
  if (ImGui::Button("Box around selection")) boxAroundSelection(0.05);
  ImGui::SameLine();
  if (ImGui::Button("Clear")) clear();
  // Typed in: a point and the normal toward the side removed, world metres.
  ImGui::InputText("##plane", typed_, sizeof typed_);
  ImGui::SameLine();
  if (ImGui::Button("Add X,Y,Z,NX,NY,NZ")) {
    try {
      add(parseSectionPlane(typed_));
      typed_[0] = '\0';
    } catch (const std::exception& e) {
      viewSay("sections: %s\n", e.what());
    }
  }
  if (!planes_.empty()) {
    float drag = drag_m_;
    if (ImGui::SliderFloat("drag last (m)", &drag, -10.0f, 10.0f, "%.2f")) {
      offsetLast(double(drag - drag_m_));
      drag_m_ = drag;
    }
  }
  ImGui::End();
}

}  // namespace tw
