// Far proxies: an aggregate of many small, disconnected parts remeshed as one closed surface
// (OpenVDB mesh -> unsigned distance field -> adaptive iso-surface). Edge collapse stalls on
// thousands of tiny CAD parts and sloppy clustering leaves them as shards; a shell around the
// aggregate at about one voxel's offset is what such a group looks like from far away.
// The LOD DAG (cluster_dag.cpp) uses it on a group's free components. OpenVDB stays inside
// far_proxy.cpp: it is expensive to compile.
#pragma once

#include <cstdint>
#include <glm/glm.hpp>
#include <span>
#include <vector>

namespace tw {

// Non-owning view of the source: positions (object space, any units), three indices per
// triangle, one object id per triangle.
struct FarProxyInput {
  std::span<const glm::vec3> positions;
  std::span<const uint32_t> indices;
  std::span<const uint32_t> triangle_object_ids;
};

struct FarProxyOptions {
  // The proxy aims at the largest triangle count <= target_triangles that the voxel-size search
  // finds; it may come out above the target when no voxel size tried gets there (the caller
  // checks FarProxy::triangleCount()).
  uint32_t target_triangles = 1024;
  // Iso-surface offset from the source, in voxels. >= 0.87 (half the voxel diagonal) keeps every
  // source point inside the shell, so no part vanishes, however small.
  float iso_voxels = 1.0f;
  // OpenVDB volumeToMesh adaptivity in [0, 1]: merges flat regions into larger polygons. Higher
  // means fewer triangles per voxel, so finer voxels for the same target.
  float adaptivity = 0.3f;
  // Voxel sizes tried (each try costs one mesh -> volume -> mesh round trip): the predicted size
  // (predictFarProxyVoxel) and at most one retry rescaled by the miss. More tries find counts
  // closer to the target on aggregates whose count jumps with the voxel size, at a remesh each.
  uint32_t max_attempts = 2;
  // A try that fits with at least min_fill * target_triangles ends the search; a sparser one is
  // retried finer (while tries remain). 0 takes the first fit: fewer remeshes, coarser proxies.
  float min_fill = 0.5f;
  // Narrow band of the distance fields beyond the iso offset, in voxels. Voxelization time grows
  // with it. >= 1: past that, cells crossing the iso-surface see some corners clamped to the
  // band's edge, which moves the surface slightly (the measured error still bounds it).
  float band_margin_voxels = 2.0f;
  // Finest voxel allowed, as a fraction of the source's largest extent (bounds memory and time:
  // the sparse grid holds about surface / voxel^2 * band voxels).
  float min_voxel_fraction = 1.0f / 1024.0f;
};

struct FarProxy {
  std::vector<glm::vec3> positions;           // welded, sorted (see determinism below)
  std::vector<uint32_t> indices;              // three per triangle, consistently oriented
  std::vector<uint32_t> triangle_object_ids;  // one per triangle, from the input's ids
  // Two-sided distance bound between proxy and source surfaces, in the input's units: both
  // surfaces are sampled (every vertex, and a barycentric grid on every triangle with sub-edges
  // of at most half a voxel), each sample's distance to the other surface is bounded from that
  // surface's distance field (exact distances at the eight voxel centres around the sample plus
  // the Lipschitz term; an exact nearest-triangle search where the sample lies outside the
  // field's narrow band), and error = largest sample bound + sample_spacing (the longest
  // sub-edge used). Distance to a surface is 1-Lipschitz and every point of a triangle lies
  // within a sub-edge of a sample, so this bounds the true Hausdorff distance (up to float
  // rounding). It is two-sided on purpose: parts hidden inside a merged shell count.
  float error = 0.0f;
  // The same bound with each source part's (connected component's) term capped at the part's
  // bounding-box diagonal: a part hidden inside a merged shell counts as vanished, its size, as
  // the LOD DAG counts a dropped part. <= error. The DAG uses this one, so proxies and dropping
  // are compared by one convention.
  float part_error = 0.0f;
  float voxel_size = 0.0f;      // the voxel size used
  float sample_spacing = 0.0f;  // see error

  uint32_t triangleCount() const { return static_cast<uint32_t>(indices.size() / 3); }
};

// Builds the proxy. Pure function: no I/O, no globals beyond OpenVDB's one-time initialisation.
// Object ids: each proxy triangle takes the id of the source triangle nearest its centroid among
// the closest source triangles OpenVDB records at the eight voxels around the centroid (ties: the
// lower source triangle index); nearly always the nearest of all.
// Orientation: every triangle faces away from the region within the iso offset of the source
// (outward for the outer shell; a part much thicker than the offset also gets an inner shell
// facing its hollow).
// Determinism: the output (vertices sorted by position, each triangle rotated to start at its
// lowest vertex, triangles sorted) depends only on the input and options, not on thread count
// or timing.
// Degenerate or non-finite source triangles are ignored. An input with no valid triangle gives
// an empty proxy. Throws std::invalid_argument if indices.size() is not a multiple of 3, an index
// is out of range, or the object ids are not one per triangle.
FarProxy buildFarProxy(const FarProxyInput& input, const FarProxyOptions& options = {});

// The first voxel size buildFarProxy tries for a source of `source_area` (input units squared)
// whose largest bounding-box extent is `extent`: sqrt(12 * area / target) (a shell of about twice
// the source's area at a few triangles per voxel face), clamped to [min_voxel_fraction * extent,
// extent]. Callers use it to predict a proxy's error (at least about iso_voxels * voxel) before
// paying for one.
float predictFarProxyVoxel(double source_area, uint32_t target_triangles, float extent,
                           const FarProxyOptions& options = {});

}  // namespace tw
