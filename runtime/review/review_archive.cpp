// The review's own BCF archive (review_archive.h).
#include "review_archive.h"

#include <algorithm>

namespace tw {

std::filesystem::path reviewArchivePathFor(const std::filesystem::path& package) {
  std::filesystem::path path = package;
  path.replace_extension(".review.bcfzip");
  return path;
}

MergeCount mergeTopics(bcf::Archive& into, const bcf::Archive& from) {
  MergeCount count;
  for (const bcf::Topic& topic : from.topics) {
    auto same = std::find_if(into.topics.begin(), into.topics.end(),
                             [&](const bcf::Topic& t) { return t.guid == topic.guid; });
    if (same == into.topics.end()) {
      into.topics.push_back(topic);
      ++count.new_topics;
      continue;
    }
    bool gained = false;
    for (const bcf::Comment& c : topic.comments)
      if (std::none_of(same->comments.begin(), same->comments.end(),
                       [&](const bcf::Comment& k) { return k.guid == c.guid; })) {
        same->comments.push_back(c);
        gained = true;
      }
    for (const bcf::Viewpoint& v : topic.viewpoints)
      if (std::none_of(same->viewpoints.begin(), same->viewpoints.end(),
                       [&](const bcf::Viewpoint& k) { return k.guid == v.guid; })) {
        same->viewpoints.push_back(v);
        gained = true;
      }
    count.updated_topics += gained;
  }
  return count;
}

}  // namespace tw
