// BCF viewpoints against a package: a viewpoint applied to a walkthrough (camera, selection,
// visibility, colours, clipping planes) and the walkthrough's state captured as a viewpoint.
//
// Components name objects by IFC GlobalId (models from IFC, whose database key is the GlobalId)
// or by the authoring tool's id (TeraWalk's database key, or the object's name where it has no
// key, with OriginatingSystem "TeraWalk"). An object carries the component of its key, so the
// objects one IFC product became (its mesh and its primitives) act as one component.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <unordered_map>
#include <vector>

#include "bcf_topics.h"
#include "camera.h"
#include "object_states.h"
#include "package_view.h"
#include "section_planes.h"

namespace tw {

inline constexpr const char* kBcfOriginatingSystem = "TeraWalk";

// The package's objects by the identities BCF components carry.
class ComponentIndex {
 public:
  explicit ComponentIndex(const PackageView& view);
  // Objects the component names: by IFC GlobalId (the database key), else by authoring tool id
  // (the database key, then the name). Empty when none has it.
  const std::vector<uint32_t>& objects(const bcf::Component& component) const;
  // The component an object is named by in what TeraWalk writes.
  bcf::Component componentOf(uint32_t object) const;
  size_t objectCount() const { return object_count_; }

 private:
  const PackageView* view_;
  size_t object_count_;
  std::unordered_map<std::string, std::vector<uint32_t>> by_key_, by_name_;
  std::vector<uint32_t> none_;
};

// The BCF camera as TeraWalk's (yaw, pitch, field of view; near and far from `base`). Ours has no
// roll: a camera rolled more than half a degree gets a warning. An orthogonal camera is
// approximated by a perspective one of 2 degrees moved back along its direction until the view's
// height at the viewpoint is ViewToWorldScale (and a warning says so).
Camera cameraFromBcf(const bcf::Camera& camera, const Camera& base, std::vector<std::string>& warnings);
bcf::Camera bcfCameraOf(const Camera& camera, double aspect_ratio);

// What applying a viewpoint did, for the user.
struct ViewpointApplied {
  Camera camera;                      // from the viewpoint's camera, or the base camera
  bool has_camera = false;
  std::vector<SectionPlane> sections;  // its clipping planes (at most kMaxUserSectionPlanes)
  uint32_t selected = 0, hidden = 0, coloured = 0;  // objects
  uint32_t components = 0, components_unknown = 0;
  std::vector<std::string> warnings;  // one per component skipped and per thing not kept
};

// Resets `states` and applies the viewpoint's visibility, selection and colours to it; converts
// its camera and clipping planes.
ViewpointApplied applyViewpoint(const bcf::Viewpoint& viewpoint, const ComponentIndex& index,
                                ObjectStates& states, const Camera& base);

// The viewpoint of a walkthrough: camera, selected objects, visibility (by the shorter list:
// the hidden objects with everything else visible, or the visible ones with the default hidden),
// colour overrides and section planes. X-ray has no BCF form and is left out. Guid is new.
bcf::Viewpoint captureViewpoint(const Camera& camera, double aspect_ratio,
                                const ObjectStates& states, const ComponentIndex& index,
                                std::span<const SectionPlane> sections);

}  // namespace tw
