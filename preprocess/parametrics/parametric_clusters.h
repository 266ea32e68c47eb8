// Parametric primitives (cylinders, cones, tori, ...) are not tessellated: they pass into the
// package as compact instance records, gathered into parametric clusters so the runtime culls and
// selects them with the same per-cluster tests as mesh clusters.
//
// Clustering: items are grouped by primitive type (a cluster holds one type, so one shader draws
// it), then each type's items are sorted by the 63-bit Morton code of their box centre (in the
// bounding cube of all items) and cut into ceil(n / max_per_cluster) runs of near-equal size;
// each run, a cluster, is then ordered by parametricShowWidth, widest first. Ties (in Morton
// order, then in width) keep input order, so the result is deterministic.
//
// LOD: a parametric cluster is a level-0 root: error 0, parent_error = +inf, no group, no parent
// group, lod spheres = its own bounding sphere. Why: the shader draws each primitive exactly at
// any distance, so there is no coarser version to switch to and no object-space error to report;
// an error > 0 would only make the runtime hide it, which is a culling decision, not a LOD one.
// The runtime skips what is too small to see by small-feature culling on the cluster's bounding
// sphere (and per instance inside visible clusters), and by frustum and occlusion tests on its
// box. Consequences: parametric clusters are always part of every cut (they are outside the mesh
// DAG, so they cannot crack against it), and they do not count toward the mesh root's
// max_root_triangles; their number is about instances / max_per_cluster. A far-field proxy (a
// mesh group over parametric clusters) is possible later without a format change.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "package_writer.h"
#include "scene.h"

namespace tw {

// One primitive placed in the world: its object (an index into the package's object table), its
// parameters and its placement (world metres, double origin).
struct ParametricItem {
  uint32_t object = 0;
  Primitive primitive;
  Transform transform;
};

// The clustering: order[] lists item indices cluster after cluster; cluster i is
// order[offsets[i], offsets[i + 1]) and holds items of primitive type types[i] only.
struct ParametricClustering {
  std::vector<uint32_t> order;
  std::vector<uint32_t> offsets;  // clusterCount() + 1 entries (or empty)
  std::vector<pkg::PrimitiveType> types;

  size_t clusterCount() const { return types.size(); }
};

// The 63-bit Morton code of a point in the unit cube (21 bits per axis, clamped): the order of
// items of one type (shared with the out-of-core clustering, parametric_external_sort.h).
uint64_t parametricMortonCode(const glm::vec3& unit);

// How wide an instance is across all but its longest direction, in metres: the second largest
// of its canonical box's sizes (primitiveBounds, formats/bounds.h), the columns' lengths applied
// (a tube's, cone's or sphere's diameter, a revolution's), and for an elbow its tube's. From far
// away the runtime first shows an instance when this width reaches a fraction of a pixel
// (shownScales in runtime/parametrics/parametric_instance_forms.h), so within a cluster the instances go
// widest first: what a far view draws of a cluster is at its front, and a far view reads few
// cache lines of it. 0 where the parameters give no number.
float parametricShowWidth(const Primitive& primitive, const Transform& transform);

// Groups `items` into clusters of at most max_per_cluster instances (see the file comment).
// Box centres are computed in the frame of `package_origin`. Throws std::invalid_argument if
// max_per_cluster is 0 or an item has parameters the format forbids (tws::primitiveProblem).
ParametricClustering clusterPrimitives(std::span<const ParametricItem> items,
                                       glm::dvec3 package_origin, uint32_t max_per_cluster = 256);

// Appends the instances of every cluster (contiguous, in clustering order) with addInstance and
// one parametric cluster each with addParametricCluster (LOD as in the file comment). Returns
// the storage index of each cluster. `clustering` must come from clusterPrimitives(items,
// storage.origin, ...); objects must already be in storage (object ids are checked by
// writePackage). `role_flags`, by item index, are passed to addInstance (sealed runs and
// covered box faces, instance_flag_marking.h; empty: none). Throws std::invalid_argument on a
// clustering or role flags that do not match the items.
std::vector<uint32_t> addParametricClusters(std::span<const ParametricItem> items,
                                            const ParametricClustering& clustering,
                                            PackageStorage& storage,
                                            std::span<const uint16_t> role_flags = {});

}  // namespace tw
