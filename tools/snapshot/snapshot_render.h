// Ray-cast shading of a SnapshotScene into an RGB image, and PNG output.
//
// One primary ray per sample; shading is base colour x (hemisphere ambient + headlight + sun),
// with an optional sun shadow ray, light distance haze, and a screen-space sky gradient behind.
// Meant to make models readable at a glance (reviews, docs, regression pictures), not to be
// physically based.
#pragma once

#include <cstdint>
#include <filesystem>
#include <vector>

#include "progress.h"
#include "snapshot_builder.h"
#include "snapshot_camera.h"

namespace tw {

enum class SnapshotColorBy {
  Auto,    // scene colours, unless every object has the same one: then a colour per object
  Scene,   // object colour, else vertex colours, else layer colour
  Object,  // a distinct pastel per object id (shows part boundaries in uncoloured CAD)
};

struct SnapshotRenderOptions {
  uint32_t width = 1280;   // pixels
  uint32_t height = 720;   // pixels
  uint32_t samples = 2;    // per axis: samples x samples primary rays per pixel, 1..8
  bool shadows = true;     // one sun shadow ray per hit sample
  SnapshotColorBy color_by = SnapshotColorBy::Auto;
};

// Tightly packed 8-bit RGB, rows top to bottom.
struct SnapshotImage {
  uint32_t width = 0;
  uint32_t height = 0;
  std::vector<uint8_t> rgb;  // width * height * 3
};

struct SnapshotRenderResult {
  SnapshotImage image;
  uint64_t hit_pixels = 0;  // pixels where at least one sample hit geometry
  uint64_t rays = 0;        // primary plus shadow rays cast
};

// The background at a pixel row (0 = top), linear RGB: what a pixel with no hit shows. Exposed
// so tests can tell sky from geometry.
glm::vec3 snapshotSkyColor(double row_fraction);

// Renders rows in parallel (TBB). Reports rows done to `progress` (stage "render") and stops
// with std::runtime_error("cancelled") when it is cancelled. Throws std::invalid_argument for a
// zero or over-large (> 16384) image size. `scene.rt` must be committed.
SnapshotRenderResult renderSnapshot(const SnapshotScene& scene, const SnapshotCamera& camera,
                                    const SnapshotRenderOptions& options, Progress* progress = nullptr);

// Writes the image as PNG, through a temporary file renamed into place. Throws
// std::runtime_error naming the path on failure.
void writePng(const SnapshotImage& image, const std::filesystem::path& path);

}  // namespace tw
