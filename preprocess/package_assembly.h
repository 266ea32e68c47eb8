// Turns a LOD DAG (cluster_dag.h, dag_merge.h) into package records: the last step of the
// preprocessor before writePackage. Kept apart from the DAG builder so the builder stays a pure
// function over buffers and the package format stays out of it.
#pragma once

#include <cstdint>

#include "cluster_dag.h"
#include "package_writer.h"

namespace tw {

// Where the DAG landed in the storage: DAG cluster i is storage.clusters[first_cluster + i] and
// DAG group g is storage.groups[first_group + g].
struct DagPlacement {
  uint32_t first_cluster = 0;
  uint32_t first_group = 0;
  uint64_t encoded_bytes = 0;  // encoded cluster bytes placed in pages (before zstd, no padding)
  uint32_t max_shift = 0;      // largest quantization shift (cell = step * 2^shift)
  uint64_t coarsened_vertices = 0;  // distinct positions snapped coarser than their finest cluster
  float lod_slack = 0.0f;  // metres added to every lod sphere: the largest snap displacement
};

// Appends every cluster of `dag` as a mesh cluster (in DAG order, so each group's produced
// clusters stay contiguous as the package requires) and every group as a GroupRecord.
//  - Positions must be metres relative to storage.origin (the DAG's frame); no normals are stored
//    (the DAG keeps none).
//  - Triangle object ids must already be indices into storage.objects (add objects first).
//  - ClusterLod: error, parent_error, level, group / parent_group (re-based), and the DAG's lod
//    and parent lod spheres, so siblings share them exactly and the cut stays consistent.
//  - GroupRecord: the DAG group's sphere and error, its level, the box of its produced clusters'
//    records (the children's when it produced none) and their largest parent_error.
// Quantization without cracks: clusters pick their grid shift by extent, and clusters of
// different levels share locked border vertices, so a shared vertex would decode differently in
// a fine and a coarse cluster. Every distinct position is therefore snapped first to the grid of
// the coarsest shift among the clusters that use it (exact when position_step_m is a power of
// two, as the default is: nested grids), which moves it by at most half that cell; then all
// clusters decode it identically and any cut closed in the DAG is closed in the package.
// Encoding (page_codec.h, quantization included) runs in parallel with TBB in batches; records
// and pages are then filled sequentially in DAG order, so the result does not depend on thread
// timing. Throws std::invalid_argument when the DAG breaks these rules (object id out of range,
// a group's produced clusters not contiguous, a level above 65535) or a cluster does not encode;
// the storage may then hold part of the DAG.
DagPlacement addDagToPackage(const ClusterDag& dag, PackageStorage& storage);

// The same, a piece at a time, so a DAG far larger than memory can be packed (the preprocessor's
// bricks, then its merged levels). `piece` holds DAG clusters [first_cluster, first_cluster +
// clusters.size()) and DAG groups [first_group, ...), every index in it (group, parent_group,
// children, clusters) in the whole DAG's numbering, and every field final (a brick root's parent
// fields set by the merge). Pieces are added in DAG order. `placement` comes from
// beginDagPlacement and has max_shift and lod_slack set by the caller for the whole DAG
// (QuantizationSnapper, quantization_snap.h, which also gives each piece's `snapped` positions and
// `shifts`); encoded_bytes and coarsened_vertices are the caller's to fill. A group's box reads
// the records of its produced clusters, or of its children (earlier pieces) when it produced none.
// Throws as addDagToPackage, and std::invalid_argument when the piece is out of order.
DagPlacement beginDagPlacement(const PackageStorage& storage);
void addDagPieceToPackage(const ClusterDag& piece, uint32_t first_cluster, uint32_t first_group,
                          const std::vector<std::vector<glm::vec3>>& snapped,
                          const std::vector<uint32_t>& shifts, DagPlacement& placement,
                          PackageStorage& storage);

}  // namespace tw
