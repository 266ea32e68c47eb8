// Reader for TeraWalk's native scene format (.tws); see docs/scene-format.md.
//
// Streams chunk by chunk: memory is bounded by the largest single chunk, which the reader checks
// against the file size before allocating.
#pragma once

#include <filesystem>

#include "read_options.h"
#include "scene_sink.h"

namespace tw {

// Hands layers and objects to `sink` in file order. Mesh chunks with more than
// options.max_part_triangles triangles are handed on as several parts (each with only the vertices
// it uses); 0 means "as stored in the file". Unknown optional chunk types are skipped.
// options.progress gets one "read" stage counted in bytes, updated after each chunk.
// Throws FormatError (file, byte offset, reason) on malformed, truncated or corrupt input
// (including a chunk checksum mismatch); layers and objects before the error have been delivered.
void readTws(const std::filesystem::path& path, SceneSink& sink, const ReadOptions& options = {});

}  // namespace tw
