// Streaming STL reader, ASCII and binary (detected by content, not by the "solid" prefix alone).
//
// A file is binary exactly when its size is 84 + 50 * N, N being the uint32 at byte 80, even if
// it starts with "solid"; otherwise it must be ASCII. ASCII: each "solid NAME" becomes an object
// (id = the solid's index in the file, name = NAME or the file stem when empty); keywords are
// case-insensitive and a loop of more than three vertices is fan-triangulated. Binary: the file is
// one object (id 0) named after the file stem. All objects are on layer 0 ("default", declared
// first). Vertices are not welded (three per triangle); facet normals and attribute bytes are
// ignored; non-finite vertices are an error. Triangles arrive in parts of at most
// ReadOptions::max_part_triangles, so memory is bounded by one part.
#pragma once

#include <filesystem>

#include "read_options.h"
#include "scene_sink.h"

namespace tw {

// Throws FormatError (file, byte offset or line, reason) on malformed or truncated input.
void readStl(const std::filesystem::path& path, SceneSink& sink, const ReadOptions& options = {});

}  // namespace tw
