// The LOD cut: decides, each frame, which groups of the DAG are refined and so which clusters are
// drawn (the rule is in lod_cut.h). One pass over the groups, parents first, touching only groups
// whose produced clusters are all shown, then one pass over the clusters those decisions expose.
#include "lod_cut.h"

#include <algorithm>
#include <limits>

namespace tw {
namespace {

constexpr uint32_t kNone = pkg::kNone;

// Projected error (pixels) of an object-space error seen at the nearest point of a sphere.
inline double errorPx(double error_m, const glm::dvec3& center, double radius,
                      const CutView& view) {
  double distance = glm::length(center - view.eye) - radius;
  return error_m * view.pixel_scale / std::max(distance, view.near_m);
}

inline glm::dvec3 toDouble(const float v[3]) { return {v[0], v[1], v[2]}; }

}  // namespace

void CutResult::clear() {
  clusters.clear();
  parametric_clusters.clear();
  wanted.clear();
  stats = {};
}

LodCut::LodCut(const PackageView& view) : view_(&view) {
  auto clusters = view.clusters();
  auto groups = view.groups();
  const auto group_count = static_cast<uint32_t>(groups.size());
  const auto cluster_count = static_cast<uint32_t>(clusters.size());

  // Children of every group (CSR by counting sort: each group's children in index order), and
  // how many produced clusters of each group wait on a parent's decision.
  child_offsets_.assign(group_count + 1, 0);
  need_.assign(group_count, 0);
  for (const pkg::ClusterRecord& c : clusters) {
    if (c.parent_group != kNone) {
      ++child_offsets_[c.parent_group + 1];
      if (c.group != kNone) ++need_[c.group];
    }
  }
  for (uint32_t g = 0; g < group_count; ++g) child_offsets_[g + 1] += child_offsets_[g];
  children_.resize(child_offsets_[group_count]);
  {
    std::vector<uint32_t> fill(child_offsets_.begin(), child_offsets_.end() - 1);
    for (uint32_t i = 0; i < cluster_count; ++i)
      if (clusters[i].parent_group != kNone) children_[fill[clusters[i].parent_group]++] = i;
  }
  child_producers_.resize(children_.size());
  for (size_t k = 0; k < children_.size(); ++k) child_producers_[k] = clusters[children_[k]].group;

  // Distinct pages of each group's mesh children: the residency test of a refinement.
  child_page_offsets_.assign(group_count + 1, 0);
  child_pages_.clear();
  child_pages_.reserve(group_count * 2);
  std::vector<uint32_t> pages;
  for (uint32_t g = 0; g < group_count; ++g) {
    pages.clear();
    for (uint32_t k = child_offsets_[g]; k < child_offsets_[g + 1]; ++k) {
      const pkg::ClusterRecord& c = clusters[children_[k]];
      if (c.kind == static_cast<uint8_t>(pkg::ClusterKind::Mesh)) pages.push_back(c.page);
    }
    std::sort(pages.begin(), pages.end());
    pages.erase(std::unique(pages.begin(), pages.end()), pages.end());
    child_pages_.insert(child_pages_.end(), pages.begin(), pages.end());
    child_page_offsets_[g + 1] = static_cast<uint32_t>(child_pages_.size());
  }

  for (uint32_t i = 0; i < cluster_count; ++i) {
    const pkg::ClusterRecord& c = clusters[i];
    if (c.parent_group != kNone) continue;
    if (c.kind == static_cast<uint8_t>(pkg::ClusterKind::Mesh)) {
      roots_.push_back(i);
      root_pages_.push_back(c.page);
    } else {
      parametric_.push_back(i);
    }
  }
  std::sort(root_pages_.begin(), root_pages_.end());
  root_pages_.erase(std::unique(root_pages_.begin(), root_pages_.end()), root_pages_.end());

  // Decision order. The format does not promise that group indices follow the build order, but
  // the view guarantees levels grow strictly along every DAG edge (a child's producer has level
  // < the child's level <= its parent group's level), so highest level first is a topological
  // order: every parent group is decided before the groups that produced its children.
  order_.resize(group_count);
  for (uint32_t g = 0; g < group_count; ++g) order_[g] = g;
  std::stable_sort(order_.begin(), order_.end(), [&](uint32_t a, uint32_t b) {
    return groups[a].level > groups[b].level;
  });

  refined_.assign(group_count, 0);
  ready_.assign(group_count, 0);
  reach_.assign(group_count, 0);
  refined_list_.reserve(group_count);
  want_slot_.assign(view.pages().size(), 0);
}

std::vector<uint32_t> LodCut::levelZeroClusters() const {
  std::vector<uint32_t> out;
  auto clusters = view_->clusters();
  for (uint32_t i = 0; i < clusters.size(); ++i)
    if (clusters[i].level == 0 && clusters[i].kind == static_cast<uint8_t>(pkg::ClusterKind::Mesh))
      out.push_back(i);
  return out;
}

void LodCut::select(const CutView& view, const CutOptions& options,
                    const std::function<bool(uint32_t page)>& page_resident,
                    CutResult& out) const {
  out.clear();
  auto clusters = view_->clusters();
  auto groups = view_->groups();
  CutStats& stats = out.stats;

  // Refined states: 0 = produced clusters shown, 1 = refined by error (children shown),
  // 2 = refined because nothing of it is in the frustum (its subtree is not visited),
  // 3 = looked past: it wants refining but waits for pages, so its produced clusters stay on
  // screen while the cut goes on below it to ask for what the finer levels will want.
  constexpr uint8_t kByError = 1, kOutside = 2, kLookedPast = 3;
  auto hides = [&](uint32_t g) { return refined_[g] == kByError || refined_[g] == kOutside; };
  std::fill(refined_.begin(), refined_.end(), uint8_t{0});
  std::fill(ready_.begin(), ready_.end(), 0u);
  std::fill(reach_.begin(), reach_.end(), 0u);
  refined_list_.clear();

  auto want = [&](uint32_t page, double priority) {
    auto p = static_cast<float>(std::min<double>(priority, std::numeric_limits<float>::max()));
    uint32_t& slot = want_slot_[page];
    // The check on the page keeps a slot left stale (a predicate that threw) harmless.
    if (slot == 0 || slot > out.wanted.size() || out.wanted[slot - 1].page != page) {
      out.wanted.push_back({page, p});
      slot = static_cast<uint32_t>(out.wanted.size());
    } else {
      out.wanted[slot - 1].priority = std::max(out.wanted[slot - 1].priority, p);
    }
  };

  // 1. Groups, parents first. A group is examined only once every produced cluster it has is a
  //    root or has a refined parent (ready_ == need_), which keeps the refined set closed toward
  //    the roots and limits the work to the groups along the cut.
  //    With look_ahead, a group blocked by missing pages, or reached only through such groups,
  //    still passes its decision down (reach_), so the finer groups it would expose are decided
  //    too: they draw nothing, but ask for their pages in the same frame.
  for (uint32_t g : order_) {
    if (reach_[g] != need_[g]) continue;
    const bool shown = ready_[g] == need_[g];  // else only reached by looking past
    if (shown) ++stats.groups_visited;
    const pkg::GroupRecord& group = groups[g];
    glm::dvec3 center = toDouble(group.lod_center);
    double radius = group.lod_radius;
    if (options.frustum_cull && !view.frustum.intersectsSphere(center, radius)) {
      if (shown) refined_[g] = kOutside;  // nothing of it shows: costs nothing, asks for no page
      continue;
    }
    double error_px = errorPx(group.error, center, radius, view);
    if (!(error_px > options.tau_px)) continue;
    bool resident = true;
    for (uint32_t k = child_page_offsets_[g]; k < child_page_offsets_[g + 1]; ++k) {
      uint32_t page = child_pages_[k];
      if (!page_resident(page)) {
        resident = false;
        want(page, error_px);
      }
    }
    if (!shown || !resident) {
      if (shown) ++stats.groups_blocked;  // its produced clusters (resident ancestors) show
      else ++stats.groups_looked_past;
      if (!options.look_ahead) continue;
      refined_[g] = kLookedPast;
      for (uint32_t k = child_offsets_[g]; k < child_offsets_[g + 1]; ++k) {
        uint32_t producer = child_producers_[k];
        if (producer != kNone) ++reach_[producer];
      }
      continue;
    }
    refined_[g] = kByError;
    ++stats.groups_refined;
    refined_list_.push_back(g);
    for (uint32_t k = child_offsets_[g]; k < child_offsets_[g + 1]; ++k) {
      uint32_t producer = child_producers_[k];
      if (producer != kNone) {
        ++ready_[producer];
        ++reach_[producer];
      }
    }
  }

  // 2. Clusters exposed by those decisions: roots, and children of groups refined by error,
  //    unless their own producing group is refined too (then finer clusters replace them).
  auto consider = [&](uint32_t index) {
    const pkg::ClusterRecord& c = clusters[index];
    if (c.group != kNone && hides(c.group)) {
      // Hidden by its own group: finer clusters replace it, or nothing of it is in view.
      if (refined_[c.group] == kOutside) ++stats.culled_frustum;
      return;
    }
    ++stats.clusters_tested;
    glm::dvec3 center = toDouble(c.center);
    if (options.frustum_cull && (!view.frustum.intersectsSphere(center, c.radius) ||
                                 !view.frustum.intersectsBox(toDouble(c.aabb_min),
                                                             toDouble(c.aabb_max)))) {
      ++stats.culled_frustum;
      return;
    }
    if (options.min_feature_px > 0.0) {
      double distance = glm::length(center - view.eye) - c.radius;
      if (distance > 0.0 &&
          2.0 * c.radius * view.pixel_scale / std::max(distance, view.near_m) <
              options.min_feature_px) {
        ++stats.culled_small;
        return;
      }
    }
    if (c.kind == static_cast<uint8_t>(pkg::ClusterKind::Mesh)) {
      out.clusters.push_back(index);
      stats.triangles += c.triangle_count;
    } else {
      out.parametric_clusters.push_back(index);
      stats.parametric_instances += c.instance_count;
    }
  };

  for (uint32_t root : roots_) {
    const pkg::ClusterRecord& c = clusters[root];
    if (c.group != kNone && hides(c.group)) {
      if (options.collect_draws) consider(root);  // counts it when culled with its group
      continue;
    }
    if (!page_resident(c.page)) {
      // Nothing resident stands in for a root: the frame loop pins root pages, so this only
      // happens at start-up. Ask for it first.
      want(c.page, std::numeric_limits<double>::max());
      continue;
    }
    if (options.collect_draws) consider(root);
  }
  if (options.collect_draws) {
    for (uint32_t p : parametric_) consider(p);
    for (uint32_t g : refined_list_)
      for (uint32_t k = child_offsets_[g]; k < child_offsets_[g + 1]; ++k) {
        uint32_t producer = child_producers_[k];
        // Replaced by finer clusters: skip without touching the record.
        if (producer != kNone && refined_[producer] == kByError) continue;
        consider(children_[k]);
      }
  }

  for (const PageWant& w : out.wanted) want_slot_[w.page] = 0;
}

}  // namespace tw
