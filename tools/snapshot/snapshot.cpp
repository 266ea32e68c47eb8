// Read -> build -> camera -> render -> PNG, with timings.
#include "snapshot.h"

#include <chrono>

#include "scene_io.h"

namespace tw {

namespace {

double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

SnapshotCamera chooseSnapshotCamera(const Aabb& bounds, const SnapshotOptions& options) {
  const double aspect = double(std::max(options.render.width, 1u)) / double(std::max(options.render.height, 1u));
  SnapshotCamera camera = autoOutsideCamera(bounds, aspect, options.up, options.fov_y_deg, options.azimuth_deg,
                                            options.elevation_deg);
  if (options.target) {
    // Keep the automatic distance and direction but look at the requested point.
    camera.eye += *options.target - camera.target;
    camera.target = *options.target;
  }
  if (options.eye) camera.eye = *options.eye;
  camera.up = options.up;
  camera.fov_y_deg = options.fov_y_deg;
  return camera;
}

SnapshotReport renderSceneSnapshot(const SnapshotScene& scene, const std::filesystem::path& png,
                                   const SnapshotOptions& options, Progress* progress, SnapshotImage* image_out) {
  SnapshotReport report;
  report.objects = scene.objects;
  report.triangles = scene.triangles;
  report.skipped_parts = scene.skipped_parts;
  report.bounds = scene.bounds;
  report.camera = chooseSnapshotCamera(scene.bounds, options);
  if (!options.eye && !options.target) {
    const double aspect = double(std::max(options.render.width, 1u)) / double(std::max(options.render.height, 1u));
    // Twice: moving closer changes the perspective, and with it the silhouette a little.
    for (int i = 0; i < 2; ++i) report.camera = fitCameraToScene(*scene.rt, report.camera, aspect);
  }
  auto start = std::chrono::steady_clock::now();
  SnapshotRenderResult result = renderSnapshot(scene, report.camera, options.render, progress);
  report.render_seconds = secondsSince(start);
  report.hit_pixels = result.hit_pixels;
  report.rays = result.rays;
  if (!png.empty()) writePng(result.image, png);
  if (image_out) *image_out = std::move(result.image);
  return report;
}

SnapshotReport snapshotFile(const std::filesystem::path& scene_path, const std::filesystem::path& png,
                            const SnapshotOptions& options, Progress* progress) {
  auto start = std::chrono::steady_clock::now();
  SnapshotBuilder builder(options.build);
  ReadOptions read_options;
  read_options.progress = progress;
  read_options.up = options.file_up;
  readScene(scene_path, builder, read_options);
  const double read_seconds = secondsSince(start);

  start = std::chrono::steady_clock::now();
  beginStage(progress, "build BVH", 0);
  SnapshotScene scene = builder.finish();
  endStage(progress);
  const double bvh_seconds = secondsSince(start);

  SnapshotReport report = renderSceneSnapshot(scene, png, options, progress);
  report.read_seconds = read_seconds;
  report.bvh_seconds = bvh_seconds;
  return report;
}

}  // namespace tw
