// report.md, gnuplot plots and --compare ratios of `terawalk bench`. See bench_report.h.
#include "bench_report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <map>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "child_process.h"

namespace tw {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

std::string fmt(double value, int decimals = 2) {
  if (!std::isfinite(value)) return "-";
  char text[64];
  std::snprintf(text, sizeof(text), "%.*f", decimals, value);
  return text;
}

double num(const json& j, const char* key) {
  return j.contains(key) && j[key].is_number() ? j[key].get<double>() : std::nan("");
}

// Triangles a mode drew per frame: mesh clusters and parametric meshes together; results written
// before that figure existed have the mesh clusters' alone, marked so.
std::string triangles(const json& r) {
  const double all = num(r, "median_all_triangles");
  if (std::isfinite(all)) return fmt(all, 0);
  return fmt(num(r, "median_triangles"), 0) + " (mesh)";
}

void writeFile(const fs::path& path, const std::string& text) {
  std::ofstream out(path);
  out << text;
  if (!out) throw std::runtime_error(path.string() + ": cannot write");
}

// gnuplot on PATH, or empty.
fs::path findGnuplot() {
  const char* path = std::getenv("PATH");
  std::stringstream dirs(path ? path : "/usr/bin:/bin");
  for (std::string dir; std::getline(dirs, dir, ':');)
    if (!dir.empty() && fs::exists(fs::path(dir) / "gnuplot")) return fs::path(dir) / "gnuplot";
  return {};
}

const char* kModeTitles[][2] = {{"reference", "reference (brute force)"},
                                {"lod", "LOD only"},
                                {"lod_frustum", "LOD + frustum"},
                                {"lod_frustum_occlusion", "LOD + frustum + occlusion"},
                                {"default", "full default"}};

std::string quoteGp(const std::string& text) { return "'" + text + "'"; }

// Renders one gnuplot script; returns the PNG's name, or empty when gnuplot failed.
std::string plot(const fs::path& gnuplot, const fs::path& dir, const std::string& name,
                 const std::string& script) {
  const fs::path gp = dir / (name + ".gp");
  writeFile(gp, "set terminal pngcairo size 900,520 noenhanced\nset output " +
                    quoteGp((dir / (name + ".png")).string()) + "\nset grid\nset key outside\n" +
                    script);
  // pngcairo may be missing from gnuplot-nox builds: fall back to the plain png terminal.
  ChildResult r = runChild({gnuplot.string(), gp.string()}, dir / (name + ".log"));
  if (r.exit_code != 0) {
    std::ifstream in(gp);
    std::stringstream text;
    text << in.rdbuf();
    std::string s = text.str();
    s.replace(s.find("pngcairo"), 8, "png");
    writeFile(gp, s);
    r = runChild({gnuplot.string(), gp.string()}, dir / (name + ".log"));
  }
  return r.exit_code == 0 && fs::exists(dir / (name + ".png")) ? name + ".png" : std::string();
}

// The run: when, where, on which machine, and with which configuration.
void writeRunHeader(std::ostringstream& md, const json& results) {
  const json& config = results.at("configuration");
  md << "# TeraWalk benchmark report\n\n";
  md << "- started " << results.value("started_utc", "?") << ", total "
     << fmt(results.value("total_s", 0.0), 0) << " s, commit `" << results.value("commit", "?")
     << "`\n";
  const json& machine = results.at("machine");
  md << "- machine: " << machine.value("cpu", "?") << ", " << machine.value("cores", 0)
     << " cores, " << fmt(machine.value("memory_bytes", 0.0) / double(1ull << 30), 1)
     << " GiB; renderer " << machine.value("renderer", "?") << "\n";
  md << "- configuration: sizes";
  for (const auto& s : config.at("sizes")) md << " " << s.get<std::string>();
  md << ", " << config.value("runs", 0) << " run(s) per mode (medians), "
     << config.value("image_size", "?") << ", " << fmt(config.value("fps", 0.0), 2)
     << " frames per path second";
  if (config.value("walk_fps", 0.0) > config.value("fps", 0.0)) {
    md << " (walked at " << fmt(config.value("walk_fps", 0.0), 1) << " between them on";
    for (const auto& p : config.value("walk_paths", json::array())) md << " " << p.get<std::string>();
    md << " by";
    for (const auto& m : config.value("walk_modes", json::array())) md << " " << m.get<std::string>();
    md << ")";
  }
  md << ", orbit " << config.value("orbit_frames", 0) << " frames"
     << (config.value("quick", false) ? ", --quick" : "") << "\n\n";

}

// Preprocessing: one row a plant, then its time per stage. Returns the stages' names, in order.
std::vector<std::string> writePreprocessTables(std::ostringstream& md, const json& models) {
  md << "## Preprocessing\n\n| plant | input triangles | wall s | CPU s | peak RSS MiB | input "
        "triangles/s | bytes/input triangle | levels |\n|---|---|---|---|---|---|---|---|\n";
  std::vector<std::string> stages;
  for (const json& m : models) {
    const json& p = m.at("preprocess");
    md << "| " << m.value("size", "?") << " | " << fmt(num(p, "input_triangles"), 0) << " | "
       << fmt(num(p, "wall_s")) << " | " << fmt(num(p, "cpu_s")) << " | "
       << fmt(num(p, "peak_rss_bytes") / 1048576.0, 0) << " | "
       << fmt(num(p, "input_triangles_per_s") / 1e6, 3) << " M | "
       << fmt(num(p, "bytes_per_input_triangle")) << " | " << fmt(num(p, "levels"), 0) << " |\n";
    if (p.contains("stages_s"))
      for (const auto& [stage, seconds] : p["stages_s"].items())
        if (std::find(stages.begin(), stages.end(), stage) == stages.end()) stages.push_back(stage);
  }
  md << "\nTime per stage (s):\n\n| plant |";
  for (const std::string& s : stages) md << " " << s << " |";
  md << "\n|---|";
  for (size_t i = 0; i < stages.size(); ++i) md << "---|";
  md << "\n";
  for (const json& m : models) {
    md << "| " << m.value("size", "?") << " |";
    const json& st = m.at("preprocess").value("stages_s", json::object());
    for (const std::string& s : stages) md << " " << fmt(num(st, s.c_str())) << " |";
    md << "\n";
  }

  return stages;
}

// One table a path: each plant's modes, their frame times, triangles and fidelity, then what the
// reference's frames show.
void writePathTables(std::ostringstream& md, const json& models,
                     const std::vector<std::string>& path_names) {
  for (const std::string& path : path_names) {
    md << "\n## Path `" << path << "`\n\n| plant | mode | median frame ms | median GPU ms | "
          "median triangles (mesh + parametric) | first frame ms | peak RSS MiB | match vs reference | occlusion "
          "pixel loss | speed-up vs reference |\n|---|---|---|---|---|---|---|---|---|---|\n";
    for (const json& m : models) {
      const json& pm = m.at("paths").at(path);
      const double ref_ms = num(pm.at("reference"), "median_frame_ms");
      for (const auto& title : kModeTitles) {
        if (!pm.contains(title[0])) continue;
        const json& r = pm[title[0]];
        std::string match = "-";
        if (r.contains("fidelity")) {
          const json& f = r["fidelity"];
          if (f.contains("mean_match_pct") && f["mean_match_pct"].is_number())
            match = fmt(f["mean_match_pct"].get<double>(), 2) + " %";
        }
        const double loss = num(r, "occlusion_lost_share");
        md << "| " << m.value("size", "?") << " | " << title[1] << " | "
           << fmt(num(r, "median_frame_ms")) << " | " << fmt(num(r, "median_gpu_ms")) << " | "
           << triangles(r) << " | " << fmt(num(r, "first_frame_ms"))
           << " | " << fmt(num(r, "peak_rss_bytes") / 1048576.0, 0) << " | " << match << " | "
           << (std::isfinite(loss) ? fmt(100.0 * loss, 4) + " %" : "-") << " | "
           << fmt(ref_ms / num(r, "median_frame_ms")) << "x |\n";
      }
    }
    // What the frames show, read off the reference's id images by the compare: the output a
    // frame's cost should follow (two plants' frames with the same census should cost alike).
    bool census_header = false;
    for (const json& m : models) {
      const json& pm = m.at("paths").at(path);
      for (const auto& title : kModeTitles) {
        if (!pm.contains(title[0]) || !pm[title[0]].contains("fidelity")) continue;
        const json& f = pm[title[0]]["fidelity"];
        if (!f.contains("median_covered_pixels_a") || !f["median_covered_pixels_a"].is_number())
          continue;
        if (!census_header)
          md << "\nShown per frame by the reference (medians over its id images):\n\n";
        census_header = true;
        md << "- " << m.value("size", "?") << ": "
           << fmt(f["median_covered_pixels_a"].get<double>(), 0) << " pixels covered, "
           << fmt(f["median_visible_objects_a"].get<double>(), 0) << " distinct objects\n";
        break;
      }
    }
  }

}

// gnuplot plots of the largest plant's frame times, frame time against size, preprocess time and
// memory, and the stages. Returns each plot's file and caption; none without gnuplot.
std::vector<std::pair<std::string, std::string>> writePlots(
    const fs::path& plots, const json& models, const std::vector<std::string>& path_names,
    const std::vector<std::string>& stages) {
  std::vector<std::pair<std::string, std::string>> made;  // png, caption
  const fs::path gnuplot = findGnuplot();
  if (!gnuplot.empty() && !models.empty()) {
    const json& largest = models.back();
    for (const std::string& path : path_names) {
      std::ostringstream dat, script;
      const json& pm = largest.at("paths").at(path);
      script << "set title " << quoteGp("frame time along " + path + ", plant " +
                                        largest.value("size", "?"))
             << "\nset xlabel 'frame'\nset ylabel 'ms'\nplot ";
      int column = 0;
      for (const auto& title : kModeTitles) {
        if (!pm.contains(title[0]) || !pm[title[0]].contains("series")) continue;
        const json& ms = pm[title[0]]["series"]["frame_ms"];
        const fs::path file = plots / ("frametime-" + path + "-" + title[0] + ".dat");
        std::ostringstream rows;
        for (size_t i = 0; i < ms.size(); ++i) rows << i << " " << ms[i].get<double>() << "\n";
        writeFile(file, rows.str());
        script << (column++ ? ", " : "") << quoteGp(file.string()) << " with lines title "
               << quoteGp(title[1]);
      }
      script << "\n";
      if (column) {
        std::string png = plot(gnuplot, plots, "frametime-" + path, script.str());
        if (!png.empty()) made.push_back({png, "Frame time along `" + path + "` per mode"});
      }
      // Output sensitivity: median frame time against model size, log scale.
      std::ostringstream sens;
      sens << "set title " << quoteGp("median frame time against model size, " + path)
           << "\nset logscale x\nset xlabel 'input triangles'\nset ylabel 'ms'\nplot ";
      int series = 0;
      for (const auto& title : kModeTitles) {
        std::ostringstream rows;
        for (const json& m : models) {
          const json& pm2 = m.at("paths").at(path);
          if (!pm2.contains(title[0])) continue;
          rows << num(m.at("preprocess"), "input_triangles") << " "
               << num(pm2[title[0]], "median_frame_ms") << "\n";
        }
        const fs::path file = plots / ("scaling-" + path + "-" + title[0] + ".dat");
        writeFile(file, rows.str());
        sens << (series++ ? ", " : "") << quoteGp(file.string()) << " with linespoints title "
             << quoteGp(title[1]);
      }
      sens << "\n";
      std::string png = plot(gnuplot, plots, "scaling-" + path, sens.str());
      if (!png.empty())
        made.push_back({png, "Median frame time against model size along `" + path + "`"});
    }
    // Preprocess time and peak memory against size.
    {
      std::ostringstream rows;
      for (const json& m : models) {
        const json& p = m.at("preprocess");
        rows << num(p, "input_triangles") << " " << num(p, "wall_s") << " "
             << num(p, "peak_rss_bytes") / 1048576.0 << "\n";
      }
      const fs::path file = plots / "preprocess.dat";
      writeFile(file, rows.str());
      std::string png = plot(
          gnuplot, plots, "preprocess",
          "set title 'preprocess time and peak memory against model size'\nset logscale x\n"
          "set xlabel 'input triangles'\nset ylabel 'wall s'\nset y2label 'peak RSS MiB'\n"
          "set ytics nomirror\nset y2tics\nplot " +
              quoteGp(file.string()) + " using 1:2 with linespoints title 'wall s', " +
              quoteGp(file.string()) + " using 1:3 axes x1y2 with linespoints title 'peak RSS MiB'\n");
      if (!png.empty()) made.push_back({png, "Preprocess wall time and peak memory"});
    }
    // Stage breakdown, stacked per size.
    if (!stages.empty()) {
      std::ostringstream rows;
      for (const json& m : models) {
        rows << m.value("size", "?");
        const json& st = m.at("preprocess").value("stages_s", json::object());
        for (const std::string& s : stages) {
          const double v = num(st, s.c_str());
          rows << " " << (std::isfinite(v) ? v : 0.0);
        }
        rows << "\n";
      }
      const fs::path file = plots / "stages.dat";
      writeFile(file, rows.str());
      std::ostringstream script;
      script << "set title 'preprocess time per stage'\nset style data histograms\n"
                "set style histogram rowstacked\nset style fill solid 0.8 border -1\n"
                "set boxwidth 0.6\nset ylabel 's'\nplot ";
      for (size_t i = 0; i < stages.size(); ++i)
        script << (i ? ", " : "") << quoteGp(file.string()) << " using " << i + 2
               << (i == 0 ? ":xtic(1)" : "") << " title " << quoteGp(stages[i]);
      script << "\n";
      std::string png = plot(gnuplot, plots, "stages", script.str());
      if (!png.empty()) made.push_back({png, "Preprocess time per stage"});
    }
  }
  return made;
}

void writeSampleFrames(std::ostringstream& md, const fs::path& out_dir) {
  md << "## Sample frames\n\nReference, full default and their difference (magenta: other object, "
        "red: colour) for the largest plant:\n\n";
  if (fs::is_directory(out_dir / "samples"))
    for (const auto& entry : fs::directory_iterator(out_dir / "samples"))
      if (entry.path().filename().string().rfind("reference-", 0) == 0) {
        const std::string rest = entry.path().filename().string().substr(10);
        md << "`" << rest << "`: ![reference](samples/reference-" << rest
           << ") ![default](samples/default-" << rest << ") ![diff](samples/diff-" << rest << ")\n\n";
      }
}

}  // namespace

void writeBenchReport(const json& results, const fs::path& out_dir) {
  const fs::path plots = out_dir / "plots";
  fs::create_directories(plots);
  const json& models = results.at("models");
  const std::vector<std::string> path_names =
      results.at("configuration").at("paths").get<std::vector<std::string>>();
  std::ostringstream md;
  writeRunHeader(md, results);
  const std::vector<std::string> stages = writePreprocessTables(md, models);
  writePathTables(md, models, path_names);
  const auto made = writePlots(plots, models, path_names, stages);
  md << "\n## Plots\n\n";
  if (findGnuplot().empty())
    md << "gnuplot was not found on PATH (Debian package gnuplot-nox): no plots.\n";
  for (const auto& [png, caption] : made) md << caption << ":\n\n![" << caption << "](plots/" << png << ")\n\n";
  writeSampleFrames(md, out_dir);
  writeFile(out_dir / "report.md", md.str());
}

std::string compareBenchResults(const json& old_results, const json& new_results) {
  std::map<std::string, double> old_values, new_values;
  std::function<void(const json&, const std::string&, std::map<std::string, double>&)> flatten =
      [&](const json& j, const std::string& prefix, std::map<std::string, double>& out) {
        if (j.is_number()) {
          out[prefix] = j.get<double>();
        } else if (j.is_object()) {
          for (const auto& [key, value] : j.items()) {
            if (key == "series" || key.ends_with("_runs") || key == "configuration" ||
                key == "machine")
              continue;
            flatten(value, prefix.empty() ? key : prefix + "." + key, out);
          }
        } else if (j.is_array()) {
          for (size_t i = 0; i < j.size(); ++i) {
            // Models are named by size, so a reordered or partial run still pairs up.
            std::string tag = j[i].is_object() && j[i].contains("size")
                                  ? j[i]["size"].get<std::string>()
                                  : std::to_string(i);
            flatten(j[i], prefix + "[" + tag + "]", out);
          }
        }
      };
  flatten(old_results, "", old_values);
  flatten(new_results, "", new_values);
  std::ostringstream out;
  out << "figure                                                                       old          new    new/old\n";
  for (const auto& [key, now] : new_values) {
    auto it = old_values.find(key);
    if (it == old_values.end()) continue;
    char line[256];
    const double ratio = it->second != 0.0 ? now / it->second : std::nan("");
    std::snprintf(line, sizeof(line), "%-72s %12.4g %12.4g %9.3f\n", key.c_str(), it->second, now,
                  ratio);
    out << line;
  }
  return out.str();
}

}  // namespace tw
