// The walkthrough frame loop: one object that owns the mapped package, the LOD cut, the pager
// and the renderer, and turns a camera into a frame. `terawalk render` (headless, EGL) and
// `terawalk view` (GLFW window) both drive it, so they draw and report exactly the same way.
//
// Each frame (docs/runtime.md): start the pager's frame; upload what loaders finished, within the
// per-frame cap; select the cut for the camera (frustum, screen-space error tau, small features,
// resident ancestors standing in for missing pages) and request the missing pages by priority;
// prefetch along the camera's velocity (a second, draw-less cut from where the camera will be);
// cull the cut by occlusion (mode hzb: view-cell occluders and two-pass hierarchical Z; pvs: the
// cell's sampled visible set; runtime/occlusion_culler.h) and draw it with multi-draws; draw the
// cut's parametric clusters (parametric_renderer.h; in hzb mode with pass 1, so their depth is
// in the pyramid: decks and walls are boxes, the plant's best occluders); adapt tau to
// --target-fps. Nothing here waits for I/O except the constructor, which loads the root pages
// once (a few, whatever the model size) so the first frame is never empty. (hzb waits for the
// GPU: it reads the pyramid back in the middle of the frame.)
#pragma once

#include <chrono>
#include <filesystem>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "camera.h"
#include "environment/environment_pass.h"
#include "frame_stats.h"
#include "gl_renderer.h"
#include "lod_cut.h"
#include "object_states.h"
#include "occlusion_culler.h"
#include "package_view.h"
#include "moved_objects_pass.h"
#include "pager.h"
#include "parametrics/parametric_renderer.h"
#include "stereo.h"

namespace tw {

struct WalkthroughOptions {
  int width = 1280;
  int height = 720;
  double tau_px = 1.0;
  double min_feature_px = 1.0;
  PagerOptions pager;
  bool reference = false;        // brute force: every level-0 cluster, no LOD, no culling
  bool frustum_cull = true;      // false: LOD alone (benchmarks separate each technique's share)
  OcclusionMode occlusion = OcclusionMode::Hzb;  // never applied in reference mode
  HzbOptions hzb;
  bool prefetch = true;          // along the camera's velocity
  // Cull back faces of mesh clusters made of closed objects when the eye is outside them
  // (pkg::kObjectClosedSurface; frame_loop.cpp appendItems). Never in reference mode.
  bool cull_closed_backfaces = true;
  double prefetch_ahead_s = 0.5;  // or the time since the last frame, when longer
  double target_fps = 0.0;       // > 0: adapt tau to hold this frame rate
  double min_tau_px = 0.25, max_tau_px = 64.0;
  bool finish_each_frame = true;  // glFinish so frame_ms includes the GPU (headless timing)
  // Parametric clusters of the cut (reference: all of them): ray-cast impostors, run-time meshes
  // by distance, or not drawn (counted in FrameStats::parametric_skipped); auto picks by the GL
  // renderer (parametric_renderer.h). docs/parametrics.md.
  ParametricMode parametrics = ParametricMode::Auto;  // resolved by the constructor
  ParametricMeshOptions parametric_meshes;
  // Replaces the package as page source (tests: a deliberately slow reader).
  std::function<std::unique_ptr<PageSource>(const PackageView&)> page_source;
};

class Walkthrough {
 public:
  // Opens the package (mmap, headers and tables only), builds the cut index, starts the pager and
  // the renderer (a GL 4.5 context must be current), and loads the root pages (reference mode:
  // every level-0 page). Throws FormatError for a bad package, std::runtime_error otherwise.
  Walkthrough(const std::filesystem::path& package, const WalkthroughOptions& options);
  ~Walkthrough();
  Walkthrough(const Walkthrough&) = delete;
  Walkthrough& operator=(const Walkthrough&) = delete;

  // Renders one frame into the renderer's framebuffer. `time_s` is recorded in the stats and
  // drives the velocity estimate for prefetching.
  FrameStats renderFrame(const Camera& camera, double time_s);

  // Stereo (stereo.h): the cut selected once, for a camera whose frustum holds both eyes, and
  // drawn for the left eye then the right one; each eye's colour read back (RGBA, rows top-down)
  // into its vector. The statistics are the left eye's frame with the right eye's drawing (its
  // time and triangles) added. The renderer is left holding the right eye's frame.
  FrameStats renderStereoFrame(const Camera& camera, double time_s, const StereoOptions& stereo,
                               std::vector<uint8_t>& left_rgba, std::vector<uint8_t>& right_rgba);

  // Renders frames from `camera` until the cut holds what the view asks for (three frames in a
  // row with no page missing and no ancestor drawn instead), at most max_frames. Returns the last
  // frame's statistics; `settled` says whether it got there. For picks and still pictures.
  // `time_s` is every frame's time (the ocean's waves stand still at it).
  FrameStats renderSettled(const Camera& camera, bool* settled = nullptr, int max_frames = 200,
                           double time_s = 0.0);

  // Draws the last frame's whole cut again into the same targets with the same camera and no
  // occlusion culling, in the order the frame drew (hzb: last frame's visible clusters first,
  // then the rest in cut order), so depth ties resolve alike and the id buffer then differs from
  // the culled frame's only where culling removed visible pixels (`--check-occlusion`). Uploads
  // nothing and leaves the cut, the pager and the visible set alone; blocks until drawn. Returns
  // the triangles drawn.
  uint64_t redrawUnculled();

  // The last frame's mesh clusters of the cut (drawn or culled by occlusion), in draw order.
  const std::vector<uint32_t>& lastCut() const { return full_order_; }

  OcclusionMode occlusion() const { return options_.occlusion; }
  // Switches the mode; the next hzb frame starts with no previous visible set.
  void setOcclusion(OcclusionMode mode);
  const OcclusionCuller& occlusionCuller() const { return *culler_; }

  const PackageView& package() const { return *view_; }
  GlRenderer& renderer() { return *renderer_; }
  Pager& pager() { return *pager_; }
  double tau() const { return tau_px_; }
  void setTau(double tau_px) { tau_px_ = tau_px; }
  void setMinFeaturePx(double px) { options_.min_feature_px = px; }
  ParametricMode parametrics() const { return options_.parametrics; }
  void setParametrics(ParametricMode mode) { options_.parametrics = resolveParametricMode(mode); }
  ParametricRenderer& parametricRenderer() { return *parametric_; }
  // Per-object state by object index (hidden, selected, X-ray, colour override): changes reach
  // the GPU in one upload at the next frame. A cluster goes to the opaque passes only when one of
  // its objects is drawn opaque, and to the X-ray pass (after the opaque frame, not culled by
  // occlusion) only when one is ghosted; selected objects are outlined.
  ObjectStates& objectStates() { return object_states_; }
  const ObjectStates& objectStates() const { return object_states_; }
  // Section planes in world coordinates (section_planes.h; at most kMaxSectionPlanes: six
  // planes and a box), applied from the next frame on to every draw path; empty: none.
  void setSections(std::span<const SectionPlane> world_planes);
  // Objects moved by review edits (moved_objects_pass.h), drawn through their moves from their
  // full-resolution geometry in every frame; they get kObjectMoved and every other object loses
  // it, so the clusters leave them out at every level. Empty: nothing moved.
  void setMovedObjects(std::vector<MovedMesh> meshes);
  // The ocean and the sky around the model (environment/environment_pass.h), drawn from the
  // next frame on after the opaque passes; validated by the caller (validateEnvironment).
  void setEnvironment(const EnvironmentOptions& options);
  const EnvironmentOptions* environment() const { return environment_ ? &environment_->options() : nullptr; }
  // World bounds of the model (double), for cameras and paths.
  glm::dvec3 worldMin() const;
  glm::dvec3 worldMax() const;

 private:
  void uploadReady(FrameStats& stats);
  FrameStats renderView(const Camera& cut_camera, const Camera& camera, const glm::dmat4& projection,
                        double time_s, bool new_cut);
  // The steps of renderFrame, in order.
  const std::vector<uint32_t>& selectCut(const Camera& camera, const glm::dvec3& eye, double aspect,
                                         double time_s, FrameStats& stats);
  void rememberView(const Camera& camera, const glm::dvec3& eye, double aspect, double time_s,
                    std::span<const uint32_t> parametric_list);
  void drawWithHzb(const glm::dvec3& eye, std::span<const uint32_t> draw_list,
                   std::span<const uint32_t> parametric_list, FrameStats& stats);
  void drawWithoutHzb(OcclusionMode mode, const glm::dvec3& eye,
                      const std::vector<uint32_t>& draw_list, FrameStats& stats);
  // The X-ray pass over the cut's clusters with a ghosted object (kept for redrawUnculled), then
  // the selection outline.
  void drawGhostsAndOutlines(const glm::dvec3& eye, std::span<const uint32_t> mesh,
                             std::span<const uint32_t> parametric, FrameStats& stats);
  void drawGhostLists(const glm::dvec3& eye, FrameStats* stats);
  // `count_frame` false: the second eye of a stereo frame (tau and the frame count stay).
  void finishFrame(std::chrono::steady_clock::time_point frame_start, FrameStats& stats,
                   bool count_frame = true);
  // The object states uploaded if they changed; `clusters` without the ones that have no object
  // drawn opaque (in `kept`, returned), or `clusters` itself when every object is opaque.
  void uploadObjectStates();
  const std::vector<uint32_t>& withOpaqueObjects(const std::vector<uint32_t>& clusters,
                                                 std::vector<uint32_t>& kept) const;
  // Appends one draw item per cluster (resident, from the cut) seen from `eye`.
  void appendItems(std::span<const uint32_t> clusters, const glm::dvec3& eye,
                   std::vector<DrawItem>& items) const;
  void adaptTau(double frame_ms);
  // Draws `clusters` (parametric) with the last frame's camera; adds to `stats` when given.
  void drawParametrics(std::span<const uint32_t> clusters, FrameStats* stats);
  // hzb: splits a pass's clusters into mesh ones (`mesh`) and parametric ones (`parametric`).
  void splitByKind(std::span<const uint32_t> clusters, std::vector<uint32_t>& mesh,
                   std::vector<uint32_t>& parametric) const;

  WalkthroughOptions options_;
  std::unique_ptr<PackageView> view_;
  std::unique_ptr<LodCut> cut_;
  std::unique_ptr<Pager> pager_;
  std::unique_ptr<GeometryPool> pool_;
  std::unique_ptr<GlRenderer> renderer_;
  std::vector<uint32_t> reference_clusters_;
  CutResult cut_result_, prefetch_result_;
  std::vector<DrawItem> items_;
  std::unique_ptr<OcclusionCuller> culler_;
  std::unique_ptr<ParametricRenderer> parametric_;
  std::unique_ptr<MovedObjectsPass> moved_;
  std::unique_ptr<EnvironmentPass> environment_;
  // Draws the ocean and sky seen from the package-frame `eye` at `time_s`; adds to `stats`.
  void drawEnvironment(const glm::dvec3& eye, double time_s, FrameStats* stats);
  std::vector<uint32_t> all_parametric_;   // reference mode: every parametric cluster
  std::vector<uint32_t> last_parametric_;  // the last frame's parametric clusters (whole cut)
  // hzb: the cut's mesh and parametric clusters together, and each pass split by kind.
  std::vector<uint32_t> hzb_cut_, mesh_pass_, parametric_pass_;
  ParametricView last_parametric_view_;
  ObjectStates object_states_;
  std::vector<SectionPlane> sections_;  // setSections's planes, in the package frame
  std::vector<uint32_t> shown_clusters_, shown_parametric_;  // the cut's clusters drawn opaque
  std::vector<uint32_t> ghost_mesh_, ghost_parametric_;     // and those drawn ghosted
  std::vector<DrawItem> ghost_items_;
  size_t full_order_pass1_ = 0;  // hzb: parametrics were drawn after this many of full_order_
  std::vector<uint32_t> pass1_, rest_, pass2_, drawn_;  // scratch of the occlusion modes
  std::vector<uint32_t> drawn_parametric_;              // pvs: parametric clusters kept
  std::vector<uint32_t> full_order_;  // last frame's whole cut, in the order it was drawn
  glm::dvec3 last_eye_{0.0};          // package frame
  double near_reach_m_ = 0.0;         // this frame's Camera::nearPlaneReach
  glm::mat4 last_rotation_{1.0f}, last_projection_{1.0f};
  double tau_px_ = 1.0;
  uint64_t frame_ = 0;
  std::optional<glm::dvec3> last_position_;
  double last_time_s_ = 0.0;
};

}  // namespace tw
