// `terawalk pick model.twk --eye X,Y,Z --target X,Y,Z --pixel x,y`: what the viewer's click
// shows, headless, for scripts and tests. Renders the view until the cut settles (no page
// missing, no ancestor drawn instead), picks the pixel (object_pick.h) and prints the object's
// index, id, name, layer and database key, the picked point in world metres (full double
// precision), and the project database's record and properties for its key (--db).
#include <cstdio>
#include <optional>
#include <stdexcept>
#include <string>

#include <nlohmann/json.hpp>

#include "command.h"
#include "command_args.h"
#include "egl_context.h"
#include "frame_loop.h"
#include "object_pick.h"
#include "package_database.h"
#include "project_database.h"
#include "snapshot_camera.h"

namespace tw {
namespace {

struct PickArgs {
  std::string file;
  std::string eye, target;
  double fov_deg = 60.0;
  std::string size = "1280x720";
  std::string pixel;
  std::string db;
  bool json = false;
};

void parsePixel(const std::string& text, int& x, int& y) {
  char extra = 0;
  if (std::sscanf(text.c_str(), "%d,%d%c", &x, &y, &extra) != 2)
    throw std::runtime_error("--pixel: expected x,y (image pixels from the top left), got '" +
                             text + "'");
}

nlohmann::json recordJson(const ProjectRecord& r) {
  return {{"db_key", r.db_key},
          {"type", r.type},
          {"line_number", r.line_number},
          {"service", r.service},
          {"material", r.material},
          {"nominal_diameter_mm", r.nominal_diameter_mm},
          {"design_pressure_bar", r.design_pressure_bar},
          {"design_temperature_c", r.design_temperature_c},
          {"description", r.description}};
}

// The picked object and what the database says of it.
nlohmann::json describe(const PackageView& view, const Pick& pick,
                        const std::optional<ProjectDatabase>& db) {
  const pkg::ObjectRecord& o = view.objects()[pick.object];
  const std::string key(view.objectDbKey(pick.object));
  nlohmann::json j = {{"object", pick.object},
                      {"id", o.id},
                      {"name", std::string(view.objectName(pick.object))},
                      {"layer", std::string(view.layerName(o.layer))},
                      {"db_key", key},
                      {"point", {pick.world.x, pick.world.y, pick.world.z}},
                      {"distance_m", pick.distance_m}};
  if (db && !key.empty()) {
    const std::optional<ProjectRecord> record = db->find(key);
    j["record"] = record ? recordJson(*record) : nlohmann::json(nullptr);
    nlohmann::json properties = nlohmann::json::array();
    for (const ProjectProperty& p : db->properties(key))
      properties.push_back({{"set", p.set}, {"name", p.name}, {"value", p.value}, {"unit", p.unit}});
    j["properties"] = properties;
  }
  return j;
}

void printText(const nlohmann::json& j) {
  std::printf("object      %llu (id %llu) %s\n", j["object"].get<unsigned long long>(),
              j["id"].get<unsigned long long>(), j["name"].get<std::string>().c_str());
  std::printf("layer       %s\n", j["layer"].get<std::string>().c_str());
  std::printf("db key      %s\n", j["db_key"].get<std::string>().c_str());
  std::printf("point       %.17g %.17g %.17g  (%.3f m from the eye)\n", j["point"][0].get<double>(),
              j["point"][1].get<double>(), j["point"][2].get<double>(),
              j["distance_m"].get<double>());
  if (j.contains("record")) {
    if (j["record"].is_null()) {
      std::printf("record      none for this key\n");
    } else {
      for (const auto& [name, value] : j["record"].items())
        std::printf("  %-22s %s\n", name.c_str(),
                    value.is_string() ? value.get<std::string>().c_str() : value.dump().c_str());
    }
    for (const auto& p : j["properties"])
      std::printf("  %s / %s = %s %s\n", p["set"].get<std::string>().c_str(),
                  p["name"].get<std::string>().c_str(), p["value"].get<std::string>().c_str(),
                  p["unit"].get<std::string>().c_str());
  }
}

void runPick(const PickArgs& args) {
  int width = 0, height = 0, x = 0, y = 0;
  parseImageSize(args.size, "--size", width, height);
  parsePixel(args.pixel, x, y);
  if (!(args.fov_deg > 1.0 && args.fov_deg < 179.0))
    throw std::runtime_error("--fov: expected degrees between 1 and 179");
  Camera camera;
  camera.position = parseVec3(args.eye);
  camera.fov_y_rad = glm::radians(args.fov_deg);
  camera.lookAt(parseVec3(args.target));
  EglContext context;
  WalkthroughOptions options;
  options.width = width;
  options.height = height;
  options.prefetch = false;
  Walkthrough walk(args.file, options);
  const std::optional<ProjectDatabase> db = openPackageDatabase(args.file, walk.package(), args.db);
  const double diagonal = glm::length(walk.worldMax() - walk.worldMin());
  camera.far_m = std::max(100.0, 10.0 * diagonal + glm::length(camera.position - walk.worldMin()));
  walk.renderSettled(camera);  // the pick reads the settled frame
  const std::optional<Pick> pick = pickPixel(walk.renderer(), camera, x, y);
  if (!pick) {
    if (args.json) std::printf("%s\n", nlohmann::json{{"object", nullptr}}.dump(1).c_str());
    else std::printf("nothing at pixel %d,%d\n", x, y);
    return;
  }
  const nlohmann::json j = describe(walk.package(), *pick, db);
  if (args.json) std::printf("%s\n", j.dump(1).c_str());
  else printText(j);
}

}  // namespace

void registerPickCommand(CLI::App& app, const GlobalOptions&) {
  auto args = std::make_shared<PickArgs>();
  CLI::App* cmd = app.add_subcommand("pick", "Which object a pixel of a view shows, and its record");
  cmd->add_option("file", args->file, "Package (.twk)")->required()->check(CLI::ExistingFile);
  cmd->add_option("--eye", args->eye, "Camera position x,y,z (world metres)")->required();
  cmd->add_option("--target", args->target, "Point at the image centre x,y,z")->required();
  cmd->add_option("--fov", args->fov_deg, "Vertical field of view, degrees (default 60)");
  cmd->add_option("--size", args->size, "Image size WIDTHxHEIGHT (default 1280x720)");
  cmd->add_option("--pixel", args->pixel, "The pixel x,y, from the image's top left")->required();
  cmd->add_option("--db", args->db,
                  "Project database (SQLite) for the object's record; default: the one the "
                  "package names")
      ->check(CLI::ExistingFile);
  cmd->add_flag("--json", args->json, "Print JSON");
  cmd->callback([args] { runPick(*args); });
}

}  // namespace tw
