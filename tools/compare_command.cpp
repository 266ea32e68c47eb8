// `terawalk compare DIR_A DIR_B`: how close two rendered frame sequences are (an LOD run against
// the brute-force --reference, usually), frame by frame: PSNR, colour and object-id mismatch
// beyond a pixel neighbourhood, and the share of pixels that match. It reports and writes diff
// images and a summary; judging the figures against thresholds is the caller's business, so it
// exits 0 whenever the inputs could be compared (docs/compare.md).
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "command.h"
#include "image_compare.h"

namespace tw {
namespace {

namespace fs = std::filesystem;

struct CompareOptions {
  std::string dir_a, dir_b;
  std::string out_dir;  // empty: no diff images, no summary files
  int tolerance_px = 1;
  int colour_threshold = ImageCompareOptions{}.colour_threshold;
  bool json = false;
};

// One frame_<digits>.png of a directory; `digits` is kept as written so that the matching
// ids_<digits>.png and the diff_<digits>.png use the same spelling.
struct FrameFile {
  uint32_t number = 0;
  std::string digits;
};

struct FrameResult {
  uint32_t number = 0;
  bool ids_compared = false;
  ImageCompareResult result;
  IdCensus census_a, census_b;  // what each frame shows (ids compared only)
};

// The frame number of "frame_<1..9 digits>.png", or nothing for any other name.
std::optional<FrameFile> parseFrameName(const std::string& name) {
  static constexpr std::string_view kPrefix = "frame_", kSuffix = ".png";
  if (name.size() <= kPrefix.size() + kSuffix.size() || !name.starts_with(kPrefix) ||
      !name.ends_with(kSuffix))
    return std::nullopt;
  std::string digits = name.substr(kPrefix.size(), name.size() - kPrefix.size() - kSuffix.size());
  if (digits.size() > 9 ||
      !std::all_of(digits.begin(), digits.end(), [](char c) { return c >= '0' && c <= '9'; }))
    return std::nullopt;
  return FrameFile{static_cast<uint32_t>(std::stoul(digits)), digits};
}

// The frames of `dir` by number. Throws when `dir` is not a directory, holds no frames, or holds
// two files for one number.
std::map<uint32_t, FrameFile> listFrames(const fs::path& dir) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) throw std::runtime_error(dir.string() + ": not a directory");
  std::map<uint32_t, FrameFile> frames;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    auto frame = parseFrameName(entry.path().filename().string());
    if (!frame) continue;
    auto [it, inserted] = frames.emplace(frame->number, *frame);
    if (!inserted)
      throw std::runtime_error(dir.string() + ": two files for frame " +
                               std::to_string(frame->number) + ": frame_" + it->second.digits +
                               ".png and frame_" + frame->digits + ".png");
  }
  if (ec) throw std::runtime_error(dir.string() + ": cannot list: " + ec.message());
  if (frames.empty()) throw std::runtime_error(dir.string() + ": no frame_*.png files");
  return frames;
}

fs::path framePath(const fs::path& dir, const FrameFile& f) {
  return dir / ("frame_" + f.digits + ".png");
}
fs::path idsPath(const fs::path& dir, const FrameFile& f) {
  return dir / ("ids_" + f.digits + ".png");
}

std::string sizeText(int width, int height) {
  return std::to_string(width) + "x" + std::to_string(height);
}

// Both directories must hold the same frame numbers; the error names the first missing file.
void checkSameFrames(const CompareOptions& o, const std::map<uint32_t, FrameFile>& a,
                     const std::map<uint32_t, FrameFile>& b) {
  using Frames = std::map<uint32_t, FrameFile>;
  auto missing = [](const Frames& has, const Frames& lacks,
                    const std::string& lacks_dir) -> std::optional<std::string> {
    for (const auto& [number, file] : has)
      if (!lacks.count(number))
        return (fs::path(lacks_dir) / ("frame_" + file.digits + ".png")).string();
    return std::nullopt;
  };
  auto gone = missing(a, b, o.dir_b);
  if (!gone) gone = missing(b, a, o.dir_a);
  if (gone)
    throw std::runtime_error(*gone + ": missing (" + o.dir_a + " has " + std::to_string(a.size()) +
                             " frames, " + o.dir_b + " has " + std::to_string(b.size()) + ")");
}

// An id image, checked against the size of its colour frame.
std::vector<uint32_t> readIds(const fs::path& path, int width, int height) {
  RgbaImage image = readPngRgba(path);
  if (image.width != width || image.height != height)
    throw std::runtime_error(path.string() + ": " + sizeText(image.width, image.height) +
                             " but its colour frame is " + sizeText(width, height));
  return idsFromRgba(image.rgba);
}

FrameResult compareFrame(const CompareOptions& o, const FrameFile& fa, const FrameFile& fb) {
  const fs::path colour_a = framePath(o.dir_a, fa), colour_b = framePath(o.dir_b, fb);
  RgbaImage a = readPngRgba(colour_a);
  RgbaImage b = readPngRgba(colour_b);
  if (a.width != b.width || a.height != b.height)
    throw std::runtime_error(colour_b.string() + ": " + sizeText(b.width, b.height) + " but " +
                             colour_a.string() + " is " + sizeText(a.width, a.height));

  // Ids are compared where both runs wrote them; a run without ids still gets a colour result.
  FrameResult frame;
  frame.number = fa.number;
  std::vector<uint32_t> ids_a, ids_b;
  const fs::path ids_path_a = idsPath(o.dir_a, fa), ids_path_b = idsPath(o.dir_b, fb);
  std::error_code ec;
  if (fs::exists(ids_path_a, ec) && fs::exists(ids_path_b, ec)) {
    ids_a = readIds(ids_path_a, a.width, a.height);
    ids_b = readIds(ids_path_b, b.width, b.height);
    frame.ids_compared = true;
    frame.census_a = censusOf(ids_a);
    frame.census_b = censusOf(ids_b);
  }

  ImageCompareOptions options;
  options.neighbourhood_px = o.tolerance_px;
  options.colour_threshold = o.colour_threshold;
  std::vector<uint8_t> diff;
  frame.result = compareImages(a.width, a.height, a.rgba, b.rgba, ids_a, ids_b, options,
                               o.out_dir.empty() ? nullptr : &diff);
  if (!o.out_dir.empty())
    writePngRgba(fs::path(o.out_dir) / ("diff_" + fa.digits + ".png"), a.width, a.height, diff);
  return frame;
}

// Per-frame results for every pair, in frame order. Frames run in parallel in small batches so
// that progress is reported between batches from this thread; batches run in order and each
// rethrows its lowest-numbered failure, so the error reported is that of the lowest-numbered
// failing frame whatever the scheduling.
std::vector<FrameResult> compareAll(const CompareOptions& o, const std::vector<FrameFile>& a,
                                    const std::vector<FrameFile>& b, Progress* progress) {
  constexpr size_t kBatch = 16;
  std::vector<FrameResult> results(a.size());
  std::vector<std::exception_ptr> errors(a.size());
  beginStage(progress, "comparing frames", a.size());
  for (size_t start = 0; start < a.size(); start += kBatch) {
    const size_t end = std::min(a.size(), start + kBatch);
    tbb::parallel_for(start, end, [&](size_t i) {
      try {
        results[i] = compareFrame(o, a[i], b[i]);
      } catch (...) {
        errors[i] = std::current_exception();
      }
    });
    for (size_t i = start; i < end; ++i)
      if (errors[i]) std::rethrow_exception(errors[i]);
    updateProgress(progress, end);
  }
  endStage(progress);
  return results;
}

double percent(double share) { return share * 100.0; }

// The median over the frames with ids of one census figure, or null when no frame had ids.
nlohmann::json medianCensus(const std::vector<FrameResult>& frames,
                            uint64_t (*figure)(const FrameResult&)) {
  std::vector<uint64_t> values;
  for (const FrameResult& f : frames)
    if (f.ids_compared) values.push_back(figure(f));
  if (values.empty()) return nullptr;
  std::sort(values.begin(), values.end());
  const size_t mid = values.size() / 2;
  return values.size() % 2 ? double(values[mid]) : 0.5 * double(values[mid - 1] + values[mid]);
}

// A frame's census figure for the per-frame records, null without ids.
nlohmann::json censusFigure(const FrameResult& f, uint64_t value) {
  return f.ids_compared ? nlohmann::json(value) : nlohmann::json(nullptr);
}

nlohmann::json summarize(const CompareOptions& o, const std::vector<FrameResult>& frames) {
  double match_sum = 0, colour_sum = 0, id_sum = 0, psnr_sum = 0;
  size_t ids_frames = 0, identical = 0, psnr_frames = 0;
  const FrameResult* worst = &frames.front();
  const FrameResult* lowest_psnr = &frames.front();
  nlohmann::json per_frame = nlohmann::json::array();
  for (const FrameResult& f : frames) {
    const ImageCompareResult& r = f.result;
    match_sum += r.match_share;
    colour_sum += r.colour_mismatch_share;
    if (f.ids_compared) {
      id_sum += r.id_mismatch_share;
      ++ids_frames;
    }
    if (r.psnr_db >= kIdenticalPsnrDb) {
      ++identical;
    } else {
      psnr_sum += r.psnr_db;
      ++psnr_frames;
    }
    if (r.match_share < worst->result.match_share) worst = &f;
    if (r.psnr_db < lowest_psnr->result.psnr_db) lowest_psnr = &f;
    per_frame.push_back({{"frame", f.number},
                         {"width", r.width},
                         {"height", r.height},
                         {"psnr_db", r.psnr_db},
                         {"colour_mismatch_pct", percent(r.colour_mismatch_share)},
                         {"id_mismatch_pct", f.ids_compared
                                                 ? nlohmann::json(percent(r.id_mismatch_share))
                                                 : nlohmann::json(nullptr)},
                         {"match_pct", percent(r.match_share)},
                         {"ids_compared", f.ids_compared},
                         {"covered_pixels_a", censusFigure(f, f.census_a.covered_pixels)},
                         {"visible_objects_a", censusFigure(f, f.census_a.visible_objects)},
                         {"covered_pixels_b", censusFigure(f, f.census_b.covered_pixels)},
                         {"visible_objects_b", censusFigure(f, f.census_b.visible_objects)}});
  }
  const double n = double(frames.size());
  nlohmann::json j;
  j["dir_a"] = o.dir_a;
  j["dir_b"] = o.dir_b;
  j["tolerance_px"] = o.tolerance_px;
  j["colour_threshold"] = o.colour_threshold;
  j["frames"] = frames.size();
  j["ids_compared_frames"] = ids_frames;
  j["mean_match_pct"] = percent(match_sum / n);
  j["worst_match_pct"] = percent(worst->result.match_share);
  j["worst_match_frame"] = worst->number;
  j["mean_colour_mismatch_pct"] = percent(colour_sum / n);
  j["mean_id_mismatch_pct"] =
      ids_frames ? nlohmann::json(percent(id_sum / double(ids_frames))) : nlohmann::json(nullptr);
  // Identical frames have no finite PSNR: they are counted apart rather than averaged as 999.
  j["mean_psnr_db"] = psnr_frames ? psnr_sum / double(psnr_frames) : kIdenticalPsnrDb;
  j["min_psnr_db"] = lowest_psnr->result.psnr_db;
  j["min_psnr_frame"] = lowest_psnr->number;
  j["identical_frames"] = identical;
  j["median_covered_pixels_a"] =
      medianCensus(frames, [](const FrameResult& f) { return f.census_a.covered_pixels; });
  j["median_visible_objects_a"] =
      medianCensus(frames, [](const FrameResult& f) { return f.census_a.visible_objects; });
  j["median_covered_pixels_b"] =
      medianCensus(frames, [](const FrameResult& f) { return f.census_b.covered_pixels; });
  j["median_visible_objects_b"] =
      medianCensus(frames, [](const FrameResult& f) { return f.census_b.visible_objects; });
  j["per_frame"] = per_frame;
  return j;
}

void writeCsv(const fs::path& path, const std::vector<FrameResult>& frames) {
  std::ofstream out(path);
  out << "frame,psnr_db,colour_mismatch_pct,id_mismatch_pct,match_pct,ids_compared,"
         "covered_pixels_a,visible_objects_a,covered_pixels_b,visible_objects_b\n";
  char line[240];
  for (const FrameResult& f : frames) {
    const ImageCompareResult& r = f.result;
    std::snprintf(line, sizeof line, "%u,%.4f,%.4f,%.4f,%.4f,%d", f.number, r.psnr_db,
                  percent(r.colour_mismatch_share), percent(r.id_mismatch_share),
                  percent(r.match_share), f.ids_compared ? 1 : 0);
    out << line;
    if (f.ids_compared) {
      std::snprintf(line, sizeof line, ",%llu,%llu,%llu,%llu\n",
                    (unsigned long long)f.census_a.covered_pixels,
                    (unsigned long long)f.census_a.visible_objects,
                    (unsigned long long)f.census_b.covered_pixels,
                    (unsigned long long)f.census_b.visible_objects);
      out << line;
    } else {
      out << ",,,,\n";
    }
  }
  if (!out.flush()) throw std::runtime_error(path.string() + ": cannot write");
}

void writeJson(const fs::path& path, const nlohmann::json& j) {
  std::ofstream out(path);
  out << j.dump(2) << "\n";
  if (!out.flush()) throw std::runtime_error(path.string() + ": cannot write");
}

void printText(const std::vector<FrameResult>& frames, const nlohmann::json& s) {
  std::printf("%7s %9s %11s %11s %9s\n", "frame", "psnr_db", "colour_mm%", "id_mm%", "match%");
  for (const FrameResult& f : frames) {
    const ImageCompareResult& r = f.result;
    char ids[32];
    if (f.ids_compared) std::snprintf(ids, sizeof ids, "%11.3f", percent(r.id_mismatch_share));
    else std::snprintf(ids, sizeof ids, "%11s", "-");
    std::printf("%7u %9.2f %11.3f %s %9.3f\n", f.number, r.psnr_db,
                percent(r.colour_mismatch_share), ids, percent(r.match_share));
  }
  std::printf("frames %zu (ids compared in %zu), tolerance %d px, colour threshold %d\n",
              s["frames"].get<size_t>(), s["ids_compared_frames"].get<size_t>(),
              s["tolerance_px"].get<int>(), s["colour_threshold"].get<int>());
  std::printf("match    mean %.3f %%, worst %.3f %% (frame %u)\n",
              s["mean_match_pct"].get<double>(), s["worst_match_pct"].get<double>(),
              s["worst_match_frame"].get<uint32_t>());
  std::printf("psnr     mean %.2f dB over %zu differing frames, min %.2f dB (frame %u), "
              "%zu identical\n",
              s["mean_psnr_db"].get<double>(),
              frames.size() - s["identical_frames"].get<size_t>(), s["min_psnr_db"].get<double>(),
              s["min_psnr_frame"].get<uint32_t>(), s["identical_frames"].get<size_t>());
  if (s["median_covered_pixels_a"].is_number())
    std::printf("shown    median per frame: A %.0f pixels covered, %.0f objects; "
                "B %.0f pixels, %.0f objects\n",
                s["median_covered_pixels_a"].get<double>(),
                s["median_visible_objects_a"].get<double>(),
                s["median_covered_pixels_b"].get<double>(),
                s["median_visible_objects_b"].get<double>());
}

}  // namespace

void registerCompareCommand(CLI::App& app, const GlobalOptions& global) {
  auto options = std::make_shared<CompareOptions>();
  CLI::App* cmd = app.add_subcommand(
      "compare", "Compare two rendered frame directories: PSNR, colour and id mismatch, diffs");
  cmd->add_option("dir_a", options->dir_a, "Reference frames (frame_NNNNN.png, ids_NNNNN.png)")
      ->required();
  cmd->add_option("dir_b", options->dir_b, "Frames to compare against the reference")->required();
  cmd->add_option("--out", options->out_dir,
                  "Write diff_NNNNN.png, summary.json and compare.csv into this directory");
  cmd->add_option("--tolerance-px", options->tolerance_px,
                  "Neighbourhood radius in pixels within which a match counts")
      ->check(CLI::Range(0, 16))
      ->capture_default_str();
  cmd->add_option("--colour-threshold", options->colour_threshold,
                  "Largest per-channel difference (0..255) that still matches in colour")
      ->check(CLI::Range(0, 255))
      ->capture_default_str();
  cmd->add_flag("--json", options->json, "Print the summary as JSON instead of a table");
  cmd->callback([options, &global] {
    const CompareOptions& o = *options;
    auto frames_a = listFrames(o.dir_a);
    auto frames_b = listFrames(o.dir_b);
    checkSameFrames(o, frames_a, frames_b);
    std::vector<FrameFile> list_a, list_b;
    for (const auto& [number, file] : frames_a) {
      list_a.push_back(file);
      list_b.push_back(frames_b.at(number));
    }
    if (!o.out_dir.empty()) {
      // The render directories hold a summary.json of their own; never overwrite it.
      std::error_code ec;
      for (const std::string& dir : {o.dir_a, o.dir_b})
        if (fs::equivalent(o.out_dir, dir, ec))
          throw std::runtime_error(o.out_dir + ": --out must not be one of the compared "
                                   "directories");
      fs::create_directories(o.out_dir, ec);
      if (!fs::is_directory(o.out_dir))
        throw std::runtime_error(o.out_dir + ": cannot create directory" +
                                 (ec ? ": " + ec.message() : std::string()));
    }

    auto progress = makeCommandProgress(global);
    std::vector<FrameResult> results = compareAll(o, list_a, list_b, progress.get());
    nlohmann::json summary = summarize(o, results);
    if (!o.out_dir.empty()) {
      writeJson(fs::path(o.out_dir) / "summary.json", summary);
      writeCsv(fs::path(o.out_dir) / "compare.csv", results);
    }
    if (o.json) std::cout << summary.dump(2) << std::endl;
    else printText(results, summary);
  });
}

}  // namespace tw
