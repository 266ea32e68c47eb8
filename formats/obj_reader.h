// Streaming Wavefront OBJ reader.
//
// Understands v (with optional per-vertex r g b), vn, vt (parsed, unused), f with v, v/vt,
// v//vn and v/vt/vn forms, negative (relative) indices, polygons (triangulated as fans), o and g
// (each starts a new object, named by it), and usemtl (the material name becomes the object's
// layer; a colour is taken from Kd in a mtllib file next to the OBJ when one is found). Vertex
// and normal pools are global to the file as the format requires; faces are streamed to the
// sink per object part.
//
// Objects: o/g start a new object only when the current one has faces (no empty objects); a
// usemtl that changes the layer after faces starts a new object with the same name and a new id,
// so each object lies on one layer. Layer 0 is "default"; others are declared in first-use order.
// Ids count from 0; unnamed objects take the file stem. Parts hold at most
// options.max_part_triangles triangles and only the vertices they use. Memory: the global vertex
// pools (about 20-24 bytes per vertex) plus one part. See docs/readers-obj-gltf.md.
#pragma once

#include <filesystem>

#include "read_options.h"
#include "scene_sink.h"

namespace tw {

// Throws FormatError (file, line, reason) on malformed or truncated input.
void readObj(const std::filesystem::path& path, SceneSink& sink, const ReadOptions& options = {});

}  // namespace tw
