// CSV and JSON forms of FrameStats, and the process RSS probe.
#include "frame_stats.h"

#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

namespace tw {

namespace {

// A share far below 1e-4 (lost pixels): printed with significant digits, not 4 decimals.
struct SmallShare {
  double value;
};

// One table of the fields, so CSV, JSON and their order never drift apart.
template <typename Visit>
void visitFields(const FrameStats& s, Visit visit) {
  visit("frame", s.frame);
  visit("time_s", s.time_s);
  visit("frame_ms", s.frame_ms);
  visit("cpu_cut_ms", s.cpu_cut_ms);
  visit("gpu_ms", s.gpu_ms);
  visit("finish_ms", s.finish_ms);
  visit("tau_px", s.tau_px);
  visit("nodes_visited", s.nodes_visited);
  visit("nodes_drawn", s.nodes_drawn);
  visit("triangles_drawn", s.triangles_drawn);
  visit("two_sided_triangles", s.two_sided_triangles);
  visit("xray_triangles", s.xray_triangles);
  visit("culled_frustum", s.culled_frustum);
  visit("culled_small", s.culled_small);
  visit("parametric_skipped", s.parametric_skipped);
  visit("parametric_clusters_drawn", s.parametric_clusters_drawn);
  visit("parametric_instances_drawn", s.parametric_instances_drawn);
  visit("parametric_triangles", s.parametric_triangles);
  visit("parametric_two_sided_triangles", s.parametric_two_sided_triangles);
  visit("parametric_thin_instances", s.parametric_thin_instances);
  visit("parametric_cpu_ms", s.parametric_cpu_ms);
  visit("parametric_occluded", s.parametric_occluded);
  visit("parametric_instances_tested", s.parametric_instances_tested);
  visit("pages_resident", s.pages_resident);
  visit("pages_requested", s.pages_requested);
  visit("pages_loading", s.pages_loading);
  visit("pages_ready", s.pages_ready);
  visit("pages_waiting_for_pool", s.pages_waiting_for_pool);
  visit("pages_loaded", s.pages_loaded);
  visit("pages_evicted", s.pages_evicted);
  visit("bytes_uploaded", s.bytes_uploaded);
  visit("ancestor_fallbacks", s.ancestor_fallbacks);
  visit("page_load_errors", s.page_load_errors);
  visit("gpu_bytes_used", s.gpu_bytes_used);
  visit("host_bytes_used", s.host_bytes_used);
  visit("rss_bytes", s.rss_bytes);
  visit("occlusion_culled", s.occlusion_culled);
  visit("occluders_drawn", s.occluders_drawn);
  visit("pass1_clusters", s.pass1_clusters);
  visit("pass2_clusters", s.pass2_clusters);
  visit("hzb_build_ms", s.hzb_build_ms);
  visit("hzb_test_ms", s.hzb_test_ms);
  visit("view_cell", s.view_cell);
  visit("occlusion_lost_px", s.occlusion_lost_px);
  visit("occlusion_lost_share", SmallShare{s.occlusion_lost_share});
  visit("occlusion_lost_depth_px", s.occlusion_lost_depth_px);
  visit("ocean_triangles", s.ocean_triangles);
  visit("ocean_cpu_ms", s.ocean_cpu_ms);
}

void to_json(nlohmann::json& j, SmallShare v) { j = v.value; }
std::string formatValue(SmallShare v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.6g", v.value);
  return text;
}

std::string formatValue(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.4f", v);
  return text;
}
template <typename T>
std::string formatValue(T v) {
  return std::to_string(v);
}

void writeText(const std::filesystem::path& file, const std::string& text) {
  std::ofstream out(file, std::ios::binary);
  out << text;
  out.close();
  if (!out) throw std::runtime_error(file.string() + ": cannot write frame statistics");
}

}  // namespace

uint64_t currentRssBytes() {
  std::FILE* f = std::fopen("/proc/self/statm", "r");
  if (!f) return 0;
  unsigned long long pages_total = 0, pages_resident = 0;
  const int read = std::fscanf(f, "%llu %llu", &pages_total, &pages_resident);
  std::fclose(f);
  if (read != 2) return 0;
  return pages_resident * static_cast<uint64_t>(sysconf(_SC_PAGESIZE));
}

std::string frameStatsCsvHeader() {
  std::string line;
  visitFields(FrameStats{}, [&](const char* name, auto) {
    if (!line.empty()) line += ',';
    line += name;
  });
  return line;
}

std::string frameStatsCsvRow(const FrameStats& stats) {
  std::string line;
  bool first = true;
  visitFields(stats, [&](const char*, auto value) {
    if (!first) line += ',';
    first = false;
    line += formatValue(value);
  });
  return line;
}

void writeFrameStatsCsv(const std::vector<FrameStats>& frames, const std::filesystem::path& file) {
  std::string text = frameStatsCsvHeader();
  text += '\n';
  for (const FrameStats& f : frames) {
    text += frameStatsCsvRow(f);
    text += '\n';
  }
  writeText(file, text);
}

void writeFrameStatsJson(const std::vector<FrameStats>& frames, const std::filesystem::path& file) {
  nlohmann::json list = nlohmann::json::array();
  for (const FrameStats& f : frames) {
    nlohmann::json row;
    visitFields(f, [&](const char* name, auto value) { row[name] = value; });
    list.push_back(std::move(row));
  }
  writeText(file, nlohmann::json{{"frames", list}}.dump(1) + "\n");
}

}  // namespace tw
