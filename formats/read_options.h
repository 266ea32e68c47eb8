// Options common to every scene reader.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "progress.h"

namespace tw {

struct ReadOptions {
  Progress* progress = nullptr;  // reports bytes read; may be nullptr
  // Large meshes are handed to the sink in parts of at most this many triangles, so a reader's
  // memory stays bounded whatever the file size. Parts of one object share its ObjectInfo.
  uint32_t max_part_triangles = 1u << 16;
  // Objects of the layers with these names are left out (layer_filter_sink.h); the layer table
  // still lists them.
  std::vector<std::string> exclude_layers;
};

}  // namespace tw
