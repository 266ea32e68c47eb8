// The frame loop: package + cut + pager + renderer, one frame at a time. See frame_loop.h.
#include "frame_loop.h"

#include <GL/gl.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

namespace tw {

namespace {

using Clock = std::chrono::steady_clock;

// The X-ray pass's parametrics: chordal tolerance this many times the frame's, and instances
// smaller than this on screen left out (drawGhostLists).
constexpr double kGhostToleranceFactor = 4.0;
constexpr double kGhostMinFeaturePx = 3.0;

double msSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

// Per object: its own colour, else its layer's, else a neutral grey.
std::vector<uint32_t> objectColors(const PackageView& view) {
  std::vector<uint32_t> colors;
  colors.reserve(view.objects().size());
  for (const pkg::ObjectRecord& object : view.objects()) {
    uint32_t rgba = object.color_rgba;
    if (rgba == 0 && object.layer < view.layers().size()) rgba = view.layers()[object.layer].color_rgba;
    colors.push_back(rgba != 0 ? rgba : 0xffb0b0b0u);
  }
  return colors;
}

// Pool bytes the given clusters need (vertices, 16-bit indices, one object per triangle).
uint64_t poolBytesFor(const PackageView& view, const std::vector<uint32_t>& clusters) {
  uint64_t bytes = 0;
  for (uint32_t c : clusters) {
    const pkg::ClusterRecord& r = view.clusters()[c];
    bytes += uint64_t(r.vertex_count) * 8 + uint64_t(r.triangle_count) * (3 * 2 + 4);
  }
  return bytes;
}

}  // namespace

Walkthrough::Walkthrough(const std::filesystem::path& package, const WalkthroughOptions& options)
    : options_(options), tau_px_(options.tau_px) {
  view_ = std::make_unique<PackageView>(PackageView::open(package, PackageView::Verify::Headers));
  cut_ = std::make_unique<LodCut>(*view_);
  std::vector<uint32_t> pinned = cut_->rootPages();
  PagerOptions pager_options = options_.pager;
  if (options_.reference) {
    // Brute force: every level-0 cluster resident for the whole run, in a pool big enough for
    // all of them whatever the budget (the pool splits its bytes by a typical ratio, hence the
    // margin).
    reference_clusters_ = cut_->levelZeroClusters();
    pinned.clear();
    for (uint32_t c : reference_clusters_) pinned.push_back(view_->clusters()[c].page);
    std::sort(pinned.begin(), pinned.end());
    pinned.erase(std::unique(pinned.begin(), pinned.end()), pinned.end());
    pager_options.gpu_budget_bytes =
        std::max(pager_options.gpu_budget_bytes, 4 * poolBytesFor(*view_, reference_clusters_));
    pager_options.evict_after_frames = UINT32_MAX;
  }
  std::unique_ptr<PageSource> source =
      options_.page_source ? options_.page_source(*view_) : makePackagePageSource(*view_);
  pager_ = std::make_unique<Pager>(*view_, std::move(source), pager_options);
  pool_ = std::make_unique<GeometryPool>(pager_->poolLayout());
  RendererOptions renderer_options;
  renderer_options.width = options_.width;
  renderer_options.height = options_.height;
  renderer_ = std::make_unique<GlRenderer>(renderer_options);
  renderer_->setObjectColors(objectColors(*view_));
  object_states_ = ObjectStates(view_->objects().size());
  last_parametric_view_.objects = &object_states_;
  culler_ = std::make_unique<OcclusionCuller>(*view_);
  culler_->setHzbOptions(options_.hzb);
  parametric_ = std::make_unique<ParametricRenderer>(*view_, *renderer_, options_.parametric_meshes);
  options_.parametrics = resolveParametricMode(options_.parametrics);
  parametric_->prepareMode(options_.parametrics);
  for (uint32_t c = 0; c < view_->clusters().size(); ++c)
    if (view_->clusters()[c].kind == static_cast<uint8_t>(pkg::ClusterKind::Parametric))
      all_parametric_.push_back(c);

  // The only wait of the run: the pinned pages, so the first frame shows the whole model.
  pager_->pin(pinned);
  pager_->waitForPinned();
  pager_->beginFrame(frame_);
  auto all_resident = [&] {
    return std::all_of(pinned.begin(), pinned.end(), [&](uint32_t p) { return pager_->resident(p); });
  };
  while (!all_resident()) {
    std::vector<PageUpload> uploads = pager_->takeUploads();
    if (uploads.empty()) {
      if (all_resident()) break;
      throw std::runtime_error(package.string() +
                               ": the GPU budget is too small for the model's root pages");
    }
    for (const PageUpload& upload : uploads) pool_->upload(upload);
  }
}

Walkthrough::~Walkthrough() = default;

glm::dvec3 Walkthrough::worldMin() const {
  const auto& h = view_->header();
  return view_->origin() + glm::dvec3(h.bounds_min[0], h.bounds_min[1], h.bounds_min[2]);
}

glm::dvec3 Walkthrough::worldMax() const {
  const auto& h = view_->header();
  return view_->origin() + glm::dvec3(h.bounds_max[0], h.bounds_max[1], h.bounds_max[2]);
}

void Walkthrough::uploadReady(FrameStats& stats) {
  for (const PageUpload& upload : pager_->takeUploads()) stats.bytes_uploaded += pool_->upload(upload);
}

void Walkthrough::setSections(std::span<const SectionPlane> world_planes) {
  if (world_planes.size() > kMaxSectionPlanes)
    throw std::invalid_argument(std::to_string(world_planes.size()) + " section planes, at most " +
                                std::to_string(kMaxSectionPlanes));
  sections_.assign(world_planes.begin(), world_planes.end());
  for (SectionPlane& plane : sections_) plane.point -= view_->origin();
}

void Walkthrough::setOcclusion(OcclusionMode mode) {
  if (mode != options_.occlusion) culler_->resetVisible();
  options_.occlusion = mode;
}

void Walkthrough::appendItems(std::span<const uint32_t> clusters, const glm::dvec3& eye,
                              std::vector<DrawItem>& items) const {
  const auto records = view_->clusters();
  for (uint32_t c : clusters) {
    const GpuCluster& g = pager_->gpuCluster(c);
    DrawItem item = makeDrawItem(g, eye);
    // Back faces go when the eye is outside the box of the cluster's closed objects, by more
    // than the near plane's reach (closer, the near plane may cut a surface open) plus how far
    // the cluster's geometry may stray from those objects: its simplification error and a grid
    // cell of quantization.
    if (g.closed && options_.cull_closed_backfaces && !options_.reference) {
      const double margin = near_reach_m_ + double(records[c].error) + g.cell_m;
      const glm::dvec3 below = glm::dvec3(g.solid_min) - eye, above = eye - glm::dvec3(g.solid_max);
      item.cull_back = std::max({below.x, below.y, below.z, above.x, above.y, above.z}) > margin;
    }
    items.push_back(item);
  }
}

void Walkthrough::drawParametrics(std::span<const uint32_t> clusters, FrameStats* stats) {
  if (options_.parametrics == ParametricMode::Off) {
    if (stats) stats->parametric_skipped += uint32_t(clusters.size());
    return;
  }
  // An empty second pass still draws the first pass's deferred instances.
  if (clusters.empty() && last_parametric_view_.pass != InstancePass::Second) return;
  const ParametricDrawStats drawn =
      parametric_->draw(clusters, last_parametric_view_, options_.parametrics, frame_);
  if (stats) {
    stats->parametric_clusters_drawn += drawn.clusters_drawn;
    stats->parametric_instances_drawn += drawn.instances_drawn;
    stats->parametric_triangles += drawn.mesh_triangles;
    stats->parametric_two_sided_triangles += drawn.two_sided_triangles;
    stats->parametric_thin_instances += drawn.thin_instances;
    stats->parametric_occluded += drawn.instances_occluded;
    stats->parametric_instances_tested += drawn.instances_tested;
    stats->parametric_cpu_ms += drawn.cpu_ms;
  }
}

void Walkthrough::splitByKind(std::span<const uint32_t> clusters, std::vector<uint32_t>& mesh,
                              std::vector<uint32_t>& parametric) const {
  mesh.clear();
  parametric.clear();
  for (uint32_t c : clusters)
    (view_->clusters()[c].kind == uint8_t(pkg::ClusterKind::Parametric) ? parametric : mesh)
        .push_back(c);
}

uint64_t Walkthrough::redrawUnculled() {
  items_.clear();
  appendItems(full_order_, last_eye_, items_);
  renderer_->beginFrame(last_rotation_, last_projection_);
  const size_t first = std::min(full_order_pass1_, items_.size());
  renderer_->draw(*pool_, std::span<const DrawItem>(items_).first(first));
  drawParametrics(last_parametric_, nullptr);
  renderer_->draw(*pool_, std::span<const DrawItem>(items_).subspan(first));
  drawEnvironment(last_eye_, last_time_s_, nullptr);
  drawGhostLists(last_eye_, nullptr);
  const RenderStats render_stats = renderer_->endFrame();
  glFinish();
  return render_stats.triangles;
}

void Walkthrough::adaptTau(double frame_ms) {
  if (options_.target_fps <= 0.0) return;
  const double target_ms = 1000.0 / options_.target_fps;
  const double ratio = frame_ms / target_ms;
  // Multiplicative steps with a dead band, so tau settles instead of oscillating.
  if (ratio > 1.1)
    tau_px_ *= std::min(1.5, std::sqrt(ratio));
  else if (ratio < 0.8)
    tau_px_ /= 1.1;
  tau_px_ = std::clamp(tau_px_, options_.min_tau_px, options_.max_tau_px);
}

// One frame: the cut (and the prefetch cut ahead), then its clusters drawn with the frame's
// occlusion mode, then the frame's statistics.
FrameStats Walkthrough::renderFrame(const Camera& camera, double time_s) {
  const double aspect = double(renderer_->width()) / double(renderer_->height());
  return renderView(camera, camera, camera.projection(aspect), time_s, true);
}

FrameStats Walkthrough::renderStereoFrame(const Camera& camera, double time_s,
                                          const StereoOptions& stereo,
                                          std::vector<uint8_t>& left_rgba,
                                          std::vector<uint8_t>& right_rgba) {
  const double aspect = double(renderer_->width()) / double(renderer_->height());
  const Camera cut_camera = stereoCutCamera(camera, aspect, stereo);
  const StereoEye left = stereoEye(camera, aspect, stereo, -1);
  const StereoEye right = stereoEye(camera, aspect, stereo, +1);
  FrameStats stats = renderView(cut_camera, left.camera, left.projection, time_s, true);
  renderer_->readColor(left_rgba, true);
  const FrameStats second = renderView(cut_camera, right.camera, right.projection, time_s, false);
  renderer_->readColor(right_rgba, true);
  // One frame of the walkthrough: the cut and the pages once, the drawing twice.
  stats.frame_ms += second.frame_ms;
  stats.gpu_ms += second.gpu_ms;
  stats.finish_ms += second.finish_ms;
  stats.triangles_drawn += second.triangles_drawn;
  stats.two_sided_triangles += second.two_sided_triangles;
  stats.parametric_triangles += second.parametric_triangles;
  stats.ocean_triangles += second.ocean_triangles;
  return stats;
}

// A frame seen by `camera` through `projection`. With `new_cut`, the pager's frame starts and the
// cut is selected for `cut_camera` (the same camera, or one whose frustum holds the eyes'); the
// second eye of a stereo pair draws the first one's cut again and counts no frame.
FrameStats Walkthrough::renderView(const Camera& cut_camera, const Camera& camera,
                                   const glm::dmat4& projection, double time_s, bool new_cut) {
  const auto frame_start = Clock::now();
  FrameStats stats;
  stats.frame = frame_;
  stats.time_s = time_s;
  stats.tau_px = options_.reference ? 0.0 : tau_px_;
  const double aspect = double(renderer_->width()) / double(renderer_->height());
  if (new_cut) {
    pager_->beginFrame(frame_ + 1);  // frame 0 of the pager was the start-up load
    uploadReady(stats);
    near_reach_m_ = cut_camera.nearPlaneReach(aspect);
    const auto cut_start = Clock::now();
    if (!options_.reference)
      selectCut(cut_camera, cut_camera.position - view_->origin(), aspect, time_s, stats);
    stats.cpu_cut_ms = msSince(cut_start);
  }
  const glm::dvec3 eye = camera.position - view_->origin();
  const std::vector<uint32_t>& cut_list = options_.reference ? reference_clusters_ : cut_result_.clusters;
  // Every cluster of the cut stays in use (LRU), drawn or hidden: hidden ones may show next frame.
  if (new_cut)
    for (uint32_t c : cut_list) pager_->touch(view_->clusters()[c].page);
  uploadObjectStates();
  const std::vector<uint32_t>& parametric_cut =
      options_.reference ? all_parametric_ : cut_result_.parametric_clusters;
  const std::vector<uint32_t>& draw_list = withOpaqueObjects(cut_list, shown_clusters_);
  const std::vector<uint32_t>& parametric_list =
      withOpaqueObjects(parametric_cut, shown_parametric_);
  rememberView(camera, eye, aspect, time_s, parametric_list);
  last_projection_ = glm::mat4(projection);
  last_position_ = cut_camera.position;  // the velocity of the walk, not of the eyes

  renderer_->beginFrame(last_rotation_, last_projection_);
  renderer_->setSections(sections_, eye);
  // Draw items in double: offset of each cluster's grid origin from the eye.
  items_.clear();
  const OcclusionMode mode = options_.reference ? OcclusionMode::Off : options_.occlusion;
  if (mode == OcclusionMode::Hzb)
    drawWithHzb(eye, draw_list, parametric_list, stats);
  else
    drawWithoutHzb(mode, eye, draw_list, stats);
  if (moved_ && !moved_->empty()) {
    moved_->draw(*renderer_, eye, last_projection_ * last_rotation_);
    stats.triangles_drawn += moved_->triangles();
  }
  drawEnvironment(eye, time_s, &stats);
  drawGhostsAndOutlines(eye, cut_list, parametric_cut, stats);
  finishFrame(frame_start, stats, new_cut);
  return stats;
}

void Walkthrough::setMovedObjects(std::vector<MovedMesh> meshes) {
  if (!moved_) moved_ = std::make_unique<MovedObjectsPass>();
  object_states_.setAll(kObjectMoved, false);
  for (const MovedMesh& m : meshes) object_states_.set(m.object, kObjectMoved, true);
  moved_->set(std::move(meshes));
}

void Walkthrough::setEnvironment(const EnvironmentOptions& options) {
  if (!environment_) environment_ = std::make_unique<EnvironmentPass>();
  environment_->set(options);
}

void Walkthrough::drawEnvironment(const glm::dvec3& eye, double time_s, FrameStats* stats) {
  if (!environment_ || !environment_->active()) return;
  const EnvironmentStats drawn =
      environment_->draw(*renderer_, eye + view_->origin(), last_rotation_, last_projection_, time_s);
  if (!stats) return;
  stats->ocean_triangles = drawn.ocean_triangles;
  stats->ocean_cpu_ms = drawn.ocean_mesh_ms;
}

FrameStats Walkthrough::renderSettled(const Camera& camera, bool* settled, int max_frames,
                                      double time_s) {
  FrameStats stats;
  int steady = 0;
  for (int i = 0; i < max_frames && steady < 3; ++i) {
    stats = renderFrame(camera, time_s);
    steady = stats.ancestor_fallbacks == 0 && stats.pages_requested == 0 ? steady + 1 : 0;
  }
  if (settled) *settled = steady == 3;
  return stats;
}

void Walkthrough::uploadObjectStates() {
  if (!object_states_.changed()) return;
  renderer_->setObjectStates(object_states_.gpuStates());
  object_states_.markUploaded();
}

const std::vector<uint32_t>& Walkthrough::withOpaqueObjects(
    const std::vector<uint32_t>& clusters, std::vector<uint32_t>& kept) const {
  if (object_states_.everyObjectOpaque()) return clusters;
  kept.clear();
  const auto records = view_->clusters();
  for (uint32_t c : clusters)
    if (object_states_.anyOpaque(records[c].object_min, records[c].object_max)) kept.push_back(c);
  return kept;
}

void Walkthrough::drawGhostsAndOutlines(const glm::dvec3& eye, std::span<const uint32_t> mesh,
                                        std::span<const uint32_t> parametric, FrameStats& stats) {
  ghost_mesh_.clear();
  ghost_parametric_.clear();
  if (object_states_.anyGhosted()) {
    const auto records = view_->clusters();
    auto ghosted = [&](uint32_t c) {
      return object_states_.anyGhosted(records[c].object_min, records[c].object_max);
    };
    std::copy_if(mesh.begin(), mesh.end(), std::back_inserter(ghost_mesh_), ghosted);
    if (options_.parametrics != ParametricMode::Off)
      std::copy_if(parametric.begin(), parametric.end(), std::back_inserter(ghost_parametric_),
                   ghosted);
  }
  drawGhostLists(eye, &stats);
}

// Ghosts are drawn whole, with no occlusion test: they are few next to the opaque rest when a
// reviewer X-rays a part, and when most of the model is ghosted there is little left to occlude.
void Walkthrough::drawGhostLists(const glm::dvec3& eye, FrameStats* stats) {
  if (!ghost_mesh_.empty() || !ghost_parametric_.empty()) {
    ghost_items_.clear();
    appendItems(ghost_mesh_, eye, ghost_items_);
    renderer_->setSurfacePass(SurfacePass::Xray);
    renderer_->draw(*pool_, ghost_items_);
    // Ghosts are seen through at a fifth of their colour: coarser tessellations and no small
    // instances cost little to the eye and much less to draw.
    const ParametricView opaque_view = last_parametric_view_;
    last_parametric_view_.surface = SurfacePass::Xray;
    last_parametric_view_.tolerance_px *= kGhostToleranceFactor;
    last_parametric_view_.min_feature_px =
        std::max(last_parametric_view_.min_feature_px, kGhostMinFeaturePx);
    drawParametrics(ghost_parametric_, stats);
    last_parametric_view_ = opaque_view;
    renderer_->setSurfacePass(SurfacePass::Opaque);
    if (stats)
      for (const DrawItem& item : ghost_items_) stats->xray_triangles += item.placement.triangle_count;
  }
  if (object_states_.anySelected()) renderer_->drawSelectionOutlines();
}

// The LOD cut from the camera, its missing pages requested; with prefetching, also the cut from
// where the camera will be, at a lower priority than what is missing now.
const std::vector<uint32_t>& Walkthrough::selectCut(const Camera& camera, const glm::dvec3& eye,
                                                    double aspect, double time_s,
                                                    FrameStats& stats) {
  CutView cut_view;
  cut_view.eye = eye;
  cut_view.frustum = makeFrustum(camera, eye, aspect);
  cut_view.pixel_scale = camera.pixelScale(renderer_->height());
  cut_view.near_m = camera.near_m;
  CutOptions cut_options;
  cut_options.tau_px = tau_px_;
  cut_options.min_feature_px = options_.min_feature_px;
  cut_options.frustum_cull = options_.frustum_cull;
  auto resident = [this](uint32_t page) { return pager_->resident(page); };
  cut_->select(cut_view, cut_options, resident, cut_result_);
  for (const PageWant& want : cut_result_.wanted) pager_->request(want.page, want.priority);

  if (options_.prefetch && last_position_ && time_s > last_time_s_) {
    const double step_s = time_s - last_time_s_;
    const glm::dvec3 velocity = (camera.position - *last_position_) / step_s;
    if (glm::length(velocity) > 1e-3) {
      // At least as far as the next frame will be, when frames are further apart than that
      // (a replay at a low frame rate).
      Camera ahead = camera;
      ahead.position += velocity * std::max(options_.prefetch_ahead_s, step_s);
      const glm::dvec3 ahead_eye = ahead.position - view_->origin();
      cut_view.eye = ahead_eye;
      cut_view.frustum = makeFrustum(ahead, ahead_eye, aspect);
      cut_options.collect_draws = false;
      cut_->select(cut_view, cut_options, resident, prefetch_result_);
      for (const PageWant& want : prefetch_result_.wanted)
        pager_->request(want.page, 0.5f * want.priority);
    }
  }
  stats.nodes_visited = cut_result_.stats.groups_visited + cut_result_.stats.clusters_tested;
  stats.culled_frustum = cut_result_.stats.culled_frustum;
  stats.culled_small = cut_result_.stats.culled_small;
  stats.ancestor_fallbacks = cut_result_.stats.groups_blocked;
  return cut_result_.clusters;
}

// What later draws of this frame (parametrics, redrawUnculled) and the next frame's prefetch use.
void Walkthrough::rememberView(const Camera& camera, const glm::dvec3& eye, double aspect,
                               double time_s, std::span<const uint32_t> parametric_list) {
  last_parametric_.assign(parametric_list.begin(), parametric_list.end());
  last_parametric_view_.eye = eye;
  last_parametric_view_.forward = camera.forward();
  last_parametric_view_.near_m = camera.near_m;
  last_parametric_view_.pixel_scale = camera.pixelScale(renderer_->height());
  last_parametric_view_.min_feature_px = options_.reference ? 0.0 : options_.min_feature_px;
  last_parametric_view_.tolerance_px = tau_px_;
  last_position_ = camera.position;
  last_time_s_ = time_s;
  last_eye_ = eye;
  last_rotation_ = glm::mat4(camera.viewRotation());
  last_projection_ = glm::mat4(camera.projection(aspect));
}

// hzb: last frame's visible clusters first, a pyramid from their depth, then the rest of the cut
// tested against it.
void Walkthrough::drawWithHzb(const glm::dvec3& eye, std::span<const uint32_t> draw_list,
                              std::span<const uint32_t> parametric_list, FrameStats& stats) {
  OcclusionFrame frame;
  frame.renderer = renderer_.get();
  frame.pool = pool_.get();
  frame.pager = pager_.get();
  frame.eye = eye;
  frame.view_projection = last_projection_ * last_rotation_;  // as the renderer multiplies
  frame.objects = &object_states_;
  stats.view_cell = -1;
  // Parametric clusters take both passes like mesh clusters (their boxes are tested the same
  // way): inside a plant most pipes are behind decks and walls, which are parametric too.
  hzb_cut_.assign(draw_list.begin(), draw_list.end());
  if (options_.parametrics != ParametricMode::Off)
    hzb_cut_.insert(hzb_cut_.end(), parametric_list.begin(), parametric_list.end());
  else
    stats.parametric_skipped = uint32_t(parametric_list.size());
  culler_->splitByLastVisible(eye, hzb_cut_, pass1_, rest_, stats);
  splitByKind(pass1_, mesh_pass_, parametric_pass_);
  // The first pass overlaps its parts (docs/runtime.md, "Overlap"): a worker starts choosing
  // and expanding the tessellated parametrics (prepare() hands their runs to it and returns)
  // while this thread submits the meshes, and the flush hands the meshes to llvmpipe's
  // rasterizer threads before the parametrics follow, each run drawn as soon as it is done.
  last_parametric_view_.pass = InstancePass::First;
  if (!parametric_pass_.empty())
    parametric_->prepare(parametric_pass_, last_parametric_view_, options_.parametrics);
  appendItems(mesh_pass_, eye, items_);
  renderer_->draw(*pool_, items_);
  glFlush();
  // Tessellated parametrics are also culled instance by instance, in the same two passes
  // (parametric_instance_meshes.h, "Occlusion").
  auto box_hidden = [this, &frame](const glm::vec3& lo, const glm::vec3& hi) {
    return culler_->boxHidden(lo, hi, frame);
  };
  drawParametrics(parametric_pass_, &stats);
  full_order_.assign(mesh_pass_.begin(), mesh_pass_.end());
  full_order_pass1_ = mesh_pass_.size();
  culler_->cullRest(frame, rest_, pass2_, stats);
  splitByKind(pass2_, mesh_pass_, parametric_pass_);
  const size_t pass1_items = items_.size();
  appendItems(mesh_pass_, eye, items_);
  renderer_->draw(*pool_, std::span<const DrawItem>(items_).subspan(pass1_items));
  last_parametric_view_.pass = InstancePass::Second;
  last_parametric_view_.box_hidden = box_hidden;
  drawParametrics(parametric_pass_, &stats);
  last_parametric_view_.pass = InstancePass::All;
  last_parametric_view_.box_hidden = nullptr;
  culler_->recordVisible(frame, pass1_, pass2_, stats);
  // Resting, the culler built no pyramid this frame: every instance drawn counts as visible,
  // without a test per instance that could only say so (47,000 a frame on the 50M orbit).
  if (options_.parametrics == ParametricMode::Tessellated) {
    if (culler_->pyramidCurrent())
      parametric_->recordInstanceVisibility(box_hidden);
    else
      parametric_->recordInstanceVisibility(nullptr);
  }
  stats.pass1_clusters = uint32_t(pass1_.size());
  stats.pass2_clusters = uint32_t(pass2_.size());
  splitByKind(rest_, mesh_pass_, parametric_pass_);
  full_order_.insert(full_order_.end(), mesh_pass_.begin(), mesh_pass_.end());
}

// off and pvs (the latter keeps the cut's clusters in the view cell's visible set): one pass.
void Walkthrough::drawWithoutHzb(OcclusionMode mode, const glm::dvec3& eye,
                                 const std::vector<uint32_t>& draw_list, FrameStats& stats) {
  const std::vector<uint32_t>* list = &draw_list;
  const std::vector<uint32_t>* parametric = &last_parametric_;
  if (mode == OcclusionMode::Pvs) {
    culler_->filterPvs(eye, draw_list, drawn_, stats);
    list = &drawn_;
    // Parametric clusters the visible set does not name (when they were candidates).
    FrameStats parametric_stats;
    culler_->filterPvs(eye, last_parametric_, drawn_parametric_, parametric_stats);
    stats.occlusion_culled += parametric_stats.occlusion_culled;
    parametric = &drawn_parametric_;
  }
  appendItems(*list, eye, items_);
  renderer_->draw(*pool_, items_);
  drawParametrics(*parametric, &stats);
  full_order_.assign(draw_list.begin(), draw_list.end());
  full_order_pass1_ = full_order_.size();
}

// Triangles drawn, GPU time, the pager's state and the frame's time; tau adapts to it.
void Walkthrough::finishFrame(Clock::time_point frame_start, FrameStats& stats, bool count_frame) {
  for (const DrawItem& item : items_) {
    stats.triangles_drawn += item.placement.triangle_count;
    if (!item.cull_back) stats.two_sided_triangles += item.placement.triangle_count;
  }
  stats.nodes_drawn = uint32_t(items_.size());
  const RenderStats render_stats = renderer_->endFrame();
  // Headless runs wait for the GPU anyway, so they report this frame's own GPU time; the window
  // takes the newest finished one (a frame or two old) rather than stall.
  if (options_.finish_each_frame) {
    const Clock::time_point finish_start = Clock::now();
    glFinish();
    stats.finish_ms = msSince(finish_start);
    stats.gpu_ms = renderer_->waitForGpuMs();
  } else {
    stats.gpu_ms = render_stats.gpu_ms;
  }

  const PagerStats pager_stats = pager_->stats();
  stats.pages_resident = pager_stats.pages_resident;
  stats.pages_requested = pager_stats.pages_requested;
  stats.pages_loading = pager_stats.pages_loading;
  stats.pages_ready = pager_stats.pages_ready;
  stats.pages_waiting_for_pool = pager_stats.pages_waiting_for_pool;
  stats.pages_loaded = pager_stats.pages_uploaded;
  stats.pages_evicted = pager_stats.pages_evicted;
  stats.page_load_errors = pager_stats.load_errors;
  stats.gpu_bytes_used = pager_stats.gpu_bytes_used;
  stats.host_bytes_used = pager_stats.host_bytes_used;
  stats.rss_bytes = currentRssBytes();
  stats.frame_ms = msSince(frame_start);
  if (!count_frame) return;
  if (!options_.reference) adaptTau(stats.frame_ms);
  ++frame_;
}

}  // namespace tw
