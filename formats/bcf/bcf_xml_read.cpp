// BCF documents read into the topic model, whichever version's layout they use (bcf_xml.h).
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <memory>

#include <libxml/parser.h>
#include <libxml/tree.h>

#include "bcf_xml.h"
#include "format_error.h"

namespace tw::bcf {
namespace {

void ignoreXmlError(void*, xmlErrorPtr) {}

// A parsed document; parsing without the network, entity expansion or DTD loading.
class XmlDocument {
 public:
  XmlDocument(std::string_view xml, const std::string& name) {
    xmlSetStructuredErrorFunc(nullptr, ignoreXmlError);
    std::unique_ptr<xmlParserCtxt, void (*)(xmlParserCtxtPtr)> context(xmlNewParserCtxt(),
                                                                        xmlFreeParserCtxt);
    if (!context) throw FormatError(name, "out of memory parsing XML");
    if (xml.size() > static_cast<size_t>(INT32_MAX)) throw FormatError(name, "XML over 2 GiB");
    doc_ = xmlCtxtReadMemory(context.get(), xml.data(), static_cast<int>(xml.size()),
                             name.c_str(), nullptr, XML_PARSE_NONET | XML_PARSE_NOBLANKS);
    if (!doc_) {
      const xmlError& e = context->lastError;
      std::string reason = e.message ? e.message : "not well-formed XML";
      while (!reason.empty() && (reason.back() == '\n' || reason.back() == ' ')) reason.pop_back();
      throw FormatError::atLine(name, e.line > 0 ? static_cast<uint64_t>(e.line) : 1,
                                "XML does not parse: " + reason);
    }
  }
  ~XmlDocument() { xmlFreeDoc(doc_); }
  XmlDocument(const XmlDocument&) = delete;
  XmlDocument& operator=(const XmlDocument&) = delete;
  xmlNodePtr root() const { return xmlDocGetRootElement(doc_); }

 private:
  xmlDocPtr doc_ = nullptr;
};

bool named(xmlNodePtr node, const char* name) {
  return node && node->type == XML_ELEMENT_NODE &&
         std::strcmp(reinterpret_cast<const char*>(node->name), name) == 0;
}

xmlNodePtr child(xmlNodePtr parent, const char* name) {
  if (!parent) return nullptr;
  for (xmlNodePtr c = parent->children; c; c = c->next)
    if (named(c, name)) return c;
  return nullptr;
}

std::vector<xmlNodePtr> children(xmlNodePtr parent, const char* name) {
  std::vector<xmlNodePtr> out;
  if (!parent) return out;
  for (xmlNodePtr c = parent->children; c; c = c->next)
    if (named(c, name)) out.push_back(c);
  return out;
}

std::string text(xmlNodePtr node) {
  if (!node) return {};
  xmlChar* content = xmlNodeGetContent(node);
  std::string out = content ? reinterpret_cast<const char*>(content) : "";
  xmlFree(content);
  const size_t first = out.find_first_not_of(" \t\r\n");
  if (first == std::string::npos) return {};
  return out.substr(first, out.find_last_not_of(" \t\r\n") - first + 1);
}

std::string childText(xmlNodePtr parent, const char* name) { return text(child(parent, name)); }

std::string attribute(xmlNodePtr node, const char* name) {
  if (!node) return {};
  xmlChar* value = xmlGetProp(node, BAD_CAST name);
  std::string out = value ? reinterpret_cast<const char*>(value) : "";
  xmlFree(value);
  return out;
}

uint64_t lineOf(xmlNodePtr node) {
  const long line = node ? xmlGetLineNo(node) : 0;
  return line > 0 ? static_cast<uint64_t>(line) : 1;
}

double number(xmlNodePtr node, const std::string& name) {
  const std::string t = text(node);
  char* end = nullptr;
  const double value = std::strtod(t.c_str(), &end);
  if (t.empty() || *end != '\0' || !std::isfinite(value))
    throw FormatError::atLine(name, lineOf(node),
                              std::string(node ? reinterpret_cast<const char*>(node->name) : "value") +
                                  " '" + t + "' is not a finite number");
  return value;
}

double requiredNumber(xmlNodePtr parent, const char* element, const std::string& name) {
  xmlNodePtr node = child(parent, element);
  if (!node)
    throw FormatError::atLine(name, lineOf(parent),
                              reinterpret_cast<const char*>(parent->name) + std::string(" has no ") +
                                  element);
  return number(node, name);
}

glm::dvec3 point(xmlNodePtr parent, const char* element, const std::string& name) {
  xmlNodePtr node = child(parent, element);
  if (!node)
    throw FormatError::atLine(name, lineOf(parent),
                              reinterpret_cast<const char*>(parent->name) + std::string(" has no ") +
                                  element);
  return {requiredNumber(node, "X", name), requiredNumber(node, "Y", name),
          requiredNumber(node, "Z", name)};
}

std::optional<int> optionalInt(xmlNodePtr node) {
  if (!node) return std::nullopt;
  const std::string t = text(node);
  char* end = nullptr;
  const long value = std::strtol(t.c_str(), &end, 10);
  if (t.empty() || *end != '\0' || value < INT32_MIN || value > INT32_MAX) return std::nullopt;
  return static_cast<int>(value);
}

bool boolean(const std::string& value, bool fallback) {
  if (value == "true" || value == "1") return true;
  if (value == "false" || value == "0") return false;
  return fallback;
}

Component component(xmlNodePtr node) {
  Component c;
  c.ifc_guid = attribute(node, "IfcGuid");
  c.originating_system = childText(node, "OriginatingSystem");
  c.authoring_tool_id = childText(node, "AuthoringToolId");
  return c;
}

std::vector<Component> components(xmlNodePtr parent) {
  std::vector<Component> out;
  for (xmlNodePtr c : children(parent, "Component")) out.push_back(component(c));
  return out;
}

uint32_t colour(xmlNodePtr node, const std::string& name) {
  const std::string t = attribute(node, "Color");
  char* end = nullptr;
  const unsigned long value = std::strtoul(t.c_str(), &end, 16);
  if ((t.size() != 6 && t.size() != 8) || *end != '\0')
    throw FormatError::atLine(name, lineOf(node), "Color '" + t + "' is not RRGGBB or AARRGGBB");
  return t.size() == 6 ? 0xff000000u | static_cast<uint32_t>(value) : static_cast<uint32_t>(value);
}

Camera camera(xmlNodePtr node, bool orthogonal, const std::string& name) {
  Camera c;
  c.orthogonal = orthogonal;
  c.position = point(node, "CameraViewPoint", name);
  c.direction = point(node, "CameraDirection", name);
  c.up = point(node, "CameraUpVector", name);
  if (glm::length(c.direction) == 0.0)
    throw FormatError::atLine(name, lineOf(child(node, "CameraDirection")),
                              "the camera direction is zero");
  if (orthogonal) c.view_to_world_scale = requiredNumber(node, "ViewToWorldScale", name);
  else c.field_of_view_deg = requiredNumber(node, "FieldOfView", name);
  if (xmlNodePtr aspect = child(node, "AspectRatio")) c.aspect_ratio = number(aspect, name);
  if (!orthogonal && !(c.field_of_view_deg > 0.0 && c.field_of_view_deg < 180.0))
    throw FormatError::atLine(name, lineOf(child(node, "FieldOfView")),
                              "a field of view of " + std::to_string(c.field_of_view_deg) +
                                  " degrees is outside (0, 180)");
  if (orthogonal && !(c.view_to_world_scale > 0.0))
    throw FormatError::atLine(name, lineOf(child(node, "ViewToWorldScale")),
                              "ViewToWorldScale must be positive");
  return c;
}

Comment comment(xmlNodePtr node) {
  Comment c;
  c.guid = attribute(node, "Guid");
  c.date = childText(node, "Date");
  c.author = childText(node, "Author");
  c.text = childText(node, "Comment");
  c.viewpoint_guid = attribute(child(node, "Viewpoint"), "Guid");
  c.modified_date = childText(node, "ModifiedDate");
  c.modified_author = childText(node, "ModifiedAuthor");
  return c;
}

}  // namespace

std::string readVersionXml(std::string_view xml, const std::string& name) {
  XmlDocument doc(xml, name);
  if (!named(doc.root(), "Version"))
    throw FormatError::atLine(name, lineOf(doc.root()), "the root element is not Version");
  return attribute(doc.root(), "VersionId");
}

void readProjectXml(std::string_view xml, const std::string& name, Archive& archive) {
  XmlDocument doc(xml, name);
  xmlNodePtr project = child(doc.root(), "Project");
  archive.project_id = attribute(project, "ProjectId");
  archive.project_name = childText(project, "Name");
}

MarkupRead readMarkupXml(std::string_view xml, const std::string& name) {
  XmlDocument doc(xml, name);
  xmlNodePtr root = doc.root();
  if (!named(root, "Markup"))
    throw FormatError::atLine(name, lineOf(root), "the root element is not Markup");
  xmlNodePtr topic_node = child(root, "Topic");
  if (!topic_node) throw FormatError::atLine(name, lineOf(root), "the markup has no Topic");

  MarkupRead read;
  Topic& topic = read.topic;
  topic.guid = attribute(topic_node, "Guid");
  topic.type = attribute(topic_node, "TopicType");
  topic.status = attribute(topic_node, "TopicStatus");
  topic.title = childText(topic_node, "Title");
  topic.priority = childText(topic_node, "Priority");
  topic.index = optionalInt(child(topic_node, "Index"));
  for (xmlNodePtr l : children(topic_node, "Labels")) {
    const std::vector<xmlNodePtr> inner = children(l, "Label");  // 3.0 wraps, 2.x repeats
    if (inner.empty()) topic.labels.push_back(text(l));
    for (xmlNodePtr i : inner) topic.labels.push_back(text(i));
  }
  topic.creation_date = childText(topic_node, "CreationDate");
  topic.creation_author = childText(topic_node, "CreationAuthor");
  topic.modified_date = childText(topic_node, "ModifiedDate");
  topic.modified_author = childText(topic_node, "ModifiedAuthor");
  topic.assigned_to = childText(topic_node, "AssignedTo");
  topic.description = childText(topic_node, "Description");

  xmlNodePtr header = child(root, "Header");
  std::vector<xmlNodePtr> files = children(header, "File");
  for (xmlNodePtr f : children(child(header, "Files"), "File")) files.push_back(f);
  for (xmlNodePtr f : files)
    topic.files.push_back({childText(f, "Filename"), childText(f, "Date"),
                           attribute(f, "IfcProject"), childText(f, "Reference")});

  // 2.x: comments and viewpoints beside the topic; 3.0: inside it.
  std::vector<xmlNodePtr> comment_nodes = children(root, "Comment");
  for (xmlNodePtr c : children(child(topic_node, "Comments"), "Comment")) comment_nodes.push_back(c);
  for (xmlNodePtr c : comment_nodes) topic.comments.push_back(comment(c));
  std::vector<xmlNodePtr> viewpoint_nodes = children(root, "Viewpoints");
  for (xmlNodePtr v : children(child(topic_node, "Viewpoints"), "ViewPoint"))
    viewpoint_nodes.push_back(v);
  for (xmlNodePtr v : viewpoint_nodes) {
    Viewpoint viewpoint;
    viewpoint.guid = attribute(v, "Guid");
    viewpoint.index = optionalInt(child(v, "Index"));
    topic.viewpoints.push_back(std::move(viewpoint));
    read.visinfo_files.push_back(childText(v, "Viewpoint"));
    read.snapshot_files.push_back(childText(v, "Snapshot"));
  }
  return read;
}

void readVisinfoXml(std::string_view xml, const std::string& name, Version version,
                    Viewpoint& viewpoint) {
  XmlDocument doc(xml, name);
  xmlNodePtr root = doc.root();
  if (!named(root, "VisualizationInfo"))
    throw FormatError::atLine(name, lineOf(root), "the root element is not VisualizationInfo");
  if (viewpoint.guid.empty()) viewpoint.guid = attribute(root, "Guid");

  xmlNodePtr comps = child(root, "Components");
  viewpoint.selection = components(child(comps, "Selection"));
  xmlNodePtr visibility = child(comps, "Visibility");
  // 2.x defaults DefaultVisibility to true; 3.0's schema to false, where a Visibility element is
  // present (none at all: everything visible).
  viewpoint.default_visibility =
      visibility ? boolean(attribute(visibility, "DefaultVisibility"), version != Version::V3_0)
                 : true;
  viewpoint.exceptions = components(child(visibility, "Exceptions"));
  xmlNodePtr hints = child(comps, "ViewSetupHints");
  if (!hints) hints = child(visibility, "ViewSetupHints");
  viewpoint.spaces_visible = boolean(attribute(hints, "SpacesVisible"), false);
  viewpoint.space_boundaries_visible = boolean(attribute(hints, "SpaceBoundariesVisible"), false);
  viewpoint.openings_visible = boolean(attribute(hints, "OpeningsVisible"), false);
  for (xmlNodePtr c : children(child(comps, "Coloring"), "Color")) {
    ColourGroup group;
    group.argb = colour(c, name);
    group.components = components(c);
    for (const Component& inner : components(child(c, "Components"))) group.components.push_back(inner);
    viewpoint.colours.push_back(std::move(group));
  }
  // BCF 2.0 lists components straight under Components, each with its own Selected, Visible
  // and Color attributes.
  for (xmlNodePtr c : children(comps, "Component")) {
    const Component flat = component(c);
    if (boolean(attribute(c, "Selected"), false)) viewpoint.selection.push_back(flat);
    if (!boolean(attribute(c, "Visible"), true)) viewpoint.exceptions.push_back(flat);
    if (!attribute(c, "Color").empty()) viewpoint.colours.push_back({colour(c, name), {flat}});
  }
  if (xmlNodePtr p = child(root, "PerspectiveCamera")) viewpoint.camera = camera(p, false, name);
  else if (xmlNodePtr o = child(root, "OrthogonalCamera")) viewpoint.camera = camera(o, true, name);
  for (xmlNodePtr p : children(child(root, "ClippingPlanes"), "ClippingPlane")) {
    ClippingPlane plane{point(p, "Location", name), point(p, "Direction", name)};
    if (glm::length(plane.direction) == 0.0)
      throw FormatError::atLine(name, lineOf(p), "a clipping plane's direction is zero");
    viewpoint.clipping_planes.push_back(plane);
  }
}

}  // namespace tw::bcf
