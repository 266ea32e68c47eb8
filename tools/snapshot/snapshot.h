// `terawalk snapshot` as a library: read any scene file, build an Embree scene, choose a camera,
// render, write a PNG. Each step is also usable on its own (snapshot_builder.h,
// snapshot_camera.h, snapshot_render.h); this file only strings them together and times them.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>

#include "progress.h"
#include "snapshot_builder.h"
#include "snapshot_camera.h"
#include "snapshot_render.h"
#include "up_axis.h"

namespace tw {

struct SnapshotOptions {
  SnapshotBuildOptions build;
  SnapshotRenderOptions render;
  // Explicit camera, world coordinates. A missing target is the bounds' centre; a missing eye
  // comes from the automatic outside view (framed for the whole model).
  std::optional<glm::dvec3> eye;
  std::optional<glm::dvec3> target;
  glm::dvec3 up{0.0, 0.0, 1.0};  // the camera's; scenes are read Z up
  UpAxis file_up = UpAxis::Auto;  // the file's up axis (ReadOptions::up)
  double fov_y_deg = 45.0;
  double azimuth_deg = 35.0;    // automatic view only
  double elevation_deg = 30.0;  // automatic view only
};

struct SnapshotReport {
  uint64_t objects = 0;
  uint64_t triangles = 0;
  uint64_t skipped_parts = 0;
  double read_seconds = 0.0;   // reading, tessellating and uploading geometry
  double bvh_seconds = 0.0;    // Embree BVH build
  double render_seconds = 0.0;
  uint64_t hit_pixels = 0;
  uint64_t rays = 0;
  SnapshotCamera camera;  // the camera actually used
  Aabb bounds;
};

// The camera `options` asks for over a model with these bounds (image aspect from the render
// options), before any fit to the geometry.
SnapshotCamera chooseSnapshotCamera(const Aabb& bounds, const SnapshotOptions& options);

// Renders an already built scene and writes `png` if it is not empty. With neither eye nor
// target given, the automatic camera is tightened on the geometry (fitCameraToScene).
SnapshotReport renderSceneSnapshot(const SnapshotScene& scene, const std::filesystem::path& png,
                                   const SnapshotOptions& options, Progress* progress = nullptr,
                                   SnapshotImage* image_out = nullptr);

// The whole command: readScene(scene_path) -> SnapshotBuilder -> render -> PNG. Throws
// FormatError for unreadable input and std::runtime_error for Embree or PNG failures.
SnapshotReport snapshotFile(const std::filesystem::path& scene_path, const std::filesystem::path& png,
                            const SnapshotOptions& options, Progress* progress = nullptr);

}  // namespace tw
