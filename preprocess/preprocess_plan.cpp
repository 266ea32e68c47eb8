// The manifest of a split preprocessing run; see preprocess_plan.h.
#include "preprocess_plan.h"

#include <cstdio>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

namespace tw {
namespace {

constexpr const char* kPlanFormat = "terawalk preprocess plan";
constexpr int kPlanVersion = 1;

nlohmann::json optionsJson(const PreprocessOptions& o) {
  nlohmann::json inputs = nlohmann::json::array();
  for (const auto& input : o.inputs) inputs.push_back(input.string());
  return {{"inputs", inputs},
          {"exclude_layers", o.exclude_layers},
          {"database", o.database.string()},
          {"memory_budget_bytes", o.memory_budget_bytes},
          {"cluster_size", o.cluster_size},
          {"parametric_cluster_size", o.parametric_cluster_size},
          {"max_brick_triangles", o.max_brick_triangles},
          {"visibility", o.visibility},
          {"visibility_rays", o.visibility_rays},
          {"view_cell_size_m", o.view_cell_size_m},
          {"parametric_occluders", o.parametric_occluders},
          {"up", upAxisName(o.up)},
          {"cad_primitives", o.cad.primitives},
          {"cad_tolerance_m", o.cad.tolerance_m},
          {"cad_conforming_bspline", o.cad.conforming_bspline}};
}

PreprocessOptions optionsFrom(const nlohmann::json& j) {
  PreprocessOptions o;
  for (const auto& input : j.at("inputs")) o.inputs.emplace_back(input.get<std::string>());
  o.exclude_layers = j.at("exclude_layers").get<std::vector<std::string>>();
  o.database = j.at("database").get<std::string>();
  o.memory_budget_bytes = j.at("memory_budget_bytes").get<uint64_t>();
  o.cluster_size = j.at("cluster_size").get<uint32_t>();
  o.parametric_cluster_size = j.at("parametric_cluster_size").get<uint32_t>();
  o.max_brick_triangles = j.at("max_brick_triangles").get<uint64_t>();
  o.visibility = j.at("visibility").get<bool>();
  o.visibility_rays = j.at("visibility_rays").get<uint32_t>();
  o.view_cell_size_m = j.at("view_cell_size_m").get<double>();
  o.parametric_occluders = j.at("parametric_occluders").get<bool>();
  o.up = parseUpAxis(j.at("up").get<std::string>());
  o.cad.primitives = j.at("cad_primitives").get<bool>();
  o.cad.tolerance_m = j.at("cad_tolerance_m").get<double>();
  o.cad.conforming_bspline = j.at("cad_conforming_bspline").get<bool>();
  return o;
}

}  // namespace

std::filesystem::path planPath(const std::filesystem::path& work_dir) {
  return work_dir / "manifest.json";
}

void writePreprocessPlan(const PreprocessPlan& plan, const std::filesystem::path& work_dir) {
  nlohmann::json jobs = nlohmann::json::array();
  for (const BrickJob& job : plan.jobs)
    jobs.push_back({{"index", job.index}, {"triangles", job.triangles}});
  char hash[17];
  std::snprintf(hash, sizeof hash, "%016llx", static_cast<unsigned long long>(plan.run_hash));
  const nlohmann::json manifest = {{"format", kPlanFormat},
                                   {"version", kPlanVersion},
                                   {"run_hash", hash},
                                   {"input_triangles", plan.input_triangles},
                                   {"primitives", plan.primitives},
                                   {"objects", plan.objects},
                                   {"options", optionsJson(plan.options)},
                                   {"bricks", jobs}};
  const std::filesystem::path path = planPath(work_dir);
  const std::filesystem::path temporary = path.string() + ".tmp";
  {
    std::ofstream out(temporary, std::ios::trunc);
    out << manifest.dump(2) << '\n';
    out.flush();
    if (!out) throw std::runtime_error(temporary.string() + ": cannot write the plan");
  }
  std::error_code ec;
  std::filesystem::rename(temporary, path, ec);
  if (ec) throw std::runtime_error(path.string() + ": cannot write the plan: " + ec.message());
}

PreprocessPlan readPreprocessPlan(const std::filesystem::path& work_dir) {
  const std::filesystem::path path = planPath(work_dir);
  std::ifstream in(path);
  if (!in)
    throw std::runtime_error(path.string() +
                             ": no plan here; run `terawalk preprocess plan INPUT... --work " +
                             work_dir.string() + "` first");
  std::stringstream text;
  text << in.rdbuf();
  try {
    const nlohmann::json manifest = nlohmann::json::parse(text.str());
    if (manifest.at("format") != kPlanFormat)
      throw std::runtime_error("not a preprocessing plan");
    if (manifest.at("version") != kPlanVersion)
      throw std::runtime_error("plan version " + manifest.at("version").dump() + ", this terawalk reads " +
                               std::to_string(kPlanVersion));
    PreprocessPlan plan;
    plan.options = optionsFrom(manifest.at("options"));
    plan.options.work_dir = work_dir;
    plan.run_hash = std::stoull(manifest.at("run_hash").get<std::string>(), nullptr, 16);
    plan.input_triangles = manifest.at("input_triangles").get<uint64_t>();
    plan.primitives = manifest.at("primitives").get<uint64_t>();
    plan.objects = manifest.at("objects").get<uint64_t>();
    for (const auto& job : manifest.at("bricks"))
      plan.jobs.push_back({job.at("index").get<uint32_t>(), job.at("triangles").get<uint64_t>()});
    return plan;
  } catch (const std::exception& e) {
    throw std::runtime_error(path.string() + ": " + e.what());
  }
}

}  // namespace tw
