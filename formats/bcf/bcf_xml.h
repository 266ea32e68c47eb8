// BCF's XML documents (bcf.version, project.bcfp, markup.bcf, *.bcfv) to and from the topic
// model (bcf_topics.h), through libxml2.
//
// Writing follows the schema of the version asked for, element order included, so what is
// written validates (the tests run xmllint --schema on it). Reading accepts 2.0, 2.1 and 3.0
// layouts alike, by element names and not by the version file, because tools write the one
// layout under the other's version number; unknown elements are ignored. A document that does
// not parse, or a number that is not one, throws FormatError naming the document (archive entry)
// and its line.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "bcf_topics.h"

namespace tw::bcf {

// Documents of one archive, as text. Notes collect what the version cannot say (a 2.1 field of
// view outside 45-60 degrees is clamped, a viewpoint without a camera has no visualisation in
// 3.0), one line each.
std::string versionXml(Version version);
std::string projectXml(Version version, const Archive& archive);
// The markup of `topic`; viewpoint files and snapshots are named by visinfoName/snapshotName.
std::string markupXml(Version version, const Topic& topic, std::vector<std::string>& notes);
// The visualisation of `viewpoint`; its camera is required for 3.0.
std::string visinfoXml(Version version, const Viewpoint& viewpoint, double aspect_ratio,
                       std::vector<std::string>& notes);
std::string visinfoName(const Viewpoint& viewpoint);
std::string snapshotName(const Viewpoint& viewpoint);

// Reading. `name` is what errors call the document ("a.bcfzip: 9f../markup.bcf").
// The markup's topic, comments and the viewpoints' references (file names in `visinfo_files` and
// `snapshot_files`, parallel to topic.viewpoints; empty where none is given).
struct MarkupRead {
  Topic topic;
  std::vector<std::string> visinfo_files;
  std::vector<std::string> snapshot_files;
};
MarkupRead readMarkupXml(std::string_view xml, const std::string& name);
// Fills `viewpoint` (all but its guid when the markup gave one, and its snapshot); `version`
// (from bcf.version: 3.0, else 2.x) decides what an absent DefaultVisibility means.
void readVisinfoXml(std::string_view xml, const std::string& name, Version version,
                    Viewpoint& viewpoint);
// The VersionId of bcf.version ("2.1", "3.0", ...).
std::string readVersionXml(std::string_view xml, const std::string& name);
// Project id and name from project.bcfp (either version's layout); absent fields stay empty.
void readProjectXml(std::string_view xml, const std::string& name, Archive& archive);

}  // namespace tw::bcf
