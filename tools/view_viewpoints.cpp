// The viewer's named viewpoints (view_viewpoints.h).
#include "view_viewpoints.h"

#define GL_GLEXT_PROTOTYPES 1
#include <GL/glcorearb.h>

#include <cstdio>

#include <imgui.h>

#include "bcf_archive.h"
#include "bcf_ids.h"
#include "image_compare.h"
#include "view_log.h"

namespace tw {
namespace {

constexpr int kThumbWidth = 160;

}  // namespace

ViewViewpoints::ViewViewpoints(Walkthrough& walk, ViewSelection& selection, ViewSections& sections,
                               std::filesystem::path archive, std::string author)
    : walk_(walk), selection_(selection), sections_(sections), file_(std::move(archive)),
      author_(std::move(author)) {
  if (!std::filesystem::exists(file_)) return;
  try {
    std::vector<std::string> warnings;
    archive_ = bcf::readArchive(file_, warnings);
    if (!warnings.empty()) throw std::runtime_error(warnings.front());
  } catch (const std::exception& e) {
    load_error_ = e.what();
    archive_ = {};
    std::fprintf(stderr, "terawalk: %s; viewpoints are kept in memory, that file is not written over\n",
                 load_error_.c_str());
    return;
  }
  for (const bcf::ViewpointRef& r : bcf::viewpointsInOrder(archive_)) {
    Entry entry{r.topic->title, *r.viewpoint};
    if (!r.viewpoint->snapshot_png.empty()) {
      try {
        const RgbaImage image = decodePngRgba(r.viewpoint->snapshot_png, file_.string());
        addThumbnail(entry, image.rgba, image.width, image.height);
      } catch (const std::exception&) {
        // No thumbnail for a snapshot that does not decode; the viewpoint is still there.
      }
    }
    entries_.push_back(std::move(entry));
  }
  viewSay("viewpoints: %zu from %s\n", entries_.size(), file_.string().c_str());
}

ViewViewpoints::~ViewViewpoints() {
  for (Entry& e : entries_)
    if (e.texture) glDeleteTextures(1, &e.texture);
}

// A thumbnail kThumbWidth wide (nearest pixel: small and sharp enough), rows as in the image.
void ViewViewpoints::addThumbnail(Entry& entry, const std::vector<uint8_t>& rgba, int width, int height) {
  if (width <= 0 || height <= 0) return;
  entry.thumb_w = kThumbWidth;
  entry.thumb_h = std::max(1, kThumbWidth * height / width);
  std::vector<uint8_t> small(size_t(entry.thumb_w) * entry.thumb_h * 4);
  for (int y = 0; y < entry.thumb_h; ++y)
    for (int x = 0; x < entry.thumb_w; ++x) {
      const int sx = x * width / entry.thumb_w, sy = y * height / entry.thumb_h;
      std::copy_n(&rgba[(size_t(sy) * width + sx) * 4], 4, &small[(size_t(y) * entry.thumb_w + x) * 4]);
    }
  glCreateTextures(GL_TEXTURE_2D, 1, &entry.texture);
  glTextureStorage2D(entry.texture, 1, GL_RGBA8, entry.thumb_w, entry.thumb_h);
  glTextureSubImage2D(entry.texture, 0, 0, 0, entry.thumb_w, entry.thumb_h, GL_RGBA, GL_UNSIGNED_BYTE,
                      small.data());
  glTextureParameteri(entry.texture, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  glTextureParameteri(entry.texture, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
}

bool ViewViewpoints::save(const std::string& name, const Camera& camera) {
  if (name.empty()) return false;
  GlRenderer& r = walk_.renderer();
  std::vector<uint8_t> rgba;
  r.readColor(rgba, true);
  bcf::Viewpoint v = captureViewpoint(camera, double(r.width()) / r.height(), walk_.objectStates(),
                                      ComponentIndex(walk_.package()), sections_.all());
  v.snapshot_png = encodePngRgba(r.width(), r.height(), rgba);
  bcf::Topic topic;
  topic.guid = bcf::newGuid();
  topic.title = name;
  topic.type = "Viewpoint";
  topic.status = "Open";
  topic.creation_author = author_;
  topic.creation_date = bcf::utcNow();
  topic.viewpoints.push_back(v);
  archive_.topics.push_back(topic);
  Entry entry{name, v};
  addThumbnail(entry, rgba, r.width(), r.height());
  entries_.push_back(std::move(entry));
  if (!load_error_.empty()) {
    std::fprintf(stderr, "terawalk: viewpoint '%s' kept in memory only: %s could not be read\n",
                 name.c_str(), file_.string().c_str());
    return false;
  }
  try {
    std::vector<std::string> notes;
    bcf::writeArchive(file_, archive_, bcf::Version::V3_0, notes);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "terawalk: %s\n", e.what());
    return false;
  }
  viewSay("viewpoints: saved '%s' (%zu in %s)\n", name.c_str(), entries_.size(), file_.string().c_str());
  return true;
}

bool ViewViewpoints::apply(const Entry& entry, Camera& camera) {
  selection_.clear();
  const ViewpointApplied applied =
      applyViewpoint(entry.viewpoint, ComponentIndex(walk_.package()), walk_.objectStates(), camera);
  if (applied.has_camera) camera = applied.camera;
  sections_.set(applied.sections);
  // The viewpoint's selection becomes the viewer's (which sets the flags again itself).
  std::vector<uint32_t> selected;
  ObjectStates& states = walk_.objectStates();
  for (uint32_t o = 0; o < states.size(); ++o)
    if (states.flags(o) & kObjectSelected) {
      selected.push_back(o);
      states.set(o, kObjectSelected, false);
    }
  selection_.select(selected);
  for (const std::string& w : applied.warnings) std::fprintf(stderr, "terawalk: warning: %s\n", w.c_str());
  viewSay("viewpoints: went to '%s' (%zu selected, %u hidden)\n", entry.title.c_str(),
      selection_.selected().size(), applied.hidden);
  return true;
}

bool ViewViewpoints::go(const std::string& name, Camera& camera) {
  for (const Entry& e : entries_)
    if (e.title == name) return apply(e, camera);
  viewSay("viewpoints: none named '%s'\n", name.c_str());
  return false;
}

bool ViewViewpoints::drawPanel(Camera& camera, const Camera& current) {
  ImGui::Begin("Review");
  if (!ImGui::CollapsingHeader("Viewpoints", ImGuiTreeNodeFlags_DefaultOpen)) {
    ImGui::End();
    return false;
  }
  ImGui::InputText("##viewpoint", name_, sizeof name_);
  ImGui::SameLine();
  if (ImGui::Button("Save viewpoint") && name_[0]) {
    save(name_, current);
    name_[0] = '\0';
  }
  if (!load_error_.empty()) ImGui::TextColored(ImVec4(1, 0.5f, 0.3f, 1), "%s", load_error_.c_str());
  bool went = false;
  for (size_t i = 0; i < entries_.size(); ++i) {
    const Entry& e = entries_[i];
    ImGui::PushID(int(i));
    if (e.texture)
      ImGui::Image(reinterpret_cast<ImTextureID>(static_cast<uintptr_t>(e.texture)),
                   ImVec2(float(e.thumb_w), float(e.thumb_h)));
    ImGui::SameLine();
    ImGui::BeginGroup();
    ImGui::TextUnformatted(e.title.c_str());
    if (ImGui::Button("Go")) went = apply(e, camera);
    ImGui::EndGroup();
    ImGui::PopID();
  }
  ImGui::End();
  return went;
}

}  // namespace tw
