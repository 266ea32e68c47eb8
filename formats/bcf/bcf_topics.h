// The content of a BCF archive (buildingSMART's BIM Collaboration Format, versions 2.0, 2.1 and
// 3.0) as TeraWalk keeps it: topics with their comments and viewpoints, each viewpoint with its
// camera, component selection, visibility, colouring, clipping planes and snapshot.
//
// Why one model for every version: the versions differ in where elements sit (3.0 nests comments
// and viewpoints in the topic, wraps colour components, moves the view set-up hints) and in a few
// defaults, not in what they say. Reading any version into this model and writing it out as 2.1
// or 3.0 (bcf_archive.h) converts between them; what one version cannot say is noted where it
// is dropped.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <glm/glm.hpp>

namespace tw::bcf {

enum class Version { V2_1, V3_0 };

// A model element: by its IFC GlobalId where the model came from IFC, else by the authoring
// tool's id (TeraWalk's database key) and the system that wrote it.
struct Component {
  std::string ifc_guid;            // 22 characters, or empty
  std::string authoring_tool_id;   // or empty
  std::string originating_system;  // or empty
};

struct Camera {
  bool orthogonal = false;
  glm::dvec3 position{0.0};  // CameraViewPoint, world metres
  glm::dvec3 direction{1.0, 0.0, 0.0};
  glm::dvec3 up{0.0, 0.0, 1.0};
  double field_of_view_deg = 60.0;  // perspective: vertical
  double view_to_world_scale = 1.0;  // orthogonal: the view's height in metres
  double aspect_ratio = 0.0;         // width / height; 0 when the file gives none (2.x)
};

struct ColourGroup {
  uint32_t argb = 0xff000000u;  // as written: "RRGGBB" (opaque) or "AARRGGBB"
  std::vector<Component> components;
};

struct ClippingPlane {
  glm::dvec3 location{0.0};
  glm::dvec3 direction{0.0, 0.0, 1.0};  // points to the side that is cut away
};

struct Viewpoint {
  std::string guid;
  std::optional<Camera> camera;
  std::vector<Component> selection;
  bool default_visibility = true;
  std::vector<Component> exceptions;  // visible when default_visibility is false, else hidden
  bool spaces_visible = false, space_boundaries_visible = false, openings_visible = false;
  std::vector<ColourGroup> colours;
  std::vector<ClippingPlane> clipping_planes;
  std::vector<uint8_t> snapshot_png;  // empty when none
  std::optional<int> index;
};

struct Comment {
  std::string guid;
  std::string date;  // xs:dateTime, as written
  std::string author;
  std::string text;
  std::string viewpoint_guid;  // or empty
  std::string modified_date, modified_author;
};

// A model file the topic refers to (the markup's header).
struct ModelFile {
  std::string filename;
  std::string date;
  std::string ifc_project;  // IfcGuid, or empty
  std::string reference;
};

struct Topic {
  std::string guid;
  std::string type;    // TopicType ("Issue", "Request", ...); required by 3.0
  std::string status;  // TopicStatus ("Open", "Closed", ...); required by 3.0
  std::string title;
  std::string priority;
  std::optional<int> index;
  std::vector<std::string> labels;
  std::string creation_date, creation_author;
  std::string modified_date, modified_author;
  std::string assigned_to;
  std::string description;
  std::vector<ModelFile> files;
  std::vector<Comment> comments;
  std::vector<Viewpoint> viewpoints;
};

struct Archive {
  std::string version_id;  // as read ("2.0", "2.1", "3.0"), or what was written
  std::string project_id, project_name;
  std::vector<Topic> topics;
};

// A viewpoint's place in an archive, in the order `bcf list` prints: topics as stored (by Index
// where every topic has one), viewpoints within a topic by Index, then as stored. 1-based.
struct ViewpointRef {
  const Topic* topic = nullptr;
  const Viewpoint* viewpoint = nullptr;
};
std::vector<ViewpointRef> viewpointsInOrder(const Archive& archive);

}  // namespace tw::bcf
