// The review's own topics: a BCF 3.0 archive kept next to the package (model.twk:
// model.review.bcfzip), which `bcf export` adds topics to and writes out, and `bcf import` merges
// other tools' topics into. An archive that cannot be read is reported and never overwritten,
// so nothing written before is lost.
#pragma once

#include <filesystem>

#include "bcf_topics.h"

namespace tw {

// The package's path with its extension replaced by ".review.bcfzip".
std::filesystem::path reviewArchivePathFor(const std::filesystem::path& package);

// Merges `from` into `into`: topics new by guid are appended; a topic already there gains the
// comments and viewpoints it does not have (by guid) and keeps its own fields. Returns how many
// topics were new and how many gained something.
struct MergeCount {
  size_t new_topics = 0, updated_topics = 0;
};
MergeCount mergeTopics(bcf::Archive& into, const bcf::Archive& from);

}  // namespace tw
