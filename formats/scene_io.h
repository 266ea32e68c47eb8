// Reading any supported scene file by its extension.
#pragma once

#include <filesystem>
#include <string_view>

#include "read_options.h"
#include "scene_sink.h"

namespace tw {

enum class SceneFormat { Unknown, Tws, Ply, Obj, Stl, Gltf };

// The format implied by the file's extension (case-insensitive): .tws, .ply, .obj, .stl,
// .gltf/.glb.
SceneFormat sceneFormatOf(const std::filesystem::path& path);
std::string_view sceneFormatName(SceneFormat format);

// Reads `path` with the reader for its format. Throws FormatError for unknown extensions and for
// any error the reader reports.
void readScene(const std::filesystem::path& path, SceneSink& sink, const ReadOptions& options = {});

}  // namespace tw
