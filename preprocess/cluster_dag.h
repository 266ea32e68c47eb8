// The LOD DAG: full-resolution clusters, then groups of neighbouring clusters simplified together
// with their shared border locked and cut again into clusters, level after level, up to a small
// root. Any cut chosen by error (see selectCut) is crack-free because a group never changes the
// edges it shares with the rest of its level.
//
// Build, level by level (pure function over buffers; per-group work runs in parallel with TBB and
// the result does not depend on thread timing):
//  1. Weld vertices by exact position (simplification only sees positions), drop degenerate
//     triangles and exact repeats of a triangle (stats.repeated_triangles), cut into clusters of
//     at most cluster_size triangles (clusterize.h).
//  2. Group the level's clusters with METIS_PartGraphKway on the cluster adjacency graph (edge
//     weight = shared vertices; weak extra edges between clusters neighbouring in Morton order
//     keep disconnected CAD parts grouped by proximity). A level of <= group_size clusters is
//     one group (METIS is not called).
//  3. Simplify each group to half its triangles with meshopt_simplify + meshopt_SimplifyLockBorder.
//     If that does not reach min_shrink_ratio, or reaches it only with an error above 1% of the
//     group's extent, vertex clustering of the whole group with its border held
//     (locked_vertex_clustering.h: vertices shared with another group and locked seams never
//     move, the rims of the parts' own open edges merge only among themselves; error: the largest
//     vertex displacement) is tried, and taken when it reaches min_shrink_ratio (with less error,
//     when the locked result reached it too). This is what halves groups of many small parts,
//     thin pipes and open sheets, which LockBorder cannot touch (it locks every open edge, the
//     parts' own included). If neither reaches it, the fallback works only on the group's *free*
//     components (connected components that share no vertex with another group, so nothing
//     outside the group can crack against them): first meshopt_simplifySloppy on them (given only
//     their vertices, so its output cannot reach the border part), then, if that is rejected or
//     not enough and there are many free components, an OpenVDB far proxy of them (far_proxy.h:
//     one closed shell around the aggregate, new vertices; error: its measured two-sided distance
//     bound, each part capped at its size), then dropping whole free components smallest first
//     (error: the dropped part's bounding-box diagonal) if still not enough, or if it reaches the
//     target with proxy_error_slack times less error than the proxy. The rest of the group keeps
//     the locked result.
//  4. Every candidate result is checked before use: each edge the group shares with another group
//     must keep its exact triangle count, and no edge may become a boundary edge (used once)
//     unless it already was one. A rejected candidate falls back to the next; the last resort
//     is the group unchanged. So a cut never shows a boundary edge the input did not have. (The
//     check matters: on non-manifold input, or inside sloppy output, meshopt_simplify sees an
//     edge shared 2 + 2 between groups as interior and collapses it.)
//  5. If the whole level does not shrink to min_shrink_ratio, it is redone with groups four times
//     as large (fewer locked borders), up to one group for the level, where every component is
//     free.
//  6. Stop at one cluster, or when a level cannot shrink and holds <= max_root_triangles. A level
//     above max_root_triangles that shrinks less than asked is kept (stats.levels_below_shrink);
//     one that cannot shrink at all ends the build with stats.root_within_limit = false.
//  With DagOptions::lock_open_boundaries, the input's open edges count as shared edges (step 4)
//  and pin their components (never free in step 3), so brick seams never move.
//
// Errors (object space, same units as the positions): level-0 clusters have error 0. A group's
// error is max(its simplification error, its children's errors + epsilon), strictly greater than
// every child's error; the clusters it produces carry it as `error` and its children carry it as
// `parent_error`. Root clusters have parent_error = +infinity.
//
// Screen-space use: project `error` with the lod sphere and `parent_error` with the parent lod
// sphere, by any measure that grows with the error and shrinks with the distance to the sphere.
// Siblings share both pairs and a group's sphere encloses its children's, so every group is
// either wholly replaced or not, and the per-cluster test picks a consistent cut.
//
// Object ids: a simplified triangle takes the majority id of its three vertices, where a vertex's
// id is the most frequent id among the group's input triangles that use it (ties: smaller id).
// Triangles kept unchanged (pass-through, kept free components) and those vertex clustering
// moved keep their own (source triangle's) id. Far-proxy
// triangles take the id of the source triangle nearest their centroid.
//
// Limitations: (a) components touching another group at a single vertex (no shared edge, e.g. two
// cone tips welded together) are not locked there; the vertex may move, leaving a gap no edge
// test sees. (b) Where two neighbouring groups both join the same two border vertices by a new
// edge (an interior vertex collapsed onto the border on both sides), a cut holds a "pinch": an
// edge with four triangles, two opposite slivers. The surface stays closed (no boundary edge) but
// is not a 2-manifold there. Forbidding such edges stalls meshopt, so they are tolerated; tests
// measure them (a few per cut on smooth meshes). (c) Heavily simplified thin closed parts may
// fold into double-sided sheets (edges with four triangles): still no boundary edge.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <limits>
#include <span>
#include <vector>

#include <glm/glm.hpp>

namespace tw {

// Non-owning view of the input: positions relative to a local origin (float), three indices per
// triangle, one object id per triangle.
struct DagInput {
  std::span<const glm::vec3> positions;
  std::span<const uint32_t> indices;
  std::span<const uint32_t> triangle_object_ids;
};

struct DagOptions {
  uint32_t cluster_size = 256;       // max triangles per cluster (sensible: 128..1024)
  uint32_t group_size = 8;           // clusters simplified together (sensible: 4..32)
  float min_shrink_ratio = 0.6f;     // a group or level "shrinks" when output <= ratio * input
  uint32_t max_root_triangles = 65536;
  float max_relative_error = 1.0f;   // meshopt target_error, relative to a group's extent
  bool allow_merge = true;           // vertex clustering of whole groups, border held
  bool allow_sloppy = true;          // meshopt_simplifySloppy on free components
  bool allow_drop = true;            // drop whole free components, smallest first
  // OpenVDB far proxy (far_proxy.h) of a group's free components when there are at least
  // proxy_min_components of them, sloppy fell short of min_shrink_ratio and the free part (not
  // the locked border part) is what keeps the group long. Not built when dropping reaches the
  // target with an error proxy_error_slack times below what a proxy's could be, nor in a level
  // attempt that could not shrink enough even with it (that attempt is redone with larger
  // groups; the DAG is the same as building them all). Used when it leaves
  // fewer triangles than the best result so far, unless dropping also reaches the target with
  // an error proxy_error_slack times lower (dropping opens holes in dense areas that its error,
  // the largest dropped part's size, does not measure; a proxy that merges whole structures
  // into one shell has a large error and loses).
  // Off by default since vertex clustering (allow_merge) halves those groups: on duplex-mep the
  // proxies cost a quarter of the brick build and set the largest level error (1.75 m against
  // 0.54 m without them), and the levels halve either way.
  bool allow_proxy = false;
  uint32_t proxy_min_components = 8;
  float proxy_error_slack = 4.0f;
  uint32_t max_levels = 64;
  // Brick seams: every edge used by exactly one triangle of the input (after welding) keeps its
  // exact triangle count at every level, and a component holding such an edge's vertex is never
  // free (neither sloppy-simplified nor dropped). Two DAGs built from the two sides of a cut then
  // show the same seam in every cut of either, so their union is crack-free. Off by default (an
  // isolated model gains nothing from it and CAD sheets could no longer be dropped); the brick
  // builds of the preprocessor turn it on.
  bool lock_open_boundaries = false;
  // With lock_open_boundaries: when set, the edges it accepts (given their two end positions)
  // are locked instead, whatever their triangle count (a non-manifold seam edge may be used three
  // times in this brick and once in the next); the input's open edges it refuses stay free like
  // in an unlocked build. The preprocessor passes the true brick seams (brick_seams.h), so CAD
  // parts with open edges of their own (uncapped pipes, sheets) still simplify and drop.
  std::function<bool(const glm::vec3&, const glm::vec3&)> is_seam_edge;
  // With lock_open_boundaries: when set, the vertices of the input's rim edges (used other than
  // twice) for which it returns true are held too (never moved, their parts never free). The
  // preprocessor passes "inside another brick's bounds, padded by the package's grid error":
  // rims that almost meet another brick's geometry without being bit-identical seams would
  // otherwise move on one side only.
  std::function<bool(const glm::vec3&)> is_near_other_brick;
  // When > 0: the package's base position step (metres). Full-resolution vertices are snapped to
  // the grid their level-0 cluster will be stored on, and welded where they coincide
  // (grid_weld.h), so that vertices the package will store as one are one vertex in the DAG too.
  // Locked seam vertices (lock_open_boundaries) are left where they are. 0: exact positions.
  double position_step_m = 0.0;
  // With position_step_m: vertices closer than this on every axis join before the snap (float
  // noise of the input; grid_weld.h). 0: one base step. The preprocessor passes the base step plus
  // two ulps of the largest coordinate the readers stored, as for the weld across bricks.
  double noise_tolerance_m = 0.0;
};

constexpr uint32_t kNoGroup = std::numeric_limits<uint32_t>::max();

struct DagCluster {
  std::vector<glm::vec3> positions;              // the cluster's own compact vertex list
  std::vector<uint32_t> indices;                 // three per triangle, into positions
  std::vector<uint32_t> triangle_object_ids;     // one per triangle
  uint32_t level = 0;                            // 0 = full resolution
  uint32_t group = kNoGroup;                     // group that produced it (level 0: none)
  uint32_t parent_group = kNoGroup;              // group that simplifies it (root: none)
  float error = 0.0f;                            // object-space error of this cluster
  float parent_error = std::numeric_limits<float>::infinity();
  // Geometry bounds, for culling.
  glm::vec3 sphere_center{0.0f};
  float sphere_radius = 0.0f;
  glm::vec3 box_min{0.0f}, box_max{0.0f};
  // Bounds to project `error` with: the producing group's sphere (level 0: the geometry sphere).
  // Siblings share it and it contains the children's, so projected errors stay monotone and all
  // clusters of a group make the same choice.
  glm::vec3 lod_center{0.0f};
  float lod_radius = 0.0f;
  // Bounds to project `parent_error` with: the parent group's sphere (root: same as lod_*).
  glm::vec3 parent_lod_center{0.0f};
  float parent_lod_radius = 0.0f;

  uint32_t triangleCount() const { return static_cast<uint32_t>(indices.size() / 3); }
};

enum class GroupMethod : uint8_t {
  Locked = 0,       // meshopt_simplify with the border locked
  Sloppy = 1,       // locked on the border part, meshopt_simplifySloppy on free components
  Dropped = 2,      // locked on the border part, smallest free components removed
  PassThrough = 3,  // nothing acceptable: the group's triangles unchanged
  Proxy = 4,        // locked on the border part, OpenVDB far proxy of the free components
  Merged = 5,       // vertex clustering of the whole group, border held (locked_vertex_clustering.h)
};

// Groups per GroupMethod, indexed by its value.
using GroupMethodCounts = std::array<uint64_t, 6>;

struct DagGroup {
  uint32_t level = 0;               // highest level of its children (equal in a single build;
                                    // merged brick roots may differ, see dag_merge.h)
  std::vector<uint32_t> children;   // clusters of `level` it replaces
  std::vector<uint32_t> clusters;   // clusters of level + 1 it produced (may be empty if dropped)
  float error = 0.0f;               // error of `clusters`, parent_error of `children`
  glm::vec3 sphere_center{0.0f};    // encloses the children's lod spheres and its clusters
  float sphere_radius = 0.0f;
  GroupMethod method = GroupMethod::Locked;
};

struct DagBuildStats {
  uint64_t input_triangles = 0;
  uint64_t skipped_triangles = 0;   // degenerate after welding, or non-finite positions
  uint64_t repeated_triangles = 0;  // exact copies of an earlier triangle, removed
  uint64_t grid_welded_vertices = 0;  // merged by the package-grid weld (position_step_m)
  uint32_t groups_locked = 0;
  uint32_t groups_sloppy = 0;
  uint32_t groups_dropped = 0;
  uint32_t groups_pass_through = 0;
  uint32_t locked_results_rejected = 0;  // locked simplify output failed the border check
  uint32_t sloppy_results_rejected = 0;  // sloppy output failed the boundary check
  uint32_t groups_proxy = 0;
  uint32_t groups_merged = 0;
  uint32_t merged_results_rejected = 0;  // vertex clustering output failed the border check
  uint32_t proxy_results_rejected = 0;   // proxy output failed the boundary check
  uint32_t proxies_skipped = 0;  // not built: dropping reached the target with far less error
  uint32_t level_retries = 0;            // level attempts redone with merged or larger groups
  uint32_t groups_kept_on_retry = 0;     // group results a retried attempt reused as they were
  uint32_t levels_below_shrink = 0;      // levels accepted although ratio > min_shrink_ratio
  bool root_within_limit = true;         // root level holds <= max_root_triangles
};

struct ClusterDag {
  // Level by level, level 0 first (a merged DAG: brick after brick, then the merged levels).
  // Each group's produced clusters are contiguous, in group order.
  std::vector<DagCluster> clusters;
  std::vector<DagGroup> groups;                  // in build order; a group follows its children's
  std::vector<uint64_t> triangles_per_level;     // index = level
  std::vector<uint32_t> clusters_per_level;
  uint64_t root_triangles = 0;                   // in clusters with parent_group == kNoGroup
  DagBuildStats stats;

  uint32_t levelCount() const { return static_cast<uint32_t>(triangles_per_level.size()); }
};

// Builds the DAG. Throws std::invalid_argument if indices.size() is not a multiple of 3, an index
// is out of range, object ids are not one per triangle, or cluster_size / group_size is 0.
// An input with no valid triangle gives an empty DAG.
ClusterDag buildClusterDag(const DagInput& input, const DagOptions& options = {});

// The clusters a runtime with object-space threshold tau would draw: error <= tau < parent_error.
// For tau >= 0 the selection covers the surface once, without cracks (see the file comment).
std::vector<uint32_t> selectCut(const ClusterDag& dag, float tau);

// The level loop of buildClusterDag (steps 2-6), run from an arbitrary front: `front_ids` are
// clusters of `dag` that have no parent group yet, `front_tris[i]` is cluster front_ids[i]'s
// triangles as indices into `positions` (one welded vertex per distinct position; the triangle
// order and object ids are the cluster's). Appends groups and clusters to `dag` and recounts
// triangles_per_level, clusters_per_level, root_triangles and stats.root_within_limit.
// `epsilon` is the strict-monotonicity margin added to the children's largest error (about 1e-6
// of the model's extent). lock_open_boundaries locks the open edges of the front as given.
// Used by buildClusterDag and mergeBrickDags (dag_merge.h). Throws std::invalid_argument when
// the front does not match the dag.
void continueClusterDag(ClusterDag& dag, const std::vector<glm::vec3>& positions,
                        std::vector<uint32_t> front_ids,
                        std::vector<std::vector<uint32_t>> front_tris, const DagOptions& options,
                        float epsilon);

}  // namespace tw
