// Tessellated mode with a level of detail per instance: each visible parametric instance drawn
// at the resolution its own distance asks for, thin ones as their silhouette or points.
//
// Why: tessellating whole clusters (parametric_meshes.h) gives every instance of a cluster the
// resolution its nearest point needs, so a 64-instance pipe run that starts at the eye is drawn at
// close-up resolution along its whole length, and a far handrail post costs as many triangles as
// a near one. Here each visible instance picks its own segment counts: the chordal error of its
// arcs projects to at most tolerance_px (the frame's tau). Thin tubes and elbows become ribbons,
// two triangles per segment facing the eye, thin beams ribbons too, things thin every way points
// (InstanceLodView::thin_px); extrusions whose profile detail is below tolerance their box.
// Instances outside the frustum's side planes or whose bounding sphere projects below
// min_feature_px are dropped. Closed surfaces seen from outside the solid (not merely outside
// its bounding sphere; extrusions too, when their profile is simple), open tubes seen from
// between their end planes, and the open tubes and elbows of sealed pipe runs while the eye is
// clear of every such run (sealed_pipe_runs.h) have their back faces culled.
// How: a unit mesh per (shape, resolution) is made once, on first use (the rows and columns
// formats/tessellate.h builds, so at equal segment counts the triangles are the same); each frame,
// every visible instance is expanded from its unit mesh on the CPU into one eye-relative vertex
// batch (the thin beams' bands and the rows of boxes, box_rows.h, into ones of their own), drawn
// with at most six calls (a far view's in flushed parts). Instancing was measured first:
// llvmpipe runs its vertex pipeline once per instance, about a microsecond each, which for
// 60,000 small far instances cost more than their triangles (docs/parametrics.md).
// Extrusions that need their true surface are handed back to the caller for
// ParametricMeshes::drawInstances.
// Occlusion (hzb mode): instances are culled one by one, two-pass like the clusters. The first
// pass draws the instances of its clusters that were not hidden last frame and keeps the others
// aside; the second pass tests those and every instance of the second-pass clusters against the
// pyramid of the first pass's depth (box_hidden), and draws the survivors; recordVisible then
// tests every instance drawn against the frame's final depth, which decides the next first pass.
// A 64-instance cluster visible through a doorway no longer draws its 60 instances behind the
// wall. Conservative as the cluster test is: only depth that was drawn hides anything. Both sets
// of tests run on TBB (box_hidden must be safe to call from several threads at once): the
// rasterizer threads have nothing else to do while they run.
// Needs a current GL 4.5 context for the object's whole life.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "object_states.h"
#include "package_view.h"
#include "parametric_meshes.h"

namespace tw {

// Which pass of an hzb frame a draw is ("Occlusion" above): All draws every visible instance
// (modes off and pvs, references, the unculled redraw).
enum class InstancePass { All, First, Second };

// The camera as the per-instance choice needs it; positions in the package frame.
struct InstanceLodView {
  glm::dvec3 eye{0.0};
  glm::mat4 view_projection{1.0f};  // eye-relative (as GlRenderer::viewProjection)
  double pixel_scale = 1.0;         // Camera::pixelScale(viewport height)
  double near_m = 0.05;
  double tolerance_px = 1.0;        // chordal error allowed on screen
  double min_feature_px = 1.0;      // instances whose bounding sphere projects below are dropped
  // Tubes and elbows thinner than this on screen (at their nearest point) are drawn as ribbons:
  // a band along the axis or centre circle facing the eye, as wide as the tube seen from there
  // (two triangles a pipe; the coarsest tube mesh has six). It covers the pixel centres the true
  // surface covers, as the one-pixel lines drawn before did not (docs/parametrics.md, "Thin
  // things and the reference"). Boxes, extrusions and revolutions thin in two directions are
  // ribbons along their longest axis, as wide as their box's cross-section seen from the eye;
  // spheres and anything thin in all three directions are points. Thinner than min_thin_px they are left out: many, each covering few
  // pixels, for a small gain (measured there).
  double thin_px = 1.0;
  double min_thin_px = 0.4;
  InstancePass pass = InstancePass::All;
  // Second pass: whether an eye-relative box is hidden by this frame's pyramid. Called from
  // several threads at once.
  std::function<bool(const glm::vec3& lo, const glm::vec3& hi)> box_hidden;
  // Instances of objects this surface pass skips are not expanded (object_states.h); read by
  // the workers, so it must not change while a frame's expansion runs.
  const ObjectStates* objects = nullptr;
  SurfacePass surface = SurfacePass::Opaque;
  // A section is active (section_planes.h): it shows the insides of what it cuts, so no back
  // face is left out of the batch or culled.
  bool keep_back_faces = false;
};

struct InstanceLodStats {
  uint64_t instances_drawn = 0;    // after culling
  uint64_t instances_culled = 0;   // frustum side planes, small features, below min_thin_px
  uint64_t triangles_drawn = 0;    // submitted (back faces included)
  uint64_t two_sided_triangles = 0;  // of triangles_drawn: without back-face culling
  uint64_t thin_instances = 0;     // of instances_drawn: as ribbons or points
  uint64_t instances_occluded = 0; // second pass: hidden by the pyramid, one by one
  // Tested one by one (culled, deferred or drawn); the others of the frame's clusters were left
  // out by InstanceScaleIndex, too small at their distance to show.
  uint64_t instances_tested = 0;
  uint32_t draw_calls = 0;
  uint32_t unit_meshes = 0;        // made so far
};

class ParametricInstanceMeshes {
 public:
  // Segment counts are rounded up to one of these (so a few dozen unit meshes serve a plant).
  static uint32_t roundedSegments(uint32_t segments);

  // Reads the instance table's bounds once (68 bytes per instance). prepare() expands the
  // frame's clusters in runs of options.clusters_per_run on TBB (0: one run, on the calling
  // thread); submit() draws the batch in flushed parts of options.primitives_per_flush (0: whole).
  // The image is the same either way. Only those two options are read. Throws
  // std::runtime_error when GL set-up fails.
  explicit ParametricInstanceMeshes(const PackageView& view,
                                    const ParametricMeshOptions& options = {});
  ~ParametricInstanceMeshes();
  ParametricInstanceMeshes(const ParametricInstanceMeshes&) = delete;
  ParametricInstanceMeshes& operator=(const ParametricInstanceMeshes&) = delete;

  // True for the types handled here: all seven (extrusions and revolutions as boxes and points,
  // their surfaces through ParametricMeshes).
  static bool handles(uint32_t type);

  // Draws the instances of `clusters` (parametric clusters of the handled types) into the bound
  // framebuffer with the caller's depth state, reading the instance table the caller bound at
  // gpu::kInstanceBinding (parametric_gpu.h: origins relative to their cluster's anchor) and the
  // object colours at gl_shaders.h kObjectColorBinding. Extrusions and revolutions that need
  // their surface are not drawn: they are listed in `profiles` (by cluster, with their distance,
  // and with their back faces to cull when a closed extrusion is seen from outside) for
  // ParametricMeshes::drawInstances.
  // prepare() then submit().
  InstanceLodStats draw(std::span<const uint32_t> clusters, const InstanceLodView& view,
                        uint32_t object_color_count, std::vector<ParametricMeshInstance>& profiles);
  // The CPU half of draw(): chooses each instance's form and expands the visible ones into the
  // batch that the next submit() draws. It makes no GL call. A first or only pass of many
  // clusters (two runs or more) is streamed: prepare() hands the runs to a TBB worker and
  // returns, and submit() draws each run as soon as it is done (expanding runs itself while it
  // waits), so llvmpipe's work on the GL thread overlaps the expansion; its counts then come
  // with submit(), and `profiles` is complete when submit() returns. Otherwise (a second pass,
  // or few clusters) the runs are expanded here on TBB, each into a part of its own, and the
  // parts appended in order into one batch. Never two at once (a prepare() not submitted is
  // finished by the next), nor beside submit() or recordVisible().
  InstanceLodStats prepare(std::span<const uint32_t> clusters, const InstanceLodView& view,
                           std::vector<ParametricMeshInstance>& profiles);
  // The GL half: uploads the prepared batch (or each streamed run) and draws it, adding its
  // draw calls and triangles, and a streamed prepare's counts, to `stats`. A batch is drawn
  // once. A far view's (fewer than four primitives an instance) is drawn in parts, a glFlush
  // after every primitives_per_flush of them: llvmpipe's rasterizer threads start on a scene
  // only when it is flushed, and until then the submitting thread shades and bins every vertex
  // alone (docs/runtime.md, "Overlap"). A near view's is drawn whole.
  void submit(const glm::mat4& view_projection, uint32_t object_color_count, InstanceLodStats& stats);

  // After the frame's final-depth pyramid: marks which instances drawn this frame (both passes)
  // `box_hidden` (called from several threads at once) hides, for the next frame's first pass.
  void recordVisible(const std::function<bool(const glm::vec3&, const glm::vec3&)>& box_hidden);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace tw
