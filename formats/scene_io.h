// Reading any supported scene file by its extension: the streaming mesh readers of formats/ and
// the CAD importers of formats/importers/ (STEP through OpenCASCADE). Library tw_scene_io.
#pragma once

#include <filesystem>
#include <string_view>

#include "read_options.h"
#include "scene_sink.h"

namespace tw {

enum class SceneFormat { Unknown, Tws, Ply, Obj, Stl, Gltf, Step, Ifc };

// The format implied by the file's extension (case-insensitive): .tws, .ply, .obj, .stl,
// .gltf/.glb, .stp/.step, .ifc.
SceneFormat sceneFormatOf(const std::filesystem::path& path);
std::string_view sceneFormatName(SceneFormat format);

// The up axis `path` is read with: `up` when given, else the format's (glTF Y, the rest Z).
UpAxis fileUpAxis(const std::filesystem::path& path, UpAxis up);

// Reads `path` with the reader for its format, Z up (a Y-up file is turned, up_axis.h). Throws FormatError for unknown extensions and for
// any error the reader reports.
void readScene(const std::filesystem::path& path, SceneSink& sink, const ReadOptions& options = {});

}  // namespace tw
