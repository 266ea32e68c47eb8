// `terawalk render model.twk`: the headless walkthrough. Renders a camera path (from a file, or a
// generated orbit or fly-through) through EGL surfaceless (Mesa llvmpipe without a GPU), writes
// per-frame statistics as CSV and JSON, PNG frames and object-id frames when asked, and prints a
// summary. `--reference` draws every full-resolution triangle with no LOD and no culling: the
// brute-force baseline that `terawalk compare` measures fidelity against. `--occlusion` picks the
// occlusion culling (off, hzb, pvs); `--check-occlusion` draws every frame's cut a second time
// without occlusion culling and counts the pixels whose object id differs (the loss culling
// caused, exact, at the same LOD). `--parametrics` picks how parametric objects are drawn:
// ray-cast impostors, run-time meshes by distance, not at all, or auto (the default: by the GL
// renderer, docs/parametrics.md).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>

#include <nlohmann/json.hpp>

#include "camera_path.h"
#include "command.h"
#include "command_args.h"
#include "egl_context.h"
#include "environment_options.h"
#include "frame_loop.h"
#include "image_compare.h"
#include "object_queries.h"
#include "bcf_viewpoint_option.h"
#include "change_set_view.h"
#include "review_state_options.h"
#include "section_planes.h"
#include "snapshot_camera.h"
#include "soak_log.h"
#include "tessellate.h"
#include "stereo_options.h"
#include "video_encoder.h"

namespace tw {
namespace {

struct RenderArgs {
  std::string file;
  std::string path_file;
  int orbit_frames = 0;
  int flythrough_frames = 0;
  int random_walk_frames = 0;
  uint64_t seed = 1;
  double soak_interval_s = 0.0;
  double max_seconds = 0.0;
  std::string save_path;
  std::string size = "1280x720";
  std::string out_dir;
  bool png = false;
  double fps = 30.0;
  double walk_fps = 0.0;
  int max_frames = 0;
  double tau_px = 1.0;
  double min_feature_px = 1.0;
  double target_fps = 0.0;
  std::string gpu_budget = "1G";
  std::string host_budget = "256M";
  double upload_mb = 32.0;
  uint32_t loader_threads = 2;
  uint32_t evict_after = 30;
  bool reference = false;
  bool no_prefetch = false;
  bool two_sided_meshes = false;
  bool no_frustum = false;
  std::string occlusion = "hzb";
  std::string parametrics = "auto";
  double parametric_tolerance_m = 0.0;
  bool check_occlusion = false;
  int hzb_read_width = kMaxTestLevelWidthPx;
  bool hzb_final_rebuild = true;
  std::string occluders = "seed";
  std::string hzb_build = "auto";
  int hzb_span = BoxTest{}.max_span_texels;
  int hzb_split = BoxTest{}.split_px;
  // Per-object state and sections along the whole path (object_states.h, section_planes.h).
  ReviewStateArgs state;
  EnvironmentArgs environment;  // --ocean, --sky and their settings
  std::string viewpoint;  // FILE.bcfzip[#N]
  std::string changes;    // a change set (model.changes.json)
  std::string video;      // FILE.mp4|.mkv|.avi: the recorded frames as a video
  StereoArgs stereo;      // --stereo and its distances
};

// The recorded frame's picture: the renderer's colour, or a stereo pair put together.
struct FrameImage {
  std::vector<uint8_t> rgba;
  int width = 0, height = 0;
};

// frame_NNNNN.png from `image`, and ids_NNNNN.png from the renderer (in stereo, the right eye's).
void writeFramePngs(GlRenderer& renderer, const std::filesystem::path& dir, uint64_t index,
                    const FrameImage& image, std::vector<uint32_t>& ids) {
  char name[64];
  std::snprintf(name, sizeof name, "frame_%05llu.png", static_cast<unsigned long long>(index));
  writePngRgba(dir / name, image.width, image.height, image.rgba);
  renderer.readObjectIds(ids, true);
  std::snprintf(name, sizeof name, "ids_%05llu.png", static_cast<unsigned long long>(index));
  writePngRgba(dir / name, renderer.width(), renderer.height(), idsToRgba(ids));
}

using Clock = std::chrono::steady_clock;

double msSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

// Limits that keep a typo from hanging the run or filling the disk: frames are sampled at most
// kMaxFps a path second, and at most kMaxWalkSteps unrecorded frames lie between two recorded ones.
constexpr double kMaxFps = 1000.0;
constexpr double kMaxWalkSteps = 1000.0;
constexpr double kMaxTauPx = 1e4;
constexpr int kMaxGeneratedFrames = 10'000'000;  // a generated path's keys: under 1 GB

// How many of the path options are given.
int pathSources(const RenderArgs& args) {
  return int(!args.path_file.empty()) + int(args.orbit_frames > 0) +
         int(args.flythrough_frames > 0) + int(args.random_walk_frames > 0);
}
bool hasPathSource(const RenderArgs& args) { return pathSources(args) > 0; }

void validateArgs(const RenderArgs& args) {
  auto number = [](double v) {
    char text[32];
    std::snprintf(text, sizeof text, "%g", v);
    return std::string(text);
  };
  if (!(args.fps > 0.0 && args.fps <= kMaxFps))
    throw std::runtime_error("--fps " + number(args.fps) + ": must be above 0 and at most " + number(kMaxFps));
  if (!(args.walk_fps >= 0.0 && args.walk_fps / args.fps <= kMaxWalkSteps))
    throw std::runtime_error("--walk-fps " + number(args.walk_fps) + ": must be 0 to " +
                             number(kMaxWalkSteps) + " times --fps (" + number(args.fps) + ")");
  if (!(args.tau_px > 0.0 && args.tau_px <= kMaxTauPx))
    throw std::runtime_error("--tau " + number(args.tau_px) + ": must be above 0 and at most " +
                             number(kMaxTauPx) + " pixels");
  if (!(args.min_feature_px >= 0.0 && args.min_feature_px <= kMaxTauPx))
    throw std::runtime_error("--min-feature-px " + number(args.min_feature_px) + ": must be 0 to " +
                             number(kMaxTauPx) + " pixels");
  if (!(args.target_fps >= 0.0 && args.target_fps <= kMaxFps))
    throw std::runtime_error("--target-fps " + number(args.target_fps) + ": must be 0 (off) to " +
                             number(kMaxFps));
  if (pathSources(args) > 1 || (pathSources(args) == 0 && args.viewpoint.empty()))
    throw std::runtime_error(
        "give exactly one of --path FILE, --orbit FRAMES, --flythrough FRAMES, --random-walk FRAMES "
        "(or --viewpoint alone for a still from its camera)");
  if (std::max({args.orbit_frames, args.flythrough_frames, args.random_walk_frames}) >
      kMaxGeneratedFrames)
    throw std::runtime_error("a generated path has at most " + std::to_string(kMaxGeneratedFrames) +
                             " frames");
  if (args.png && args.out_dir.empty()) throw std::runtime_error("--png needs --out DIR");
  if (!args.video.empty() && (args.soak_interval_s > 0.0 || args.check_occlusion))
    throw std::runtime_error("--video cannot be combined with --soak-interval or --check-occlusion");
  if (!(args.max_seconds >= 0.0 && args.max_seconds <= 1e7))
    throw std::runtime_error("--max-seconds " + number(args.max_seconds) + ": must be 0 (no limit) to 1e7");
  if (args.soak_interval_s != 0.0 && (args.out_dir.empty() || !(args.soak_interval_s > 0.0) ||
                                      args.png || args.check_occlusion))
    throw std::runtime_error(
        "--soak-interval takes a positive number of seconds and --out DIR, without --png or "
        "--check-occlusion");
  validateReviewStateArgs(args.state);
}

// --stereo and its distances, checked against what render can write (halves must be whole).
StereoOptions renderStereoOptions(const RenderArgs& args, int width, int height) {
  const StereoOptions stereo = stereoOptions(args.stereo);
  if (stereo.mode == StereoMode::QuadBuffered)
    throw std::runtime_error("--stereo quad-buffered: only the viewer's window shows it (render writes "
                             "side-by-side, top-bottom or anaglyph frames)");
  if ((stereo.mode == StereoMode::SideBySide && width % 2 != 0) ||
      (stereo.mode == StereoMode::TopBottom && height % 2 != 0))
    throw std::runtime_error("--stereo " + args.stereo.mode + ": the frame must split into two equal halves; give an even " +
                             (stereo.mode == StereoMode::SideBySide ? "width" : "height"));
  if (stereo.mode != StereoMode::Off && args.check_occlusion)
    throw std::runtime_error("--check-occlusion does not check stereo frames");
  return stereo;
}

WalkthroughOptions walkthroughOptions(const RenderArgs& args, int width, int height) {
  WalkthroughOptions options;
  options.width = width;
  options.height = height;
  options.tau_px = args.tau_px;
  options.min_feature_px = args.min_feature_px;
  options.target_fps = args.target_fps;
  options.reference = args.reference;
  options.prefetch = !args.no_prefetch;
  options.cull_closed_backfaces = !args.two_sided_meshes;
  options.frustum_cull = !args.no_frustum;
  options.occlusion = parseOcclusionMode(args.occlusion);
  options.parametrics = parseParametricMode(args.parametrics);
  options.parametric_meshes.fixed_tolerance_m = args.parametric_tolerance_m;
  if (args.reference) {
    // Brute force means the full-resolution model: parametrics as the triangles the preprocessor
    // would have made (its chordal tolerance), unless asked otherwise.
    if (args.parametrics == "auto") options.parametrics = ParametricMode::Tessellated;
    if (args.parametric_tolerance_m == 0.0)
      options.parametric_meshes.fixed_tolerance_m = kDefaultChordalTolerance;
  }
  options.hzb.read_width_px = args.hzb_read_width;
  options.hzb.rebuild_from_final_depth = args.hzb_final_rebuild;
  options.hzb.build = parseHzbBuild(args.hzb_build);
  options.hzb.box_test.max_span_texels = args.hzb_span;
  options.hzb.box_test.split_px = args.hzb_split;
  options.hzb.occluders = parseOccluders(args.occluders);
  options.pager.gpu_budget_bytes = parseByteSize(args.gpu_budget, "--gpu-budget");
  options.pager.host_budget_bytes = parseByteSize(args.host_budget, "--host-budget");
  options.pager.upload_bytes_per_frame = static_cast<uint64_t>(args.upload_mb * 1024 * 1024);
  options.pager.loader_threads = args.loader_threads;
  options.pager.evict_after_frames = args.evict_after;
  return options;
}

// The camera path from --path, or an orbit, fly-through or random walk around the model's bounds;
// written to --save-path when asked.
CameraPath cameraPath(const RenderArgs& args, const Aabb& bounds) {
  CameraPath path;
  if (!args.path_file.empty()) path = readCameraPath(args.path_file);
  else if (args.orbit_frames > 0) path = generateOrbitPath(bounds, args.orbit_frames, args.fps);
  else if (args.random_walk_frames > 0)
    path = generateRandomWalkPath(bounds, args.random_walk_frames, args.fps, args.seed);
  else path = generateFlythroughPath(bounds, args.flythrough_frames, args.fps);
  if (path.keys.empty()) throw std::runtime_error("the camera path has no key frames");
  if (!args.save_path.empty()) writeCameraPath(path, args.save_path);
  return path;
}

// --check-occlusion: each frame's cut drawn again without occlusion culling, and the pixels whose
// object id (or depth) differs counted, frame by frame and in total.
class OcclusionLossCheck {
 public:
  void check(Walkthrough& walk, FrameStats& stats) {
    walk.renderer().readObjectIds(culled_ids_, false);
    walk.renderer().readDepth(culled_depth_, false);
    walk.redrawUnculled();
    walk.renderer().readObjectIds(unculled_ids_, false);
    walk.renderer().readDepth(unculled_depth_, false);
    uint64_t lost = 0, lost_depth = 0;
    for (size_t p = 0; p < culled_ids_.size(); ++p) {
      const bool id_differs = culled_ids_[p] != unculled_ids_[p];
      lost += id_differs;
      lost_depth += id_differs || culled_depth_[p] != unculled_depth_[p];
    }
    stats.occlusion_lost_px = int64_t(lost);
    stats.occlusion_lost_depth_px = int64_t(lost_depth);
    lost_depth_px_total_ += lost_depth;
    stats.occlusion_lost_share = culled_ids_.empty() ? 0.0 : double(lost) / culled_ids_.size();
    lost_px_total_ += lost;
    checked_px_total_ += culled_ids_.size();
  }

  // The totals into the summary, and a line on stderr.
  void summarize(const RenderArgs& args, const std::vector<FrameStats>& all,
                 nlohmann::json& summary) const {
    uint64_t lossy_frames = 0;
    double max_lost_share = 0.0;
    for (const FrameStats& f : all) {
      lossy_frames += f.occlusion_lost_px > 0;
      max_lost_share = std::max(max_lost_share, f.occlusion_lost_share);
    }
    const int frames = int(all.size());
    const double share = checked_px_total_ ? double(lost_px_total_) / double(checked_px_total_) : 0.0;
    summary["occlusion_lost_px_total"] = lost_px_total_;
    summary["occlusion_checked_px_total"] = checked_px_total_;
    summary["occlusion_lost_share"] = share;
    summary["occlusion_max_frame_lost_share"] = max_lost_share;
    summary["occlusion_frames_with_loss"] = lossy_frames;
    summary["occlusion_lost_depth_px_total"] = lost_depth_px_total_;
    summary["occlusion_lost_depth_share"] =
        checked_px_total_ ? double(lost_depth_px_total_) / double(checked_px_total_) : 0.0;
    std::fprintf(stderr,
                 "render: occlusion %s lost %llu of %llu pixels (%.6f%%) over %d frames; "
                 "worst frame %.6f%%, %llu frames with loss; id or depth differs: %llu pixels\n",
                 args.occlusion.c_str(), static_cast<unsigned long long>(lost_px_total_),
                 static_cast<unsigned long long>(checked_px_total_), 100.0 * share, frames,
                 100.0 * max_lost_share, static_cast<unsigned long long>(lossy_frames),
                 static_cast<unsigned long long>(lost_depth_px_total_));
  }

 private:
  std::vector<uint32_t> culled_ids_, unculled_ids_;
  std::vector<float> culled_depth_, unculled_depth_;
  uint64_t lost_px_total_ = 0, checked_px_total_ = 0, lost_depth_px_total_ = 0;
};

// What rendering the path gave: the recorded frames' statistics and the walk between them.
struct RenderedPath {
  std::vector<FrameStats> frames;
  uint64_t walk_frames = 0;
  int walk_steps = 1;
  double first_frame_ms = 0.0;  // from opening the package to the first recorded frame
  std::vector<std::string> load_errors;  // pages that failed to load, in order
  uint64_t soak_frames = 0, soak_intervals = 0, soak_peak_rss = 0;  // --soak-interval (frames
                                                                     // then logs none)
  uint64_t video_frames = 0;
  std::string video_error;  // why the video stopped (ffmpeg failed); the PNGs went on
};

// --video: each recorded frame, rendered settled (a film waits for its pages), goes to ffmpeg.
// A failure (a full disk) stops the video but not the PNGs; it is reported at the end.
void writeVideoFrame(VideoEncoder& video, const FrameImage& image, RenderedPath& rendered) {
  if (!rendered.video_error.empty()) return;
  try {
    video.write(image.rgba);
    ++rendered.video_frames;
  } catch (const std::runtime_error& e) {
    rendered.video_error = e.what();
    std::fprintf(stderr, "terawalk: error: %s\n", e.what());
  }
}

// Pages that failed to load (a checksum mismatch, a read error) are drawn from their coarser
// ancestors; each is said once on stderr, as it happens, so the frames are not silently wrong.
constexpr size_t kMostLoadErrorsPrinted = 10;

void reportLoadErrors(Walkthrough& walk, RenderedPath& rendered) {
  for (const std::string& message : walk.pager().takeLoadErrors()) {
    if (rendered.load_errors.size() < kMostLoadErrorsPrinted)
      std::fprintf(stderr, "terawalk: warning: %s; its clusters are drawn from coarser levels\n",
                   message.c_str());
    rendered.load_errors.push_back(message);
  }
}

RenderedPath renderPath(const RenderArgs& args, const GlobalOptions& global, Walkthrough& walk,
                        const CameraPath& path, const Aabb& bounds, Clock::time_point open_start,
                        OcclusionLossCheck& occlusion_check, VideoEncoder* video,
                        int frame_width, int frame_height, const StereoOptions& stereo) {
  Camera base;
  const double diagonal = glm::length(bounds.max - bounds.min);
  base.near_m = 0.05;
  base.far_m = std::max(100.0, 10.0 * diagonal);
  // A path of one key is a still (a BCF viewpoint): its frame is rendered until the cut settles,
  // with a far plane that reaches the model from wherever the camera stands.
  const bool still = path.keys.size() == 1;
  if (still)
    base.far_m = std::max(base.far_m, 2.0 * (glm::length(path.keys.front().camera.position -
                                                         0.5 * (bounds.min + bounds.max)) + diagonal));
  int frames = static_cast<int>(std::floor(path.durationS() * args.fps + 1e-9)) + 1;
  if (args.max_frames > 0) frames = std::min(frames, args.max_frames);
  RenderedPath rendered;
  // --walk-fps: steps per recorded frame, so the recorded frames keep their times exactly.
  rendered.walk_steps = std::max(1, int(std::lround(args.walk_fps / args.fps)));
  // A soak keeps no per-frame log: its intervals go to soak.csv as they close (soak_log.h).
  std::optional<SoakLog> soak;
  if (args.soak_interval_s > 0.0)
    soak.emplace(std::filesystem::path(args.out_dir) / "soak.csv", args.soak_interval_s);
  else
    rendered.frames.reserve(frames);
  const std::filesystem::path out_dir = args.out_dir;
  FrameImage image;
  std::vector<uint8_t> left, right;  // stereo: each eye's picture
  int eye_width = 0, eye_height = 0;
  stereoEyeSize(stereo.mode, frame_width, frame_height, eye_width, eye_height);
  const double aspect = double(eye_width) / double(eye_height);
  std::vector<uint32_t> ids;
  const double t0 = path.keys.front().time_s;
  std::unique_ptr<Progress> progress;
  if (video) {
    progress = makeCommandProgress(global);
    progress->beginStage("video", uint64_t(frames));
  }
  const Clock::time_point loop_start = Clock::now();
  for (int i = 0; i < frames; ++i) {
    if (args.max_seconds > 0.0 && msSince(loop_start) >= args.max_seconds * 1000.0) break;
    const double t = t0 + i / args.fps;
    // The camera between the previous recorded frame and this one, rendered and not recorded:
    // the pager, prefetch and occlusion see it move as in an interactive walkthrough.
    for (int step = 1; i > 0 && step < rendered.walk_steps; ++step) {
      const double walk_t = t0 + (i - 1 + double(step) / rendered.walk_steps) / args.fps;
      walk.renderFrame(path.sample(walk_t, base), walk_t);
      ++rendered.walk_frames;
    }
    const Camera camera = path.sample(t, base);
    FrameStats stats;
    if (stereo.mode == StereoMode::Off) {
      stats = still || video ? walk.renderSettled(camera, nullptr, 200, t) : walk.renderFrame(camera, t);
    } else {
      // Stills and films wait for the pages of the eyes' shared cut, then draw both eyes.
      if (still || video) walk.renderSettled(stereoCutCamera(camera, aspect, stereo), nullptr, 200, t);
      stats = walk.renderStereoFrame(camera, t, stereo, left, right);
    }
    stats.frame = uint64_t(i);  // the recorded sequence, as the PNG names count
    reportLoadErrors(walk, rendered);
    if (i == 0) rendered.first_frame_ms = msSince(open_start);
    if (args.png || video) {
      if (stereo.mode == StereoMode::Off) {
        walk.renderer().readColor(image.rgba, true);
        image.width = eye_width;
        image.height = eye_height;
      } else {
        composeStereo(stereo.mode, eye_width, eye_height, left, right, image.rgba);
        image.width = stereo.mode == StereoMode::SideBySide ? 2 * eye_width : eye_width;
        image.height = stereo.mode == StereoMode::TopBottom ? 2 * eye_height : eye_height;
      }
    }
    if (args.png) writeFramePngs(walk.renderer(), out_dir, uint64_t(i), image, ids);
    if (video) {
      writeVideoFrame(*video, image, rendered);
      if (!rendered.video_error.empty() && !args.png) break;
      if (progress) progress->update(uint64_t(i + 1));
    }
    if (args.check_occlusion) occlusion_check.check(walk, stats);
    if (soak)
      soak->add(stats);
    else
      rendered.frames.push_back(stats);
    if (!global.quiet && !video && (i % 30 == 0 || i + 1 == frames))
      std::fprintf(stderr, "render: frame %d/%d  %.1f ms  %llu triangles\n", i + 1, frames,
                   stats.frame_ms, static_cast<unsigned long long>(stats.triangles_drawn));
  }
  if (progress) progress->endStage();
  if (soak) {
    soak->finish();
    rendered.soak_frames = soak->frames();
    rendered.soak_intervals = soak->intervals();
    rendered.soak_peak_rss = soak->peakRssBytes();
  }
  return rendered;
}

struct RenderTimes {
  double context_ms = 0.0;
  double open_ms = 0.0;
};

nlohmann::json renderSummary(const RenderArgs& args, const WalkthroughOptions& options,
                             const EglContext& context, const Walkthrough& walk,
                             const RenderedPath& rendered, const RenderTimes& times) {
  const std::vector<FrameStats>& all = rendered.frames;
  const int frames = int(all.size());
  int width = 0, height = 0;  // the frame's (in stereo, both eyes')
  parseImageSize(args.size, "--size", width, height);
  const double context_ms = times.context_ms, open_ms = times.open_ms;
  const double first_frame_ms = rendered.first_frame_ms;
  const uint64_t walk_frames = rendered.walk_frames;
  const int walk_steps = rendered.walk_steps;
  uint64_t peak_rss = rendered.soak_peak_rss, fallback_frames = 0, occlusion_culled_total = 0,
           cell_frames = 0;
  for (const FrameStats& f : all) {
    peak_rss = std::max(peak_rss, f.rss_bytes);
    fallback_frames += f.ancestor_fallbacks > 0;
    occlusion_culled_total += f.occlusion_culled;
    cell_frames += f.view_cell >= 0;
  }
  return {
      {"package", args.file},
      {"mode", args.reference ? "reference" : "lod"},
      {"width", width},
      {"height", height},
      {"frames", rendered.soak_intervals > 0 ? int64_t(rendered.soak_frames) : int64_t(frames)},
      {"soak_intervals", rendered.soak_intervals},
      {"walk_fps", walk_steps * args.fps},
      {"walk_frames", walk_frames},
      {"tau_px", args.tau_px},
      {"context_ms", context_ms},
      {"open_ms", open_ms},
      {"first_frame_ms", first_frame_ms},
      {"median_frame_ms", medianOf(all, [](const FrameStats& f) { return f.frame_ms; })},
      {"median_gpu_ms", medianOf(all, [](const FrameStats& f) { return f.gpu_ms; })},
      {"median_finish_ms", medianOf(all, [](const FrameStats& f) { return f.finish_ms; })},
      {"median_cpu_cut_ms", medianOf(all, [](const FrameStats& f) { return f.cpu_cut_ms; })},
      {"median_triangles", medianOf(all, [](const FrameStats& f) { return f.triangles_drawn; })},
      // Mesh clusters and run-time parametric meshes together: what the frame rasterized.
      {"median_all_triangles",
       medianOf(all, [](const FrameStats& f) { return f.triangles_drawn + f.parametric_triangles; })},
      {"median_xray_triangles",
       medianOf(all, [](const FrameStats& f) { return f.xray_triangles; })},
      {"max_triangles",
       all.empty() ? 0 : std::max_element(all.begin(), all.end(), [](auto& a, auto& b) {
                           return a.triangles_drawn < b.triangles_drawn;
                         })->triangles_drawn},
      {"frames_with_ancestor_fallback", fallback_frames},
      {"occlusion", args.reference ? "off" : args.occlusion},
      {"parametrics", parametricModeName(walk.parametrics())},
      {"median_parametric_clusters_drawn",
       medianOf(all, [](const FrameStats& f) { return f.parametric_clusters_drawn; })},
      {"median_parametric_instances_drawn",
       medianOf(all, [](const FrameStats& f) { return f.parametric_instances_drawn; })},
      {"median_parametric_triangles",
       medianOf(all, [](const FrameStats& f) { return f.parametric_triangles; })},
      {"median_parametric_skipped",
       medianOf(all, [](const FrameStats& f) { return f.parametric_skipped; })},
      {"hzb_read_width_px", args.hzb_read_width},
      {"hzb_final_rebuild", args.hzb_final_rebuild},
      {"hzb_build", args.hzb_build},
      {"hzb_span_texels", args.hzb_span},
      {"hzb_split_px", args.hzb_split},
      {"occluders", args.occluders},
      {"occlusion_culled_total", occlusion_culled_total},
      {"median_occlusion_culled",
       medianOf(all, [](const FrameStats& f) { return f.occlusion_culled; })},
      {"median_pass1_clusters", medianOf(all, [](const FrameStats& f) { return f.pass1_clusters; })},
      {"median_pass2_clusters", medianOf(all, [](const FrameStats& f) { return f.pass2_clusters; })},
      {"median_occluders_drawn",
       medianOf(all, [](const FrameStats& f) { return f.occluders_drawn; })},
      {"median_hzb_build_ms", medianOf(all, [](const FrameStats& f) { return f.hzb_build_ms; })},
      {"median_hzb_test_ms", medianOf(all, [](const FrameStats& f) { return f.hzb_test_ms; })},
      {"frames_in_view_cell", cell_frames},
      {"page_load_errors", rendered.load_errors.size()},
      {"peak_rss_bytes", peak_rss},
      {"gpu_budget_bytes", options.pager.gpu_budget_bytes},
      {"host_budget_bytes", options.pager.host_budget_bytes},
      {"stereo", args.stereo.mode},
      {"eye_width", options.width},
      {"eye_height", options.height},
      {"video", args.video},
      {"video_frames", rendered.video_frames},
      {"ocean", args.environment.ocean},
      {"sky", args.environment.sky},
      {"median_ocean_triangles", medianOf(all, [](const FrameStats& f) { return f.ocean_triangles; })},
      {"median_ocean_cpu_ms", medianOf(all, [](const FrameStats& f) { return f.ocean_cpu_ms; })},
      {"renderer", context.renderer()},
  };
}

void writeRenderOutputs(const std::filesystem::path& out_dir, const RenderedPath& rendered,
                        const nlohmann::json& summary) {
  if (rendered.soak_intervals == 0) {
    writeFrameStatsCsv(rendered.frames, out_dir / "frames.csv");
    writeFrameStatsJson(rendered.frames, out_dir / "frames.json");
  }
  std::FILE* f = std::fopen((out_dir / "summary.json").string().c_str(), "w");
  if (!f) throw std::runtime_error((out_dir / "summary.json").string() + ": cannot write");
  const std::string text = summary.dump(1) + "\n";
  std::fwrite(text.data(), 1, text.size(), f);
  std::fclose(f);
}

// Steps: the GL context, the walkthrough over the package, the path rendered frame by frame,
// the summary printed and, with --out, written beside the frames' statistics.
void runRender(const RenderArgs& args, const GlobalOptions& global) {
  int width = 0, height = 0;
  parseImageSize(args.size, "--size", width, height);
  validateArgs(args);
  const StereoOptions stereo = renderStereoOptions(args, width, height);
  if (!args.out_dir.empty()) std::filesystem::create_directories(args.out_dir);

  RenderTimes times;
  const auto start = Clock::now();
  EglContext context;
  times.context_ms = msSince(start);
  // In stereo the walkthrough draws one eye at a time, at the eye's size.
  int eye_width = 0, eye_height = 0;
  stereoEyeSize(stereo.mode, width, height, eye_width, eye_height);
  const WalkthroughOptions options = walkthroughOptions(args, eye_width, eye_height);
  const auto open_start = Clock::now();
  Walkthrough walk(args.file, options);
  times.open_ms = msSince(open_start);
  // A BCF viewpoint first (it resets the objects' states), then the options on top of it.
  std::optional<ViewpointApplied> viewpoint;
  if (!args.viewpoint.empty())
    viewpoint = applyViewpointOption(args.viewpoint, walk.package(), walk.objectStates(), Camera{});
  if (!args.changes.empty()) {
    const ChangeSet changes = readChangeSet(args.changes);
    applyChangeStates(changes, walk.package(), walk.objectStates());
    walk.setMovedObjects(movedMeshes(changes, walk.package()));
  }
  applyReviewState(args.state, walk.package(), walk.objectStates());
  if (const auto environment = environmentOptions(args.environment, 0.5 * (walk.worldMin() + walk.worldMax())))
    walk.setEnvironment(*environment);
  walk.setSections(withReviewSectionPlanes(viewpoint ? viewpoint->sections : std::vector<SectionPlane>{},
                                           args.state));

  Aabb bounds;
  bounds.add(walk.worldMin());
  bounds.add(walk.worldMax());
  CameraPath path;
  if (viewpoint && !hasPathSource(args)) {
    if (!viewpoint->has_camera)
      throw std::runtime_error(args.viewpoint + ": the viewpoint has no camera; give a path");
    path.keys.push_back({0.0, viewpoint->camera});  // a still, rendered settled
  } else {
    path = cameraPath(args, bounds);
  }
  OcclusionLossCheck occlusion_check;
  std::optional<VideoEncoder> video;
  if (!args.video.empty()) video.emplace(args.video, width, height, args.fps);
  RenderedPath rendered = renderPath(args, global, walk, path, bounds, open_start, occlusion_check,
                                     video ? &*video : nullptr, width, height, stereo);
  if (video && rendered.video_error.empty()) {
    try {
      video->finish();
    } catch (const std::runtime_error& e) {
      rendered.video_error = e.what();
    }
  }
  nlohmann::json summary = renderSummary(args, options, context, walk, rendered, times);
  if (args.check_occlusion) occlusion_check.summarize(args, rendered.frames, summary);
  if (!args.out_dir.empty()) writeRenderOutputs(args.out_dir, rendered, summary);
  std::printf("%s\n", summary.dump(1).c_str());
  if (!rendered.video_error.empty())
    throw std::runtime_error(rendered.video_error + (args.png ? "; every frame was still written as PNG to " +
                                                                    args.out_dir
                                                              : ""));
  // The frames and statistics are written; the exit status still says they are not the package's.
  if (!rendered.load_errors.empty())
    throw std::runtime_error(std::to_string(rendered.load_errors.size()) +
                             " pages failed to load and were drawn from coarser levels (first: " +
                             rendered.load_errors.front() + ")");
}

}  // namespace

void registerRenderCommand(CLI::App& app, const GlobalOptions& global) {
  auto args = std::make_shared<RenderArgs>();
  CLI::App* cmd = app.add_subcommand(
      "render", "Render a camera path headless (EGL, no X, no GPU needed); write stats and frames");
  cmd->add_option("file", args->file, "Package (.twk)")->required()->check(CLI::ExistingFile);
  cmd->add_option("--path", args->path_file, "Camera path file (docs/runtime.md)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--orbit", args->orbit_frames, "Generate an orbit around the model, N frames");
  cmd->add_option("--flythrough", args->flythrough_frames, "Generate a fly-through, N frames");
  cmd->add_option("--random-walk", args->random_walk_frames,
                  "Generate a random walk, N frames: teleports, fast flights, turns in place and "
                  "walks (a soak test's path; docs/runtime.md)");
  cmd->add_option("--seed", args->seed, "Seed of --random-walk")->capture_default_str();
  cmd->add_option("--max-seconds", args->max_seconds,
                  "Stop recording after this many seconds of wall time (the frames so far are "
                  "kept and written)");
  cmd->add_option("--soak-interval", args->soak_interval_s,
                  "Soak: keep no per-frame log; write OUT/soak.csv, one row of memory, pager "
                  "queues, evictions and frame times per this many seconds of wall time");
  cmd->add_option("--save-path", args->save_path, "Write the (generated) camera path here");
  cmd->add_option("--size", args->size, "Image size WIDTHxHEIGHT")->capture_default_str();
  cmd->add_option("--out", args->out_dir, "Directory for frames.csv, frames.json, summary.json");
  cmd->add_flag("--png", args->png, "Also write frame_NNNNN.png and ids_NNNNN.png");
  cmd->add_option("--fps", args->fps, "Path sampling rate, frames per path second")
      ->capture_default_str();
  cmd->add_option("--walk-fps", args->walk_fps,
                  "Also render the path between recorded frames at this rate, without recording "
                  "them (rounded to a whole number of steps per frame): paging and occlusion see "
                  "the camera move as in an interactive walkthrough");
  cmd->add_option("--max-frames", args->max_frames, "Stop after this many recorded frames")
      ->check(CLI::Range(1, 1000000000));
  cmd->add_option("--tau", args->tau_px, "Screen-space error threshold, pixels")
      ->capture_default_str();
  cmd->add_option("--min-feature-px", args->min_feature_px,
                  "Cull clusters smaller than this on screen, pixels")
      ->capture_default_str();
  cmd->add_option("--target-fps", args->target_fps, "Adapt tau to hold this frame rate");
  cmd->add_option("--gpu-budget", args->gpu_budget, "GPU geometry pool size")->capture_default_str();
  cmd->add_option("--host-budget", args->host_budget, "Host staging for decoded pages")
      ->capture_default_str();
  cmd->add_option("--upload-mb", args->upload_mb, "GPU upload cap per frame, MiB")
      ->capture_default_str();
  cmd->add_option("--loader-threads", args->loader_threads, "Page loader threads")
      ->capture_default_str();
  cmd->add_option("--evict-after", args->evict_after,
                  "Frames a page must go unused before it may be evicted")
      ->capture_default_str();
  cmd->add_flag("--reference", args->reference,
                "Brute force: every full-resolution triangle, no LOD, no culling (parametrics "
                "tessellated at the preprocessor's 2 mm unless --parametrics or "
                "--parametric-tolerance say otherwise)");
  cmd->add_flag("--no-prefetch", args->no_prefetch, "Do not prefetch along the camera's velocity");
  cmd->add_flag("--two-sided-meshes", args->two_sided_meshes,
                "Draw both sides of closed mesh objects (no back-face culling)");
  cmd->add_flag("--no-frustum", args->no_frustum,
                "No frustum culling: LOD alone (benchmarks measure each technique's share)");
  cmd->add_option("--parametrics", args->parametrics,
                  "Parametric objects: impostor (ray-cast in the fragment shader), tessellated "
                  "(meshes built by distance at run time), off (not drawn), auto (tessellated "
                  "on llvmpipe, where it measured faster; impostor on GPUs)")
      ->check(CLI::IsMember({"impostor", "tessellated", "off", "auto"}))
      ->capture_default_str();
  cmd->add_option("--parametric-tolerance", args->parametric_tolerance_m,
                  "tessellated (and extrusions, revolutions): one fixed chordal tolerance in "
                  "metres instead of distance buckets (fine references)")
      ->check(CLI::Range(0.0, 10.0));
  cmd->add_option("--occlusion", args->occlusion,
                  "Occlusion culling: off, hzb (view-cell occluders + two-pass HZB), pvs "
                  "(sampled visible sets)")
      ->check(CLI::IsMember({"off", "hzb", "pvs"}))
      ->capture_default_str();
  cmd->add_option("--hzb-read-width", args->hzb_read_width,
                  "hzb: read the pyramid back from the first level at most this wide, pixels")
      ->check(CLI::Range(1, 1 << 16))
      ->capture_default_str();
  cmd->add_option("--hzb-build", args->hzb_build,
                  "Where the HZB is built: auto (CPU on llvmpipe), gpu (compute shader), cpu")
      ->capture_default_str();
  cmd->add_option("--hzb-span", args->hzb_span,
                  "Texels per axis a box may cover at its HZB test level (finer: more culled)")
      ->capture_default_str();
  cmd->add_option("--hzb-split", args->hzb_split,
                  "hzb: a box not hidden as a whole is halved while it spans at least this many "
                  "pixels, and hidden when its halves are (0: never)")
      ->check(CLI::Range(0, 1 << 16))
      ->capture_default_str();
  cmd->add_option("--occluders", args->occluders,
                  "Use of the view cell's occluder set in hzb mode: seed (pass 1 when nothing was "
                  "visible before), always, coarse (own LOD, pushed back; not conservative), none")
      ->capture_default_str();
  cmd->add_flag("--hzb-final-rebuild,!--no-hzb-final-rebuild", args->hzb_final_rebuild,
                "hzb: next frame's visible set from a second pyramid of the final depth (default)");
  addReviewStateOptions(*cmd, args->state);
  addEnvironmentOptions(*cmd, args->environment);
  addStereoOptions(*cmd, args->stereo,
                   "Two eyes: off, side-by-side, top-bottom, anaglyph (red-cyan); --size is the "
                   "whole frame (quad-buffered: in the viewer only)");
  cmd->add_option("--video", args->video,
                  "Write the recorded frames as a video at --fps (FILE.mp4 or .mkv: H.264; .avi: "
                  "MJPEG), each frame rendered settled; needs ffmpeg");
  cmd->add_option("--changes", args->changes,
                  "Draw a review's change set (model.changes.json): moved objects at their new "
                  "placement, hidden and recoloured ones")
      ->check(CLI::ExistingFile);
  cmd->add_option("--viewpoint", args->viewpoint,
                  "Render from a BCF viewpoint: FILE.bcfzip or FILE.bcfzip#N (the Nth viewpoint as "
                  "`terawalk bcf list` numbers them; default 1), with its selection, visibility, "
                  "colours and clipping planes");
  cmd->add_flag("--check-occlusion", args->check_occlusion,
                "Draw each frame's cut again without occlusion culling and count the pixels "
                "whose object id differs (occlusion_lost_px)");
  cmd->callback([args, &global] { runRender(*args, global); });
}

}  // namespace tw
