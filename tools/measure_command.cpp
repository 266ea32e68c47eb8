// `terawalk measure model.twk`: what the viewer's measure tool shows, headless. Between two
// points (the distance and its X, Y, Z parts), the angle at a vertex from three points, or the
// minimum distance between two objects named by their database keys, on their full-resolution
// geometry, with the two closest points (docs/review.md).
#include <cstdio>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "change_set_view.h"
#include "command.h"
#include "object_distance.h"
#include "object_queries.h"
#include "package_view.h"
#include "snapshot_camera.h"

namespace tw {
namespace {

struct MeasureArgs {
  std::string file;
  std::vector<std::string> between, points, angle;
  bool centre_lines = false;
  std::string changes;  // a change set: moved objects measured where they were moved
  double tolerance_m = 0.0;
  bool json = false;
};

nlohmann::json pointJson(const glm::dvec3& p) { return {p.x, p.y, p.z}; }

// The objects with database key `key` (an IFC product's mesh and primitives share one), else
// those named `key` (mesh files carry names only), or an error naming the key and the package.
std::vector<uint32_t> objectsOfKey(const PackageView& view, const std::string& key) {
  std::vector<uint32_t> objects = objectsWithKeys(view, {key});
  if (objects.empty())
    for (uint32_t o = 0; o < view.objects().size(); ++o)
      if (view.objectName(o) == key) objects.push_back(o);
  if (objects.empty())
    throw std::runtime_error(view.fileName() + ": no object has the database key or name '" +
                             key + "'");
  return objects;
}

nlohmann::json measureBetween(const MeasureArgs& args) {
  const PackageView view = PackageView::open(args.file);
  const std::vector<uint32_t> a = objectsOfKey(view, args.between[0]);
  const std::vector<uint32_t> b = objectsOfKey(view, args.between[1]);
  // Parametrics tessellated a millionth of the model's size inside their surfaces (at least a
  // micrometre), unless --tolerance says otherwise.
  const auto& h = view.header();
  const double diagonal = glm::length(glm::dvec3(h.bounds_max[0] - h.bounds_min[0],
                                                 h.bounds_max[1] - h.bounds_min[1],
                                                 h.bounds_max[2] - h.bounds_min[2]));
  const double tolerance = args.tolerance_m > 0.0 ? args.tolerance_m : std::max(1e-6, 1e-6 * diagonal);
  const ChangeSet changes = args.changes.empty() ? ChangeSet() : readChangeSet(args.changes);
  const MeasureShape shape_a =
      movedShape(view, measureShape(view, a, tolerance), changes.placement(args.between[0]));
  const MeasureShape shape_b =
      movedShape(view, measureShape(view, b, tolerance), changes.placement(args.between[1]));
  const MeasuredDistance d = args.centre_lines ? centreLineDistance(view, shape_a, shape_b)
                                               : minimumDistance(view, shape_a, shape_b);
  const glm::dvec3 delta = d.points.b - d.points.a;
  return {{"between", args.between},
          {"method", d.method},
          {"distance_m", d.points.distance},
          {"error_bound_m", d.error_bound_m},
          {"delta_m", pointJson(delta)},
          {"point_a", pointJson(d.points.a)},
          {"point_b", pointJson(d.points.b)},
          {"triangles", {shape_a.triangles.size(), shape_b.triangles.size()}}};
}

nlohmann::json measurePoints(const MeasureArgs& args) {
  const glm::dvec3 a = parseVec3(args.points[0]), b = parseVec3(args.points[1]);
  return {{"distance_m", glm::length(b - a)}, {"delta_m", pointJson(b - a)}};
}

nlohmann::json measureAngle(const MeasureArgs& args) {
  const glm::dvec3 a = parseVec3(args.angle[0]), vertex = parseVec3(args.angle[1]),
                   c = parseVec3(args.angle[2]);
  const glm::dvec3 u = a - vertex, v = c - vertex;
  if (!(glm::length(u) > 0.0 && glm::length(v) > 0.0))
    throw std::runtime_error("--angle: the first and last points must differ from the vertex");
  const double radians = std::atan2(glm::length(glm::cross(u, v)), glm::dot(u, v));
  return {{"angle_deg", radians * 180.0 / std::numbers::pi}};
}

void printText(const nlohmann::json& j) {
  if (j.contains("angle_deg")) {
    std::printf("angle %.6f degrees\n", j["angle_deg"].get<double>());
    return;
  }
  const auto& d = j["delta_m"];
  std::printf("distance %.9g m (dx %.9g, dy %.9g, dz %.9g)\n", j["distance_m"].get<double>(),
              d[0].get<double>(), d[1].get<double>(), d[2].get<double>());
  if (!j.contains("method")) return;
  std::printf("method   %s, within %.3g m\n", j["method"].get<std::string>().c_str(),
              j["error_bound_m"].get<double>());
  for (const char* side : {"point_a", "point_b"}) {
    const auto& p = j[side];
    std::printf("%s  %.17g, %.17g, %.17g\n", side, p[0].get<double>(), p[1].get<double>(),
                p[2].get<double>());
  }
}

void runMeasure(const MeasureArgs& args) {
  const int modes = int(!args.between.empty()) + int(!args.points.empty()) + int(!args.angle.empty());
  if (modes != 1)
    throw std::runtime_error("give exactly one of --between KEY_A KEY_B, --points A B, --angle A B C");
  if (args.centre_lines && args.between.empty())
    throw std::runtime_error("--centre-lines goes with --between");
  const nlohmann::json j = !args.between.empty() ? measureBetween(args)
                           : !args.points.empty() ? measurePoints(args)
                                                  : measureAngle(args);
  if (args.json) std::printf("%s\n", j.dump(1).c_str());
  else printText(j);
}

}  // namespace

void registerMeasureCommand(CLI::App& app, const GlobalOptions&) {
  auto args = std::make_shared<MeasureArgs>();
  CLI::App* cmd = app.add_subcommand(
      "measure", "Distances and angles: between points, or the minimum distance between objects");
  cmd->add_option("file", args->file, "Package (.twk)")->required()->check(CLI::ExistingFile);
  cmd->add_option("--between", args->between,
                  "Two database keys: the minimum distance between their objects, on their "
                  "full-resolution geometry, with the closest points")
      ->expected(2);
  cmd->add_option("--points", args->points, "Two points x,y,z (world metres): their distance")
      ->expected(2);
  cmd->add_option("--angle", args->angle, "Three points x,y,z: the angle at the second, degrees")
      ->expected(3);
  cmd->add_flag("--centre-lines", args->centre_lines,
                "With --between: the distance between the objects' cylinder axes instead");
  cmd->add_option("--tolerance", args->tolerance_m,
                  "Metres: how far inside their surfaces parametrics are tessellated for "
                  "measuring (default a millionth of the model's size, at least 1 um)");
  cmd->add_option("--changes", args->changes,
                  "With --between: a review's change set (model.changes.json); moved objects are "
                  "measured where they were moved")
      ->check(CLI::ExistingFile);
  cmd->add_flag("--json", args->json, "Print JSON");
  cmd->callback([args] { runMeasure(*args); });
}

}  // namespace tw
