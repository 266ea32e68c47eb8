// Streaming PLY reader: ASCII, binary little- and big-endian.
//
// Reads the "vertex" element (x, y, z; optional nx, ny, nz; optional red, green, blue[, alpha] as
// uchar or float) and the "face" element (vertex_indices or vertex_index list; polygons are
// triangulated as fans). Other elements and properties are skipped. The whole file becomes one
// object named after the file, on layer 0 ("default"), handed over in parts of at most
// ReadOptions::max_part_triangles triangles. Vertices are kept in a temporary vertex table only
// as large as the file's vertex element (binary files: 12-40 bytes per vertex).
#pragma once

#include <filesystem>

#include "read_options.h"
#include "scene_sink.h"

namespace tw {

// Throws FormatError (file, byte offset or line, reason) on malformed or truncated input.
void readPly(const std::filesystem::path& path, SceneSink& sink, const ReadOptions& options = {});

}  // namespace tw
