// The viewer's named viewpoints: the camera, the visibility and selection, the section planes
// and the colour overrides of a moment of the review, kept as topics of the review's own BCF
// archive (model.review.bcfzip, review_archive.h) with a snapshot, so `bcf export` hands them to
// CAD tools and `render --viewpoint` draws them headless. The panel lists them with thumbnails;
// going to one applies it (bcf_viewpoint.h). An archive that cannot be read is reported, and
// never written over.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "bcf_topics.h"
#include "bcf_viewpoint.h"
#include "camera.h"
#include "frame_loop.h"
#include "view_sections.h"
#include "view_selection.h"

namespace tw {

class ViewViewpoints {
 public:
  ViewViewpoints(Walkthrough& walk, ViewSelection& selection, ViewSections& sections,
                 std::filesystem::path archive, std::string author);
  ~ViewViewpoints();
  ViewViewpoints(const ViewViewpoints&) = delete;
  ViewViewpoints& operator=(const ViewViewpoints&) = delete;

  // Saves what the frame just drawn with `camera` shows under `name`, with its picture.
  bool save(const std::string& name, const Camera& camera);
  // Applies the viewpoint named `name` (its topic's title) to the walkthrough and `camera`.
  bool go(const std::string& name, Camera& camera);
  size_t size() const { return entries_.size(); }

  // The "Viewpoints" part of the review window: a name field and Save, then each viewpoint's
  // thumbnail, title and Go. Returns true when Go was pressed (the camera changed).
  bool drawPanel(Camera& camera, const Camera& current);

 private:
  struct Entry {
    std::string title;
    bcf::Viewpoint viewpoint;
    unsigned texture = 0;
    int thumb_w = 0, thumb_h = 0;
  };
  void addThumbnail(Entry& entry, const std::vector<uint8_t>& rgba, int width, int height);
  bool apply(const Entry& entry, Camera& camera);

  Walkthrough& walk_;
  ViewSelection& selection_;
  ViewSections& sections_;
  std::filesystem::path file_;
  std::string author_;
  bcf::Archive archive_;
  std::string load_error_;
  std::vector<Entry> entries_;
  char name_[64] = {};
};

}  // namespace tw
