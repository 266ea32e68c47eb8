// Reader for TeraWalk's native scene format (.tws); see docs/scene-format.md.
//
// Streams chunk by chunk: memory is bounded by the largest single chunk, which the reader checks
// against the file size before allocating.
#pragma once

#include <filesystem>

#include "read_options.h"
#include "scene_sink.h"

namespace tw {

// Throws FormatError (file, byte offset, reason) on malformed, truncated or corrupt input
// (including a chunk checksum mismatch).
void readTws(const std::filesystem::path& path, SceneSink& sink, const ReadOptions& options = {});

}  // namespace tw
