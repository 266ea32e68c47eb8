// Joins the LOD DAGs of spatial bricks into one DAG: the preprocessor builds each brick in memory
// (buildClusterDag with lock_open_boundaries, so seams never move), then builds the upper levels
// from all the bricks' roots together, so the final root is small whatever the brick count.
//
// mergeBrickDags concatenates the bricks' clusters and groups (brick after brick, indices
// re-based), welds the roots' vertices by exact position (clusters of two bricks meeting at a seam
// share the seam's vertices, so METIS sees them as neighbours and a group holding both sides may
// move the seam), and runs the level loop of cluster_dag.cpp (continueClusterDag) from the set of
// all root clusters until the root holds <= max_root_triangles and cannot shrink, or is one
// cluster. Crack-freedom is the ordinary DAG rule: a merged group replaces exactly its children,
// and every edge it shares with another group of its front keeps its triangle count.
//
// Levels: brick roots may sit at different levels. A merged group takes the highest level of its
// children and produces clusters one level above, so a child's level may be below its parent
// group's (the package allows child level <= parent group level; produced == group level + 1).
// Errors: a merged group's error is max(its simplification error, largest child error + epsilon)
// with epsilon about 1e-6 of the merged extent, so errors grow strictly toward the root.
//
// Options: cluster_size, group_size, ratios and fallbacks apply to the merged levels.
// lock_open_boundaries would lock the open edges of the merged front (the model's own open
// edges, seams being closed by now): leave it false unless the result is itself a brick of a
// larger merge. Bricks must share one position frame (one package origin) and weld exactly.
#pragma once

#include <span>
#include <vector>

#include "cluster_dag.h"

namespace tw {

// Consumes the bricks. Empty bricks are skipped; no brick gives an empty DAG. Stats are summed
// over the bricks and the merge; triangles_per_level, clusters_per_level and root_triangles are
// recounted over the whole DAG.
ClusterDag mergeBrickDags(std::vector<ClusterDag> bricks, const DagOptions& options = {});

// The merge from the bricks' roots alone, for a preprocessor that keeps only those in memory (the
// full brick DAGs wait on disk). `roots` are every brick's root clusters (parent_group ==
// kNoGroup), brick after brick, each in its brick's cluster order. The result's clusters are
// first those roots, in the same order (front_count of them), with parent_group (an index into
// result.dag.groups), parent_error and parent_lod_* set where a merged group took them, then the
// merged clusters; its groups are the merged groups, children and clusters indexing
// result.dag.clusters. Stats hold the merge's own counts; triangles_per_level,
// clusters_per_level and root_triangles count the roots and the merged clusters. Exactly what
// mergeBrickDags builds on top of the bricks (it is implemented with this).
struct MergedRoots {
  ClusterDag dag;
  uint32_t front_count = 0;
};
MergedRoots mergeBrickRoots(std::vector<DagCluster> roots, const DagOptions& options = {});

// Moves the merged levels (the clusters after the front, and every group) of `merged` into a
// DAG's numbering: front cluster i is `front_ids[i]`, merged cluster j (j >= front_count) becomes
// cluster_base + j - front_count and merged group g becomes group_base + g. The front's own
// records (their new parents) are the caller's to update.
void appendMergedLevels(MergedRoots& merged, std::span<const uint32_t> front_ids,
                        uint32_t cluster_base, uint32_t group_base,
                        std::vector<DagCluster>& clusters, std::vector<DagGroup>& groups);

// Bookkeeping shared with the preprocessor, which sums bricks without holding them: `to` += the
// counters of `from` (root_within_limit untouched); triangles_per_level, clusters_per_level and
// root_triangles recounted from dag.clusters.
void addStats(DagBuildStats& to, const DagBuildStats& from);
void countLevels(ClusterDag& dag);

}  // namespace tw
