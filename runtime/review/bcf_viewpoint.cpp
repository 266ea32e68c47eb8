// BCF viewpoints applied to and captured from a walkthrough's state (bcf_viewpoint.h).
#include "bcf_viewpoint.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <set>

#include "bcf_ids.h"

namespace tw {
namespace {

constexpr double kDegree = std::numbers::pi / 180.0;
constexpr double kOrthogonalStandInFovDeg = 2.0;
constexpr double kRollWarningDeg = 0.5;

std::string describe(const bcf::Component& c) {
  if (!c.ifc_guid.empty()) return "IfcGuid " + c.ifc_guid;
  if (!c.authoring_tool_id.empty()) return "AuthoringToolId '" + c.authoring_tool_id + "'";
  return "a component with no identity";
}

// 0xAARRGGBB (BCF) to the renderer's 0xAABBGGRR.
uint32_t rgbaOfArgb(uint32_t argb) {
  return (argb & 0xff000000u) | ((argb & 0xffu) << 16) | (argb & 0xff00u) | ((argb >> 16) & 0xffu);
}
uint32_t argbOfRgba(uint32_t rgba) { return rgbaOfArgb(rgba); }  // the same swap of R and B

std::string componentKey(const bcf::Component& c) {
  return c.ifc_guid.empty() ? "a:" + c.authoring_tool_id : "g:" + c.ifc_guid;
}

}  // namespace

ComponentIndex::ComponentIndex(const PackageView& view)
    : view_(&view), object_count_(view.objects().size()) {
  for (uint32_t o = 0; o < object_count_; ++o) {
    const std::string_view key = view.objectDbKey(o);
    if (!key.empty()) by_key_[std::string(key)].push_back(o);
    const std::string_view name = view.objectName(o);
    if (!name.empty()) by_name_[std::string(name)].push_back(o);
  }
}

const std::vector<uint32_t>& ComponentIndex::objects(const bcf::Component& component) const {
  if (!component.ifc_guid.empty()) {
    const auto it = by_key_.find(component.ifc_guid);
    return it == by_key_.end() ? none_ : it->second;
  }
  if (component.authoring_tool_id.empty()) return none_;
  if (const auto it = by_key_.find(component.authoring_tool_id); it != by_key_.end()) return it->second;
  if (const auto it = by_name_.find(component.authoring_tool_id); it != by_name_.end())
    return it->second;
  return none_;
}

bcf::Component ComponentIndex::componentOf(uint32_t object) const {
  bcf::Component c;
  const std::string_view key = view_->objectDbKey(object);
  if (!key.empty() && bcf::isIfcGlobalId(key)) {
    c.ifc_guid = std::string(key);
    return c;
  }
  c.authoring_tool_id = std::string(key.empty() ? view_->objectName(object) : key);
  if (!c.authoring_tool_id.empty()) c.originating_system = kBcfOriginatingSystem;
  return c;
}

Camera cameraFromBcf(const bcf::Camera& in, const Camera& base, std::vector<std::string>& warnings) {
  Camera camera = base;
  const glm::dvec3 d = glm::normalize(in.direction);
  camera.pitch_rad = std::asin(std::clamp(d.z, -1.0, 1.0));
  const double horizontal = std::hypot(d.x, d.y);
  // Looking straight up or down, the up vector tells which way the image's top faces.
  camera.yaw_rad = horizontal > 1e-9 ? std::atan2(d.y, d.x)
                                     : std::atan2(d.z < 0 ? in.up.y : -in.up.y,
                                                  d.z < 0 ? in.up.x : -in.up.x);
  glm::dvec3 up = in.up - glm::dot(in.up, d) * d;
  if (glm::length(up) > 1e-12 && horizontal > 1e-9) {
    up = glm::normalize(up);
    const double roll = std::acos(std::clamp(glm::dot(up, camera.up()), -1.0, 1.0)) / kDegree;
    if (roll > kRollWarningDeg)
      warnings.push_back("the camera is rolled by " + std::to_string(roll) +
                         " degrees about its direction; TeraWalk's camera keeps Z up, so the "
                         "picture is drawn unrolled");
  }
  if (in.orthogonal) {
    camera.fov_y_rad = kOrthogonalStandInFovDeg * kDegree;
    const double back = 0.5 * in.view_to_world_scale / std::tan(0.5 * camera.fov_y_rad);
    camera.position = in.position - d * back;
    camera.far_m = std::max(camera.far_m, 4.0 * back);
    warnings.push_back("an orthogonal camera (view height " + std::to_string(in.view_to_world_scale) +
                       " m) is drawn as a 2-degree perspective from " + std::to_string(back) +
                       " m behind its viewpoint");
  } else {
    camera.position = in.position;
    camera.fov_y_rad = in.field_of_view_deg * kDegree;
  }
  return camera;
}

bcf::Camera bcfCameraOf(const Camera& camera, double aspect_ratio) {
  bcf::Camera out;
  out.position = camera.position;
  out.direction = camera.forward();
  out.up = camera.up();
  out.field_of_view_deg = camera.fov_y_rad / kDegree;
  out.aspect_ratio = aspect_ratio;
  return out;
}

ViewpointApplied applyViewpoint(const bcf::Viewpoint& viewpoint, const ComponentIndex& index,
                                ObjectStates& states, const Camera& base) {
  ViewpointApplied applied;
  applied.camera = base;
  if (viewpoint.camera) {
    applied.camera = cameraFromBcf(*viewpoint.camera, base, applied.warnings);
    applied.has_camera = true;
  }
  states.setAll(kObjectHidden | kObjectSelected | kObjectXray, false);
  for (uint32_t o = 0; o < index.objectCount(); ++o) states.clearColor(o);

  // Each list's components resolved to objects; unknown ones warned about once each.
  auto resolve = [&](const std::vector<bcf::Component>& list, const char* role) {
    std::vector<uint32_t> objects;
    for (const bcf::Component& c : list) {
      ++applied.components;
      const std::vector<uint32_t>& found = index.objects(c);
      if (found.empty()) {
        ++applied.components_unknown;
        applied.warnings.push_back(std::string(role) + ": " + describe(c) +
                                   ": no object of the model has it; skipped");
      }
      objects.insert(objects.end(), found.begin(), found.end());
    }
    return objects;
  };

  const std::vector<uint32_t> exceptions = resolve(viewpoint.exceptions, "visibility exception");
  if (!viewpoint.default_visibility) states.setAll(kObjectHidden, true);
  for (uint32_t o : exceptions) states.set(o, kObjectHidden, viewpoint.default_visibility);
  for (uint32_t o : resolve(viewpoint.selection, "selection")) {
    states.set(o, kObjectSelected, true);
    ++applied.selected;
  }
  for (const bcf::ColourGroup& group : viewpoint.colours)
    for (uint32_t o : resolve(group.components, "colouring")) {
      states.setColor(o, rgbaOfArgb(group.argb));
      ++applied.coloured;
    }
  for (uint32_t o = 0; o < index.objectCount(); ++o) applied.hidden += (states.flags(o) & kObjectHidden) != 0;

  for (const bcf::ClippingPlane& p : viewpoint.clipping_planes) {
    if (applied.sections.size() == kMaxUserSectionPlanes) {
      applied.warnings.push_back("clipping planes past the first " +
                                 std::to_string(kMaxUserSectionPlanes) + " skipped");
      break;
    }
    applied.sections.push_back({p.location, glm::normalize(p.direction)});
  }
  return applied;
}

bcf::Viewpoint captureViewpoint(const Camera& camera, double aspect_ratio,
                                const ObjectStates& states, const ComponentIndex& index,
                                std::span<const SectionPlane> sections) {
  bcf::Viewpoint v;
  v.guid = bcf::newGuid();
  v.camera = bcfCameraOf(camera, aspect_ratio);

  // Components in object order, each once; a component is hidden when all its objects are.
  std::map<std::string, bcf::Component> components;
  std::map<std::string, bool> all_hidden, any_selected;
  std::map<uint32_t, std::set<std::string>> by_colour;
  std::vector<std::string> order;
  for (uint32_t o = 0; o < index.objectCount() && o < states.size(); ++o) {
    const bcf::Component c = index.componentOf(o);
    if (c.ifc_guid.empty() && c.authoring_tool_id.empty()) continue;
    const std::string key = componentKey(c);
    if (components.emplace(key, c).second) {
      order.push_back(key);
      all_hidden[key] = true;
      any_selected[key] = false;
    }
    const uint32_t flags = states.flags(o);
    all_hidden[key] = all_hidden[key] && (flags & kObjectHidden);
    any_selected[key] = any_selected[key] || (flags & kObjectSelected);
    if (flags & kObjectRecolored) by_colour[states.gpuStates()[o].color_rgba].insert(key);
  }
  size_t hidden = 0;
  for (const std::string& key : order) hidden += all_hidden[key];
  v.default_visibility = hidden * 2 <= order.size();
  for (const std::string& key : order) {
    if (any_selected[key]) v.selection.push_back(components[key]);
    if (all_hidden[key] == v.default_visibility) v.exceptions.push_back(components[key]);
  }
  for (const auto& [rgba, keys] : by_colour) {
    bcf::ColourGroup group;
    group.argb = argbOfRgba(rgba);
    for (const std::string& key : order)
      if (keys.count(key)) group.components.push_back(components[key]);
    v.colours.push_back(std::move(group));
  }
  for (const SectionPlane& p : sections) v.clipping_planes.push_back({p.point, p.normal});
  return v;
}

}  // namespace tw
