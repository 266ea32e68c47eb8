// `terawalk info FILE`: what a scene file holds, for people (text) and scripts (--json).
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>

#include <nlohmann/json.hpp>

#include "command.h"
#include "scene_io.h"
#include "scene_stats.h"
#include "tessellate.h"

namespace tw {
namespace {

struct InfoOptions {
  std::string file;
  bool json = false;
  float tolerance = kDefaultChordalTolerance;
};

nlohmann::json statsToJson(const std::string& file, uint64_t file_bytes, const SceneStats& s,
                           float tolerance) {
  nlohmann::json j;
  j["file"] = file;
  j["format"] = sceneFormatName(sceneFormatOf(file));
  j["file_bytes"] = file_bytes;
  j["objects"] = s.objects;
  j["object_parts"] = s.parts;
  j["objects_with_db_key"] = s.objects_with_db_key;
  nlohmann::json kinds;
  for (size_t k = 0; k < SceneStats::kGeometryKinds; ++k)
    kinds[SceneStats::geometryKindName(k)] = s.objects_by_kind[k];
  j["objects_by_kind"] = kinds;
  nlohmann::json prims;
  for (size_t t = 0; t < SceneStats::kPrimitiveTypes; ++t)
    prims[SceneStats::primitiveTypeName(t)] = s.primitives_by_type[t];
  j["primitives_by_type"] = prims;
  j["nurbs_patches"] = s.nurbs_patches;
  j["tolerance"] = tolerance;
  j["triangles"] = {{"mesh", s.mesh_triangles},
                    {"primitive_equivalent", s.primitive_triangles},
                    {"nurbs_equivalent", s.nurbs_triangles},
                    {"total", s.totalTriangles()}};
  j["mesh_vertices"] = s.mesh_vertices;
  if (!s.bounds.empty()) {
    j["bounds"] = {{"min", {s.bounds.min.x, s.bounds.min.y, s.bounds.min.z}},
                   {"max", {s.bounds.max.x, s.bounds.max.y, s.bounds.max.z}}};
  } else {
    j["bounds"] = nullptr;
  }
  nlohmann::json layers = nlohmann::json::array();
  for (const auto& layer : s.layers)
    layers.push_back({{"name", layer.name}, {"objects", layer.objects},
                      {"triangles", layer.triangles}});
  j["layers"] = layers;
  return j;
}

void printText(const std::string& file, uint64_t file_bytes, const SceneStats& s, float tolerance,
               double seconds) {
  std::printf("file        %s (%s, %llu bytes)\n", file.c_str(),
              std::string(sceneFormatName(sceneFormatOf(file))).c_str(),
              static_cast<unsigned long long>(file_bytes));
  std::printf("objects     %llu (%llu parts, %llu with a database key)\n",
              static_cast<unsigned long long>(s.objects), static_cast<unsigned long long>(s.parts),
              static_cast<unsigned long long>(s.objects_with_db_key));
  std::printf("geometry   ");
  for (size_t k = 0; k < SceneStats::kGeometryKinds; ++k)
    std::printf(" %s %llu", SceneStats::geometryKindName(k),
                static_cast<unsigned long long>(s.objects_by_kind[k]));
  std::printf("\n");
  if (s.objects_by_kind[static_cast<size_t>(GeometryKind::Parametric)] > 0) {
    std::printf("primitives ");
    for (size_t t = 0; t < SceneStats::kPrimitiveTypes; ++t)
      std::printf(" %s %llu", SceneStats::primitiveTypeName(t),
                  static_cast<unsigned long long>(s.primitives_by_type[t]));
    std::printf("\n");
  }
  if (s.nurbs_patches)
    std::printf("nurbs       %llu patches\n", static_cast<unsigned long long>(s.nurbs_patches));
  std::printf("triangles   %llu (mesh %llu, primitives %llu, nurbs %llu; at tolerance %g)\n",
              static_cast<unsigned long long>(s.totalTriangles()),
              static_cast<unsigned long long>(s.mesh_triangles),
              static_cast<unsigned long long>(s.primitive_triangles),
              static_cast<unsigned long long>(s.nurbs_triangles), double(tolerance));
  if (!s.bounds.empty()) {
    glm::dvec3 e = s.bounds.extent();
    std::printf("bounds      min (%.3f, %.3f, %.3f) max (%.3f, %.3f, %.3f) size %.3f x %.3f x %.3f\n",
                s.bounds.min.x, s.bounds.min.y, s.bounds.min.z, s.bounds.max.x, s.bounds.max.y,
                s.bounds.max.z, e.x, e.y, e.z);
  } else {
    std::printf("bounds      empty\n");
  }
  std::printf("layers      %zu\n", s.layers.size());
  for (const auto& layer : s.layers)
    std::printf("  %-24s %10llu objects %14llu triangles\n", layer.name.c_str(),
                static_cast<unsigned long long>(layer.objects),
                static_cast<unsigned long long>(layer.triangles));
  std::printf("read in     %.2f s\n", seconds);
}

}  // namespace

void registerInfoCommand(CLI::App& app, const GlobalOptions& global) {
  auto options = std::make_shared<InfoOptions>();
  CLI::App* cmd = app.add_subcommand("info", "Print what a scene file holds");
  cmd->add_option("file", options->file, "Scene file (.tws, .ply, .obj, .stl, .gltf, .glb)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_flag("--json", options->json, "Machine-readable output");
  cmd->add_option("--tolerance", options->tolerance,
                  "Chordal tolerance for tessellated-equivalent triangle counts (scene units)")
      ->check(CLI::PositiveNumber);
  cmd->callback([options, &global] {
    auto progress = makeCommandProgress(global);
    SceneStats stats(options->tolerance);
    ReadOptions read;
    read.progress = progress.get();
    auto start = std::chrono::steady_clock::now();
    readScene(options->file, stats, read);
    double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    uint64_t bytes = std::filesystem::file_size(options->file);
    if (options->json)
      std::cout << statsToJson(options->file, bytes, stats, options->tolerance).dump(2) << "\n";
    else
      printText(options->file, bytes, stats, options->tolerance, seconds);
  });
}

}  // namespace tw
