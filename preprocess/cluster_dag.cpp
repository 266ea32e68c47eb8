// Level-by-level LOD DAG builder: grouping (cluster_grouping.h), locked-border simplification with a checked
// topology-free fallback, re-clustering, errors and bounds. See cluster_dag.h for the contract.
#include "cluster_dag.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

#include <meshoptimizer.h>
#include <optional>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include "cluster_grouping.h"
#include "clusterize.h"
#include "edge_counts.h"
#include "far_proxy.h"
#include "grid_weld.h"
#include "locked_vertex_clustering.h"
#include "near_group_vertices.h"
#include "repeated_triangles.h"
#include "rim_join.h"
#include "union_find.h"

namespace tw {

namespace {

static_assert(sizeof(glm::vec3) == 3 * sizeof(float), "meshoptimizer reads packed float3");

constexpr uint32_t kUnowned = std::numeric_limits<uint32_t>::max();
constexpr uint32_t kMulti = kUnowned - 1;  // vertex or edge used by more than one group

struct BoundSphere {
  glm::vec3 center{0.0f};
  float radius = 0.0f;
};

// A sphere enclosing spheres: centred on their bounding box, radius to the farthest one.
BoundSphere enclose(const std::vector<BoundSphere>& spheres) {
  if (spheres.empty()) return {};
  glm::vec3 lo(INFINITY), hi(-INFINITY);
  for (const BoundSphere& s : spheres) {
    lo = glm::min(lo, s.center - glm::vec3(s.radius));
    hi = glm::max(hi, s.center + glm::vec3(s.radius));
  }
  BoundSphere out;
  out.center = 0.5f * (lo + hi);
  for (const BoundSphere& s : spheres)
    out.radius = std::max(out.radius, glm::length(s.center - out.center) + s.radius);
  out.radius *= 1.0f + 1e-6f;  // float rounding must not make a child poke out
  return out;
}

// A cluster while the DAG is built: global (welded) vertex indices and one id per triangle.
struct WorkCluster {
  std::vector<uint32_t> tris;
  std::vector<uint32_t> ids;
};

// tris index positions; vertices are numbered in order of first use. slot: one entry per
// position, all kUnowned on entry and on return (scratch, so a cluster costs its own size rather
// than a hash map).
DagCluster makeCluster(std::span<const glm::vec3> positions, std::span<const uint32_t> tris,
                       const std::vector<uint32_t>& ids, std::vector<uint32_t>& slot) {
  DagCluster c;
  c.indices.reserve(tris.size());
  for (uint32_t v : tris) {
    if (slot[v] == kUnowned) {
      slot[v] = static_cast<uint32_t>(c.positions.size());
      c.positions.push_back(positions[v]);
    }
    c.indices.push_back(slot[v]);
  }
  for (uint32_t v : tris) slot[v] = kUnowned;
  c.triangle_object_ids = ids;
  c.box_min = glm::vec3(INFINITY);
  c.box_max = glm::vec3(-INFINITY);
  for (const glm::vec3& p : c.positions) {
    c.box_min = glm::min(c.box_min, p);
    c.box_max = glm::max(c.box_max, p);
  }
  c.sphere_center = 0.5f * (c.box_min + c.box_max);
  for (const glm::vec3& p : c.positions)
    c.sphere_radius = std::max(c.sphere_radius, glm::length(p - c.sphere_center));
  c.sphere_radius *= 1.0f + 1e-6f;
  c.lod_center = c.parent_lod_center = c.sphere_center;
  c.lod_radius = c.parent_lod_radius = c.sphere_radius;
  return c;
}

// Per vertex: the most frequent object id among the triangles using it (ties: the smaller id).
std::vector<uint32_t> vertexObjectIds(const std::vector<uint32_t>& tris,
                                      const std::vector<uint32_t>& ids, size_t vertex_count) {
  // Bucket the corners by vertex (counting sort), then sort each vertex's few ids.
  std::vector<uint32_t> offsets(vertex_count + 1, 0);
  for (uint32_t v : tris) ++offsets[v + 1];
  for (size_t v = 0; v < vertex_count; ++v) offsets[v + 1] += offsets[v];
  std::vector<uint32_t> fill(offsets.begin(), offsets.end() - 1);
  std::vector<uint32_t> corner_ids(tris.size());
  for (size_t i = 0; i < tris.size(); ++i) corner_ids[fill[tris[i]]++] = ids[i / 3];
  std::vector<uint32_t> result(vertex_count, 0);
  for (size_t v = 0; v < vertex_count; ++v) {
    auto first = corner_ids.begin() + offsets[v], last = corner_ids.begin() + offsets[v + 1];
    std::sort(first, last);
    size_t best_run = 0;
    for (auto i = first; i != last;) {
      auto j = i + 1;
      while (j != last && *j == *i) ++j;
      if (size_t(j - i) > best_run) {
        best_run = size_t(j - i);
        result[v] = *i;
      }
      i = j;
    }
  }
  return result;
}

std::vector<uint32_t> triangleObjectIds(const std::vector<uint32_t>& tris,
                                        const std::vector<uint32_t>& vertex_ids) {
  std::vector<uint32_t> ids(tris.size() / 3);
  for (size_t t = 0; t < ids.size(); ++t) {
    uint32_t a = vertex_ids[tris[3 * t]], b = vertex_ids[tris[3 * t + 1]],
             c = vertex_ids[tris[3 * t + 2]];
    ids[t] = (b == c && a != b) ? b : a;  // majority of three; all different: the first
  }
  return ids;
}

// Read-only state shared by the groups of one level attempt.
struct LevelContext {
  const std::vector<glm::vec3>& positions;
  const std::vector<uint32_t>& vertex_owner;      // group id, or kMulti
  const std::vector<uint64_t>& shared_edges;  // global edges used by several groups, sorted
  const std::vector<uint8_t>& open_vertex;         // on a locked open edge (lock_open_boundaries)
  const std::vector<uint8_t>& near_other_group;    // within the package's grid error of another
                                                   // group's vertex (near_group_vertices.h)
  const std::vector<uint64_t>& open_edges;  // locked open edges of the first front, sorted
  // The level's vertex pairs within what the package's grid will not tell apart (nullptr: exact
  // positions, no grid).
  const NearVertexIndex* near_index;
  const DagOptions& options;
  // false: a group that wants a far proxy (options.allow_proxy) only says so (GroupOutcome::
  // proxy_wanted) and keeps its best result without one. See the level loop.
  bool build_proxies = true;
};

struct GroupOutcome {
  // Vertices the group created (far proxy). The clusters refer to new vertex j as
  // positions.size() + j, positions being the level's; the caller renumbers them when it appends.
  std::vector<glm::vec3> new_positions;
  std::vector<WorkCluster> clusters;
  // The same clusters as package clusters (makeCluster), made here so that the level's groups
  // make them in parallel; level, group, error and LOD bounds are set when the level is put
  // together.
  std::vector<DagCluster> made;
  float error = 0.0f;  // absolute simplification error, before taking the children's into account
  GroupMethod method = GroupMethod::PassThrough;
  uint64_t triangles = 0;
  bool locked_rejected = false;
  bool merged_rejected = false;
  bool sloppy_rejected = false;
  bool proxy_rejected = false;
  bool proxy_skipped = false;  // dropping was sure to win: no proxy built
  bool proxy_wanted = false;   // would build a proxy, but ctx.build_proxies was false
  // With a proxy, the group could come down to no fewer than this many triangles (the border
  // part plus one): the level loop's optimistic estimate.
  uint64_t proxy_floor_triangles = 0;
};

// A far proxy's voxel comes out at least this fraction of predictFarProxyVoxel's (one retry
// refines by at most 0.7x), and its measured error is at least about iso_voxels voxels.
constexpr float kProxyVoxelFloor = 0.7f;

// A locked result with an error above this fraction of its group's extent is weighed against
// vertex clustering (well simplified groups stay near 1e-3).
constexpr float kMergeTrialError = 0.01f;

struct Candidate {
  std::vector<uint32_t> tris;  // local vertex indices; vcount + j is extra[j]
  std::vector<uint32_t> ids;
  float error = 0.0f;
  GroupMethod method = GroupMethod::PassThrough;
  std::vector<glm::vec3> extra;  // new vertices (far proxy)
};

void append(std::vector<uint32_t>& to, const std::vector<uint32_t>& from) {
  to.insert(to.end(), from.begin(), from.end());
}

// Global vertex -> group-local index: open addressing sized to the group, so per-group memory
// stays proportional to the group whatever the model size. A slot holds key << 32 | value.
struct LocalIndexMap {
  static constexpr uint64_t kEmpty = ~uint64_t(0);
  std::vector<uint64_t> slots;
  int shift = 32;

  // Room for up to n keys at load factor <= 1/2.
  void reset(size_t n) {
    size_t bits = 4;
    while ((size_t(1) << bits) < 2 * n) ++bits;
    slots.assign(size_t(1) << bits, kEmpty);
    shift = 32 - int(bits);
  }
  size_t find(uint32_t key) const {
    const size_t mask = slots.size() - 1;
    size_t i = shift >= 32 ? 0 : size_t((key * 2654435761u) >> shift);
    while (slots[i] != kEmpty && uint32_t(slots[i] >> 32) != key) i = (i + 1) & mask;
    return i;
  }
  void release() {
    if (slots.size() > (size_t(1) << 20)) slots = {};  // a huge one-off group: give it back
  }
};

GroupOutcome processGroup(const LevelContext& ctx, const std::vector<WorkCluster>& work,
                          const std::vector<uint32_t>& members) {
  const DagOptions& options = ctx.options;
  GroupOutcome outcome;

  // Gather the group into a compact local vertex buffer: meshoptimizer's cost and its error
  // scale both depend on the whole vertex buffer it is given.
  std::vector<uint32_t> gtris, gids;
  for (uint32_t m : members) {
    append(gtris, work[m].tris);
    append(gids, work[m].ids);
  }
  // Local vertices in ascending global order (unique first, so only they are sorted).
  thread_local LocalIndexMap to_local;
  to_local.reset(gtris.size());
  std::vector<uint32_t> l2g;
  l2g.reserve(gtris.size() / 2 + 16);
  for (uint32_t v : gtris) {
    const size_t i = to_local.find(v);
    if (to_local.slots[i] == LocalIndexMap::kEmpty) {
      to_local.slots[i] = uint64_t(v) << 32;
      l2g.push_back(v);
    }
  }
  std::sort(l2g.begin(), l2g.end());
  for (size_t v = 0; v < l2g.size(); ++v)
    to_local.slots[to_local.find(l2g[v])] = (uint64_t(l2g[v]) << 32) | v;
  std::vector<uint32_t> ltris(gtris.size());
  for (size_t i = 0; i < gtris.size(); ++i)
    ltris[i] = uint32_t(to_local.slots[to_local.find(gtris[i])]);
  to_local.release();
  std::vector<glm::vec3> lpos(l2g.size());
  for (size_t v = 0; v < l2g.size(); ++v) lpos[v] = ctx.positions[l2g[v]];
  const float* pos = &lpos[0].x;
  const size_t vcount = lpos.size();
  const size_t stride = sizeof(glm::vec3);
  const float scale = meshopt_simplifyScale(pos, vcount, stride);
  auto isMulti = [&](uint32_t local) { return ctx.vertex_owner[l2g[local]] == kMulti; };
  // A vertex that pins its component: shared with another group, on a locked open edge, or
  // where another group's vertex almost touches it.
  auto isPinned = [&](uint32_t local) {
    return isMulti(local) || (!ctx.open_vertex.empty() && ctx.open_vertex[l2g[local]]) ||
           ctx.near_other_group[l2g[local]];
  };

  // Rims of the group that almost meet are joined first (rim_join.h). Only vertices the level's
  // near-vertex index saw near another are candidates (most groups have none).
  float joined_m = 0.0f;
  if (ctx.near_index) {
    std::vector<uint8_t> may_join(vcount, 0);
    for (uint32_t v = 0; v < vcount; ++v)
      may_join[v] = ctx.near_index->hasNeighbour(l2g[v]) && !isPinned(v);
    joined_m = joinNearRims(lpos, ltris, gids, may_join, ctx.near_index->tolerance());
  }

  const EdgeCounts in = countEdges(ltris, vcount);
  std::vector<uint64_t> shared;  // edges whose triangle count must not change
  for (const EdgeCount& ec : in) {
    const uint64_t e = ec.key;
    uint32_t a = uint32_t(e >> 32), b = uint32_t(e);
    const uint64_t global = edgeKey(l2g[a], l2g[b]);
    if ((isMulti(a) && isMulti(b) && containsSorted(ctx.shared_edges, global)) ||
        (!ctx.open_edges.empty() && containsSorted(ctx.open_edges, global)))
      shared.push_back(e);
  }
  // Already sorted: in is sorted by key.
  const std::vector<uint32_t> vertex_ids = vertexObjectIds(ltris, gids, vcount);

  const size_t n = gids.size();
  const size_t limit = static_cast<size_t>(options.min_shrink_ratio * double(n));
  const size_t half_indices = (n / 2) * 3;
  Candidate best{ltris, gids, 0.0f, GroupMethod::PassThrough, {}};
  auto consider = [&](Candidate&& c) {
    if (!c.tris.empty() && c.tris.size() < best.tris.size()) best = std::move(c);
  };

  // 1. The whole group, border locked.
  std::vector<uint32_t> out(ltris.size());
  float err = 0.0f;
  size_t count = meshopt_simplify(out.data(), ltris.data(), ltris.size(), pos, vcount, stride,
                                  half_indices, options.max_relative_error,
                                  meshopt_SimplifyLockBorder, &err);
  out.resize(count);
  if (count < ltris.size()) {
    if (borderPreserved(in, shared, out, vcount)) {
      auto ids = triangleObjectIds(out, vertex_ids);
      consider({std::move(out), std::move(ids), err * scale, GroupMethod::Locked, {}});
    } else {
      outcome.locked_rejected = true;
    }
  }

  // 2. Vertex clustering of the whole group with its border held (every vertex shared with
  // another group or on a locked seam; the rims of unbalanced edges merge only among themselves).
  // Tried when the locked result falls short, or reaches the target only with an error above
  // kMergeTrialError of the group's extent (meshopt then collapsed whole features, which the
  // clustering may do with less); of two results that both reach the target, the smaller error
  // wins.
  const bool locked_fits = best.tris.size() / 3 <= limit;
  if ((!locked_fits || best.error > kMergeTrialError * scale) && options.allow_merge) {
    std::vector<uint8_t> roles(vcount, kFreeVertex);
    for (uint32_t v = 0; v < vcount; ++v)
      if (isPinned(v)) roles[v] = kLockedVertex;
    markRimVertices(ltris, roles);
    VertexClusteringResult merged = simplifyByLockedVertexClustering(lpos, ltris, roles, n / 2, limit);
    std::vector<uint8_t> locked(vcount);
    for (uint32_t v = 0; v < vcount; ++v) locked[v] = (roles[v] & kLockedVertex) != 0;
    if (merged.tris.size() < best.tris.size() && !merged.tris.empty()) {
      if (borderPreserved(in, shared, merged.tris, vcount, &locked)) {
        std::vector<uint32_t> ids(merged.source_triangle.size());
        for (size_t t = 0; t < ids.size(); ++t) ids[t] = gids[merged.source_triangle[t]];
        // It is smaller than best (tested above); it must reach the target, and beat a locked
        // result that reached it too on error.
        if (merged.tris.size() / 3 <= limit && (!locked_fits || merged.error < best.error))
          best = {std::move(merged.tris), std::move(ids), merged.error, GroupMethod::Merged, {}};
      } else {
        outcome.merged_rejected = true;
      }
    }
  }

  // 3. Still not enough: topology-free simplification, only on free components.
  if (best.tris.size() / 3 > limit && (options.allow_sloppy || options.allow_drop)) {
    UnionFind components(vcount);
    for (size_t i = 0; i < ltris.size(); i += 3) {
      components.unite(ltris[i], ltris[i + 1]);
      components.unite(ltris[i], ltris[i + 2]);
    }
    std::vector<uint8_t> free_root(vcount, 1);
    for (uint32_t v = 0; v < vcount; ++v)
      if (isPinned(v)) free_root[components.find(v)] = 0;
    std::vector<uint32_t> btris, bids, ftris, fids;
    for (size_t t = 0; t < n; ++t) {
      bool is_free = free_root[components.find(ltris[3 * t])];
      auto& tris = is_free ? ftris : btris;
      (is_free ? fids : bids).push_back(gids[t]);
      tris.insert(tris.end(), ltris.begin() + 3 * t, ltris.begin() + 3 * t + 3);
    }

    if (!ftris.empty()) {
      // The border part keeps the locked treatment.
      std::vector<uint32_t> rb = btris, rb_ids = bids;
      float err_b = 0.0f;
      if (!btris.empty()) {
        out.resize(btris.size());
        count = meshopt_simplify(out.data(), btris.data(), btris.size(), pos, vcount, stride,
                                 (btris.size() / 6) * 3, options.max_relative_error,
                                 meshopt_SimplifyLockBorder, &err);
        out.resize(count);
        if (count < btris.size() && borderPreserved(in, shared, out, vcount)) {
          rb_ids = triangleObjectIds(out, vertex_ids);
          rb = std::move(out);
          err_b = err * scale;
        }
      }
      const size_t nb = rb.size() / 3, nf = ftris.size() / 3;
      const size_t wanted = n / 2 > nb ? n / 2 - nb : 0;
      const size_t target_f = std::clamp(wanted, nf / 4, nf / 2);
      const std::vector<uint64_t> no_shared;  // free components share no edge by definition

      if (options.allow_sloppy) {
        // Sloppy picks each grid cell's representative among *all* vertices it is given, so it
        // gets the free components' vertices only: its output must not touch the border part.
        // Free vertices in ascending order; l2f maps a group-local vertex to its place among them.
        std::vector<uint32_t> l2f(vcount, kUnowned);
        std::vector<uint32_t> f2l;
        for (uint32_t v : ftris)
          if (l2f[v] == kUnowned) {
            l2f[v] = 0;
            f2l.push_back(v);
          }
        std::sort(f2l.begin(), f2l.end());
        for (size_t v = 0; v < f2l.size(); ++v) l2f[f2l[v]] = uint32_t(v);
        std::vector<uint32_t> flocal(ftris.size());
        for (size_t i = 0; i < ftris.size(); ++i) flocal[i] = l2f[ftris[i]];
        std::vector<glm::vec3> fpos(f2l.size());
        for (size_t v = 0; v < f2l.size(); ++v) fpos[v] = lpos[f2l[v]];
        std::vector<uint32_t> rf(ftris.size());
        float err_f = 0.0f;
        count = meshopt_simplifySloppy(rf.data(), flocal.data(), flocal.size(), &fpos[0].x,
                                       fpos.size(), stride, target_f * 3,
                                       options.max_relative_error, &err_f);
        rf.resize(count);
        for (uint32_t& v : rf) v = f2l[v];
        const float f_scale = meshopt_simplifyScale(&fpos[0].x, fpos.size(), stride);
        if (borderPreserved(in, no_shared, rf, vcount)) {
          Candidate c{rb, rb_ids, std::max(err_b, err_f * f_scale), GroupMethod::Sloppy, {}};
          append(c.tris, rf);
          append(c.ids, triangleObjectIds(rf, vertex_ids));
          consider(std::move(c));
        } else {
          outcome.sloppy_rejected = true;
        }
      }

      // Dropping whole free components, smallest first (a vanished part's error is its size):
      // the last resort, and the far proxy's rival. Built first, as it is cheap and tells
      // whether a proxy is worth its cost.
      const bool short_of_target = best.tris.size() / 3 > limit;
      Candidate drop{{}, {}, 0.0f, GroupMethod::Dropped, {}};
      if (short_of_target && options.allow_drop) {
        struct Component {
          float diagonal;
          uint32_t first_triangle;
          uint32_t root;
          uint32_t triangles;
        };
        std::vector<uint32_t> slot(vcount, kUnowned);  // component root -> index in parts
        std::vector<Component> parts;
        std::vector<glm::vec3> lo, hi;
        for (size_t t = 0; t < nf; ++t) {
          uint32_t root = components.find(ftris[3 * t]);
          if (slot[root] == kUnowned) {
            slot[root] = uint32_t(parts.size());
            parts.push_back({0.0f, uint32_t(t), root, 0});
            lo.push_back(glm::vec3(INFINITY));
            hi.push_back(glm::vec3(-INFINITY));
          }
          const uint32_t part = slot[root];
          parts[part].triangles++;
          for (int k = 0; k < 3; ++k) {
            lo[part] = glm::min(lo[part], lpos[ftris[3 * t + k]]);
            hi[part] = glm::max(hi[part], lpos[ftris[3 * t + k]]);
          }
        }
        for (size_t p = 0; p < parts.size(); ++p) parts[p].diagonal = glm::length(hi[p] - lo[p]);
        std::sort(parts.begin(), parts.end(), [](const Component& a, const Component& b) {
          return a.diagonal < b.diagonal ||
                 (a.diagonal == b.diagonal && a.first_triangle < b.first_triangle);
        });
        std::vector<uint8_t> dropped(vcount, 0);  // by component root
        size_t kept = nf;
        float dropped_error = 0.0f;
        for (size_t p = 0; p < parts.size() && kept > target_f; ++p) {
          if (p + 1 == parts.size() && nb == 0) break;  // a group never vanishes entirely
          dropped[parts[p].root] = 1;
          kept -= parts[p].triangles;
          dropped_error = std::max(dropped_error, parts[p].diagonal);
        }
        drop = Candidate{rb, rb_ids, std::max(err_b, dropped_error), GroupMethod::Dropped, {}};
        for (size_t t = 0; t < nf; ++t) {
          if (dropped[components.find(ftris[3 * t])]) continue;
          drop.tris.insert(drop.tris.end(), ftris.begin() + 3 * t, ftris.begin() + 3 * t + 3);
          drop.ids.push_back(fids[t]);
        }
      }
      const bool drop_fits = !drop.tris.empty() && drop.tris.size() / 3 <= limit;

      // Far proxy: many small free parts as one closed shell, when sloppy fell short on them.
      // (Tried also against an accepted sloppy result, it never won on error in the tests:
      // sloppy's error is meshopt's estimate, the proxy's a measured bound; so it is not paid
      // for.) When the best result already holds no more than target_f free triangles, the
      // border part is what keeps the group long, which a proxy cannot fix: on the 10M plant
      // such proxies were 63% of those built and 92% of them were thrown away.
      const bool free_part_short = best.tris.size() / 3 > nb + target_f;
      if (options.allow_proxy && short_of_target && free_part_short) {
        uint32_t free_components = 0;
        double free_area = 0.0;
        glm::vec3 free_lo(INFINITY), free_hi(-INFINITY);
        {
          std::vector<uint8_t> seen(vcount, 0);
          for (size_t i = 0; i < ftris.size(); i += 3) {
            const uint32_t root = components.find(ftris[i]);
            free_components += seen[root] == 0;
            seen[root] = 1;
            const glm::vec3 &a = lpos[ftris[i]], &b = lpos[ftris[i + 1]], &c = lpos[ftris[i + 2]];
            free_area += 0.5 * double(glm::length(glm::cross(b - a, c - a)));
            free_lo = glm::min(free_lo, glm::min(a, glm::min(b, c)));
            free_hi = glm::max(free_hi, glm::max(a, glm::max(b, c)));
          }
        }
        FarProxyOptions po;
        po.target_triangles = uint32_t(std::max<size_t>(target_f, 1));
        po.min_fill = 0.0f;
        po.band_margin_voxels = 1.0f;
        // A proxy's error is at least about its iso offset, and its voxel comes out at least
        // 0.7x the predicted one: when dropping already reaches the target with proxy_error_slack
        // times less than that, dropping wins below anyway, so the proxy is not built.
        const glm::vec3 free_extent = free_hi - free_lo;
        const float predicted_voxel = predictFarProxyVoxel(
            free_area, po.target_triangles,
            std::max({free_extent.x, free_extent.y, free_extent.z}), po);
        const float proxy_error_floor =
            std::max(err_b, kProxyVoxelFloor * po.iso_voxels * predicted_voxel);
        const bool drop_wins_anyway =
            options.allow_drop && drop_fits &&
            drop.error * options.proxy_error_slack < proxy_error_floor;
        if (free_components >= options.proxy_min_components && drop_wins_anyway) {
          outcome.proxy_skipped = true;
        } else if (free_components >= options.proxy_min_components && !ctx.build_proxies) {
          outcome.proxy_wanted = true;
          outcome.proxy_floor_triangles = nb + 1;
        } else if (free_components >= options.proxy_min_components) {
          FarProxy proxy = buildFarProxy({lpos, ftris, fids}, po);
          const size_t total = nb + proxy.triangleCount();
          std::vector<uint32_t> rp(proxy.indices);
          for (uint32_t& v : rp) v += uint32_t(vcount);
          if (proxy.triangleCount() == 0 || total >= best.tris.size() / 3) {
            // no gain: keep what we have
          } else if (!borderPreserved(in, no_shared, rp, vcount + proxy.positions.size())) {
            outcome.proxy_rejected = true;  // a proxy shell is closed: this is only a guard
          } else {
            Candidate c{rb, rb_ids, std::max(err_b, proxy.part_error), GroupMethod::Proxy,
                        std::move(proxy.positions)};
            append(c.tris, rp);
            append(c.ids, proxy.triangle_object_ids);
            best = std::move(c);
          }
        }
      }

      // Both count a part that disappears (dropped, or hidden in a shell) as its size, but the
      // proxy keeps dense areas closed where dropping opens holes the error does not see; so
      // dropping replaces a proxy only with an error proxy_error_slack times lower.
      if (!drop.tris.empty()) {
        const bool proxy_fits =
            best.method == GroupMethod::Proxy && best.tris.size() / 3 <= limit;
        if (!proxy_fits)
          consider(std::move(drop));
        else if (drop_fits && drop.error * options.proxy_error_slack < best.error)
          best = std::move(drop);
      }
    }
  }

  // 4. Cut the result into clusters again.
  outcome.error = std::max(best.error, joined_m);
  outcome.method = best.method;
  outcome.triangles = best.tris.size() / 3;
  lpos.insert(lpos.end(), best.extra.begin(), best.extra.end());
  const uint32_t first_new = uint32_t(ctx.positions.size());
  auto toGlobal = [&](uint32_t local) {
    return local < vcount ? l2g[local] : first_new + (local - uint32_t(vcount));
  };
  outcome.new_positions = std::move(best.extra);
  TriangleClusters split =
      clusterizeTrianglesByObject(lpos, best.tris, best.ids, options.cluster_size);
  outcome.clusters.resize(split.clusterCount());
  outcome.made.reserve(split.clusterCount());
  std::vector<uint32_t> local_tris, slot(lpos.size(), kUnowned);
  for (size_t c = 0; c < split.clusterCount(); ++c) {
    WorkCluster& wc = outcome.clusters[c];
    const uint32_t first = split.offsets[c], last = split.offsets[c + 1];
    wc.tris.reserve(3 * size_t(last - first));
    wc.ids.reserve(last - first);
    local_tris.clear();
    for (uint32_t i = first; i < last; ++i) {
      uint32_t t = split.triangles[i];
      for (int k = 0; k < 3; ++k) {
        local_tris.push_back(best.tris[3 * t + k]);
        wc.tris.push_back(toGlobal(best.tris[3 * t + k]));
      }
      wc.ids.push_back(best.ids[t]);
    }
    // Local and global numbering list the same positions in the same order of first use.
    outcome.made.push_back(makeCluster(lpos, local_tris, wc.ids, slot));
  }
  return outcome;
}

// Whether lock_open_boundaries locks a first-front edge used by `triangles` triangles: a brick
// seam (is_seam_edge) whatever its count here, as the other brick may use it too (a non-manifold
// edge used three times here and once there is still where the two bricks meet); without
// is_seam_edge, every open edge.
bool isLockedEdge(size_t triangles, const glm::vec3& a, const glm::vec3& b,
                  const DagOptions& options) {
  if (!options.lock_open_boundaries) return false;
  return options.is_seam_edge ? options.is_seam_edge(a, b) : triangles == 1;
}

// Vertices of the open edges that continueClusterDag will lock for good (lock_open_boundaries,
// filtered by is_seam_edge): the grid weld must not move them. Empty when nothing is locked.
std::vector<uint8_t> lockedSeamVertices(const std::vector<glm::vec3>& positions,
                                        const std::vector<uint32_t>& tris,
                                        const DagOptions& options) {
  std::vector<uint8_t> keep;
  if (!options.lock_open_boundaries) return keep;
  keep.assign(positions.size(), 0);
  for (const EdgeCount& e : countEdges(tris, positions.size())) {
    const uint32_t a = uint32_t(e.key >> 32), b = uint32_t(e.key);
    if (isLockedEdge(e.count, positions[a], positions[b], options)) keep[a] = keep[b] = 1;
  }
  return keep;
}

// Groups the clusters listed in `regroup` (ascending) and puts those groups after the groups of
// the previous attempt that hold none of them, which keep their outcomes; fresh[g] = 1 for the
// new groups. When `regroup` lists every cluster, the level is grouped anew. Large objects are
// grouped apart, except when the groups would be as large as the clusters to group: then they
// are one group (the level's last resort).
void regroupClusters(std::span<const std::span<const uint32_t>> cluster_tris,
                     std::span<const std::span<const uint32_t>> cluster_ids,
                     std::span<const glm::vec3> centers, const std::vector<uint32_t>& regroup,
                     uint64_t group_size, uint32_t cluster_size, size_t vertex_count,
                     std::vector<std::vector<uint32_t>>& groups,
                     std::vector<GroupOutcome>& outcomes, std::vector<uint8_t>& fresh) {
  std::vector<std::span<const uint32_t>> sub_tris, sub_ids;
  std::vector<glm::vec3> sub_centers;
  for (uint32_t c : regroup) {
    sub_tris.push_back(cluster_tris[c]);
    sub_ids.push_back(cluster_ids[c]);
    sub_centers.push_back(centers[c]);
  }
  const uint32_t size = uint32_t(std::min<uint64_t>(group_size, regroup.size()));
  std::vector<std::vector<uint32_t>> made =
      size < regroup.size()
          ? groupClustersByObject(sub_tris, sub_ids, sub_centers, size, cluster_size, vertex_count)
          : groupClusters(sub_tris, sub_centers, size, vertex_count);
  for (std::vector<uint32_t>& group : made)
    for (uint32_t& m : group) m = regroup[m];

  std::vector<std::vector<uint32_t>> next_groups;
  std::vector<GroupOutcome> next_outcomes;
  if (regroup.size() < cluster_tris.size()) {
    std::vector<uint8_t> regrouped(cluster_tris.size(), 0);
    for (uint32_t c : regroup) regrouped[c] = 1;
    for (size_t g = 0; g < groups.size(); ++g)
      if (!regrouped[groups[g].front()]) {
        next_groups.push_back(std::move(groups[g]));
        next_outcomes.push_back(std::move(outcomes[g]));
      }
  }
  fresh.assign(next_groups.size(), 0);
  for (std::vector<uint32_t>& group : made) {
    next_groups.push_back(std::move(group));
    next_outcomes.emplace_back();
    fresh.push_back(1);
  }
  groups = std::move(next_groups);
  outcomes = std::move(next_outcomes);
}

// Whether each group did not shrink to min_shrink_ratio of its input.
std::vector<uint8_t> failedGroups(const std::vector<WorkCluster>& work,
                                  const std::vector<std::vector<uint32_t>>& groups,
                                  const std::vector<GroupOutcome>& outcomes,
                                  float min_shrink_ratio) {
  std::vector<uint8_t> failed(groups.size(), 0);
  for (size_t g = 0; g < groups.size(); ++g) {
    uint64_t input = 0;
    for (uint32_t m : groups[g]) input += work[m].ids.size();
    failed[g] = double(outcomes[g].triangles) > min_shrink_ratio * double(input);
  }
  return failed;
}

// A retried level's first resort: each group that did not shrink is merged with the groups it
// shares a vertex with (their common border is locked, which is what keeps a group from
// shrinking). A group merged with nothing keeps its outcome: its shared vertices
// stay shared whatever the others become, so its borders, and so its result, are the same.
// fresh[g] = 1 for the merged groups. Returns false, changing nothing, when no failed group
// shares a vertex with another.
bool mergeFailedGroupsWithNeighbours(const std::vector<WorkCluster>& work,
                                     const std::vector<uint8_t>& failed,
                                     const std::vector<uint32_t>& vertex_owner,
                                     std::vector<std::vector<uint32_t>>& groups,
                                     std::vector<GroupOutcome>& outcomes,
                                     std::vector<uint8_t>& fresh) {
  std::vector<std::pair<uint32_t, uint32_t>> vertex_group;  // shared vertex, a group using it
  for (uint32_t g = 0; g < groups.size(); ++g)
    for (uint32_t m : groups[g])
      for (uint32_t v : work[m].tris)
        if (vertex_owner[v] == kMulti) vertex_group.emplace_back(v, g);
  tbb::parallel_sort(vertex_group.begin(), vertex_group.end());
  vertex_group.erase(std::unique(vertex_group.begin(), vertex_group.end()), vertex_group.end());
  // Each failed group, in order, takes its neighbours that no earlier one took. Not transitive:
  // on a connected model the failed groups' neighbourhoods chain into one group of most of the
  // level; a failed group that still does not shrink merges again in the next attempt.
  std::vector<std::vector<uint32_t>> neighbours(groups.size());
  for (size_t i = 0; i < vertex_group.size();) {
    size_t j = i;
    while (j < vertex_group.size() && vertex_group[j].first == vertex_group[i].first) ++j;
    for (size_t a = i; a < j; ++a)
      if (failed[vertex_group[a].second])
        for (size_t b = i; b < j; ++b)
          if (b != a) neighbours[vertex_group[a].second].push_back(vertex_group[b].second);
    i = j;
  }
  constexpr uint32_t kAlone = kUnowned;
  std::vector<uint32_t> taken_by(groups.size(), kAlone);
  bool merged = false;
  for (uint32_t g = 0; g < groups.size(); ++g) {
    if (!failed[g] || taken_by[g] != kAlone) continue;
    std::sort(neighbours[g].begin(), neighbours[g].end());
    neighbours[g].erase(std::unique(neighbours[g].begin(), neighbours[g].end()),
                        neighbours[g].end());
    for (uint32_t n : neighbours[g])
      if (taken_by[n] == kAlone) {
        taken_by[n] = g;
        taken_by[g] = g;
        merged = true;
      }
  }
  if (!merged) return false;
  // The merged groups in place of their first member; the others kept with their outcomes.
  std::vector<uint32_t> slot(groups.size(), kUnowned);
  std::vector<std::vector<uint32_t>> next_groups;
  std::vector<GroupOutcome> next_outcomes;
  std::vector<uint8_t> next_fresh;
  for (uint32_t g = 0; g < groups.size(); ++g) {
    const uint32_t head = taken_by[g] == kAlone ? g : taken_by[g];
    if (slot[head] == kUnowned) {
      slot[head] = uint32_t(next_groups.size());
      next_groups.emplace_back();
      const bool kept = taken_by[g] == kAlone;
      next_outcomes.push_back(kept ? std::move(outcomes[g]) : GroupOutcome{});
      next_fresh.push_back(kept ? 0 : 1);
    }
    std::vector<uint32_t>& members = next_groups[slot[head]];
    members.insert(members.end(), groups[g].begin(), groups[g].end());
  }
  for (std::vector<uint32_t>& members : next_groups) std::sort(members.begin(), members.end());
  groups = std::move(next_groups);
  outcomes = std::move(next_outcomes);
  fresh = std::move(next_fresh);
  return true;
}

// A retried level's second resort, when no failed group touches another: the failed groups'
// clusters, grouped again with larger groups (disconnected small parts merge with their
// neighbours in space). When they are the clusters of the last attempt, already one group, the
// whole level is grouped again.
std::vector<uint32_t> clustersOfFailedGroups(const std::vector<std::vector<uint32_t>>& groups,
                                             const std::vector<uint8_t>& failed,
                                             size_t cluster_count,
                                             const std::vector<uint32_t>& last_regroup,
                                             uint64_t last_group_size) {
  std::vector<uint32_t> regroup;
  for (size_t g = 0; g < groups.size(); ++g)
    if (failed[g]) regroup.insert(regroup.end(), groups[g].begin(), groups[g].end());
  std::sort(regroup.begin(), regroup.end());
  if (regroup == last_regroup && last_group_size >= last_regroup.size()) {
    regroup.resize(cluster_count);
    std::iota(regroup.begin(), regroup.end(), 0u);
  }
  return regroup;
}

}  // namespace

ClusterDag buildClusterDag(const DagInput& input, const DagOptions& options) {
  if (input.indices.size() % 3 != 0)
    throw std::invalid_argument("buildClusterDag: index count is not a multiple of 3");
  if (input.triangle_object_ids.size() != input.indices.size() / 3)
    throw std::invalid_argument("buildClusterDag: need one object id per triangle");
  if (options.cluster_size == 0 || options.group_size == 0)
    throw std::invalid_argument("buildClusterDag: cluster_size and group_size must be > 0");
  for (uint32_t v : input.indices)
    if (v >= input.positions.size())
      throw std::invalid_argument("buildClusterDag: index out of range");

  ClusterDag dag;
  dag.stats.input_triangles = input.indices.size() / 3;
  if (input.indices.empty()) {
    dag.stats.root_within_limit = true;
    return dag;
  }

  // Weld by exact position: split vertices (normals, uvs) would read as open borders and lock.
  // meshopt compares bytes, so -0 becomes +0 first.
  std::vector<glm::vec3> source(input.positions.begin(), input.positions.end());
  for (glm::vec3& p : source)
    for (int k = 0; k < 3; ++k)
      if (p[k] == 0.0f) p[k] = 0.0f;
  std::vector<uint32_t> remap(source.size());
  size_t unique = meshopt_generateVertexRemap(remap.data(), input.indices.data(),
                                              input.indices.size(), &source[0].x, source.size(),
                                              sizeof(glm::vec3));
  std::vector<glm::vec3> positions(unique);
  for (size_t v = 0; v < remap.size(); ++v)
    if (remap[v] != ~0u) positions[remap[v]] = source[v];
  source = {};
  std::vector<uint32_t> tris;
  std::vector<uint32_t> ids;
  tris.reserve(input.indices.size());
  ids.reserve(input.triangle_object_ids.size());
  glm::vec3 lo(INFINITY), hi(-INFINITY);
  for (size_t t = 0; t < input.triangle_object_ids.size(); ++t) {
    uint32_t a = remap[input.indices[3 * t]], b = remap[input.indices[3 * t + 1]],
             c = remap[input.indices[3 * t + 2]];
    bool finite = true;
    for (uint32_t v : {a, b, c})
      for (int k = 0; k < 3; ++k) finite = finite && std::isfinite(positions[v][k]);
    if (a == b || b == c || a == c || !finite) {
      ++dag.stats.skipped_triangles;
      continue;
    }
    for (uint32_t v : {a, b, c}) {
      lo = glm::min(lo, positions[v]);
      hi = glm::max(hi, positions[v]);
    }
    tris.insert(tris.end(), {a, b, c});
    ids.push_back(input.triangle_object_ids[t]);
  }
  dag.stats.repeated_triangles = dropRepeatedTriangles(tris, ids);
  if (tris.empty()) return dag;
  // Strict monotonicity margin: far below any visible error, far above float rounding.
  const float epsilon = std::max(glm::length(hi - lo) * 1e-6f, 1e-12f);

  // Level 0.
  std::vector<std::vector<uint32_t>> front_tris;
  std::vector<uint32_t> front_ids;
  {
    TriangleClusters split =
        clusterizeTrianglesByObject(positions, tris, ids, options.cluster_size);
    if (options.position_step_m > 0.0) {
      GridWeld weld = weldOnPackageGrid(positions, tris, split,
                                        lockedSeamVertices(positions, tris, options),
                                        options.position_step_m, options.noise_tolerance_m);
      for (uint32_t& v : tris) v = weld.remap[v];
      positions = std::move(weld.positions);
      dag.stats.grid_welded_vertices = weld.merged_vertices;
    }
    std::vector<uint32_t> slot(positions.size(), kUnowned);
    for (size_t c = 0; c < split.clusterCount(); ++c) {
      WorkCluster wc;
      for (uint32_t i = split.offsets[c]; i < split.offsets[c + 1]; ++i) {
        uint32_t t = split.triangles[i];
        const uint32_t a = tris[3 * t], b = tris[3 * t + 1], d = tris[3 * t + 2];
        if (a == b || b == d || a == d) {  // collapsed by the grid weld
          ++dag.stats.skipped_triangles;
          continue;
        }
        wc.tris.insert(wc.tris.end(), {a, b, d});
        wc.ids.push_back(ids[t]);
      }
      if (wc.ids.empty()) continue;
      front_ids.push_back(uint32_t(dag.clusters.size()));
      dag.clusters.push_back(makeCluster(positions, wc.tris, wc.ids, slot));
      front_tris.push_back(std::move(wc.tris));
    }
  }
  continueClusterDag(dag, positions, std::move(front_ids), std::move(front_tris), options, epsilon);
  return dag;
}

void continueClusterDag(ClusterDag& dag, const std::vector<glm::vec3>& positions,
                        std::vector<uint32_t> front_ids,
                        std::vector<std::vector<uint32_t>> front_tris, const DagOptions& options,
                        float epsilon) {
  if (front_ids.size() != front_tris.size())
    throw std::invalid_argument("continueClusterDag: one triangle list per front cluster");
  std::vector<WorkCluster> current_work(front_ids.size());
  for (size_t c = 0; c < front_ids.size(); ++c) {
    const DagCluster& cluster = dag.clusters.at(front_ids[c]);
    if (front_tris[c].size() != cluster.indices.size())
      throw std::invalid_argument("continueClusterDag: front triangles do not match the cluster");
    for (uint32_t v : front_tris[c])
      if (v >= positions.size())
        throw std::invalid_argument("continueClusterDag: vertex index out of range");
    current_work[c].tris = std::move(front_tris[c]);
    current_work[c].ids = cluster.triangle_object_ids;
  }
  std::vector<uint32_t> current_ids = std::move(front_ids);

  // Open edges of the first front (used by exactly one triangle) are locked for good when asked:
  // they are brick seams another DAG must meet exactly.
  std::vector<uint8_t> open_vertex;
  std::vector<uint64_t> open_edges;
  if (options.lock_open_boundaries) {
    std::vector<uint64_t> unsorted, keys;
    {
      std::vector<uint32_t> offsets;
      for (const WorkCluster& wc : current_work)
        for (size_t i = 0; i < wc.tris.size(); i += 3)
          for (int k = 0; k < 3; ++k)
            unsorted.push_back(edgeKey(wc.tris[i + k], wc.tris[i + (k + 1) % 3]));
      bucketSortEdgeKeys(unsorted, positions.size(), keys, offsets);
      unsorted = {};
    }
    open_vertex.assign(positions.size(), 0);
    for (size_t i = 0; i < keys.size();) {
      size_t j = i + 1;
      while (j < keys.size() && keys[j] == keys[i]) ++j;
      const uint32_t a = uint32_t(keys[i] >> 32), b = uint32_t(keys[i]);
      if (isLockedEdge(j - i, positions[a], positions[b], options)) {
        open_edges.push_back(keys[i]);
        open_vertex[uint32_t(keys[i] >> 32)] = open_vertex[uint32_t(keys[i])] = 1;
      } else if (j - i != 2 && options.is_near_other_brick) {
        // A rim where another brick may hold geometry within the package's grid error: held
        // like a seam (never moved), though it is not one bit for bit.
        for (uint32_t v : {a, b})
          if (options.is_near_other_brick(positions[v])) open_vertex[v] = 1;
      }
      i = j;
    }
  }

  // Far proxies create vertices: they are appended to a copy of the positions, made only when
  // the first proxy is accepted (most models never pay for it).
  const std::vector<glm::vec3>* all_positions = &positions;
  std::vector<glm::vec3> grown_positions;
  std::vector<uint32_t> vertex_owner(positions.size());
  std::vector<uint8_t> near_other_group(positions.size(), 0);
  std::vector<uint32_t> slot(positions.size(), kUnowned);
  while (current_work.size() > 1) {
    // Fixed for the level: the groups number new vertices from its size.
    const std::vector<glm::vec3>& level_positions = *all_positions;
    const uint32_t level_vertex_count = uint32_t(level_positions.size());
    uint64_t level_triangles = 0;
    uint32_t front_level = 0;
    for (size_t c = 0; c < current_work.size(); ++c) {
      level_triangles += current_work[c].ids.size();
      front_level = std::max(front_level, dag.clusters[current_ids[c]].level);
    }
    if (front_level + 1 >= options.max_levels) break;
    std::vector<glm::vec3> centers;
    for (uint32_t id : current_ids) centers.push_back(dag.clusters[id].sphere_center);

    std::vector<std::vector<uint32_t>> groups;
    std::vector<GroupOutcome> outcomes;
    uint64_t new_triangles = 0;
    bool shrunk = false;
    // The level's vertices, each once, and the near-vertex index over them (built on demand).
    std::vector<uint32_t> level_vertices;
    if (options.position_step_m > 0.0) {
      for (const WorkCluster& wc : current_work)
        for (uint32_t v : wc.tris)
          if (slot[v] == kUnowned) {
            slot[v] = 0;
            level_vertices.push_back(v);
          }
      for (uint32_t v : level_vertices) slot[v] = kUnowned;
    }
    std::optional<NearVertexIndex> near_index;
    std::vector<std::span<const uint32_t>> cluster_tris, cluster_ids;
    cluster_tris.reserve(current_work.size());
    cluster_ids.reserve(current_work.size());
    for (const WorkCluster& wc : current_work) {
      cluster_tris.push_back(wc.tris);
      cluster_ids.push_back(wc.ids);
    }
    // A level that does not shrink enough is retried: groups that did not shrink merge with
    // their neighbours (mergeFailedGroupsWithNeighbours), or, where they touch none, are grouped
    // again four times larger (clustersOfFailedGroups); the other groups keep their results.
    std::vector<uint32_t> regroup(current_work.size());
    std::iota(regroup.begin(), regroup.end(), 0u);
    std::vector<uint8_t> fresh;  // per group: its outcome is to be computed in this attempt
    float attempt_tolerance = -1.0f;
    bool regroup_pending = true;
    for (uint64_t group_size = options.group_size;; group_size *= 4) {
      if (regroup_pending)
        regroupClusters(cluster_tris, cluster_ids, centers, regroup, group_size,
                        options.cluster_size, level_positions.size(), groups, outcomes, fresh);
      // Which vertices and edges are shared between groups: those are the locked borders.
      // Only the level's own vertices are ever read: reset those, not the whole model's.
      for (const WorkCluster& wc : current_work)
        for (uint32_t v : wc.tris) vertex_owner[v] = kUnowned;
      for (uint32_t g = 0; g < groups.size(); ++g)
        for (uint32_t m : groups[g])
          for (uint32_t v : current_work[m].tris)
            vertex_owner[v] = vertex_owner[v] == kUnowned || vertex_owner[v] == g ? g : kMulti;
      // Edges between two multi-group vertices, with their group; an edge seen in two groups is
      // shared. Sorted pairs instead of a hash map: the set is the same, the cost much lower.
      std::vector<std::pair<uint64_t, uint32_t>> edge_group;
      for (uint32_t g = 0; g < groups.size(); ++g)
        for (uint32_t m : groups[g]) {
          const auto& t = current_work[m].tris;
          for (size_t i = 0; i < t.size(); i += 3)
            for (int k = 0; k < 3; ++k) {
              uint32_t a = t[i + k], b = t[i + (k + 1) % 3];
              if (vertex_owner[a] != kMulti || vertex_owner[b] != kMulti) continue;
              edge_group.emplace_back(edgeKey(a, b), g);
            }
        }
      tbb::parallel_sort(edge_group.begin(), edge_group.end());
      std::vector<uint64_t> shared_edges;
      for (size_t i = 0; i < edge_group.size();) {
        size_t j = i + 1;
        bool several = false;
        while (j < edge_group.size() && edge_group[j].first == edge_group[i].first) {
          several = several || edge_group[j].second != edge_group[i].second;
          ++j;
        }
        if (several) shared_edges.push_back(edge_group[i].first);
        i = j;
      }

      // Far proxies cost far more than the rest of a group, and a level attempt that does not
      // shrink enough is thrown away (retried with larger groups). So every group runs first
      // without them; only when the attempt could still shrink enough if every group that wants
      // a proxy came down to its floor (or when it cannot be retried) do those groups run again
      // with one. The outcome is the same as building them all, at a fraction of the cost (on
      // the 10M plant 64% of the proxies were built in attempts that were retried).
      // Vertices almost touching another group's, within what the package's grid will not
      // tell apart: the largest group decides the coarsest grid of the level (grid_weld.h).
      for (const WorkCluster& wc : current_work)
        for (uint32_t v : wc.tris) near_other_group[v] = 0;
      if (options.position_step_m > 0.0) {
        glm::vec3 largest(0.0f);
        for (const std::vector<uint32_t>& members : groups) {
          glm::vec3 lo(INFINITY), hi(-INFINITY);
          for (uint32_t m : members) {
            lo = glm::min(lo, dag.clusters[current_ids[m]].box_min);
            hi = glm::max(hi, dag.clusters[current_ids[m]].box_max);
          }
          largest = glm::max(largest, hi - lo);
        }
        const float tolerance = packageGridTolerance(largest, options.position_step_m);
        // Kept results hold only while the near-vertex tolerance does.
        if (tolerance != attempt_tolerance) fresh.assign(groups.size(), 1);
        attempt_tolerance = tolerance;
        // Attempts of one level mostly share the tolerance (the grid shift is a power of two):
        // the index is rebuilt only when it changes.
        if (!near_index || near_index->tolerance() != tolerance)
          near_index.emplace(level_positions, level_vertices, tolerance);
        near_index->markNearOtherGroups(level_positions, vertex_owner, kMulti, near_other_group);
      }
      LevelContext ctx{level_positions, vertex_owner, shared_edges,
                       open_vertex,     near_other_group, open_edges,
                       near_index ? &*near_index : nullptr, options, !options.allow_proxy};
      // Proxies are built in a second pass over the whole level: with them, nothing is kept.
      if (options.allow_proxy) fresh.assign(groups.size(), 1);
      std::vector<uint32_t> to_build;
      for (uint32_t g = 0; g < groups.size(); ++g)
        if (fresh[g]) to_build.push_back(g);
      dag.stats.groups_kept_on_retry += uint32_t(groups.size() - to_build.size());
      tbb::parallel_for(tbb::blocked_range<size_t>(0, to_build.size(), 1),
                        [&](const tbb::blocked_range<size_t>& range) {
                          for (size_t i = range.begin(); i != range.end(); ++i)
                            outcomes[to_build[i]] =
                                processGroup(ctx, current_work, groups[to_build[i]]);
                        });
      if (options.allow_proxy) {
        std::vector<uint32_t> wanting;
        uint64_t optimistic = 0;
        for (uint32_t g = 0; g < groups.size(); ++g) {
          const GroupOutcome& o = outcomes[g];
          if (o.proxy_wanted) wanting.push_back(g);
          optimistic += o.proxy_wanted ? std::min(o.triangles, o.proxy_floor_triangles)
                                       : o.triangles;
        }
        const bool could_shrink =
            optimistic < level_triangles &&
            double(optimistic) <= options.min_shrink_ratio * double(level_triangles);
        if (!wanting.empty() && (could_shrink || groups.size() == 1)) {
          ctx.build_proxies = true;
          tbb::parallel_for(tbb::blocked_range<size_t>(0, wanting.size(), 1),
                            [&](const tbb::blocked_range<size_t>& range) {
                              for (size_t i = range.begin(); i != range.end(); ++i)
                                outcomes[wanting[i]] =
                                    processGroup(ctx, current_work, groups[wanting[i]]);
                            });
        }
      }
      new_triangles = 0;
      for (const GroupOutcome& o : outcomes) new_triangles += o.triangles;
      if (new_triangles < level_triangles &&
          double(new_triangles) <= options.min_shrink_ratio * double(level_triangles)) {
        shrunk = true;
        break;
      }
      if (groups.size() == 1) break;  // one group: no locked borders left to blame
      ++dag.stats.level_retries;
      const std::vector<uint8_t> failed =
          failedGroups(current_work, groups, outcomes, options.min_shrink_ratio);
      regroup_pending =
          !mergeFailedGroupsWithNeighbours(current_work, failed, vertex_owner, groups, outcomes,
                                           fresh);
      if (regroup_pending)
        regroup = clustersOfFailedGroups(groups, failed, current_work.size(), regroup, group_size);
    }
    if (!shrunk) {
      // A small level that cannot shrink is the root; a big one takes whatever progress it got.
      if (level_triangles <= options.max_root_triangles || new_triangles >= level_triangles) break;
      ++dag.stats.levels_below_shrink;
    }

    // Assemble the next front. A group's level is its highest child level (children of merged
    // brick roots may differ); it produces clusters one level above.
    std::vector<WorkCluster> next_work;
    std::vector<uint32_t> next_ids;
    for (size_t g = 0; g < groups.size(); ++g) {
      GroupOutcome& o = outcomes[g];
      const uint32_t group_id = uint32_t(dag.groups.size());
      DagGroup group;
      group.method = o.method;
      float max_child_error = 0.0f;
      std::vector<BoundSphere> spheres;
      for (uint32_t m : groups[g]) {
        const DagCluster& child = dag.clusters[current_ids[m]];
        group.children.push_back(current_ids[m]);
        group.level = std::max(group.level, child.level);
        max_child_error = std::max(max_child_error, child.error);
        spheres.push_back({child.lod_center, child.lod_radius});
      }
      float error = std::max(o.error, max_child_error + epsilon);
      if (!(error > max_child_error)) error = std::nextafter(max_child_error, INFINITY);
      group.error = error;

      if (!o.new_positions.empty()) {
        // Renumber the group's new vertices to where they land in the grown positions.
        if (all_positions != &grown_positions) {
          grown_positions = positions;
          all_positions = &grown_positions;
        }
        const uint32_t shift = uint32_t(grown_positions.size()) - level_vertex_count;
        for (WorkCluster& wc : o.clusters)
          for (uint32_t& v : wc.tris)
            if (v >= level_vertex_count) v += shift;
        grown_positions.insert(grown_positions.end(), o.new_positions.begin(),
                               o.new_positions.end());
        vertex_owner.resize(grown_positions.size());
        near_other_group.resize(grown_positions.size(), 0);
        slot.resize(grown_positions.size(), kUnowned);
        if (!open_vertex.empty()) open_vertex.resize(grown_positions.size(), 0);
      }
      std::vector<DagCluster>& made = o.made;
      for (const DagCluster& dc : made) spheres.push_back({dc.sphere_center, dc.sphere_radius});
      BoundSphere bound = enclose(spheres);
      group.sphere_center = bound.center;
      group.sphere_radius = bound.radius;
      for (uint32_t child : group.children) {
        DagCluster& c = dag.clusters[child];
        c.parent_group = group_id;
        c.parent_error = error;
        c.parent_lod_center = bound.center;
        c.parent_lod_radius = bound.radius;
      }
      for (size_t c = 0; c < made.size(); ++c) {
        DagCluster& dc = made[c];
        dc.level = group.level + 1;
        dc.group = group_id;
        dc.error = error;
        dc.lod_center = dc.parent_lod_center = bound.center;
        dc.lod_radius = dc.parent_lod_radius = bound.radius;
        group.clusters.push_back(uint32_t(dag.clusters.size()));
        next_ids.push_back(uint32_t(dag.clusters.size()));
        dag.clusters.push_back(std::move(dc));
        next_work.push_back(std::move(o.clusters[c]));
      }
      switch (o.method) {
        case GroupMethod::Locked: ++dag.stats.groups_locked; break;
        case GroupMethod::Sloppy: ++dag.stats.groups_sloppy; break;
        case GroupMethod::Dropped: ++dag.stats.groups_dropped; break;
        case GroupMethod::PassThrough: ++dag.stats.groups_pass_through; break;
        case GroupMethod::Proxy: ++dag.stats.groups_proxy; break;
        case GroupMethod::Merged: ++dag.stats.groups_merged; break;
      }
      dag.stats.merged_results_rejected += o.merged_rejected;
      dag.stats.proxy_results_rejected += o.proxy_rejected;
      dag.stats.proxies_skipped += o.proxy_skipped;
      dag.stats.locked_results_rejected += o.locked_rejected;
      dag.stats.sloppy_results_rejected += o.sloppy_rejected;
      dag.groups.push_back(std::move(group));
    }
    current_work = std::move(next_work);
    current_ids = std::move(next_ids);
  }

  // Per-level totals and the root, from the clusters (bricks merged from different depths make
  // levels uneven, so they are counted rather than tracked).
  uint32_t top = 0;
  for (const DagCluster& c : dag.clusters) top = std::max(top, c.level);
  dag.triangles_per_level.assign(dag.clusters.empty() ? 0 : top + 1, 0);
  dag.clusters_per_level.assign(dag.triangles_per_level.size(), 0);
  uint64_t root_triangles = 0;
  for (const DagCluster& c : dag.clusters) {
    dag.triangles_per_level[c.level] += c.triangleCount();
    ++dag.clusters_per_level[c.level];
    if (c.parent_group == kNoGroup) root_triangles += c.triangleCount();
  }
  dag.root_triangles = root_triangles;
  dag.stats.root_within_limit = root_triangles <= options.max_root_triangles;
}

std::vector<uint32_t> selectCut(const ClusterDag& dag, float tau) {
  std::vector<uint32_t> cut;
  for (uint32_t c = 0; c < dag.clusters.size(); ++c)
    if (dag.clusters[c].error <= tau && tau < dag.clusters[c].parent_error) cut.push_back(c);
  return cut;
}

}  // namespace tw
