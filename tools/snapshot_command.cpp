// `terawalk snapshot FILE --out img.png`: a CPU ray-cast picture of any scene (tools/snapshot/).
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>

#include "command.h"
#include "scene_io.h"
#include "snapshot.h"

namespace tw {
namespace {

struct SnapshotCommandOptions {
  std::string file;
  std::string out;
  uint32_t width = 1280;
  uint32_t height = 720;
  std::string eye;
  std::string target;
  std::string up = "auto";
  std::string auto_view = "outside";
  std::string color_by = "auto";
  double fov_deg = 45.0;
  double azimuth_deg = 35.0;
  double elevation_deg = 30.0;
  float tolerance = kDefaultChordalTolerance;
  uint32_t samples = 2;
  bool no_shadows = false;
};

}  // namespace

void registerSnapshotCommand(CLI::App& app, const GlobalOptions& global) {
  auto o = std::make_shared<SnapshotCommandOptions>();
  CLI::App* cmd = app.add_subcommand("snapshot", "Render a CPU ray-cast picture (PNG) of a scene file");
  cmd->add_option("file", o->file, "Scene file (.tws, .ply, .obj, .stl, .gltf, .glb, .stp, .step, .ifc)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("-o,--out", o->out, "Output PNG")->required();
  cmd->add_option("--width", o->width, "Image width in pixels")->check(CLI::Range(1u, 16384u));
  cmd->add_option("--height", o->height, "Image height in pixels")->check(CLI::Range(1u, 16384u));
  cmd->add_option("--eye", o->eye, "Camera position x,y,z (world coordinates); default: automatic");
  cmd->add_option("--target", o->target, "Point at the image centre x,y,z; default: the model's centre");
  cmd->add_option("--up", o->up,
                  "The file's up axis: y or z (default: y for glTF, z for everything else); the "
                  "scene is turned Z up as it is read")
      ->check(CLI::IsMember({"auto", "y", "z"}));
  cmd->add_option("--auto", o->auto_view, "Automatic camera when --eye is not given")
      ->check(CLI::IsMember({"outside"}));
  cmd->add_option("--azimuth", o->azimuth_deg, "Automatic view: degrees right of the front view");
  cmd->add_option("--elevation", o->elevation_deg, "Automatic view: degrees above the horizon")
      ->check(CLI::Range(-89.0, 89.0));
  cmd->add_option("--fov", o->fov_deg, "Vertical field of view in degrees")->check(CLI::Range(1.0, 170.0));
  cmd->add_option("--tolerance", o->tolerance, "Chordal tolerance for tessellation (scene units)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--samples", o->samples, "Supersampling per axis (N x N rays per pixel)")
      ->check(CLI::Range(1u, 8u));
  cmd->add_option("--color-by", o->color_by,
                  "auto (scene colours unless all alike), scene, or object (a colour per object)")
      ->check(CLI::IsMember({"auto", "scene", "object"}));
  cmd->add_flag("--no-shadows", o->no_shadows, "Skip the sun shadow rays (faster)");

  cmd->callback([o, &global] {
    SnapshotOptions options;
    options.build.tolerance = o->tolerance;
    options.render.width = o->width;
    options.render.height = o->height;
    options.render.samples = o->samples;
    options.render.shadows = !o->no_shadows;
    options.render.color_by = o->color_by == "scene"    ? SnapshotColorBy::Scene
                              : o->color_by == "object" ? SnapshotColorBy::Object
                                                        : SnapshotColorBy::Auto;
    options.file_up = parseUpAxis(o->up);
    if (!o->eye.empty()) options.eye = parseVec3(o->eye);
    if (!o->target.empty()) options.target = parseVec3(o->target);
    options.fov_y_deg = o->fov_deg;
    options.azimuth_deg = o->azimuth_deg;
    options.elevation_deg = o->elevation_deg;

    auto progress = makeCommandProgress(global);
    SnapshotReport r = snapshotFile(o->file, o->out, options, progress.get());
    progress.reset();  // finish any progress line before the summary
    const double pixels = double(o->width) * double(o->height);
    const std::string skipped = r.skipped_parts ? ", " + std::to_string(r.skipped_parts) + " parts skipped" : "";
    std::printf(
        "snapshot: %llu triangles, %llu object%s%s; read %.2f s, BVH %.2f s, render %.2f s (%ux%u, %u spp, %.0f%% "
        "covered) -> %s\n",
        static_cast<unsigned long long>(r.triangles), static_cast<unsigned long long>(r.objects), r.objects == 1 ? "" : "s",
        skipped.c_str(), r.read_seconds,
        r.bvh_seconds, r.render_seconds, o->width, o->height, o->samples * o->samples,
        100.0 * double(r.hit_pixels) / pixels, o->out.c_str());
  });
}

}  // namespace tw
