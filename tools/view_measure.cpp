// The viewer's measure tool (view_measure.h).
#include "view_measure.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

#include <imgui.h>

#include "change_set_view.h"
#include "object_distance.h"
#include "object_pick.h"
#include "object_queries.h"
#include "view_log.h"

namespace tw {
namespace {

constexpr double kSnapPx = 10.0;
const ImU32 kMeasureColour = IM_COL32(255, 0, 255, 255);

std::optional<ImVec2> screen(const Camera& camera, int width, int height, const glm::dvec3& p) {
  const std::optional<glm::dvec2> s = imagePoint(camera, width, height, p);
  if (!s) return std::nullopt;
  return ImVec2(float(s->x), float(s->y));
}

}  // namespace

ViewMeasure::ViewMeasure(Walkthrough& walk, const ViewSelection& selection,
                         std::function<glm::dmat4(const std::string&)> placement)
    : walk_(walk), selection_(selection), placement_(std::move(placement)) {}

std::string ViewMeasure::keyOf(uint32_t object) const {
  const PackageView& view = walk_.package();
  return std::string(view.objectDbKey(object).empty() ? view.objectName(object) : view.objectDbKey(object));
}

void ViewMeasure::toggle() {
  on_ = !on_;
  viewSay("measure: %s\n", on_ ? "on (clicks place points)" : "off");
}

bool ViewMeasure::addPoint(const Camera& camera, int x, int y) {
  const GlRenderer& r = walk_.renderer();
  if (x < 0 || y < 0 || x >= r.width() || y >= r.height()) return false;
  const std::optional<Pick> pick = pickPixel(r, camera, x, y);
  if (!pick) {
    viewSay("measure: nothing under %d,%d\n", x, y);
    return false;
  }
  if (points_.size() == 3) points_.clear();
  closest_.reset();
  // Ten pixels at the point's distance, in metres.
  const double radius = kSnapPx * pick->distance_m * 2.0 * std::tan(0.5 * camera.fov_y_rad) / r.height();
  const uint32_t object[] = {pick->object};
  const MeasureShape shape = movedShape(walk_.package(),
                                        measureShape(walk_.package(), object, std::max(1e-4, radius * 0.1)),
                                        placement_(keyOf(pick->object)));
  const SnappedPoint p = snapPoint(walk_.package(), shape, pick->world, radius);
  points_.push_back(p);
  viewSay("measure: point %zu (%s) at (%.4f, %.4f, %.4f)\n", points_.size(), snapKindName(p.kind),
      p.world.x, p.world.y, p.world.z);
  char text[160];
  if (points_.size() == 2) {
    const glm::dvec3 d = points_[1].world - points_[0].world;
    std::snprintf(text, sizeof text, "distance %.4f m  (dx %.4f, dy %.4f, dz %.4f)", glm::length(d),
                  d.x, d.y, d.z);
    result_ = text;
    viewSay("measure: %s\n", text);
  } else if (points_.size() == 3) {
    const glm::dvec3 a = points_[0].world - points_[1].world, b = points_[2].world - points_[1].world;
    const double angle = std::acos(std::clamp(glm::dot(a, b) / (glm::length(a) * glm::length(b)), -1.0, 1.0));
    std::snprintf(text, sizeof text, "angle %.3f deg", angle * 180.0 / std::numbers::pi);
    result_ = text;
    viewSay("measure: %s\n", text);
  }
  return true;
}

bool ViewMeasure::between(bool centre_lines) {
  // The selection's objects grouped by key: the first two keys are the two sides.
  const PackageView& view = walk_.package();
  std::vector<std::string> keys;
  for (uint32_t o : selection_.selected()) {
    const std::string key = keyOf(o);
    if (std::find(keys.begin(), keys.end(), key) == keys.end()) keys.push_back(key);
  }
  if (keys.size() != 2) {
    viewSay("measure: select two objects (%zu selected)\n", keys.size());
    return false;
  }
  auto objectsOf = [&](const std::string& key) {
    std::vector<uint32_t> objects = objectsWithKeys(view, {key});
    if (objects.empty())
      for (uint32_t o : selection_.selected())
        if (view.objectName(o) == key) objects.push_back(o);
    return objects;
  };
  const auto& h = view.header();
  const double diagonal = glm::length(glm::dvec3(h.bounds_max[0] - h.bounds_min[0],
                                                 h.bounds_max[1] - h.bounds_min[1],
                                                 h.bounds_max[2] - h.bounds_min[2]));
  const double tolerance = std::max(1e-6, 1e-6 * diagonal);  // as `terawalk measure`
  try {
    const MeasureShape a = movedShape(view, measureShape(view, objectsOf(keys[0]), tolerance), placement_(keys[0]));
    const MeasureShape b = movedShape(view, measureShape(view, objectsOf(keys[1]), tolerance), placement_(keys[1]));
    const MeasuredDistance d = centre_lines ? centreLineDistance(view, a, b) : minimumDistance(view, a, b);
    closest_ = std::make_pair(d.points.a, d.points.b);
    points_.clear();
    char text[200];
    std::snprintf(text, sizeof text, "%s to %s: %.6f m (%s)", keys[0].c_str(), keys[1].c_str(),
                  glm::length(d.points.b - d.points.a), d.method.c_str());
    result_ = text;
    viewSay("measure: between %s\n", text);
    return true;
  } catch (const std::exception& e) {
    viewSay("measure: %s\n", e.what());
    return false;
  }
}

void ViewMeasure::clear() {
  points_.clear();
  closest_.reset();
  result_.clear();
}

void ViewMeasure::draw(const Camera& camera, int width, int height) const {
  ImDrawList* draw = ImGui::GetForegroundDrawList();
  std::vector<ImVec2> on_screen;
  for (const SnappedPoint& p : points_)
    if (const auto s = screen(camera, width, height, p.world)) on_screen.push_back(*s);
  if (closest_)
    for (const glm::dvec3& p : {closest_->first, closest_->second})
      if (const auto s = screen(camera, width, height, p)) on_screen.push_back(*s);
  for (size_t i = 1; i < on_screen.size(); ++i) draw->AddLine(on_screen[i - 1], on_screen[i], kMeasureColour, 2.0f);
  for (const ImVec2& s : on_screen) draw->AddCircle(s, 6.0f, kMeasureColour, 16, 2.0f);
  if (!result_.empty() && on_screen.size() >= 2) {
    const ImVec2 mid((on_screen[0].x + on_screen[1].x) * 0.5f + 8.0f, (on_screen[0].y + on_screen[1].y) * 0.5f);
    draw->AddRectFilled(ImVec2(mid.x - 2, mid.y - 2),
                        ImVec2(mid.x + ImGui::CalcTextSize(result_.c_str()).x + 2, mid.y + 16),
                        IM_COL32(0, 0, 0, 200));
    draw->AddText(mid, IM_COL32(255, 255, 255, 255), result_.c_str());
  }
}

void ViewMeasure::drawPanel() {
  ImGui::Begin("Review");
  if (!ImGui::CollapsingHeader("Measure")) {
    ImGui::End();
    return;
  }
  if (bool shown = on_; ImGui::Checkbox("points on click [M]", &shown)) toggle();
  ImGui::SameLine();
  if (ImGui::Button("Between selected")) between(false);
  ImGui::SameLine();
  if (ImGui::Button("Centre lines")) between(true);
  ImGui::SameLine();
  if (ImGui::Button("Clear##measure")) clear();
  if (!result_.empty()) ImGui::TextUnformatted(result_.c_str());
  ImGui::End();
}

}  // namespace tw
