// glTF 2.0 (.gltf with external or embedded buffers) and GLB reader, through tinygltf.
//
// tinygltf loads the whole file, which glTF's design requires. Each node that holds a mesh
// becomes one object, named by the node (or its mesh when the node is unnamed), with the node's
// accumulated world transform applied: the translation goes to the object's double-precision
// origin, the rest to its linear part. Triangle primitives are read (indexed or not); points and
// lines are skipped. Base colour factors become the object colour.
#pragma once

#include <filesystem>

#include "read_options.h"
#include "scene_sink.h"

namespace tw {

// Throws FormatError on bad input: (file, byte offset, reason) for a damaged GLB container,
// (file, reason) otherwise, with tinygltf's own message in the reason. Every accessor, buffer view
// and index is range-checked before use. See docs/readers-obj-gltf.md for what is supported.
void readGltf(const std::filesystem::path& path, SceneSink& sink, const ReadOptions& options = {});

}  // namespace tw
