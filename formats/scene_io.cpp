// Dispatch from file extension to reader.
#include "scene_io.h"

#include <algorithm>
#include <cctype>
#include <string>

#include "format_error.h"
#include "gltf_reader.h"
#include "layer_filter_sink.h"
#include "obj_reader.h"
#include "ply_reader.h"
#include "scene_range.h"
#include "ifc_importer.h"
#include "step_importer.h"
#include "stl_reader.h"
#include "tws_reader.h"

namespace tw {

SceneFormat sceneFormatOf(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (ext == ".tws") return SceneFormat::Tws;
  if (ext == ".ply") return SceneFormat::Ply;
  if (ext == ".obj") return SceneFormat::Obj;
  if (ext == ".stl") return SceneFormat::Stl;
  if (ext == ".gltf" || ext == ".glb") return SceneFormat::Gltf;
  if (ext == ".stp" || ext == ".step") return SceneFormat::Step;
  if (ext == ".ifc") return SceneFormat::Ifc;
  return SceneFormat::Unknown;
}

std::string_view sceneFormatName(SceneFormat format) {
  switch (format) {
    case SceneFormat::Tws: return "tws";
    case SceneFormat::Ply: return "ply";
    case SceneFormat::Obj: return "obj";
    case SceneFormat::Stl: return "stl";
    case SceneFormat::Gltf: return "gltf";
    case SceneFormat::Step: return "step";
    case SceneFormat::Ifc: return "ifc";
    case SceneFormat::Unknown: break;
  }
  return "unknown";
}

UpAxis fileUpAxis(const std::filesystem::path& path, UpAxis up) {
  if (up != UpAxis::Auto) return up;
  return sceneFormatOf(path) == SceneFormat::Gltf ? UpAxis::Y : UpAxis::Z;
}

void readScene(const std::filesystem::path& path, SceneSink& sink, const ReadOptions& options) {
  if (!options.exclude_layers.empty()) {
    LayerFilterSink filter(sink, options.exclude_layers);
    ReadOptions unfiltered = options;
    unfiltered.exclude_layers.clear();
    return readScene(path, filter, unfiltered);
  }
  if (fileUpAxis(path, options.up) == UpAxis::Y) {
    UpAxisSink turn(sink);
    ReadOptions z_up = options;
    z_up.up = UpAxis::Z;
    return readScene(path, turn, z_up);
  }
  RangeCheckedSink checked(path.string(), sink);
  switch (sceneFormatOf(path)) {
    case SceneFormat::Tws: return readTws(path, checked, options);
    case SceneFormat::Ply: return readPly(path, checked, options);
    case SceneFormat::Obj: return readObj(path, checked, options);
    case SceneFormat::Stl: return readStl(path, checked, options);
    case SceneFormat::Gltf: return readGltf(path, checked, options);
    case SceneFormat::Step: return readStep(path, checked, options);
    case SceneFormat::Ifc: return readIfc(path, checked, options);
    case SceneFormat::Unknown: break;
  }
  throw FormatError(path.string(),
                    "unknown file type (expected .tws, .ply, .obj, .stl, .gltf, .glb, .stp, .step or .ifc)");
}

}  // namespace tw
