// Streaming PLY reader: ASCII, binary little- and big-endian (format 1.0).
//
// Reads the "vertex" element (x, y, z; optional nx, ny, nz; optional red, green, blue[, alpha] as
// integers 0..255, ushort 0..65535 or floats 0..1) and the "face" element (vertex_indices or
// vertex_index list of any integer type; polygons are fan-triangulated; faces with fewer than
// three indices are skipped). Any scalar type or alias (char..double, int8..float64) is accepted;
// other elements and properties, lists included, are skipped. The vertex element must come before
// the face element. The whole file becomes one object (id 0, named after the file stem, layer 0,
// declared as "default" before anything else), handed over in parts of at most
// ReadOptions::max_part_triangles triangles, each carrying only the vertices it references.
//
// Memory: a vertex table of 16 bytes per vertex (positions and a remap slot) plus 12 with normals
// and 4 with colours, sized only after the element count has been checked against the bytes left
// in the file; plus one part. Faces are streamed. At most 2^32 - 2 vertices.
#pragma once

#include <filesystem>

#include "read_options.h"
#include "scene_sink.h"

namespace tw {

// Throws FormatError (file, byte offset or line, reason) on malformed or truncated input.
void readPly(const std::filesystem::path& path, SceneSink& sink, const ReadOptions& options = {});

}  // namespace tw
