// Streaming STL reader, ASCII and binary (detected by content, not by the "solid" prefix alone).
//
// ASCII: each "solid NAME" becomes an object named NAME. Binary: the file is one object named
// after the file. Vertices are not welded (STL has none to share); facet normals are ignored.
#pragma once

#include <filesystem>

#include "read_options.h"
#include "scene_sink.h"

namespace tw {

// Throws FormatError (file, byte offset or line, reason) on malformed or truncated input.
void readStl(const std::filesystem::path& path, SceneSink& sink, const ReadOptions& options = {});

}  // namespace tw
