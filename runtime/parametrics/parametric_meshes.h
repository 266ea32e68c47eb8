// Parametric instances turned into triangles at run time, by distance (`--parametrics
// tessellated`, and the extrusions and revolutions of impostor mode, which have no ray-cast
// shader).
//
// Why: ENVIRON kept pipes parametric and built their meshes at a level of detail chosen by
// distance; this is that path, for comparison with the impostors and for GPUs whose fragment
// throughput is poor. Each parametric cluster is tessellated whole (formats/tessellate.h, in the
// canonical frames of scene.h, then placed) at one of kBucketCount chordal tolerances,
// kBaseToleranceM * 4^bucket: the coarsest whose error projects to at most tolerance_px pixels at
// the cluster's nearest point. Meshes are cached per (cluster, bucket) in GL buffers, with
// positions in float metres relative to the cluster's anchor (its bounding-sphere centre; the
// anchor's offset from the eye is computed in double per draw), and evicted least recently used
// past budget_bytes. Builds cost CPU time on the render thread: after build_ms_per_frame, a
// cluster that already has another bucket cached draws that one instead (never a hole).
// Needs a current GL 4.5 context for the object's whole life.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "instance_primitive.h"
#include "package_view.h"
#include "scene.h"

namespace tw {

struct ParametricMeshOptions {
  double tolerance_px = 0.5;          // chordal error allowed on screen, pixels
  uint64_t budget_bytes = 256ull << 20;  // GL buffers of cached meshes
  double build_ms_per_frame = 30.0;   // CPU time for new meshes per frame, see above
  double fixed_tolerance_m = 0.0;     // > 0: every cluster at this tolerance (tests, references)
  // Tessellated mode: the frame's clusters are expanded in runs of this many, on TBB
  // (ParametricInstanceMeshes::prepare); 0: all in one run, on the calling thread.
  uint32_t clusters_per_run = 32;
  // Tessellated mode: a far view's batch (fewer than four primitives an instance) is drawn in
  // parts of at most this many triangles or points, each flushed
  // (ParametricInstanceMeshes::submit); 0: one draw a batch, no flush.
  uint32_t primitives_per_flush = 8192;
  // Tessellated mode: visit only the instances of a cluster whose distance lets them show
  // (InstanceScaleIndex); false tests every instance, for comparison. The frame is the same.
  bool scale_index = true;
  // Tessellated mode: rows of equal boxes end to end drawn as one box each (box_rows.h); false
  // draws every box on its own, for comparison. The frame is the same.
  bool box_rows = true;
};

// One vertex of a tessellated cluster: 20 bytes. The normal is the surface's own (the
// tessellator's, placed), so a tessellation shades like the smooth surface it approximates,
// whatever its tolerance: a reference at 2 mm and a coarse level differ by their silhouettes,
// not by the bands of their facets.
struct ParametricVertex {
  glm::vec3 position;  // metres from the cluster's anchor
  uint32_t object;     // object index
  uint32_t normal;     // packNormal
};

// A unit (or zero) normal as GL_INT_2_10_10_10_REV, normalized.
uint32_t packNormal(const glm::vec3& unit_or_zero);

// The matrix that carries normals of an instance's canonical frame through `linear`: its cofactor
// matrix (the inverse transpose times the determinant, three cross products), with the
// determinant's sign taken out so a mirroring frame keeps normals outward. Not normalized.
glm::mat3 normalMatrix(const glm::mat3& linear);

// Appends the triangles of every instance of parametric cluster `cluster` at chordal tolerance
// `tolerance_m`, placed relative to the cluster's anchor. Instances whose parameters
// tessellate to nothing (invalid) add nothing. `instance_offsets`, when given, receives the first
// index of each instance and the end (instance_count + 1 entries). Throws std::out_of_range for a
// cluster that is not parametric or out of range. `simplify_profiles`: extrusions' profiles lose
// the points within `tolerance_m` of the rest (ProfileSimplifier::simplifyClosed) where the
// simplified profile stays as simple as it was and keeps its winding; references keep them all.
void tessellateCluster(const PackageView& view, uint32_t cluster, float tolerance_m,
                       std::vector<ParametricVertex>& vertices, std::vector<uint32_t>& indices,
                       std::vector<uint32_t>* instance_offsets = nullptr,
                       bool simplify_profiles = false);

// Which faces of an instance a draw may skip: none (an open surface, or the eye inside the solid
// or near it), or the back faces of a closed solid seen from outside, whose front faces wind
// counter-clockwise on screen (clockwise under a mirroring transform).
enum class FaceCull : uint8_t { None, BackOfCcw, BackOfCw };

// One instance of a parametric cluster to draw from the cluster's mesh, at the resolution its own
// distance asks for.
struct ParametricMeshInstance {
  uint32_t cluster = 0;
  uint32_t instance = 0;     // index into the instance table, within the cluster's range
  double distance_m = 0.0;   // from the eye to the instance's nearest point (bounding sphere)
  FaceCull cull = FaceCull::None;
};

// The anchor of a parametric cluster: its bounding-sphere centre, package frame metres.
glm::dvec3 clusterAnchor(const pkg::ClusterRecord& cluster);

struct ParametricMeshStats {
  uint32_t clusters_drawn = 0;
  uint64_t instances_drawn = 0;
  uint64_t triangles_drawn = 0;
  uint64_t two_sided_triangles = 0;  // of triangles_drawn: without back-face culling
  uint32_t meshes_built = 0;      // this call
  uint32_t meshes_cached = 0;     // after this call
  uint64_t cached_bytes = 0;
};

class ParametricMeshes {
 public:
  static constexpr int kBucketCount = 6;
  static constexpr double kBaseToleranceM = 0.001;  // bucket 0: 1 mm; bucket 5: 1.024 m

  ParametricMeshes(const PackageView& view, const ParametricMeshOptions& options);
  ~ParametricMeshes();
  ParametricMeshes(const ParametricMeshes&) = delete;
  ParametricMeshes& operator=(const ParametricMeshes&) = delete;

  static double bucketToleranceM(int bucket);
  // The bucket for `cluster` seen from `eye` (package frame) with Camera::pixelScale.
  int bucketFor(uint32_t cluster, const glm::dvec3& eye, double pixel_scale, double near_m) const;

  // Draws `clusters` (parametric cluster indices) into the currently bound framebuffer with the
  // GL state the caller set (depth test, viewport), binding its own program and the object
  // colours the caller bound at gl_shaders.h kObjectColorBinding. `frame` orders the LRU.
  ParametricMeshStats draw(std::span<const uint32_t> clusters, const glm::dvec3& eye,
                           const glm::mat4& view_projection, double pixel_scale, double near_m,
                           uint32_t object_color_count, uint64_t frame);
  // Draws single instances, each from its cluster's mesh at the bucket of its own distance with
  // `tolerance_px` (consecutive entries of one cluster share its meshes; one multi-draw per
  // cluster mesh used and face culling asked for), back faces culled as each entry's `cull`
  // says. Same GL contract as draw(); face culling is left off.
  ParametricMeshStats drawInstances(std::span<const ParametricMeshInstance> instances,
                                    const glm::dvec3& eye, const glm::mat4& view_projection,
                                    double pixel_scale, double tolerance_px,
                                    uint32_t object_color_count, uint64_t frame);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace tw
