// `terawalk bench`: the end-to-end benchmark suite. Generates plants of several sizes (cached
// between runs), preprocesses each one, replays the standard camera paths in every runtime mode,
// measures fidelity against the brute-force reference, and writes results.json, report.md, gnuplot
// plots and sample frames (docs/bench.md). Every run is a child process of
// this executable (child_process.h), so each figure belongs to one run alone.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "bench_report.h"
#include "child_process.h"
#include "command.h"
#include "command_args.h"

namespace tw {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

struct BenchOptions {
  bool quick = false;
  std::string sizes;  // empty: by --quick
  std::string out_dir = "bench-report";
  std::string cache_dir;  // empty: $XDG_CACHE_HOME/terawalk/bench or ~/.cache/terawalk/bench
  std::string paths_dir;  // empty: data/paths found from here or from the executable
  std::string image_size;
  double fps = 0.0;
  double walk_fps = -1.0;  // negative: by --quick
  int runs = 0;
  int orbit_frames = 0;
  std::string compare;
  std::string report_only;  // a saved results.json: only write its report (and --compare)
  bool keep_frames = false;
  bool ocean = false, sky = false;  // the setting, in every render run (docs/presentation.md)
  double waterline_m = -10.0;       // the generated plant's hull draws 10 m
};

// A runtime mode of the suite: its name in results.json, its `terawalk render` flags, and
// whether it walks the paths inside the plant between recorded frames (`--walk-fps`): the modes
// that occlusion compares and the default do; the reference keeps no state from frame to frame,
// and LOD alone is a yardstick only its paging would see walking.
struct Mode {
  const char* name;
  std::vector<std::string> flags;
  bool walks;
};

// The paths walked between recorded frames: the walks inside the plant (the orbit's recorded
// frames are a few degrees apart already).
const std::vector<std::string> kWalkPaths = {"decks", "rack"};

const std::vector<Mode>& modes() {
  static const std::vector<Mode> kModes = {
      {"reference", {"--reference"}, false},
      {"lod", {"--occlusion", "off", "--no-frustum", "--no-prefetch"}, false},
      {"lod_frustum", {"--occlusion", "off", "--no-prefetch"}, true},
      {"lod_frustum_occlusion", {"--occlusion", "hzb", "--no-prefetch"}, true},
      {"default", {}, true},
  };
  return kModes;
}

// "10M" -> 10000000 (K, M, G, decimal).
uint64_t parseCount(const std::string& text) {
  size_t used = 0;
  double value = 0.0;
  try {
    value = std::stod(text, &used);
  } catch (const std::exception&) {
    throw std::runtime_error("--sizes: expected counts such as 1M,10M,50M, got '" + text + "'");
  }
  std::string suffix = text.substr(used);
  double scale = 1.0;
  if (suffix == "K" || suffix == "k") scale = 1e3;
  else if (suffix == "M" || suffix == "m") scale = 1e6;
  else if (suffix == "G" || suffix == "g") scale = 1e9;
  else if (!suffix.empty())
    throw std::runtime_error("--sizes: unknown suffix in '" + text + "'");
  if (!(value > 0.0)) throw std::runtime_error("--sizes: '" + text + "' is not positive");
  return uint64_t(std::llround(value * scale));
}

std::vector<std::string> splitList(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream in(text);
  for (std::string item; std::getline(in, item, ',');)
    if (!item.empty()) out.push_back(item);
  return out;
}

fs::path defaultCacheDir() {
  if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg && *xdg)
    return fs::path(xdg) / "terawalk" / "bench";
  if (const char* home = std::getenv("HOME"); home && *home)
    return fs::path(home) / ".cache" / "terawalk" / "bench";
  return fs::temp_directory_path() / "terawalk-bench-cache";
}

fs::path findPathsDir(const std::string& given) {
  if (!given.empty()) {
    if (!fs::is_directory(given)) throw std::runtime_error(given + ": not a directory");
    return given;
  }
  std::vector<fs::path> tries = {fs::current_path() / "data" / "paths"};
  for (fs::path p = selfExecutable().parent_path(); !p.empty() && p != p.root_path();
       p = p.parent_path())
    tries.push_back(p / "data" / "paths");
  for (const fs::path& p : tries)
    if (fs::exists(p / "plant-decks.path")) return p;
  throw std::runtime_error(
      "cannot find data/paths (plant-decks.path); run from the source tree or pass --paths DIR");
}

std::string readText(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

json readJson(const fs::path& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path.string() + ": cannot read");
  try {
    return json::parse(in);
  } catch (const json::exception& e) {
    throw std::runtime_error(path.string() + ": " + e.what());
  }
}

// Runs a verb of this executable; throws with the log's tail when it fails.
ChildResult runVerb(const std::vector<std::string>& args, const fs::path& log) {
  std::vector<std::string> argv = {selfExecutable().string()};
  argv.insert(argv.end(), args.begin(), args.end());
  ChildResult r = runChild(argv, log);
  if (r.exit_code != 0) {
    std::string text = readText(log);
    if (text.size() > 2000) text = "..." + text.substr(text.size() - 2000);
    std::string command;
    for (const std::string& a : args) command += " " + a;
    throw std::runtime_error("terawalk" + command + " failed (exit " +
                             std::to_string(r.exit_code) + "), log " + log.string() + ":\n" + text);
  }
  return r;
}

// The preprocess summary printed by `terawalk preprocess`: stage seconds, input triangles and
// package bytes per input triangle (docs/preprocess.md).
json parsePreprocessLog(const std::string& text) {
  json out = {{"stages_s", json::object()}};
  static const std::regex kStage(R"(^  ([a-z][a-z ]*[a-z])\s+([0-9.]+) s(,|$))");
  static const std::regex kInput(R"(^  input\s+([0-9]+) triangles, ([0-9]+) parametric)");
  static const std::regex kPackage(R"(^  package\s+([0-9]+) bytes, ([0-9.]+) bytes per input)");
  static const std::regex kLevels(R"(^  levels\s+([0-9]+):)");
  std::stringstream in(text);
  for (std::string line; std::getline(in, line);) {
    std::smatch m;
    if (std::regex_search(line, m, kInput)) {
      out["input_triangles"] = std::stoull(m[1]);
      out["parametric_instances"] = std::stoull(m[2]);
    } else if (std::regex_search(line, m, kPackage)) {
      out["package_bytes"] = std::stoull(m[1]);
      out["bytes_per_input_triangle"] = std::stod(m[2]);
    } else if (std::regex_search(line, m, kLevels)) {
      out["levels"] = std::stoi(m[1]);
    } else if (std::regex_search(line, m, kStage)) {
      const std::string stage = m[1];
      if (stage == "total") continue;
      out["stages_s"][stage] = std::stod(m[2]);
    }
  }
  return out;
}

// Frame times (ms) and triangles of a render's frames.json.
json frameSeries(const fs::path& frames_json) {
  const json frames = readJson(frames_json).at("frames");
  json ms = json::array(), tris = json::array();
  for (const json& f : frames) {
    ms.push_back(f.value("frame_ms", 0.0));
    tris.push_back(f.value("triangles_drawn", 0ull));
  }
  return {{"frame_ms", ms}, {"triangles", tris}};
}

std::string machineCpu() {
  std::ifstream in("/proc/cpuinfo");
  for (std::string line; std::getline(in, line);)
    if (line.rfind("model name", 0) == 0) {
      const size_t colon = line.find(':');
      if (colon != std::string::npos) return line.substr(colon + 2);
    }
  return "unknown";
}

uint64_t machineMemoryBytes() {
  std::ifstream in("/proc/meminfo");
  std::string key;
  uint64_t kib = 0;
  if (in >> key >> kib && key == "MemTotal:") return kib * 1024;
  return 0;
}

std::string gitCommit(const fs::path& source_dir) {
  const std::string command = "git -C '" + source_dir.string() + "' rev-parse HEAD 2>/dev/null";
  std::FILE* pipe = ::popen(command.c_str(), "r");
  if (!pipe) return "unknown";
  char buffer[64] = {};
  std::string out;
  if (std::fgets(buffer, sizeof(buffer), pipe)) out = buffer;
  ::pclose(pipe);
  while (!out.empty() && (out.back() == '\n' || out.back() == ' ')) out.pop_back();
  return out.size() == 40 ? out : "unknown";
}

std::string utcNow() {
  const std::time_t now = std::time(nullptr);
  char text[32];
  std::strftime(text, sizeof(text), "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&now));
  return text;
}

double medianOf(std::vector<double> v) {
  if (v.empty()) return std::nan("");
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// A bench run's resolved configuration: the options with the defaults of the mode filled in.
struct BenchPlan {
  std::vector<std::string> size_names;
  std::vector<uint64_t> sizes;
  int runs = 3;
  double fps = 2.0;
  double walk_fps = 10.0;
  int orbit_frames = 120;
  std::string size_text;
  fs::path out_dir, work, cache, paths_dir;
  bool keep_frames = false;
  bool quiet = false;
  std::vector<std::string> setting;  // --ocean, --sky and the waterline, for every render run

  void say(const std::string& text) const {
    if (!quiet) std::fprintf(stderr, "bench: %s\n", text.c_str());
  }
};

BenchPlan planBench(const BenchOptions& o, const GlobalOptions& global) {
  BenchPlan plan;
  plan.size_names = splitList(!o.sizes.empty() ? o.sizes : (o.quick ? "100K,300K" : "1M,10M,50M"));
  for (const std::string& s : plan.size_names) plan.sizes.push_back(parseCount(s));
  plan.runs = o.runs > 0 ? o.runs : (o.quick ? 1 : 3);
  plan.fps = o.fps > 0.0 ? o.fps : (o.quick ? 0.2 : 2.0);
  plan.walk_fps = o.walk_fps >= 0.0 ? o.walk_fps : (o.quick ? 0.0 : 10.0);
  plan.orbit_frames = o.orbit_frames > 0 ? o.orbit_frames : (o.quick ? 8 : 120);
  if (o.ocean) plan.setting.push_back("--ocean");
  if (o.sky) plan.setting.push_back("--sky");
  if (o.ocean || o.sky) {
    char waterline[32];
    std::snprintf(waterline, sizeof waterline, "%.17g", o.waterline_m);
    plan.setting.insert(plan.setting.end(), {"--waterline", waterline});
  }
  int width = o.quick ? 320 : 1280, height = o.quick ? 180 : 720;
  if (!o.image_size.empty()) parseImageSize(o.image_size, "--size", width, height);
  plan.size_text = std::to_string(width) + "x" + std::to_string(height);
  plan.out_dir = o.out_dir;
  plan.work = plan.out_dir / "work";
  plan.cache = o.cache_dir.empty() ? defaultCacheDir() : fs::path(o.cache_dir);
  plan.paths_dir = findPathsDir(o.paths_dir);
  plan.keep_frames = o.keep_frames;
  plan.quiet = global.quiet;
  fs::create_directories(plan.work);
  fs::create_directories(plan.cache);
  fs::create_directories(plan.out_dir / "samples");
  return plan;
}

json resultsHeader(const BenchPlan& plan, const BenchOptions& o) {
  const auto& size_names = plan.size_names;
  const int runs = plan.runs;
  const double fps = plan.fps, walk_fps = plan.walk_fps;
  const int orbit_frames = plan.orbit_frames;
  const std::string& size_text = plan.size_text;
  const fs::path& paths_dir = plan.paths_dir;
  json results = {
      {"schema", "terawalk-bench-1"},
      {"started_utc", utcNow()},
      {"commit", gitCommit(paths_dir.parent_path().parent_path())},
      {"machine",
       {{"cpu", machineCpu()},
        {"cores", std::thread::hardware_concurrency()},
        {"memory_bytes", machineMemoryBytes()}}},
      {"configuration",
       {{"quick", o.quick},
        {"sizes", size_names},
        {"runs", runs},
        {"fps", fps},
        {"walk_fps", walk_fps},
        {"walk_paths", kWalkPaths},
        {"walk_modes", json::array()},
        {"image_size", size_text},
        {"orbit_frames", orbit_frames},
        {"setting", plan.setting},
        {"modes", json::array()},
        {"paths", {"decks", "rack", "orbit"}}}},
      {"models", json::array()}};
  for (const Mode& m : modes()) {
    results["configuration"]["modes"].push_back(m.name);
    if (m.walks) results["configuration"]["walk_modes"].push_back(m.name);
  }

  return results;
}

// 1. The plant, cached by size and seed.
fs::path cachedPlant(const BenchPlan& plan, const std::string& name) {
  const fs::path tws = plan.cache / ("plant-" + name + ".tws");
  if (!fs::exists(tws)) {
    plan.say("generating the " + name + " plant");
    const fs::path partial = plan.cache / ("plant-" + name + ".partial.tws");
    runVerb({"-q", "gen", "plant", "--triangles", name, "--seed", "1", "--no-db", "-o",
             partial.string()},
            plan.work / ("gen-" + name + ".log"));
    fs::rename(partial, tws);
  }
  return tws;
}

// 2. Preprocess, measured: the child's wall time, CPU time and peak RSS, and its own summary.
json preprocessPlant(const BenchPlan& plan, const std::string& name, const fs::path& tws,
                     const fs::path& twk) {
  plan.say("preprocessing the " + name + " plant");
  const fs::path pre_log = plan.work / ("preprocess-" + name + ".log");
  ChildResult pre = runVerb({"preprocess", tws.string(), "-o", twk.string()}, pre_log);
  json prep = parsePreprocessLog(readText(pre_log));
  prep["wall_s"] = pre.wall_s;
  prep["cpu_s"] = pre.user_s + pre.system_s;
  prep["peak_rss_bytes"] = pre.peak_rss_bytes;
  const double input = prep.value("input_triangles", 0.0);
  prep["input_triangles_per_s"] = pre.wall_s > 0 ? input / pre.wall_s : 0.0;
  return prep;
}

// 3. Every mode along one path, the modes alternating run after run; each run's summary.
std::map<std::string, std::vector<json>> renderModes(const BenchPlan& plan, const std::string& name,
                                                     const fs::path& twk,
                                                     const std::string& path_name,
                                                     const fs::path& path_file, json& per_mode) {
  const int runs = plan.runs;
  const double fps = plan.fps, walk_fps = plan.walk_fps;
  const std::string& size_text = plan.size_text;
  std::map<std::string, std::vector<json>> summaries;
  for (int run = 1; run <= runs; ++run) {
    for (const Mode& mode : modes()) {
      plan.say(name + " " + path_name + " " + mode.name + " run " + std::to_string(run));
      const fs::path dir =
          plan.work / name / path_name / (std::string(mode.name) + "-" + std::to_string(run));
      fs::remove_all(dir);
      fs::create_directories(dir.parent_path());
      std::vector<std::string> args = {"-q",     "render", twk.string(), "--path",
                                       path_file.string(), "--fps", std::to_string(fps),
                                       "--size", size_text, "--out", dir.string()};
      args.insert(args.end(), mode.flags.begin(), mode.flags.end());
      args.insert(args.end(), plan.setting.begin(), plan.setting.end());
      // As an interactive walkthrough moves between recorded frames.
      const bool walked_path =
          std::find(kWalkPaths.begin(), kWalkPaths.end(), path_name) != kWalkPaths.end();
      if (mode.walks && walk_fps > fps && walked_path) {
        args.push_back("--walk-fps");
        args.push_back(std::to_string(walk_fps));
      }
      // The first run also keeps frames for fidelity and measures occlusion's pixel loss.
      if (run == 1) {
        args.push_back("--png");
        if (std::string(mode.name).find("occlusion") != std::string::npos ||
            std::string(mode.name) == "default")
          args.push_back("--check-occlusion");
      }
      runVerb(args, dir.string() + ".log");
      summaries[mode.name].push_back(readJson(dir / "summary.json"));
      if (run == 1) per_mode[mode.name]["series"] = frameSeries(dir / "frames.json");
    }
  }
  return summaries;
}

// Medians over the runs, and 4. fidelity against the reference frames of the first run.
void summarizeModes(const BenchPlan& plan, const std::string& name, const std::string& path_name,
                    const std::map<std::string, std::vector<json>>& summaries, json& per_mode,
                    json& results) {
  const fs::path& work = plan.work;
  for (const Mode& mode : modes()) {
    json& m = per_mode[mode.name];
    const auto& rows = summaries.at(mode.name);
    for (const char* key : {"median_frame_ms", "median_gpu_ms", "median_triangles",
                            "median_all_triangles", "first_frame_ms", "peak_rss_bytes",
                            "median_cpu_cut_ms"}) {
      std::vector<double> values;
      for (const json& r : rows)
        if (r.contains(key) && r[key].is_number()) values.push_back(r[key].get<double>());
      m[key] = medianOf(values);
      m[std::string(key) + "_runs"] = values;
    }
    m["frames"] = rows.front().value("frames", 0);
    m["walk_frames"] = rows.front().value("walk_frames", 0);
    if (rows.front().contains("occlusion_lost_share"))
      m["occlusion_lost_share"] = rows.front()["occlusion_lost_share"];
    if (!results["machine"].contains("renderer") && rows.front().contains("renderer"))
      results["machine"]["renderer"] = rows.front()["renderer"];
    // 4. Fidelity against the reference frames of the first run.
    if (std::string(mode.name) == "reference") continue;
    const fs::path ref_dir = work / name / path_name / "reference-1";
    const fs::path mode_dir = work / name / path_name / (std::string(mode.name) + "-1");
    const fs::path diff_dir = work / name / path_name / (std::string(mode.name) + "-diff");
    const fs::path compare_log = diff_dir.string() + ".json";
    runVerb({"-q", "compare", ref_dir.string(), mode_dir.string(), "--out", diff_dir.string(),
             "--json"},
            compare_log);
    const json cmp = readJson(compare_log);
    m["fidelity"] = cmp.contains("summary") ? cmp["summary"] : cmp;
  }
}

// 5. Sample frames of the largest model: reference, default and their diff, side by side.
void copySamples(const BenchPlan& plan, const std::string& name, const std::string& path_name,
                 const json& per_mode) {
  const fs::path& work = plan.work;
  const fs::path& out_dir = plan.out_dir;
  const fs::path ref_dir = work / name / path_name / "reference-1";
  const int frames = per_mode.at("reference").value("frames", 0);
  for (int k : {frames / 4, frames / 2, (3 * frames) / 4}) {
    char file[32];
    std::snprintf(file, sizeof(file), "%05d.png", k);
    const std::string base = path_name + "-" + file;
    auto copy = [&](const fs::path& from, const std::string& to) {
      if (fs::exists(from))
        fs::copy_file(from, out_dir / "samples" / to, fs::copy_options::overwrite_existing);
    };
    copy(ref_dir / ("frame_" + std::string(file)), "reference-" + base);
    copy(work / name / path_name / "default-1" / ("frame_" + std::string(file)),
         "default-" + base);
    copy(work / name / path_name / "default-diff" / ("diff_" + std::string(file)),
         "diff-" + base);
  }
}

// Frames are large: keep only the samples unless asked.
void removeFrames(const BenchPlan& plan, const std::string& name, const std::string& path_name) {
  if (plan.keep_frames) return;
  for (const auto& entry : fs::directory_iterator(plan.work / name / path_name))
    if (entry.is_directory())
      for (const auto& f : fs::directory_iterator(entry.path()))
        if (f.path().extension() == ".png") fs::remove(f.path());
}

// One plant: generated (or cached), preprocessed, and its three paths rendered in every mode.
json benchModel(const BenchPlan& plan, size_t index, json& results) {
  const std::string& name = plan.size_names[index];
  json model = {{"size", name}, {"target_triangles", plan.sizes[index]}};
  const fs::path tws = cachedPlant(plan, name);
  const fs::path twk = plan.work / ("plant-" + name + ".twk");
  model["preprocess"] = preprocessPlant(plan, name, tws, twk);

  // The two walks from data/paths and an orbit generated around this model. The orbit's keys are
  // spaced for the replay's rate, so the replay renders all orbit_frames of it.
  const fs::path orbit = plan.work / ("orbit-" + name + ".path");
  runVerb({"-q", "render", twk.string(), "--orbit", std::to_string(plan.orbit_frames), "--fps",
           std::to_string(plan.fps), "--save-path", orbit.string(), "--max-frames", "1",
           "--size", "64x36"},
          plan.work / ("orbit-" + name + ".log"));
  const std::vector<std::pair<std::string, fs::path>> paths = {
      {"decks", plan.paths_dir / "plant-decks.path"},
      {"rack", plan.paths_dir / "plant-rack.path"},
      {"orbit", orbit}};
  json path_results = json::object();
  for (const auto& [path_name, path_file] : paths) {
    json per_mode = json::object();
    const auto summaries = renderModes(plan, name, twk, path_name, path_file, per_mode);
    summarizeModes(plan, name, path_name, summaries, per_mode, results);
    path_results[path_name] = per_mode;
    if (index + 1 == plan.sizes.size()) copySamples(plan, name, path_name, per_mode);
    removeFrames(plan, name, path_name);
  }
  model["paths"] = path_results;
  return model;
}

void writeResults(const json& results, const fs::path& out_dir) {
  const fs::path results_file = out_dir / "results.json";
  {
    std::ofstream out(results_file);
    out << results.dump(1) << "\n";
    if (!out) throw std::runtime_error(results_file.string() + ": cannot write");
  }
  writeBenchReport(results, out_dir);
  std::printf("bench: %s and report.md written in %.0f s\n", results_file.string().c_str(),
              results.value("total_s", 0.0));
}

// --report-only: the report (and, with --compare, the ratios) of a saved run.
void reportSavedRun(const BenchOptions& o) {
  const json results = readJson(o.report_only);
  if (!results.contains("models") || !results.contains("configuration"))
    throw std::runtime_error(o.report_only + ": not a terawalk bench results.json");
  fs::create_directories(o.out_dir);
  writeBenchReport(results, o.out_dir);
  if (!o.compare.empty())
    std::printf("%s", compareBenchResults(readJson(o.compare), results).c_str());
}

void runBench(const BenchOptions& o, const GlobalOptions& global) {
  if (!o.report_only.empty()) {
    reportSavedRun(o);
    return;
  }
  const auto started = std::chrono::steady_clock::now();
  const BenchPlan plan = planBench(o, global);
  json results = resultsHeader(plan, o);
  for (size_t i = 0; i < plan.sizes.size(); ++i)
    results["models"].push_back(benchModel(plan, i, results));
  results["total_s"] =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  writeResults(results, plan.out_dir);
  if (!o.compare.empty()) std::printf("%s", compareBenchResults(readJson(o.compare), results).c_str());
}

}  // namespace

void registerBenchCommand(CLI::App& app, const GlobalOptions& global) {
  auto options = std::make_shared<BenchOptions>();
  CLI::App* cmd = app.add_subcommand(
      "bench", "End-to-end benchmark: generate, preprocess, replay paths in every mode, report");
  cmd->add_flag("--quick", options->quick, "Small plants and short paths (a smoke run)");
  cmd->add_option("--sizes", options->sizes,
                  "Plant sizes, comma-separated (default 1M,10M,50M; --quick 100K,300K)");
  cmd->add_option("--out", options->out_dir, "Report directory")->capture_default_str();
  cmd->add_option("--cache", options->cache_dir,
                  "Where generated plants are kept between runs (default ~/.cache/terawalk/bench)");
  cmd->add_option("--paths", options->paths_dir, "Directory of the standard camera paths");
  cmd->add_option("--size", options->image_size, "Image size WIDTHxHEIGHT (default 1280x720)");
  cmd->add_option("--fps", options->fps, "Path sampling rate (default 2; --quick 0.2)");
  cmd->add_option("--walk-fps", options->walk_fps,
                  "Rate at which the modes that keep frame-to-frame state walk the decks and rack "
                  "paths between recorded frames (default 10; --quick 0: no walking)");
  cmd->add_option("--runs", options->runs, "Runs per mode (default 3; --quick 1)");
  cmd->add_option("--orbit-frames", options->orbit_frames, "Frames of the orbit path");
  cmd->add_option("--compare", options->compare,
                  "An earlier results.json: print each figure's ratio to it");
  cmd->add_option("--report-only", options->report_only,
                  "Write the report of a saved results.json without running anything");
  cmd->add_flag("--keep-frames", options->keep_frames, "Keep every rendered PNG under work/");
  cmd->add_flag("--ocean", options->ocean, "Every render run draws the ocean (docs/presentation.md)");
  cmd->add_flag("--sky", options->sky, "Every render run draws the sky");
  cmd->add_option("--waterline", options->waterline_m, "The ocean's still water, world metres")
      ->capture_default_str();
  cmd->callback([options, &global] { runBench(*options, global); });
}

}  // namespace tw
