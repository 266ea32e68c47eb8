// The LOD cut: which clusters of the package's DAG to draw this frame, chosen by screen-space
// error, frustum and small-feature culling, and by what is resident.
//
// The rule (docs/runtime.md): a group G (a simplification step: children -> produced clusters)
// is *refined* this frame, i.e. its children are shown instead of its produced clusters, when
// (c) every produced cluster of G is a root or has a parent group refined by (b), and
//   (a) G's lod sphere is outside the frustum (nothing of it is visible; refining costs nothing
//       and keeps the groups around it free to refine), or
//   (b) errorPx(G.error, G's lod sphere) > tau and every child's page is resident.
// Groups are decided from the roots down: by level, highest first, which is a topological order
// for any package the view accepts (levels grow strictly along every DAG edge; the format does
// not promise that group indices follow the build order, so the LodCut does not rely on it).
// Only groups for which (c) holds are examined, so the work follows the cut, not the whole DAG.
// A group refined by (a) does not open its subtree (lod spheres nest, so all of it is outside
// too): it asks for no page and costs one sphere test.
// Clusters drawn: every cluster c whose parent group is refined by (b) (or that is a root) and
// whose producing group is not refined (or that is level 0), minus clusters outside the frustum
// and clusters whose bounding sphere projects below min_feature_px.
// (c) keeps the refined set closed toward the roots, so the drawn set is always a valid cut of
// the DAG: crack-free and without overlap. With every page resident it is exactly the cut of
// error <= tau < parent_error; a group blocked only by missing pages shows its produced clusters
// (the nearest resident ancestor) and asks for the missing pages: never a hole, never a wait.
// Below such a blocked group the decisions go on (CutOptions::look_ahead) as if it were refined,
// drawing nothing, so the pages of every level down to the cut the view wants are asked for in
// the same frame, coarser ones first (their projected errors are larger): after a jump the cut
// converges in about as many frames as the pager needs to load them, not one level a round trip.
//
// errorPx(e, sphere) = e * pixelScale / max(distance(eye, sphere) - radius, near_m): monotone in
// e, and a group's sphere encloses its children's, so projected errors grow toward the roots.
//
// Pages holding root clusters must be resident for anything to show; rootPages() lists them and
// the frame loop pins them in the pager at start. Parametric clusters (roots of level 0 with no
// page) are culled the same way and listed apart (drawn by the parametrics renderer).
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include "camera.h"
#include "package_view.h"

namespace tw {

struct CutView {
  glm::dvec3 eye{0.0};  // package frame: world - PackageHeader::origin
  Frustum frustum;      // package frame
  double pixel_scale = 1.0;  // Camera::pixelScale(viewport height)
  double near_m = 0.05;
};

struct CutOptions {
  double tau_px = 1.0;           // screen-space error threshold, pixels
  double min_feature_px = 1.0;   // clusters whose sphere diameter projects below this are culled
  bool frustum_cull = true;
  bool collect_draws = true;     // false: only `wanted` (prefetch from a predicted camera)
  // Ask for the pages of the whole cut at once: below a group blocked by missing pages, go on
  // deciding as if it were refined (drawing nothing there) and ask for what the finer groups
  // want too. Without it the cut asks one level deeper per round trip through the pager.
  bool look_ahead = true;
};

// A page the cut would like resident; priority grows with how much it matters (the projected
// error in pixels of the group that wants it, divided by nothing else).
struct PageWant {
  uint32_t page = 0;
  float priority = 0.0f;
};

struct CutStats {
  uint32_t groups_visited = 0;      // groups whose (c) held, so they were tested
  uint32_t groups_refined = 0;      // refined by error (b); groups wholly outside are not counted
  uint32_t groups_blocked = 0;      // wanted refinement, children not resident (ancestor shown)
  uint32_t groups_looked_past = 0;  // below a blocked group, wanting refinement (look_ahead)
  uint32_t clusters_tested = 0;
  uint32_t culled_frustum = 0;      // tested outside, or hidden with a group wholly outside
  uint32_t culled_small = 0;
  uint64_t triangles = 0;           // in `clusters`
  uint32_t parametric_instances = 0;  // in `parametric_clusters`
};

struct CutResult {
  std::vector<uint32_t> clusters;             // mesh clusters to draw (all resident)
  std::vector<uint32_t> parametric_clusters;  // visible parametric clusters
  std::vector<PageWant> wanted;               // each page at most once, highest priority kept
  CutStats stats;
  void clear();
};

class LodCut {
 public:
  // Indexes the DAG (children of every group, roots, root pages). Touches the cluster and group
  // tables only. The view must outlive the LodCut.
  explicit LodCut(const PackageView& view);

  const std::vector<uint32_t>& rootPages() const { return root_pages_; }
  const std::vector<uint32_t>& roots() const { return roots_; }  // mesh root clusters

  // Selects the cut; `out` is cleared first. page_resident(page) must be cheap and must not
  // change during the call. Not reentrant: it reuses scratch kept in the LodCut, so one caller
  // at a time (no allocation per frame once the vectors in `out` have grown).
  void select(const CutView& view, const CutOptions& options,
              const std::function<bool(uint32_t page)>& page_resident, CutResult& out) const;

  // Every level-0 mesh cluster: the brute-force reference cut (no LOD, no culling).
  std::vector<uint32_t> levelZeroClusters() const;

 private:
  const PackageView* view_;
  std::vector<uint32_t> child_offsets_;  // CSR: children of group g are
  std::vector<uint32_t> children_;       // children_[child_offsets_[g] .. child_offsets_[g+1])
  std::vector<uint32_t> child_producers_;  // group of each children_ entry (kNone at level 0),
                                           // so decisions do not touch the cluster records
  std::vector<uint32_t> child_page_offsets_;  // CSR: distinct pages of group g's mesh children
  std::vector<uint32_t> child_pages_;
  std::vector<uint32_t> roots_;
  std::vector<uint32_t> root_pages_;
  std::vector<uint32_t> parametric_;     // parametric root clusters (those with a parent group
                                         // are reached as children, like mesh clusters)
  std::vector<uint32_t> order_;          // groups by level, highest first: parents before children
  std::vector<uint32_t> need_;           // per group: produced clusters that have a parent group
  mutable std::vector<uint8_t> refined_;  // per group, scratch of select()
  mutable std::vector<uint32_t> ready_;   // per group: produced clusters whose parent is refined
  mutable std::vector<uint32_t> reach_;   // the same, counting parents looked past (look_ahead)
  mutable std::vector<uint32_t> refined_list_;  // groups refined by error, this call
  mutable std::vector<uint32_t> want_slot_;     // per page: 1 + index in `wanted`, 0 = none
};

}  // namespace tw
