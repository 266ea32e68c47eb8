// Occlusion culling of the LOD cut: two-pass HZB with view-cell occluders, and the sampled PVS.
// The contract is in occlusion_culler.h; the frame loop (frame_loop.cpp) calls it.
#include "occlusion_culler.h"

#define GL_GLEXT_PROTOTYPES 1
#include <GL/glcorearb.h>

#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>

#include "hzb_builder.h"
#include "pvs_mapping.h"

namespace tw {

namespace {

using Clock = std::chrono::steady_clock;

double msSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

// Half the diagonal of a quantization cell: the farthest a decoded vertex lies from where the
// preprocessor put it.
double quantizationErrorM(double cell_m) { return 0.5 * std::sqrt(3.0) * cell_m; }

}  // namespace

const char* occlusionModeName(OcclusionMode mode) {
  switch (mode) {
    case OcclusionMode::Off: return "off";
    case OcclusionMode::Hzb: return "hzb";
    case OcclusionMode::Pvs: return "pvs";
  }
  return "off";
}

OcclusionMode parseOcclusionMode(std::string_view name) {
  if (name == "off") return OcclusionMode::Off;
  if (name == "hzb") return OcclusionMode::Hzb;
  if (name == "pvs") return OcclusionMode::Pvs;
  throw std::invalid_argument("unknown occlusion mode '" + std::string(name) +
                              "' (expected off, hzb or pvs)");
}

int hzbTestLevel(int width, int height, int max_width_px) {
  int level = 0;
  while (width > std::max(max_width_px, 1) && (width > 1 || height > 1)) {
    width = std::max(1, width / 2);
    height = std::max(1, height / 2);
    ++level;
  }
  return level;
}

OcclusionCuller::OcclusionCuller(const PackageView& view) : view_(&view) {
  const pkg::SectionEntry& section = view.section(pkg::SectionType::Visibility);
  visibility_ = VisibilityView::parse(view.visibility(), view.fileName(), section.offset,
                                      view.clusters().size());
  if (!visibility_.empty())
    pvs_ = std::make_unique<PvsMapping>(view, visibility_.header().candidate_level,
                                        visibility_.parametricCandidates());
  last_visible_.assign(view.clusters().size(), 0);
}

OcclusionCuller::~OcclusionCuller() {
  glDeleteFramebuffers(1, &occlusion_fbo_);
  glDeleteTextures(1, &occlusion_depth_);
}

bool OcclusionCuller::hasVisibleSets() const {
  return !visibility_.empty() && (visibility_.header().flags & pkg::kVisibleSetsPresent) != 0;
}

const pkg::VisibilityCellRecord* OcclusionCuller::cellAt(const glm::dvec3& eye) const {
  if (visibility_.empty()) return nullptr;
  return visibility_.cellAt(eye);
}

uint64_t OcclusionCuller::restingWeight(const pkg::ClusterRecord& record) {
  if (record.kind == uint8_t(pkg::ClusterKind::Parametric))
    return uint64_t(record.instance_count) * kParametricRestingWeight;
  return record.triangle_count;
}

void OcclusionCuller::resetVisible() {
  for (uint32_t c : last_visible_list_) last_visible_[c] = 0;
  last_visible_list_.clear();
  resting_left_ = 0;
  poor_frames_ = 0;
}

void OcclusionCuller::splitByLastVisible(const glm::dvec3& eye, std::span<const uint32_t> cut,
                                         std::vector<uint32_t>& pass1,
                                         std::vector<uint32_t>& rest, FrameStats& stats) {
  pass1.clear();
  rest.clear();
  pyramid_current_ = false;
  cut_triangles_ = hidden_triangles_ = 0;
  for (uint32_t c : cut) cut_triangles_ += restingWeight(view_->clusters()[c]);
  if (resting_left_ > 0) {
    pass1.assign(cut.begin(), cut.end());
    if (const pkg::VisibilityCellRecord* here = pvs_ ? cellAt(eye) : nullptr)
      stats.view_cell = int64_t(here->grid_index);
    return;
  }
  // The eye's cell's occluders, mapped onto whatever LOD the cut holds (PvsMapping: the clusters
  // that stand for an occluder's surface at finer or coarser levels), join pass 1: they are
  // drawn as they are anyway, so their depth is exact.
  using Occluders = HzbOptions::Occluders;
  // Seed: only when nothing of the cut was visible last frame (first frame, mode switch,
  // teleport).
  bool seen_before = false;
  for (uint32_t c : cut)
    if (last_visible_[c]) {
      seen_before = true;
      break;
    }
  const bool promote = hzb_options_.occluders == Occluders::Always ||
                       (hzb_options_.occluders == Occluders::Seed && !seen_before);
  const pkg::VisibilityCellRecord* here = pvs_ ? cellAt(eye) : nullptr;
  if (here) stats.view_cell = int64_t(here->grid_index);
  const pkg::VisibilityCellRecord* cell = promote ? here : nullptr;
  if (cell && cell->grid_index != occluder_cell_) {
    pvs_->flags(visibility_.occluders(*cell), occluder_flags_);
    // The mapping keeps every parametric cluster that is not a listed candidate; as occluders
    // only those the set names count (none for sections without parametric occluders).
    const auto clusters = view_->clusters();
    for (uint32_t c = 0; c < clusters.size(); ++c)
      if (clusters[c].kind == uint8_t(pkg::ClusterKind::Parametric)) occluder_flags_[c] = 0;
    if (visibility_.header().flags & pkg::kParametricCandidates)
      for (uint32_t id : visibility_.occluders(*cell))
        if (clusters[id].kind == uint8_t(pkg::ClusterKind::Parametric)) occluder_flags_[id] = 1;
    occluder_cell_ = cell->grid_index;
  }
  uint32_t promoted = 0;
  for (uint32_t c : cut) {
    const bool occluder = cell && occluder_flags_[c];
    promoted += occluder && !last_visible_[c];
    (last_visible_[c] || occluder ? pass1 : rest).push_back(c);
  }
  if (cell) stats.occluders_drawn = promoted;
}

const char* occludersName(HzbOptions::Occluders occluders) {
  switch (occluders) {
    case HzbOptions::Occluders::Seed: return "seed";
    case HzbOptions::Occluders::Always: return "always";
    case HzbOptions::Occluders::Coarse: return "coarse";
    case HzbOptions::Occluders::None: return "none";
  }
  return "?";
}

HzbOptions::Occluders parseOccluders(std::string_view name) {
  if (name == "seed") return HzbOptions::Occluders::Seed;
  if (name == "always") return HzbOptions::Occluders::Always;
  if (name == "coarse") return HzbOptions::Occluders::Coarse;
  if (name == "none") return HzbOptions::Occluders::None;
  throw std::invalid_argument("unknown occluder use '" + std::string(name) +
                              "' (expected seed, always, coarse or none)");
}

const char* hzbBuildName(HzbBuild build) {
  switch (build) {
    case HzbBuild::Auto: return "auto";
    case HzbBuild::Gpu: return "gpu";
    case HzbBuild::Cpu: return "cpu";
  }
  return "?";
}

HzbBuild parseHzbBuild(std::string_view name) {
  if (name == "auto") return HzbBuild::Auto;
  if (name == "gpu") return HzbBuild::Gpu;
  if (name == "cpu") return HzbBuild::Cpu;
  throw std::invalid_argument("unknown HZB build '" + std::string(name) +
                              "' (expected auto, gpu or cpu)");
}

void OcclusionCuller::ensureGl(int width, int height) {
  if (!builder_) {
    builder_ = std::make_unique<HzbBuilder>();
    const char* renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
    const std::string name = renderer ? renderer : "";
    cpu_build_ = hzb_options_.build == HzbBuild::Cpu ||
                 (hzb_options_.build == HzbBuild::Auto &&
                  (name.find("llvmpipe") != std::string::npos ||
                   name.find("softpipe") != std::string::npos));
  }
  if (width == gl_width_ && height == gl_height_ && occlusion_fbo_ != 0) return;
  glDeleteFramebuffers(1, &occlusion_fbo_);
  glDeleteTextures(1, &occlusion_depth_);
  occlusion_fbo_ = occlusion_depth_ = 0;
  glCreateTextures(GL_TEXTURE_2D, 1, &occlusion_depth_);
  glTextureStorage2D(occlusion_depth_, 1, GL_DEPTH_COMPONENT32F, width, height);
  glTextureParameteri(occlusion_depth_, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTextureParameteri(occlusion_depth_, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  glCreateFramebuffers(1, &occlusion_fbo_);
  glNamedFramebufferTexture(occlusion_fbo_, GL_DEPTH_ATTACHMENT, occlusion_depth_, 0);
  glNamedFramebufferDrawBuffer(occlusion_fbo_, GL_NONE);
  glNamedFramebufferReadBuffer(occlusion_fbo_, GL_NONE);
  if (glCheckNamedFramebufferStatus(occlusion_fbo_, GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
    throw std::runtime_error("OcclusionCuller: cannot create the occlusion depth target");
  gl_width_ = width;
  gl_height_ = height;
}

void OcclusionCuller::buildAndReadBack(unsigned depth_texture, int width, int height,
                                       FrameStats& stats) {
  // The draws before are finished outside the timed span, so hzb_build_ms is the pyramid's own
  // cost (the read-back would wait for them anyway).
  glFinish();
  const auto start = Clock::now();
  if (cpu_build_) {
    const std::span<float> base = pyramid_.beginBuild(width, height);
    glBindBuffer(GL_PIXEL_PACK_BUFFER, 0);
    glPixelStorei(GL_PACK_ALIGNMENT, 4);
    glGetTextureImage(depth_texture, 0, GL_DEPTH_COMPONENT, GL_FLOAT, GLsizei(base.size_bytes()),
                      base.data());
    pyramid_.finishBuild();
  } else {
    builder_->build(depth_texture, width, height);
    builder_->readBack(pyramid_, hzbTestLevel(width, height, hzb_options_.read_width_px));
  }
  stats.hzb_build_ms += msSince(start);
}

bool OcclusionCuller::hidden(uint32_t cluster, const OcclusionFrame& frame,
                             bool& offscreen) const {
  const pkg::ClusterRecord& r = view_->clusters()[cluster];
  const glm::dvec3 box_min(r.aabb_min[0], r.aabb_min[1], r.aabb_min[2]);
  const glm::dvec3 box_max(r.aabb_max[0], r.aabb_max[1], r.aabb_max[2]);
  // Eye-relative in double, then rounded outward to float, so the box never shrinks.
  const glm::dvec3 lo = box_min - frame.eye, hi = box_max - frame.eye;
  glm::vec3 lo_f(lo), hi_f(hi);
  for (int k = 0; k < 3; ++k) {
    if (double(lo_f[k]) > lo[k]) lo_f[k] = std::nextafter(lo_f[k], -INFINITY);
    if (double(hi_f[k]) < hi[k]) hi_f[k] = std::nextafter(hi_f[k], INFINITY);
  }
  return testBox(lo_f, hi_f, frame, offscreen);
}

bool OcclusionCuller::testBox(const glm::vec3& lo, const glm::vec3& hi, const OcclusionFrame& frame,
                              bool& offscreen) const {
  const BoxVisibility visibility =
      occludedBox(pyramid_, lo, hi, frame.view_projection, hzb_options_.box_test);
  offscreen = visibility == BoxVisibility::Offscreen;
  return visibility != BoxVisibility::Visible;
}

bool OcclusionCuller::boxHidden(const glm::vec3& lo, const glm::vec3& hi,
                                const OcclusionFrame& frame) const {
  bool offscreen = false;
  return pyramid_current_ && testBox(lo, hi, frame, offscreen);
}

void OcclusionCuller::cullRest(const OcclusionFrame& frame, std::span<const uint32_t> rest,
                               std::vector<uint32_t>& pass2, FrameStats& stats) {
  pass2.clear();
  if (resting_left_ > 0) return;  // rest is empty: nothing to build or test
  const int width = frame.renderer->width(), height = frame.renderer->height();
  ensureGl(width, height);
  unsigned depth_source = frame.renderer->depthTexture();
  // The view cells' occluders are drawn whole, depth only: behind a section they would hide what
  // the cut shows, so they sit out while one is active.
  const pkg::VisibilityCellRecord* cell =
      hzb_options_.occluders == HzbOptions::Occluders::Coarse && !frame.renderer->sectionsActive()
          ? cellAt(frame.eye)
          : nullptr;
  if (cell) {
    stats.view_cell = int64_t(cell->grid_index);
    occluder_items_.clear();
    for (uint32_t id : visibility_.occluders(*cell)) {
      const pkg::ClusterRecord& r = view_->clusters()[id];
      if (r.kind != uint8_t(pkg::ClusterKind::Mesh) || r.triangle_count == 0 ||
          !std::isfinite(r.error))
        continue;
      if (frame.objects && !frame.objects->allOpaque(r.object_min, r.object_max)) continue;
      if (!frame.pager->resident(r.page)) {
        frame.pager->request(r.page, kOccluderPagePriority);  // never waited for
        continue;
      }
      frame.pager->touch(r.page);
      const GpuCluster& placement = frame.pager->gpuCluster(id);
      DrawItem item = makeDrawItem(placement, frame.eye);
      item.push_m = float(double(r.error) + quantizationErrorM(placement.cell_m));
      occluder_items_.push_back(item);
    }
    if (!occluder_items_.empty()) {
      // The occluders go into a copy, so the frame's own depth keeps only what it shows.
      glCopyImageSubData(frame.renderer->depthTexture(), GL_TEXTURE_2D, 0, 0, 0, 0,
                         occlusion_depth_, GL_TEXTURE_2D, 0, 0, 0, 0, width, height, 1);
      frame.renderer->drawDepth(*frame.pool, occluder_items_, occlusion_fbo_);
      depth_source = occlusion_depth_;
      stats.occluders_drawn = uint32_t(occluder_items_.size());
    }
  }
  buildAndReadBack(depth_source, width, height, stats);
  pyramid_current_ = true;

  const auto test_start = Clock::now();
  for (uint32_t c : rest) {
    bool offscreen = false;
    if (!hidden(c, frame, offscreen)) {
      pass2.push_back(c);
    } else if (offscreen) {
      ++stats.culled_frustum;
    } else {
      ++stats.occlusion_culled;
      hidden_triangles_ += restingWeight(view_->clusters()[c]);
    }
  }
  stats.hzb_test_ms += msSince(test_start);
}

void OcclusionCuller::recordVisible(const OcclusionFrame& frame, std::span<const uint32_t> pass1,
                                    std::span<const uint32_t> pass2, FrameStats& stats) {
  auto keep = [this](uint32_t c) {
    last_visible_[c] = 1;
    last_visible_list_.push_back(c);
  };
  // Resting: only the last resting frame looks at its depth, to hand the next frame a visible set.
  if (resting_left_ > 1) {
    --resting_left_;
    return;
  }
  const bool last_rest = resting_left_ == 1;
  const bool rebuild = hzb_options_.rebuild_from_final_depth || last_rest;
  if (rebuild) {
    const int width = frame.renderer->width(), height = frame.renderer->height();
    ensureGl(width, height);
    buildAndReadBack(frame.renderer->depthTexture(), width, height, stats);
    pyramid_current_ = true;
  }
  if (last_rest) {
    resting_left_ = 0;
    poor_frames_ = hzb_options_.rest_after_frames - 1;  // one poor frame rests again
  } else if (hzb_options_.rest_after_frames > 0) {
    const bool poor = double(hidden_triangles_) < hzb_options_.min_hidden_share *
                                                      double(cut_triangles_);
    poor_frames_ = poor ? poor_frames_ + 1 : 0;
  }
  const auto test_start = Clock::now();
  for (uint32_t c : last_visible_list_) last_visible_[c] = 0;
  last_visible_list_.clear();
  for (uint32_t c : pass1) {
    bool offscreen = false;
    if (!hidden(c, frame, offscreen)) keep(c);
  }
  for (uint32_t c : pass2) {
    bool offscreen = false;
    // Survivors of step 2 drew into the frame; only the final depth can say they are hidden.
    if (!rebuild || !hidden(c, frame, offscreen)) keep(c);
  }
  stats.hzb_test_ms += msSince(test_start);
  if (hzb_options_.rest_after_frames > 0 && poor_frames_ >= hzb_options_.rest_after_frames &&
      hzb_options_.rest_frames > 0) {
    resting_left_ = hzb_options_.rest_frames;
    poor_frames_ = 0;
  }
}

void OcclusionCuller::filterPvs(const glm::dvec3& eye, std::span<const uint32_t> cut,
                                std::vector<uint32_t>& out, FrameStats& stats) {
  out.clear();
  stats.view_cell = -1;
  const pkg::VisibilityCellRecord* cell = pvs_ ? cellAt(eye) : nullptr;
  if (!cell) {
    out.assign(cut.begin(), cut.end());
    return;
  }
  stats.view_cell = int64_t(cell->grid_index);
  if (cell->grid_index != pvs_cell_) {
    pvs_->flags(visibility_.visible(*cell), pvs_flags_);
    pvs_cell_ = cell->grid_index;
  }
  for (uint32_t c : cut) {
    if (pvs_flags_[c]) out.push_back(c);
    else ++stats.occlusion_culled;
  }
}

}  // namespace tw
