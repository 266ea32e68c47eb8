// `terawalk gen plant`: streams a procedural offshore plant to a .tws scene, its SQLite project
// database and, optionally, the tessellated scene as PLY or OBJ for other tools.
#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "command.h"
#include "obj_writer.h"
#include "plant_generator.h"
#include "ply_writer.h"
#include "project_database.h"
#include "tws_writer.h"

namespace tw {
namespace {

struct GenPlantOptions {
  std::string triangles = "1M";
  uint64_t seed = 1;
  float tolerance = kDefaultChordalTolerance;
  std::string output = "plant.tws";
  std::string db;
  bool no_db = false;
  std::string mesh;
};

// "250000", "100K", "10M", "1.5G" (powers of 1000, case-insensitive).
uint64_t parseCount(const std::string& text) {
  std::string s = text;
  s.erase(std::remove(s.begin(), s.end(), '_'), s.end());
  double scale = 1.0;
  if (!s.empty()) {
    switch (std::toupper(static_cast<unsigned char>(s.back()))) {
      case 'K': scale = 1e3; break;
      case 'M': scale = 1e6; break;
      case 'G': scale = 1e9; break;
      default: break;
    }
    if (scale != 1.0) s.pop_back();
  }
  size_t used = 0;
  double value = 0.0;
  try {
    value = std::stod(s, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (s.empty() || used != s.size() || !std::isfinite(value) || value * scale < 1.0 ||
      value * scale > 1e13)
    throw std::runtime_error("--triangles: expected a count such as 250000, 100K, 10M or 1G, got '" +
                             text + "'");
  return static_cast<uint64_t>(std::llround(value * scale));
}

std::string lowerExtension(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

std::string formatBytes(uint64_t bytes) {
  char buf[32];
  if (bytes >= (uint64_t{1} << 30)) std::snprintf(buf, sizeof buf, "%.2f GiB", bytes / 1073741824.0);
  else if (bytes >= (uint64_t{1} << 20)) std::snprintf(buf, sizeof buf, "%.1f MiB", bytes / 1048576.0);
  else std::snprintf(buf, sizeof buf, "%.1f KiB", bytes / 1024.0);
  return buf;
}

void runGenPlant(const GenPlantOptions& o, const GlobalOptions& global) {
  auto start = std::chrono::steady_clock::now();
  PlantOptions options;
  options.target_triangles = parseCount(o.triangles);
  options.seed = o.seed;
  options.tolerance = o.tolerance;
  if (!(o.tolerance > 0.0f) || !std::isfinite(o.tolerance))
    throw std::runtime_error("--tolerance must be a positive number of metres");

  std::filesystem::path tws_path = o.output;
  std::filesystem::path db_path;
  if (!o.no_db) {
    db_path = o.db.empty() ? std::filesystem::path(tws_path).replace_extension(".db")
                           : std::filesystem::path(o.db);
  }
  std::unique_ptr<SceneWriter> mesh_writer;
  if (!o.mesh.empty()) {
    std::string ext = lowerExtension(o.mesh);
    if (ext == ".ply") mesh_writer = std::make_unique<PlyWriter>(o.mesh, o.tolerance);
    else if (ext == ".obj") mesh_writer = std::make_unique<ObjWriter>(o.mesh, o.tolerance);
    else throw std::runtime_error(o.mesh + ": --mesh must end in .ply or .obj");
  }

  TwsWriter tws(tws_path);
  FanOutSink sink;
  sink.add(tws);
  if (mesh_writer) sink.add(*mesh_writer);
  std::unique_ptr<Progress> progress = makeCommandProgress(global);
  std::optional<ProjectDatabase> db;
  if (!db_path.empty()) db.emplace(ProjectDatabase::create(db_path));
  PlantSummary summary;
  try {
    summary = generatePlant(options, sink, db ? &*db : nullptr, progress.get());
    if (db) db->commit();
    tws.finish();
    if (mesh_writer) mesh_writer->finish();
  } catch (...) {
    // Writers drop their temporary files on destruction; the database has no such step.
    db.reset();
    if (!db_path.empty()) {
      std::error_code ec;
      std::filesystem::remove(db_path, ec);
    }
    throw;
  }
  double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  std::printf("plant: seed %llu, target %llu equivalent triangles at %.4g m tolerance\n",
              static_cast<unsigned long long>(o.seed),
              static_cast<unsigned long long>(options.target_triangles), o.tolerance);
  std::printf("  objects      %llu (%llu parametric, %llu mesh, %llu NURBS with %llu patches)\n",
              static_cast<unsigned long long>(summary.objects),
              static_cast<unsigned long long>(summary.primitive_objects),
              static_cast<unsigned long long>(summary.mesh_objects),
              static_cast<unsigned long long>(summary.nurbs_objects),
              static_cast<unsigned long long>(summary.nurbs_patches));
  std::printf("  triangles    %llu equivalent (%llu in meshes; %llu with NURBS counted per patch, "
              "as the target)\n",
              static_cast<unsigned long long>(summary.triangles),
              static_cast<unsigned long long>(summary.mesh_triangles),
              static_cast<unsigned long long>(summary.budget_triangles));
  std::printf("  layers       %llu\n  modules      %llu on %llu hulls\n  records      %llu\n",
              static_cast<unsigned long long>(summary.layers),
              static_cast<unsigned long long>(summary.modules),
              static_cast<unsigned long long>(summary.hulls),
              static_cast<unsigned long long>(summary.db_records));
  std::vector<std::filesystem::path> files = {tws_path};
  if (!db_path.empty()) files.push_back(db_path);
  if (!o.mesh.empty()) files.push_back(o.mesh);
  for (const auto& f : files) {
    std::error_code ec;
    uint64_t size = std::filesystem::file_size(f, ec);
    std::printf("  wrote        %s (%s)\n", f.string().c_str(), ec ? "?" : formatBytes(size).c_str());
  }
  std::printf("  time         %.2f s\n", seconds);
}

}  // namespace

void registerGenCommand(CLI::App& app, const GlobalOptions& global) {
  CLI::App* gen = app.add_subcommand("gen", "Generate synthetic benchmark scenes");
  gen->require_subcommand(1);
  gen->fallthrough();  // global flags such as --quiet may follow the verb
  CLI::App* plant = gen->add_subcommand(
      "plant", "Generate a procedural offshore plant (.tws + SQLite project database)");
  plant->fallthrough();
  auto o = std::make_shared<GenPlantOptions>();
  plant->add_option("--triangles", o->triangles,
                    "Size in equivalent triangles; suffixes K, M, G (default 1M)");
  plant->add_option("--seed", o->seed, "Random seed: same seed, same plant (default 1)");
  plant->add_option("--tolerance", o->tolerance,
                    "Chordal tolerance in metres for counting and tessellating (default 0.002)");
  plant->add_option("-o,--output", o->output, "Scene file to write (default plant.tws)");
  plant->add_option("--db", o->db, "Project database to write (default: output with .db)");
  plant->add_flag("--no-db", o->no_db, "Write no project database");
  plant->add_option("--mesh", o->mesh, "Also write the tessellated scene as FILE.ply or FILE.obj");
  plant->callback([o, &global]() { runGenPlant(*o, global); });
}

}  // namespace tw
