// Per-frame statistics of the walkthrough, and their CSV / JSON forms (`terawalk render` writes
// both for every frame; the viewer shows them live). One struct so the headless and windowed
// paths report the same thing.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace tw {

struct FrameStats {
  uint64_t frame = 0;
  double time_s = 0.0;         // path time of the frame
  double frame_ms = 0.0;       // wall time of the whole frame (CPU + waiting for the GPU)
  double cpu_cut_ms = 0.0;     // LOD traversal (select + prefetch)
  double gpu_ms = 0.0;         // draw time from GL timer queries
  // Headless: wall time spent in the frame's final glFinish, the drawing still to do after the
  // draw calls returned. On llvmpipe vertex processing and binning run inside the draw calls,
  // outside both this and gpu_ms (docs/runtime.md, "Frame time on llvmpipe"). 0 in the window.
  double finish_ms = 0.0;
  double tau_px = 0.0;         // the tau in use (changes with --target-fps)
  uint32_t nodes_visited = 0;  // groups visited + clusters tested
  uint32_t nodes_drawn = 0;    // mesh clusters drawn
  uint64_t triangles_drawn = 0;
  uint64_t two_sided_triangles = 0;  // of triangles_drawn: without back-face culling
  uint64_t xray_triangles = 0;  // mesh triangles drawn again ghosted (X-ray pass)
  uint32_t culled_frustum = 0;
  uint32_t culled_small = 0;
  // Parametric clusters of the cut (parametric_renderer.h): drawn, or not drawn (mode off).
  uint32_t parametric_skipped = 0;          // visible parametric clusters not drawn: 0 unless off
  uint32_t parametric_clusters_drawn = 0;
  uint64_t parametric_instances_drawn = 0;  // submitted, before per-instance small-feature culling
  uint64_t parametric_triangles = 0;        // of run-time meshes (tessellated mode, extrusions...)
  uint64_t parametric_two_sided_triangles = 0;  // of parametric_triangles: no back-face culling
  uint64_t parametric_thin_instances = 0;   // of parametric_instances_drawn: ribbons and points
  double parametric_cpu_ms = 0.0;           // CPU time to submit them (and build new meshes)
  // hzb, tessellated mode: instances of drawn clusters not drawn because their own box was
  // hidden (parametric_instance_meshes.h, "Occlusion").
  uint64_t parametric_occluded = 0;
  // Tessellated mode: instances of drawn clusters tested one by one; the others were too small
  // at their distance to show (InstanceScaleIndex) and never looked at.
  uint64_t parametric_instances_tested = 0;
  uint32_t pages_resident = 0;
  uint32_t pages_requested = 0;     // in the queue at the end of the frame
  uint32_t pages_loading = 0;       // being read and decoded by a loader thread then
  uint32_t pages_ready = 0;         // decoded, waiting for their upload (or for pool space)
  uint32_t pages_waiting_for_pool = 0;  // this frame: ready pages that found no room in the pool
  uint32_t pages_loaded = 0;        // uploaded this frame
  uint32_t pages_evicted = 0;
  uint64_t bytes_uploaded = 0;
  uint32_t ancestor_fallbacks = 0;  // groups drawn coarser because pages were missing
  uint64_t page_load_errors = 0;    // pages that failed to load so far (never retried; their
                                    // clusters are drawn from coarser levels)
  uint64_t gpu_bytes_used = 0;
  uint64_t host_bytes_used = 0;
  uint64_t rss_bytes = 0;
  // Occlusion (runtime/occlusion_culler.h; zero or -1 in mode off and in the reference).
  uint32_t occlusion_culled = 0;  // clusters of the cut not drawn because of occlusion
  uint32_t occluders_drawn = 0;   // hzb: view-cell occluder clusters drawn into the HZB depth
  uint32_t pass1_clusters = 0;    // hzb: clusters drawn first (visible last frame)
  uint32_t pass2_clusters = 0;    // hzb: clusters drawn after the HZB test
  double hzb_build_ms = 0.0;      // hzb: both pyramid builds and read-backs
  double hzb_test_ms = 0.0;       // hzb: CPU box tests of both passes
  int64_t view_cell = -1;         // grid index of the eye's stored view cell, -1 for none
  // `terawalk render --check-occlusion`: pixels whose object id differs from the same cut drawn
  // without occlusion culling, and their share of the image; -1 when not checked. The depth
  // variant also counts pixels whose depth differs (same id): a model made of one object (an
  // all-mesh PLY) shows a loss only there.
  int64_t occlusion_lost_px = -1;
  double occlusion_lost_share = -1.0;
  int64_t occlusion_lost_depth_px = -1;  // id or depth differs
  // The setting (environment/environment_pass.h): the ocean's triangles, and the CPU time to
  // build and upload its mesh; 0 without an ocean.
  uint64_t ocean_triangles = 0;
  double ocean_cpu_ms = 0.0;
};

// Resident set size of this process now, from /proc/self/statm (0 if unavailable).
uint64_t currentRssBytes();

std::string frameStatsCsvHeader();
std::string frameStatsCsvRow(const FrameStats& stats);
// Writes `frames` as CSV (header + one row per frame) and as JSON ({"frames": [...]}).
// Throws std::runtime_error naming the file on I/O failure.
void writeFrameStatsCsv(const std::vector<FrameStats>& frames, const std::filesystem::path& file);
void writeFrameStatsJson(const std::vector<FrameStats>& frames, const std::filesystem::path& file);

// Median of a field over frames (e.g. [](auto& f) { return f.frame_ms; }); 0 for no frames.
template <typename Field>
double medianOf(const std::vector<FrameStats>& frames, Field field);

}  // namespace tw

#include <algorithm>

namespace tw {
template <typename Field>
double medianOf(const std::vector<FrameStats>& frames, Field field) {
  if (frames.empty()) return 0.0;
  std::vector<double> values;
  values.reserve(frames.size());
  for (const FrameStats& f : frames) values.push_back(static_cast<double>(field(f)));
  std::sort(values.begin(), values.end());
  const size_t n = values.size();
  return n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}
}  // namespace tw
