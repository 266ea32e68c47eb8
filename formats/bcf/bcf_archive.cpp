// .bcfzip archives read and written with libzip (bcf_archive.h).
#include "bcf_archive.h"

#include <algorithm>
#include <cstdio>
#include <deque>
#include <map>
#include <memory>
#include <stdexcept>
#include <unistd.h>

#include <zip.h>

#include "bcf_xml.h"
#include "format_error.h"

namespace tw::bcf {
namespace {

std::string zipReason(int code) {
  zip_error_t error;
  zip_error_init_with_code(&error, code);
  std::string reason = zip_error_strerror(&error);
  zip_error_fini(&error);
  return reason;
}

// An archive open for reading, its entries by name.
class ZipIn {
 public:
  ZipIn(const std::filesystem::path& path, const ReadLimits& limits) : name_(path.string()) {
    int code = 0;
    zip_ = zip_open(name_.c_str(), ZIP_RDONLY | ZIP_CHECKCONS, &code);
    if (!zip_) throw FormatError(name_, "not a readable BCF archive (zip): " + zipReason(code));
    const zip_int64_t count = zip_get_num_entries(zip_, 0);
    if (count < 0 || static_cast<uint64_t>(count) > limits.max_entries)
      throw FormatError(name_, "the archive lists " + std::to_string(count) +
                                   " entries, more than the " + std::to_string(limits.max_entries) +
                                   " a BCF archive is read with");
    for (zip_int64_t i = 0; i < count; ++i) {
      zip_stat_t st;
      if (zip_stat_index(zip_, static_cast<zip_uint64_t>(i), 0, &st) != 0 || !st.name) continue;
      entries_[st.name] = {static_cast<zip_uint64_t>(i), st.size};
    }
  }
  ~ZipIn() {
    if (zip_) zip_discard(zip_);
  }
  ZipIn(const ZipIn&) = delete;
  ZipIn& operator=(const ZipIn&) = delete;

  const std::string& name() const { return name_; }
  bool has(const std::string& entry) const { return entries_.count(entry) > 0; }
  std::vector<std::string> names() const {
    std::vector<std::string> out;
    for (const auto& [n, e] : entries_) out.push_back(n);
    return out;
  }
  // The entry's bytes; throws FormatError naming the entry when it is missing, over `limit` or
  // damaged (a bad CRC, a short read).
  std::string read(const std::string& entry, uint64_t limit) const {
    const auto it = entries_.find(entry);
    if (it == entries_.end()) throw FormatError(where(entry), "the archive has no such entry");
    if (it->second.size > limit)
      throw FormatError(where(entry), std::to_string(it->second.size) + " bytes, over the limit of " +
                                          std::to_string(limit));
    std::unique_ptr<zip_file_t, int (*)(zip_file_t*)> file(zip_fopen_index(zip_, it->second.index, 0),
                                                           zip_fclose);
    if (!file) throw FormatError(where(entry), std::string("cannot be opened: ") + zip_strerror(zip_));
    std::string bytes(it->second.size, '\0');
    uint64_t done = 0;
    while (done < bytes.size()) {
      const zip_int64_t got = zip_fread(file.get(), bytes.data() + done, bytes.size() - done);
      if (got < 0)
        throw FormatError(where(entry), std::string("damaged: ") + zip_file_strerror(file.get()));
      if (got == 0) break;
      done += static_cast<uint64_t>(got);
    }
    if (done != bytes.size())
      throw FormatError(where(entry), "damaged: " + std::to_string(done) + " of " +
                                          std::to_string(bytes.size()) + " bytes could be read");
    return bytes;
  }
  std::string where(const std::string& entry) const { return name_ + ": " + entry; }

 private:
  struct Entry {
    zip_uint64_t index = 0;
    uint64_t size = 0;
  };
  std::string name_;
  zip_t* zip_ = nullptr;
  std::map<std::string, Entry> entries_;
};

std::string folderOf(const std::string& entry) {
  const size_t slash = entry.rfind('/');
  return slash == std::string::npos ? std::string() : entry.substr(0, slash + 1);
}

// One topic folder: its markup, then each viewpoint's visualisation and snapshot.
void readTopic(const ZipIn& zip, const std::string& markup_entry, Version version,
               const ReadLimits& limits, Archive& archive, std::vector<std::string>& warnings) {
  const std::string folder = folderOf(markup_entry);
  MarkupRead read = readMarkupXml(zip.read(markup_entry, limits.max_xml_bytes), zip.where(markup_entry));
  // BCF 2.0 writers may leave the one viewpoint of a topic out of the markup.
  if (read.topic.viewpoints.empty() && zip.has(folder + "viewpoint.bcfv")) {
    read.topic.viewpoints.emplace_back();
    read.visinfo_files.push_back("viewpoint.bcfv");
    read.snapshot_files.push_back(zip.has(folder + "snapshot.png") ? "snapshot.png" : "");
  }
  Topic& topic = read.topic;
  std::vector<Viewpoint> kept;
  for (size_t i = 0; i < topic.viewpoints.size(); ++i) {
    Viewpoint& v = topic.viewpoints[i];
    try {
      if (!read.visinfo_files[i].empty()) {
        const std::string entry = folder + read.visinfo_files[i];
        readVisinfoXml(zip.read(entry, limits.max_xml_bytes), zip.where(entry), version, v);
      }
    } catch (const FormatError& e) {
      warnings.push_back(std::string(e.what()) + "; viewpoint skipped");
      continue;
    }
    if (!read.snapshot_files[i].empty()) {
      const std::string entry = folder + read.snapshot_files[i];
      try {
        const std::string png = zip.read(entry, limits.max_snapshot_bytes);
        v.snapshot_png.assign(png.begin(), png.end());
      } catch (const FormatError& e) {
        warnings.push_back(std::string(e.what()) + "; snapshot skipped");
      }
    }
    kept.push_back(std::move(v));
  }
  topic.viewpoints = std::move(kept);
  archive.topics.push_back(std::move(topic));
}

}  // namespace

Archive readArchive(const std::filesystem::path& path, std::vector<std::string>& warnings,
                    const ReadLimits& limits) {
  ZipIn zip(path, limits);
  Archive archive;
  Version version = Version::V2_1;
  if (zip.has("bcf.version")) {
    try {
      archive.version_id = readVersionXml(zip.read("bcf.version", limits.max_xml_bytes),
                                          zip.where("bcf.version"));
      if (archive.version_id.rfind("3", 0) == 0) version = Version::V3_0;
    } catch (const FormatError& e) {
      warnings.push_back(std::string(e.what()) + "; read as BCF 2.1");
    }
  } else {
    warnings.push_back(zip.where("bcf.version") + ": missing; read as BCF 2.1");
  }
  for (const char* project : {"project.bcfp"}) {
    if (!zip.has(project)) continue;
    try {
      readProjectXml(zip.read(project, limits.max_xml_bytes), zip.where(project), archive);
    } catch (const FormatError& e) {
      warnings.push_back(std::string(e.what()) + "; project name skipped");
    }
  }
  size_t markups = 0;
  for (const std::string& entry : zip.names()) {
    if (entry.size() < 11 || entry.compare(entry.size() - 11, 11, "/markup.bcf") != 0) continue;
    ++markups;
    try {
      readTopic(zip, entry, version, limits, archive, warnings);
    } catch (const FormatError& e) {
      warnings.push_back(std::string(e.what()) + "; topic skipped");
    }
  }
  if (markups > 0 && archive.topics.empty())
    throw FormatError(path.string(), "none of its " + std::to_string(markups) +
                                         " topics could be read (" + warnings.back() + ")");
  // Topics in their Index order where every one has an index, else as stored.
  const bool all_indexed = std::all_of(archive.topics.begin(), archive.topics.end(),
                                       [](const Topic& t) { return t.index.has_value(); });
  if (all_indexed)
    std::stable_sort(archive.topics.begin(), archive.topics.end(),
                     [](const Topic& a, const Topic& b) { return *a.index < *b.index; });
  return archive;
}

double pngAspectRatio(const std::vector<uint8_t>& png) {
  static const uint8_t signature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  if (png.size() < 24 || !std::equal(signature, signature + 8, png.begin())) return 0.0;
  auto be32 = [&](size_t at) {
    return (uint32_t{png[at]} << 24) | (uint32_t{png[at + 1]} << 16) | (uint32_t{png[at + 2]} << 8) |
           uint32_t{png[at + 3]};
  };
  const uint32_t width = be32(16), height = be32(20);
  return width > 0 && height > 0 ? static_cast<double>(width) / height : 0.0;
}

void writeArchive(const std::filesystem::path& path, const Archive& archive, Version version,
                  std::vector<std::string>& notes) {
  const std::string name = path.string();
  const std::string temporary = name + ".tmp" + std::to_string(getpid());
  int code = 0;
  zip_t* zip = zip_open(temporary.c_str(), ZIP_CREATE | ZIP_TRUNCATE, &code);
  if (!zip) throw std::runtime_error(name + ": cannot be written: " + zipReason(code));
  std::deque<std::string> contents;  // alive until zip_close has written them
  auto add = [&](const std::string& entry, std::string bytes) {
    contents.push_back(std::move(bytes));
    zip_source_t* source = zip_source_buffer(zip, contents.back().data(), contents.back().size(), 0);
    if (!source || zip_file_add(zip, entry.c_str(), source, ZIP_FL_OVERWRITE | ZIP_FL_ENC_UTF_8) < 0) {
      if (source) zip_source_free(source);
      const std::string reason = zip_strerror(zip);
      zip_discard(zip);
      std::remove(temporary.c_str());
      throw std::runtime_error(name + ": cannot add " + entry + ": " + reason);
    }
  };
  try {
    add("bcf.version", versionXml(version));
    if (!archive.project_id.empty()) add("project.bcfp", projectXml(version, archive));
    for (const Topic& topic : archive.topics) {
      const std::string folder = topic.guid + "/";
      add(folder + "markup.bcf", markupXml(version, topic, notes));
      for (const Viewpoint& v : topic.viewpoints) {
        double aspect = v.camera ? v.camera->aspect_ratio : 0.0;
        if (aspect <= 0.0) aspect = pngAspectRatio(v.snapshot_png);
        if (v.camera || version == Version::V2_1)
          add(folder + visinfoName(v), visinfoXml(version, v, aspect, notes));
        if (!v.snapshot_png.empty())
          add(folder + snapshotName(v), std::string(v.snapshot_png.begin(), v.snapshot_png.end()));
      }
    }
  } catch (const std::invalid_argument& e) {
    zip_discard(zip);
    std::remove(temporary.c_str());
    throw std::runtime_error(name + ": " + e.what());
  }
  if (zip_close(zip) != 0) {
    const std::string reason = zip_strerror(zip);
    zip_discard(zip);
    std::remove(temporary.c_str());
    throw std::runtime_error(name + ": cannot be written: " + reason);
  }
  std::error_code error;
  std::filesystem::rename(temporary, path, error);
  if (error) {
    std::remove(temporary.c_str());
    throw std::runtime_error(name + ": cannot be written: " + error.message());
  }
}

std::vector<ViewpointRef> viewpointsInOrder(const Archive& archive) {
  std::vector<ViewpointRef> out;
  for (const Topic& topic : archive.topics) {
    std::vector<const Viewpoint*> views;
    for (const Viewpoint& v : topic.viewpoints) views.push_back(&v);
    std::stable_sort(views.begin(), views.end(), [](const Viewpoint* a, const Viewpoint* b) {
      return a->index.value_or(INT32_MAX) < b->index.value_or(INT32_MAX);
    });
    for (const Viewpoint* v : views) out.push_back({&topic, v});
  }
  return out;
}

}  // namespace tw::bcf
