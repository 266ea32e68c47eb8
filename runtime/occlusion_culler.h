// Occlusion culling in the frame loop: the `hzb` mode (a view cell's occluders plus two-pass
// hierarchical-Z) and the `pvs` mode (the cell's sampled visible set), on top of the LOD cut.
//
// Why a class of its own: the frame loop keeps the cut, the pager and the draw; everything that
// decides which clusters of the cut occlusion removes, and the GL objects it needs (occlusion
// depth texture, HZB builder), lives here, so the two can be read and tested apart.
//
// hzb, per frame (docs/occlusion.md, "Runtime: frame loop"):
//  1. splitByLastVisible: the cut C splits into P1 = C ∩ (visible last frame), in cut order, and
//     the rest R. The frame loop draws P1 normally.
//  2. cullRest: occlusion depth = the depth of P1, plus (when the eye is in a stored view cell)
//     the cell's resident occluder clusters drawn depth-only, each vertex pushed away from the eye
//     by the cluster's error plus its quantization error; occluders not resident are requested
//     from the pager at high priority, never waited for. Without a cell the depth of P1 alone is
//     used. The HZB of that depth is built on the GPU and read back from the first level at most
//     kMaxTestLevelWidthPx wide; each cluster of R is tested with its AABB (eye-relative, in
//     double) and survivors P2 are returned. The frame loop draws P2.
//  3. recordVisible: with HzbOptions::rebuild_from_final_depth (the default since the pyramid is
//     built on the CPU on llvmpipe, where it costs about 1.5 ms), the HZB of the final depth
//     (P1 ∪ P2) is built and read back the same way, and the clusters of P1 ∪ P2 it does not hide
//     become next frame's P1. A cluster is tested against depth it wrote itself, so it stays iff
//     some of it is in front (nearest box depth >= its own surface); this keeps P1 small when the
//     camera turns away from things (10M decks path: 754K triangles against 821K without). Without
//     it, next frame's P1 is P2 plus the clusters of P1 that
//     step 2's pyramid (P1's own depth and the occluders) does not hide: a cluster hidden only by
//     this frame's P2 leaves the set one frame later, which costs a little culling, never a pixel.
// Conservative as long as the depth is exact: P1's depth is the true depth of drawn geometry,
// and pushed occluders lie behind the surfaces they approximate (up to the pushes' accuracy, see
// the docs); the `--check-occlusion` option of `terawalk render` measures the loss.
//
// pvs: the eye's stored cell, when it has a visible set, filters the cut through
// PvsMapping::flags (computed once per cell change); outside any cell nothing is filtered.
//
// Needs a current GL 4.5 context for the culler's whole life (hzb mode only touches GL). Not
// thread-safe; the render thread owns it.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string_view>
#include <vector>

#include <glm/glm.hpp>

#include "frame_stats.h"
#include "gl_renderer.h"
#include "hzb_pyramid.h"
#include "object_states.h"
#include "package_view.h"
#include "pager.h"
#include "visibility_section.h"

namespace tw {

class HzbBuilder;
class PvsMapping;

enum class OcclusionMode { Off, Hzb, Pvs };

// "off", "hzb", "pvs".
const char* occlusionModeName(OcclusionMode mode);
// Parses a mode name; throws std::invalid_argument naming the value otherwise.
OcclusionMode parseOcclusionMode(std::string_view name);

// The HZB levels read back for the CPU test: the first level at most this wide. 1280x720 reads
// level 2 (320x180, 225 KiB of floats); finer levels only sharpen the test of clusters smaller
// than about 4 texels, and cost 4x the read-back per level.
inline constexpr int kMaxTestLevelWidthPx = 320;
// Pager priority for occluder pages: above any projected error (pixels) the cut asks with, below
// the pinned roots' +inf.
inline constexpr float kOccluderPagePriority = 1e9f;

// Where the pyramid is built. On Mesa llvmpipe the compute shader costs about 20 ms at
// 1280x720 against 1.5 ms for reading the depth back and reducing it on the CPU (bench_hzb,
// docs/occlusion.md), so Auto picks the CPU there and the compute shader on real GPUs.
enum class HzbBuild { Auto, Gpu, Cpu };

// "auto", "gpu", "cpu"; parseHzbBuild throws std::invalid_argument naming the value otherwise.
const char* hzbBuildName(HzbBuild build);
HzbBuild parseHzbBuild(std::string_view name);

struct HzbOptions {
  int read_width_px = kMaxTestLevelWidthPx;  // GPU build: read back from the first level at most
                                             // this wide (the CPU build keeps every level)
  bool rebuild_from_final_depth = true;      // step 3 builds a second pyramid (see above)
  HzbBuild build = HzbBuild::Auto;
  // How boxes are tested (occludedBox): at the finest level where a box covers at most
  // max_span_texels texels per axis, halved while it spans at least split_px pixels
  // (docs/occlusion.md, "Halving boxes").
  BoxTest box_test;
  // How the view cell's occluder set is used (docs/occlusion.md, measured on the decks path of
  // the 10M tessellated plant):
  // - Seed (default): on a frame where nothing of the cut was visible the frame before (the
  //   first frame, a mode switch, a teleport), the cut's clusters that stand for the occluders (PvsMapping, at
  //   whatever LOD the cut draws them) make pass 1. Their depth is that of what the frame shows:
  //   exact. Later frames use last frame's visible set alone, which is tighter.
  // - Always: they join pass 1 every frame (the mapping's fan-out then draws about 1,200 more
  //   clusters per frame: 996K triangles against 754K).
  // - Coarse: the occluder clusters themselves, at the candidate front's LOD, are drawn
  //   depth-only into a copy of the depth, pushed back by their error; coarse silhouettes and far
  //   proxies reach past the true surfaces, so this loses pixels (2.5 %).
  // - None: two-pass HZB alone.
  enum class Occluders { Seed, Always, Coarse, None } occluders = Occluders::Seed;
  // Resting: where occlusion hides little (an orbit outside the model, an open deck), the two
  // pyramids and the box tests cost more than the triangles they save. When the clusters hidden
  // in a frame hold less than min_hidden_share of the cut's weight (restingWeight: triangles,
  // parametric instances) for rest_after_frames frames in a row, the culler rests for
  // rest_frames frames: the whole cut is drawn in pass 1 and nothing is built or tested (drawing
  // everything is conservative). The last resting frame builds the final-depth pyramid once, so
  // the next frame has a visible set and measures the share again; one poor frame after a rest
  // starts the next rest. rest_after_frames = 0: never.
  uint32_t rest_after_frames = 8;
  uint32_t rest_frames = 24;
  double min_hidden_share = 0.1;
};

// "seed", "always", "coarse", "none"; parseOccluders throws std::invalid_argument otherwise.
const char* occludersName(HzbOptions::Occluders occluders);
HzbOptions::Occluders parseOccluders(std::string_view name);

// What one frame's occlusion work needs from the frame loop.
struct OcclusionFrame {
  GlRenderer* renderer = nullptr;   // its beginFrame has run with the frame's camera
  const GeometryPool* pool = nullptr;
  Pager* pager = nullptr;
  glm::dvec3 eye{0.0};              // package frame, metres
  glm::mat4 view_projection{1.0f};  // projection * rotation-only view, as the renderer uses
  // Coarse occluders holding an object not drawn opaque are left out: hidden and ghosted
  // objects occlude nothing.
  const ObjectStates* objects = nullptr;
};

// The first pyramid level whose width is at most max_width_px, for a width x height buffer
// (levels halve, rounding down, at least 1; hzb_pyramid.h).
int hzbTestLevel(int width, int height, int max_width_px = kMaxTestLevelWidthPx);

class OcclusionCuller {
 public:
  // Parses the package's visibility section (an empty one is fine: no cells) and, when it holds
  // visible sets, indexes the DAG for PvsMapping. No GL work. The view must outlive the culler.
  // Throws FormatError for a damaged visibility section.
  explicit OcclusionCuller(const PackageView& view);
  ~OcclusionCuller();
  OcclusionCuller(const OcclusionCuller&) = delete;
  OcclusionCuller& operator=(const OcclusionCuller&) = delete;

  const VisibilityView& visibility() const { return visibility_; }
  bool hasVisibleSets() const;
  // The stored cell containing `eye` (package frame), or nullptr.
  const pkg::VisibilityCellRecord* cellAt(const glm::dvec3& eye) const;

  void setHzbOptions(const HzbOptions& options) { hzb_options_ = options; }
  const HzbOptions& hzbOptions() const { return hzb_options_; }

  // Forgets last frame's visible set (a mode switch, a teleport): the next frame tests all of C.
  void resetVisible();

  // hzb step 1. pass1 and rest are cleared first; together they are `cut`, each in cut order.
  // Pass 1 holds the clusters visible last frame and, as HzbOptions::occluders says, the
  // clusters of the cut that stand for the eye's cell's occluders; fills view_cell and
  // occluders_drawn (clusters promoted by the occluder set alone).
  void splitByLastVisible(const glm::dvec3& eye, std::span<const uint32_t> cut,
                          std::vector<uint32_t>& pass1, std::vector<uint32_t>& rest,
                          FrameStats& stats);
  // hzb step 2, after P1 was drawn into frame.renderer's targets. Appends the survivors of `rest`
  // to `pass2` (cleared first), in order. Fills occluders_drawn, view_cell, occlusion_culled
  // (clusters of `rest` hidden), hzb_build_ms and hzb_test_ms (adds to them); clusters whose box
  // lies wholly off screen are dropped too and counted in culled_frustum.
  void cullRest(const OcclusionFrame& frame, std::span<const uint32_t> rest,
                std::vector<uint32_t>& pass2, FrameStats& stats);
  // Whether the eye-relative box [lo, hi] is hidden by this frame's pyramid (step 2's, or step
  // 3's once recordVisible rebuilt it) or lies wholly off screen; false when no pyramid was
  // built this frame (resting, or the frame before step 2). For finer tests than clusters: the
  // parametric instances of tessellated mode.
  bool boxHidden(const glm::vec3& lo, const glm::vec3& hi, const OcclusionFrame& frame) const;
  // hzb step 3, after P2 was drawn: next frame's P1 (see above). Adds to hzb_build_ms and
  // hzb_test_ms.
  void recordVisible(const OcclusionFrame& frame, std::span<const uint32_t> pass1,
                     std::span<const uint32_t> pass2, FrameStats& stats);

  // pvs: `out` (cleared first) = the clusters of `cut` potentially visible from `eye`'s cell, in
  // order; all of `cut` outside any cell or without visible sets. Fills view_cell and
  // occlusion_culled.
  void filterPvs(const glm::dvec3& eye, std::span<const uint32_t> cut, std::vector<uint32_t>& out,
                 FrameStats& stats);

  // What a cluster of the cut weighs in the resting decision: its triangles, or for a
  // parametric cluster kParametricRestingWeight per instance (on llvmpipe an instance costs about
  // what 8 cluster triangles do: 2.6 us against 0.29 us, 10M plant decks path and
  // bench_cluster_draw).
  static constexpr uint64_t kParametricRestingWeight = 8;
  static uint64_t restingWeight(const pkg::ClusterRecord& record);

  // True while resting (HzbOptions::rest_after_frames): this frame draws the whole cut in pass 1.
  bool resting() const { return resting_left_ > 0; }
  // True once this frame has built a pyramid (cullRest, or recordVisible outside a rest): only
  // then can boxHidden hide anything.
  bool pyramidCurrent() const { return pyramid_current_; }

  // The pyramid of the last build (after cullRest: the occlusion depth's; after recordVisible:
  // the final depth's). For tests and debugging.
  const HzbPyramid& lastPyramid() const { return pyramid_; }

 private:
  void ensureGl(int width, int height);
  void buildAndReadBack(unsigned depth_texture, int width, int height, FrameStats& stats);
  // True when the pyramid certainly hides cluster c; sets offscreen when its box is off screen.
  bool hidden(uint32_t cluster, const OcclusionFrame& frame, bool& offscreen) const;
  // The same for an eye-relative box.
  bool testBox(const glm::vec3& lo, const glm::vec3& hi, const OcclusionFrame& frame,
               bool& offscreen) const;

  const PackageView* view_;
  HzbOptions hzb_options_;
  bool cpu_build_ = false;           // resolved from hzb_options_.build by ensureGl
  VisibilityView visibility_;
  std::unique_ptr<PvsMapping> pvs_;
  uint32_t pvs_cell_ = UINT32_MAX;   // grid index whose flags pvs_flags_ hold
  uint32_t occluder_cell_ = UINT32_MAX;  // grid index whose flags occluder_flags_ hold
  std::vector<uint8_t> occluder_flags_;
  std::vector<uint8_t> pvs_flags_;

  // Resting (HzbOptions::rest_after_frames): frames left to rest, poor frames in a row, and the
  // triangles of the cut and of what this frame hid.
  uint32_t resting_left_ = 0;
  uint32_t poor_frames_ = 0;
  uint64_t cut_triangles_ = 0, hidden_triangles_ = 0;

  std::vector<uint8_t> last_visible_;         // per cluster: in last frame's visible set
  std::vector<uint32_t> last_visible_list_;   // the same, as a list (to clear)

  // GL (hzb mode), created on first use.
  std::unique_ptr<HzbBuilder> builder_;
  unsigned occlusion_depth_ = 0, occlusion_fbo_ = 0;
  int gl_width_ = 0, gl_height_ = 0;
  HzbPyramid pyramid_;
  bool pyramid_current_ = false;  // pyramid_ was built from this frame's depth
  std::vector<DrawItem> occluder_items_;
};

}  // namespace tw
