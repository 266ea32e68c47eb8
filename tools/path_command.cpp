// `terawalk path smooth IN.path -o OUT.path`: a recorded camera path made steady for a film
// (camera_path.h, smoothCameraPath): control keys every --interval seconds, each the mean of the
// walk around it, and a Catmull-Rom spline through them sampled --fps times a second. The
// viewer's Path panel does the same for the path it plays.
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>

#include "camera_path.h"
#include "command.h"

namespace tw {
namespace {

struct SmoothArgs {
  std::string in, out;
  double interval_s = 1.0;
  double fps = 30.0;
};

void runSmooth(const SmoothArgs& args, const GlobalOptions& global) {
  if (!(args.interval_s > 0.0 && args.interval_s <= 3600.0))
    throw std::runtime_error("--interval must be above 0 and at most 3600 s");
  if (!(args.fps > 0.0 && args.fps <= 1000.0)) throw std::runtime_error("--fps must be above 0 and at most 1000");
  const CameraPath recorded = readCameraPath(args.in);
  if (recorded.keys.empty()) throw std::runtime_error(args.in + ": the path has no key frames");
  const CameraPath smooth = smoothCameraPath(recorded, args.interval_s, args.fps);
  writeCameraPath(smooth, args.out);
  if (!global.quiet)
    std::printf("path: %zu keys over %.2f s -> %zu keys at %g a second, control keys every %g s: %s\n",
                recorded.keys.size(), recorded.durationS(), smooth.keys.size(), args.fps, args.interval_s,
                args.out.c_str());
}

}  // namespace

void registerPathCommand(CLI::App& app, const GlobalOptions& global) {
  CLI::App* path = app.add_subcommand("path", "Work on camera paths (docs/runtime.md, \"Camera paths\")");
  path->require_subcommand(1);
  auto args = std::make_shared<SmoothArgs>();
  CLI::App* smooth = path->add_subcommand(
      "smooth", "Write a steadier copy of a path: a Catmull-Rom spline through its walk's means");
  smooth->add_option("in", args->in, "Camera path (a recorded one)")->required()->check(CLI::ExistingFile);
  smooth->add_option("-o,--out", args->out, "Smoothed path")->required();
  smooth->add_option("--interval", args->interval_s, "Seconds between control keys")->capture_default_str();
  smooth->add_option("--fps", args->fps, "Keys a second written")->capture_default_str();
  smooth->callback([args, &global] { runSmooth(*args, global); });
}

}  // namespace tw
