// Streaming Wavefront OBJ reader.
//
// Understands v (with optional per-vertex r g b), vn, vt (parsed, unused), f with v, v/vt,
// v//vn and v/vt/vn forms, negative (relative) indices, polygons (triangulated as fans), o and g
// (each starts a new object, named by it), and usemtl (the material name becomes the object's
// layer; a colour is taken from Kd in a mtllib file next to the OBJ when one is found). Vertex
// and normal pools are global to the file as the format requires; faces are streamed to the
// sink per object part.
#pragma once

#include <filesystem>

#include "read_options.h"
#include "scene_sink.h"

namespace tw {

// Throws FormatError (file, line, reason) on malformed or truncated input.
void readObj(const std::filesystem::path& path, SceneSink& sink, const ReadOptions& options = {});

}  // namespace tw
