// `terawalk info FILE`: what a scene file or a package holds, for people (text) and scripts
// (--json). A package (.twk, recognised by extension or magic) gets its per-level summary
// (package_summary.h) instead of the scene statistics.
#include <cctype>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>

#include <nlohmann/json.hpp>

#include "command.h"
#include "package_summary.h"
#include "package_view.h"
#include "scene_io.h"
#include "scene_stats.h"
#include "tessellate.h"

namespace tw {
namespace {

struct InfoOptions {
  std::string file;
  bool json = false;
  float tolerance = kDefaultChordalTolerance;
  std::string up = "auto";
};

// Models are mostly wider than tall (plants, buildings, ships). Read with the wrong up axis, the
// true vertical lies along Y and the scene's Z is a plan dimension: Y is then the thinnest axis
// and Z clearly taller than it. Worth a warning, not an error (a wall on its own is like that).
bool looksLikeTheOtherUp(const SceneStats& s) {
  if (s.bounds.empty()) return false;
  const glm::dvec3 e = s.bounds.extent();
  return e.y < e.x && e.y < e.z && e.z > 1.2 * e.y;
}

// Share of the triangle equivalent that stays parametric (primitives), in [0, 1].
double parametricShare(const SceneStats& s) {
  return s.totalTriangles() ? double(s.primitive_triangles) / double(s.totalTriangles()) : 0.0;
}

nlohmann::json statsToJson(const std::string& file, uint64_t file_bytes, const SceneStats& s,
                           float tolerance, UpAxis up) {
  nlohmann::json j;
  j["file"] = file;
  j["format"] = sceneFormatName(sceneFormatOf(file));
  j["up"] = upAxisName(up);
  j["looks_like_the_other_up"] = looksLikeTheOtherUp(s);
  j["parametric_share"] = parametricShare(s);
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
               UpAxis up, double seconds) {
  std::printf("file        %s (%s, %llu bytes, read %s up)\n", file.c_str(),
              std::string(sceneFormatName(sceneFormatOf(file))).c_str(),
              static_cast<unsigned long long>(file_bytes), up == UpAxis::Y ? "Y" : "Z");
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
  std::printf("parametric  %.1f %% of the triangle equivalent stays parametric\n",
              100.0 * parametricShare(s));
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

// A package by extension, or by its magic whatever the name.
bool isPackageFile(const std::string& file) {
  std::string ext = std::filesystem::path(file).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (ext == ".twk") return true;
  char magic[sizeof(pkg::kMagic)] = {};
  std::ifstream in(file, std::ios::binary);
  return in.read(magic, sizeof(magic)) && std::memcmp(magic, pkg::kMagic, sizeof(magic)) == 0;
}

nlohmann::json vec3Json(const glm::vec3& v) { return {v.x, v.y, v.z}; }

nlohmann::json packageToJson(const PackageSummary& s) {
  nlohmann::json j;
  j["file"] = s.file;
  j["format"] = "twk";
  j["version"] = std::to_string(s.version) + "." + std::to_string(s.minor_version);
  j["file_bytes"] = s.file_bytes;
  j["origin"] = {s.origin.x, s.origin.y, s.origin.z};
  j["position_step_m"] = s.position_step_m;
  j["bounds"] = {{"min", vec3Json(s.bounds_min)}, {"max", vec3Json(s.bounds_max)}};
  j["input_hash"] = s.input_hash;
  j["level_count"] = s.level_count;
  j["triangles"] = {{"level0", s.total_triangles}, {"all_levels", s.all_level_triangles}};
  j["max_cluster_triangles"] = s.max_cluster_triangles;
  j["clusters"] = s.clusters;
  j["groups"] = s.groups;
  j["far_proxy"] = {{"clusters", s.far_proxy_clusters}, {"triangles", s.far_proxy_triangles}};
  j["bytes_per_input_triangle"] = s.bytesPerInputTriangle();
  nlohmann::json levels = nlohmann::json::array();
  for (const PackageLevelSummary& l : s.levels)
    levels.push_back({{"level", l.level},
                      {"clusters", l.clusters},
                      {"parametric_clusters", l.parametric_clusters},
                      {"triangles", l.triangles},
                      {"vertices", l.vertices},
                      {"instances", l.instances},
                      {"roots", l.roots},
                      {"groups", l.groups},
                      {"encoded_bytes", l.encoded_bytes},
                      {"error_m", {{"min", l.min_error_m},
                                   {"max", l.max_error_m},
                                   {"mean", l.mean_error_m}}}});
  j["levels"] = levels;
  j["pages"] = {{"count", s.pages},
                {"compressed", s.pages_compressed},
                {"stored_bytes", s.page_stored_bytes},
                {"raw_bytes", s.page_raw_bytes},
                {"target_bytes", s.target_page_bytes}};
  nlohmann::json sections, raw_sections;
  for (uint32_t i = 0; i < pkg::kSectionCount; ++i) {
    sections[pkg::kSectionNames[i]] = s.section_bytes[i];
    raw_sections[pkg::kSectionNames[i]] = s.section_raw_bytes[i];
  }
  j["section_bytes"] = sections;          // in the file
  j["section_raw_bytes"] = raw_sections;  // decompressed (differs for zstd-stored tables)
  nlohmann::json prims;
  for (uint32_t t = 0; t < pkg::kPrimitiveTypeCount; ++t)
    prims[packagePrimitiveTypeName(t)] = s.instances_by_type[t];
  j["instances"] = {
      {"total", s.instances}, {"by_type", prims}, {"profile_points", s.profile_points}};
  j["sealed_runs"] = {{"marked", s.sealed_runs_marked},
                      {"members", s.sealed_run_members},
                      {"closers", s.sealed_run_closers}};
  j["covered_box_faces"] = {{"marked", s.covered_faces_marked}, {"faces", s.covered_box_faces}};
  j["objects"] = s.objects;
  j["objects_with_db_key"] = s.objects_with_db_key;
  j["closed_objects"] = s.closed_objects;
  j["database"] = s.database_path;
  nlohmann::json layers = nlohmann::json::array();
  for (const auto& layer : s.layers)
    layers.push_back({{"name", layer.name}, {"objects", layer.objects},
                      {"color_rgba", layer.color_rgba}});
  j["layers"] = layers;
  const PackageSummary::Visibility& v = s.visibility;
  j["visibility"] = {{"present", v.present},
                     {"bytes", v.bytes},
                     {"cells", v.cells},
                     {"solid_cells", v.solid_cells},
                     {"grid_dims", {v.grid_dims.x, v.grid_dims.y, v.grid_dims.z}},
                     {"grid_min", {v.grid_min.x, v.grid_min.y, v.grid_min.z}},
                     {"cell_size_m", v.cell_size_m},
                     {"rays_cast", v.rays_cast},
                     {"rays_per_cell", v.rays_per_cell},
                     {"candidate_level", v.candidate_level},
                     {"candidate_triangles", v.candidate_triangles},
                     {"visible_sets", v.visible_sets},
                     {"parametric_candidates", v.parametric_candidates},
                     {"occluder_ids", v.occluder_ids},
                     {"visible_ids", v.visible_ids},
                     {"average_occluders", v.average_occluders},
                     {"average_visible", v.average_visible},
                     {"average_coverage", v.average_coverage}};
  return j;
}

std::string mib(uint64_t bytes) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.2f MiB", double(bytes) / (1024.0 * 1024.0));
  return buf;
}

void printPackage(const PackageSummary& s, double seconds) {
  using ull = unsigned long long;
  std::printf("file        %s (twk %u.%u, %llu bytes, %s)\n", s.file.c_str(), s.version,
              s.minor_version, ull(s.file_bytes), mib(s.file_bytes).c_str());
  std::printf("origin      (%.3f, %.3f, %.3f) m, position step %.3g m\n", s.origin.x, s.origin.y,
              s.origin.z, s.position_step_m);
  const glm::vec3 e = s.bounds_max - s.bounds_min;
  std::printf("bounds      min (%.3f, %.3f, %.3f) max (%.3f, %.3f, %.3f) size %.3f x %.3f x "
              "%.3f\n",
              s.bounds_min.x, s.bounds_min.y, s.bounds_min.z, s.bounds_max.x, s.bounds_max.y,
              s.bounds_max.z, e.x, e.y, e.z);
  std::printf("triangles   %llu input (level 0), %llu over all levels (%.2fx); %.2f bytes per "
              "input triangle\n",
              ull(s.total_triangles), ull(s.all_level_triangles),
              s.total_triangles ? double(s.all_level_triangles) / double(s.total_triangles) : 0.0,
              s.bytesPerInputTriangle());
  std::printf("dag         %u levels, %llu clusters (largest %u triangles), %llu groups; "
              "%llu far-proxy clusters (%llu triangles)\n",
              s.level_count, ull(s.clusters), s.max_cluster_triangles, ull(s.groups),
              ull(s.far_proxy_clusters), ull(s.far_proxy_triangles));
  std::printf("  %5s %10s %14s %8s %8s %8s %12s %12s %12s %12s\n", "level", "clusters",
              "triangles", "param", "groups", "roots", "err min m", "err mean m", "err max m",
              "encoded");
  for (const PackageLevelSummary& l : s.levels)
    std::printf("  %5u %10llu %14llu %8llu %8llu %8llu %12.4g %12.4g %12.4g %12s\n", l.level,
                ull(l.clusters), ull(l.triangles), ull(l.parametric_clusters), ull(l.groups),
                ull(l.roots), double(l.min_error_m), l.mean_error_m, double(l.max_error_m),
                mib(l.encoded_bytes).c_str());
  std::printf("pages       %llu (%llu zstd), stored %s, raw %s (%.1f%%), target %u bytes\n",
              ull(s.pages), ull(s.pages_compressed), mib(s.page_stored_bytes).c_str(),
              mib(s.page_raw_bytes).c_str(),
              s.page_raw_bytes ? 100.0 * double(s.page_stored_bytes) / double(s.page_raw_bytes)
                               : 100.0,
              s.target_page_bytes);
  std::printf("sections   ");
  for (uint32_t i = 0; i < pkg::kSectionCount; ++i)
    if (s.section_bytes[i]) {
      std::printf(" %s %llu", pkg::kSectionNames[i], ull(s.section_bytes[i]));
      if (s.section_raw_bytes[i] != s.section_bytes[i])
        std::printf(" (zstd of %llu)", ull(s.section_raw_bytes[i]));
    }
  std::printf("\n");
  if (s.instances) {
    std::printf("instances   %llu:", ull(s.instances));
    for (uint32_t t = 0; t < pkg::kPrimitiveTypeCount; ++t)
      if (s.instances_by_type[t])
        std::printf(" %s %llu", packagePrimitiveTypeName(t), ull(s.instances_by_type[t]));
    std::printf("\n");
    if (s.sealed_runs_marked)
      std::printf("sealed runs %llu open parts, %llu closing cylinders (found by the preprocessor)\n",
                  ull(s.sealed_run_members), ull(s.sealed_run_closers));
    else
      std::printf("sealed runs not marked (the runtime searches at start-up)\n");
    if (s.covered_faces_marked)
      std::printf("box faces   %llu covered by another box's face (found by the preprocessor)\n",
                  ull(s.covered_box_faces));
  }
  std::printf("objects     %llu (%llu with a database key, %llu closed solids)\n", ull(s.objects),
              ull(s.objects_with_db_key), ull(s.closed_objects));
  if (!s.database_path.empty()) std::printf("database    %s\n", s.database_path.c_str());
  std::printf("layers      %zu\n", s.layers.size());
  for (const auto& layer : s.layers)
    std::printf("  %-24s %10llu objects\n", layer.name.c_str(), ull(layer.objects));
  const PackageSummary::Visibility& v = s.visibility;
  if (!v.present) {
    std::printf("visibility  none\n");
  } else {
    std::printf("visibility  %llu cells (%llu solid) in a %u x %u x %u grid of %.3g m cells, %s\n",
                ull(v.cells), ull(v.solid_cells), v.grid_dims.x, v.grid_dims.y, v.grid_dims.z,
                v.cell_size_m, mib(v.bytes).c_str());
    std::printf("  rays %llu (%u per cell); candidates: level %u front, %llu triangles%s\n",
                ull(v.rays_cast), v.rays_per_cell, v.candidate_level, ull(v.candidate_triangles),
                v.parametric_candidates ? ", and the parametric clusters" : "");
    std::printf("  occluders %.2f per cell (covering %.1f%% of rays)", v.average_occluders,
                100.0 * v.average_coverage);
    if (v.visible_sets)
      std::printf("; visible set %.1f per cell", v.average_visible);
    std::printf("\n");
  }
  std::printf("read in     %.2f s\n", seconds);
}

void infoPackage(const std::string& file, bool json) {
  const auto start = std::chrono::steady_clock::now();
  // Headers only: info reads the tables, never the page data (verify checks that).
  PackageView view = PackageView::open(file, PackageView::Verify::Headers);
  PackageSummary summary = summarizePackage(view);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (json)
    std::cout << packageToJson(summary).dump(2) << "\n";
  else
    printPackage(summary, seconds);
}

}  // namespace

void registerInfoCommand(CLI::App& app, const GlobalOptions& global) {
  auto options = std::make_shared<InfoOptions>();
  CLI::App* cmd = app.add_subcommand("info", "Print what a scene file or package holds");
  cmd->add_option("file", options->file,
                  "Scene file (.tws, .ply, .obj, .stl, .gltf, .glb, .stp, .step, .ifc) or package (.twk)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_flag("--json", options->json, "Machine-readable output");
  cmd->add_option("--tolerance", options->tolerance,
                  "Chordal tolerance for tessellated-equivalent triangle counts (scene units)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--up", options->up,
                  "The file's up axis: y or z (default: y for glTF, z for everything else)")
      ->check(CLI::IsMember({"auto", "y", "z"}));
  cmd->callback([options, &global] {
    if (isPackageFile(options->file)) {
      infoPackage(options->file, options->json);
      return;
    }
    auto progress = makeCommandProgress(global);
    SceneStats stats(options->tolerance);
    ReadOptions read;
    read.progress = progress.get();
    read.up = parseUpAxis(options->up);
    std::vector<std::string> notes;
    read.note = [&notes](const std::string& note) { notes.push_back(note); };
    const UpAxis up = fileUpAxis(options->file, read.up);
    auto start = std::chrono::steady_clock::now();
    readScene(options->file, stats, read);
    double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    uint64_t bytes = std::filesystem::file_size(options->file);
    if (options->json)
      std::cout << statsToJson(options->file, bytes, stats, options->tolerance, up).dump(2)
                << "\n";
    else
      printText(options->file, bytes, stats, options->tolerance, up, seconds);
    if (!options->json)
      for (const std::string& note : notes) std::printf("import      %s\n", note.c_str());
    if (looksLikeTheOtherUp(stats)) {
      const glm::dvec3 e = stats.bounds.extent();
      std::fprintf(stderr,
                   "warning: %s: read %s up, the model is %.3g tall but only %.3g deep (%.3g "
                   "wide); if the file is %s up, read it with --up %s\n",
                   options->file.c_str(), up == UpAxis::Y ? "Y" : "Z", e.z, e.y, e.x,
                   up == UpAxis::Y ? "Z" : "Y", up == UpAxis::Y ? "z" : "y");
    }
  });
}

}  // namespace tw
