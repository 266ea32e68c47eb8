// BCF documents written as the schemas of 2.1 and 3.0 order them (bcf_xml.h).
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <stdexcept>

#include <libxml/xmlwriter.h>

#include "bcf_xml.h"

namespace tw::bcf {
namespace {

// A document built with libxml2's text writer into memory; every call checked.
class XmlOut {
 public:
  XmlOut() : buffer_(xmlBufferCreate(), xmlBufferFree) {
    if (!buffer_) throw std::runtime_error("BCF: out of memory");
    writer_ = xmlNewTextWriterMemory(buffer_.get(), 0);
    if (!writer_) throw std::runtime_error("BCF: out of memory");
    xmlTextWriterSetIndent(writer_, 1);
    xmlTextWriterSetIndentString(writer_, BAD_CAST "  ");
    check(xmlTextWriterStartDocument(writer_, "1.0", "UTF-8", "yes"));
  }
  ~XmlOut() {
    if (writer_) xmlFreeTextWriter(writer_);
  }
  XmlOut(const XmlOut&) = delete;
  XmlOut& operator=(const XmlOut&) = delete;

  void open(const char* name) { check(xmlTextWriterStartElement(writer_, BAD_CAST name)); }
  void close() { check(xmlTextWriterEndElement(writer_)); }
  void attribute(const char* name, const std::string& value) {
    check(xmlTextWriterWriteAttribute(writer_, BAD_CAST name, BAD_CAST value.c_str()));
  }
  void element(const char* name, const std::string& text) {
    check(xmlTextWriterWriteElement(writer_, BAD_CAST name, BAD_CAST text.c_str()));
  }
  // An element written only when it has text (optional elements; 3.0 forbids blank ones).
  void optional(const char* name, const std::string& text) {
    if (!text.empty()) element(name, text);
  }
  void number(const char* name, double value) { element(name, formatNumber(value)); }
  void point(const char* name, const glm::dvec3& p) {
    open(name);
    number("X", p.x);
    number("Y", p.y);
    number("Z", p.z);
    close();
  }
  std::string finish() {
    check(xmlTextWriterEndDocument(writer_));
    xmlFreeTextWriter(writer_);
    writer_ = nullptr;
    return std::string(reinterpret_cast<const char*>(xmlBufferContent(buffer_.get())),
                       static_cast<size_t>(xmlBufferLength(buffer_.get())));
  }

  // Shortest text that reads back as the same double.
  static std::string formatNumber(double value) {
    char text[40];
    for (int digits = 15; digits <= 17; ++digits) {
      std::snprintf(text, sizeof text, "%.*g", digits, value);
      if (std::strtod(text, nullptr) == value) break;
    }
    return text;
  }

 private:
  static void check(int result) {
    if (result < 0) throw std::runtime_error("BCF: the XML writer failed");
  }
  std::unique_ptr<xmlBuffer, void (*)(xmlBufferPtr)> buffer_;
  xmlTextWriterPtr writer_ = nullptr;
};

std::string colourText(uint32_t argb) {
  char text[9];
  if ((argb >> 24) == 0xff) std::snprintf(text, sizeof text, "%06X", argb & 0xffffffu);
  else std::snprintf(text, sizeof text, "%08X", argb);
  return text;
}

bool hasIdentity(const Component& c) {
  return !c.ifc_guid.empty() || !c.authoring_tool_id.empty();
}

void writeComponent(XmlOut& out, const Component& c) {
  out.open("Component");
  if (!c.ifc_guid.empty()) out.attribute("IfcGuid", c.ifc_guid);
  out.optional("OriginatingSystem", c.originating_system);
  out.optional("AuthoringToolId", c.authoring_tool_id);
  out.close();
}

// Components with an identity; returns how many were written.
size_t writeComponents(XmlOut& out, const std::vector<Component>& components) {
  size_t written = 0;
  for (const Component& c : components)
    if (hasIdentity(c)) {
      writeComponent(out, c);
      ++written;
    }
  return written;
}

size_t countWithIdentity(const std::vector<Component>& components) {
  size_t n = 0;
  for (const Component& c : components) n += hasIdentity(c);
  return n;
}

void writeViewSetupHints(XmlOut& out, const Viewpoint& v) {
  out.open("ViewSetupHints");
  out.attribute("SpacesVisible", v.spaces_visible ? "true" : "false");
  out.attribute("SpaceBoundariesVisible", v.space_boundaries_visible ? "true" : "false");
  out.attribute("OpeningsVisible", v.openings_visible ? "true" : "false");
  out.close();
}

// Colour groups with an identified component; 3.0 wraps each group's components in Components.
void writeColoring(XmlOut& out, const Viewpoint& v, bool wrap_components) {
  bool coloured = false;
  for (const ColourGroup& g : v.colours) coloured = coloured || countWithIdentity(g.components) > 0;
  if (!coloured) return;
  out.open("Coloring");
  for (const ColourGroup& g : v.colours) {
    if (countWithIdentity(g.components) == 0) continue;
    out.open("Color");
    out.attribute("Color", colourText(g.argb));
    if (wrap_components) out.open("Components");
    writeComponents(out, g.components);
    if (wrap_components) out.close();
    out.close();
  }
  out.close();
}

void writeComponentsV21(XmlOut& out, const Viewpoint& v) {
  out.open("Components");
  writeViewSetupHints(out, v);
  if (countWithIdentity(v.selection) > 0) {
    out.open("Selection");
    writeComponents(out, v.selection);
    out.close();
  }
  out.open("Visibility");
  out.attribute("DefaultVisibility", v.default_visibility ? "true" : "false");
  if (countWithIdentity(v.exceptions) > 0) {
    out.open("Exceptions");
    writeComponents(out, v.exceptions);
    out.close();
  }
  out.close();
  writeColoring(out, v, false);
  out.close();
}

void writeComponentsV30(XmlOut& out, const Viewpoint& v) {
  out.open("Components");
  if (countWithIdentity(v.selection) > 0) {
    out.open("Selection");
    writeComponents(out, v.selection);
    out.close();
  }
  out.open("Visibility");
  out.attribute("DefaultVisibility", v.default_visibility ? "true" : "false");
  writeViewSetupHints(out, v);
  if (countWithIdentity(v.exceptions) > 0) {
    out.open("Exceptions");
    writeComponents(out, v.exceptions);
    out.close();
  }
  out.close();
  writeColoring(out, v, true);
  out.close();
}

void writeCamera(XmlOut& out, Version version, const Camera& camera, double aspect_ratio,
                 std::vector<std::string>& notes, const std::string& guid) {
  out.open(camera.orthogonal ? "OrthogonalCamera" : "PerspectiveCamera");
  out.point("CameraViewPoint", camera.position);
  out.point("CameraDirection", camera.direction);
  out.point("CameraUpVector", camera.up);
  if (camera.orthogonal) {
    out.number("ViewToWorldScale", camera.view_to_world_scale);
  } else {
    double fov = camera.field_of_view_deg;
    if (version == Version::V2_1 && (fov < 45.0 || fov > 60.0)) {
      const double clamped = fov < 45.0 ? 45.0 : 60.0;
      notes.push_back("viewpoint " + guid + ": BCF 2.1 allows a field of view of 45 to 60 " +
                      "degrees; " + XmlOut::formatNumber(fov) + " written as " +
                      XmlOut::formatNumber(clamped));
      fov = clamped;
    }
    out.number("FieldOfView", fov);
  }
  if (version == Version::V3_0) out.number("AspectRatio", aspect_ratio > 0.0 ? aspect_ratio : 1.0);
  out.close();
}

}  // namespace

std::string visinfoName(const Viewpoint& viewpoint) { return viewpoint.guid + ".bcfv"; }
std::string snapshotName(const Viewpoint& viewpoint) { return viewpoint.guid + ".png"; }

std::string versionXml(Version version) {
  XmlOut out;
  out.open("Version");
  if (version == Version::V3_0) {
    out.attribute("VersionId", "3.0");
  } else {
    out.attribute("VersionId", "2.1");
    out.element("DetailedVersion", "2.1");
  }
  out.close();
  return out.finish();
}

std::string projectXml(Version version, const Archive& archive) {
  XmlOut out;
  out.open(version == Version::V3_0 ? "ProjectInfo" : "ProjectExtension");
  out.open("Project");
  out.attribute("ProjectId", archive.project_id);
  out.optional("Name", archive.project_name);
  out.close();
  if (version == Version::V2_1) out.element("ExtensionSchema", "");
  out.close();
  return out.finish();
}

std::string visinfoXml(Version version, const Viewpoint& viewpoint, double aspect_ratio,
                       std::vector<std::string>& notes) {
  if (version == Version::V3_0 && !viewpoint.camera)
    throw std::invalid_argument("viewpoint " + viewpoint.guid +
                                ": BCF 3.0 needs a camera in every visualisation");
  XmlOut out;
  out.open("VisualizationInfo");
  out.attribute("Guid", viewpoint.guid);
  if (version == Version::V3_0) writeComponentsV30(out, viewpoint);
  else writeComponentsV21(out, viewpoint);
  if (viewpoint.camera) writeCamera(out, version, *viewpoint.camera, aspect_ratio, notes, viewpoint.guid);
  if (!viewpoint.clipping_planes.empty()) {
    out.open("ClippingPlanes");
    for (const ClippingPlane& p : viewpoint.clipping_planes) {
      out.open("ClippingPlane");
      out.point("Location", p.location);
      out.point("Direction", p.direction);
      out.close();
    }
    out.close();
  }
  out.close();
  return out.finish();
}

namespace {

void writeComment(XmlOut& out, Version version, const Comment& c) {
  out.open("Comment");
  out.attribute("Guid", c.guid);
  out.element("Date", c.date);
  out.element("Author", c.author);
  if (version == Version::V3_0) out.optional("Comment", c.text);
  else out.element("Comment", c.text);
  if (!c.viewpoint_guid.empty()) {
    out.open("Viewpoint");
    out.attribute("Guid", c.viewpoint_guid);
    out.close();
  }
  out.optional("ModifiedDate", c.modified_date);
  out.optional("ModifiedAuthor", c.modified_author);
  out.close();
}

// The markup's reference to a viewpoint: its visualisation (when it can be written) and snapshot.
void writeViewpointReference(XmlOut& out, Version version, const Viewpoint& v, bool v30_layout) {
  out.open(v30_layout ? "ViewPoint" : "Viewpoints");
  out.attribute("Guid", v.guid);
  if (v.camera || version == Version::V2_1) out.element("Viewpoint", visinfoName(v));
  if (!v.snapshot_png.empty()) out.element("Snapshot", snapshotName(v));
  if (v.index) out.element("Index", std::to_string(*v.index));
  out.close();
}

void writeFile(XmlOut& out, const ModelFile& f) {
  out.open("File");
  if (!f.ifc_project.empty()) out.attribute("IfcProject", f.ifc_project);
  out.optional("Filename", f.filename);
  out.optional("Date", f.date);
  out.optional("Reference", f.reference);
  out.close();
}

}  // namespace

std::string markupXml(Version version, const Topic& topic, std::vector<std::string>& notes) {
  const bool v30 = version == Version::V3_0;
  XmlOut out;
  out.open("Markup");
  if (!topic.files.empty()) {
    out.open("Header");
    if (v30) out.open("Files");
    for (const ModelFile& f : topic.files) writeFile(out, f);
    if (v30) out.close();
    out.close();
  }
  out.open("Topic");
  out.attribute("Guid", topic.guid);
  if (v30 || !topic.type.empty()) out.attribute("TopicType", topic.type.empty() ? "Issue" : topic.type);
  if (v30 || !topic.status.empty())
    out.attribute("TopicStatus", topic.status.empty() ? "Open" : topic.status);
  out.element("Title", topic.title.empty() ? "Untitled" : topic.title);
  out.optional("Priority", topic.priority);
  if (topic.index) out.element("Index", std::to_string(*topic.index));
  if (v30 && !topic.labels.empty()) {
    out.open("Labels");
    for (const std::string& l : topic.labels) out.optional("Label", l);
    out.close();
  } else if (!v30) {
    for (const std::string& l : topic.labels) out.element("Labels", l);
  }
  out.element("CreationDate", topic.creation_date);
  out.element("CreationAuthor", topic.creation_author.empty() ? "unknown" : topic.creation_author);
  out.optional("ModifiedDate", topic.modified_date);
  out.optional("ModifiedAuthor", topic.modified_author);
  out.optional("AssignedTo", topic.assigned_to);
  out.optional("Description", topic.description);
  if (v30) {
    if (!topic.comments.empty()) {
      out.open("Comments");
      for (const Comment& c : topic.comments) writeComment(out, version, c);
      out.close();
    }
    if (!topic.viewpoints.empty()) {
      out.open("Viewpoints");
      for (const Viewpoint& v : topic.viewpoints) {
        if (!v.camera)
          notes.push_back("viewpoint " + v.guid + ": no camera, so BCF 3.0 gets no visualisation " +
                          "for it (its snapshot is kept)");
        writeViewpointReference(out, version, v, true);
      }
      out.close();
    }
    out.close();  // Topic
  } else {
    out.close();  // Topic
    for (const Comment& c : topic.comments) writeComment(out, version, c);
    for (const Viewpoint& v : topic.viewpoints) writeViewpointReference(out, version, v, false);
  }
  out.close();
  return out.finish();
}

}  // namespace tw::bcf
