// DAG -> package records: parallel cluster encoding, sequential placement. See
// package_assembly.h for the contract.
#include "package_assembly.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <tuple>
#include <stdexcept>
#include <string>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "quantization_snap.h"

namespace tw {

namespace {

using namespace pkg;

// Bounds the memory of encoded clusters waiting to be placed (about 2 KB each).
constexpr size_t kEncodeBatch = 8192;

void setVec3(float out[3], const glm::vec3& v) {
  out[0] = v.x;
  out[1] = v.y;
  out[2] = v.z;
}

uint32_t rebase(uint32_t index, uint32_t base) { return index == kNoGroup ? kNone : index + base; }

}  // namespace

DagPlacement beginDagPlacement(const PackageStorage& storage) {
  DagPlacement placement;
  placement.first_cluster = storage.clusterCount();
  placement.first_group = storage.groupCount();
  return placement;
}

void addDagPieceToPackage(const ClusterDag& dag, uint32_t first_cluster, uint32_t first_group,
                          const std::vector<std::vector<glm::vec3>>& snapped,
                          const std::vector<uint32_t>& shifts, DagPlacement& placement,
                          PackageStorage& storage) {
  if (uint64_t(placement.first_cluster) + first_cluster != storage.clusterCount() ||
      uint64_t(placement.first_group) + first_group != storage.groupCount())
    throw std::invalid_argument("addDagPieceToPackage: piece added out of order");
  if (snapped.size() != dag.clusters.size() || shifts.size() != dag.clusters.size())
    throw std::invalid_argument("addDagPieceToPackage: one snapped cluster and shift per cluster");
  if (uint64_t(storage.clusterCount()) + dag.clusters.size() >= kNone ||
      uint64_t(storage.groupCount()) + dag.groups.size() >= kNone)
    throw std::invalid_argument("addDagToPackage: too many clusters or groups for the format");

  // Check the piece before writing anything that depends on it.
  const size_t object_count = storage.objectCount();
  for (size_t c = 0; c < dag.clusters.size(); ++c) {
    const DagCluster& cl = dag.clusters[c];
    if (cl.level > std::numeric_limits<uint16_t>::max())
      throw std::invalid_argument("addDagToPackage: cluster level above 65535");
    for (uint32_t id : cl.triangle_object_ids)
      if (id >= object_count)
        throw std::invalid_argument("addDagToPackage: cluster " + std::to_string(first_cluster + c) +
                                    " has object id " + std::to_string(id) + " but storage has " +
                                    std::to_string(object_count) + " objects");
  }
  const uint64_t cluster_end = uint64_t(first_cluster) + dag.clusters.size();
  for (size_t g = 0; g < dag.groups.size(); ++g) {
    const std::vector<uint32_t>& made = dag.groups[g].clusters;
    for (size_t i = 0; i < made.size(); ++i)
      if (made[i] != made[0] + i || made[i] < first_cluster || made[i] >= cluster_end)
        throw std::invalid_argument("addDagToPackage: group " + std::to_string(first_group + g) +
                                    " produced clusters that are not contiguous in its piece");
    for (uint32_t child : dag.groups[g].children)
      if (child >= cluster_end)
        throw std::invalid_argument("addDagToPackage: group " + std::to_string(first_group + g) +
                                    " has a child after its piece");
  }

  const float lod_slack = placement.lod_slack;
  ClusterEncodeOptions encode_options;
  encode_options.position_step_m = storage.position_step_m;
  std::vector<std::vector<uint8_t>> encoded;
  std::vector<EncodedClusterInfo> infos;
  // This piece's cluster boxes, for its groups' boxes (the records may already be spilled).
  std::vector<std::pair<glm::vec3, glm::vec3>> piece_boxes;
  piece_boxes.reserve(dag.clusters.size());
  for (size_t batch = 0; batch < dag.clusters.size(); batch += kEncodeBatch) {
    const size_t count = std::min(kEncodeBatch, dag.clusters.size() - batch);
    encoded.assign(count, {});
    infos.assign(count, {});
    tbb::parallel_for(tbb::blocked_range<size_t>(0, count, 16),
                      [&](const tbb::blocked_range<size_t>& range) {
                        for (size_t i = range.begin(); i != range.end(); ++i) {
                          const DagCluster& cl = dag.clusters[batch + i];
                          ClusterGeometryInput geometry;
                          geometry.positions = snapped[batch + i];
                          geometry.indices = cl.indices;
                          geometry.triangle_objects = cl.triangle_object_ids;
                          ClusterEncodeOptions options = encode_options;
                          options.min_shift = shifts[batch + i];
                          infos[i] = encodeCluster(geometry, options, encoded[i]);
                        }
                      });
    for (size_t i = 0; i < count; ++i) {
      const DagCluster& cl = dag.clusters[batch + i];
      const EncodedClusterInfo& info = infos[i];
      if (info.shift != shifts[batch + i])
        throw std::logic_error("addDagToPackage: the encoder chose another quantization shift");
      ClusterRecord r{};
      setVec3(r.center, info.center);
      r.radius = info.radius;
      setVec3(r.aabb_min, info.aabb_min);
      setVec3(r.aabb_max, info.aabb_max);
      // A zero radius (a cluster shrunk to a point cannot happen after welding, but be safe)
      // falls back to the decoded sphere, as addMeshCluster does.
      ClusterLod lod;
      lod.error = cl.error;
      lod.parent_error = cl.parent_error;
      lod.group = rebase(cl.group, placement.first_group);
      lod.parent_group = rebase(cl.parent_group, placement.first_group);
      lod.level = static_cast<uint16_t>(cl.level);
      if (cl.lod_radius > 0.0f) lod.lod_sphere = glm::vec4(cl.lod_center, cl.lod_radius + lod_slack);
      if (cl.parent_lod_radius > 0.0f)
        lod.parent_lod_sphere = glm::vec4(cl.parent_lod_center, cl.parent_lod_radius + lod_slack);
      setClusterLod(r, lod, info.center, info.radius + lod_slack);
      r.kind = static_cast<uint8_t>(ClusterKind::Mesh);
      if (cl.group < dag.groups.size() && dag.groups[cl.group].method == GroupMethod::Proxy &&
          cl.level > 0)
        r.flags |= kClusterFarProxy;
      r.triangle_count = info.triangle_count;
      r.vertex_count = info.vertex_count;
      r.object_min = info.object_min;
      r.object_max = info.object_max;
      storage.placeEncodedCluster(encoded[i], r);
      storage.appendCluster(r);
      piece_boxes.emplace_back(info.aabb_min, info.aabb_max);
      placement.encoded_bytes += encoded[i].size();
    }
  }

  for (const DagGroup& g : dag.groups) {
    GroupRecord r{};
    setVec3(r.lod_center, g.sphere_center);
    r.lod_radius = g.sphere_radius + lod_slack;
    r.error = g.error;
    r.level = g.level;
    const std::vector<uint32_t>& boxed = g.clusters.empty() ? g.children : g.clusters;
    glm::vec3 lo(std::numeric_limits<float>::max()), hi(-std::numeric_limits<float>::max());
    for (uint32_t c : boxed) {
      glm::vec3 box_min, box_max;
      if (c >= first_cluster) {
        std::tie(box_min, box_max) = piece_boxes[c - first_cluster];
      } else {  // a child in an earlier piece (a brick root under a merged group)
        const ClusterRecord cr = storage.clusterRecord(placement.first_cluster + c);
        box_min = glm::vec3(cr.aabb_min[0], cr.aabb_min[1], cr.aabb_min[2]);
        box_max = glm::vec3(cr.aabb_max[0], cr.aabb_max[1], cr.aabb_max[2]);
      }
      lo = glm::min(lo, box_min);
      hi = glm::max(hi, box_max);
    }
    if (boxed.empty()) lo = hi = g.sphere_center;
    setVec3(r.aabb_min, lo);
    setVec3(r.aabb_max, hi);
    r.max_parent_error = g.error;
    for (uint32_t c : g.clusters)
      r.max_parent_error = std::max(r.max_parent_error, dag.clusters[c - first_cluster].parent_error);
    r.first_cluster = g.clusters.empty() ? 0 : placement.first_cluster + g.clusters[0];
    r.cluster_count = uint32_t(g.clusters.size());
    storage.appendGroup(r);
  }
}

DagPlacement addDagToPackage(const ClusterDag& dag, PackageStorage& storage) {
  DagPlacement placement = beginDagPlacement(storage);
  QuantizationSnapper snapper(storage.position_step_m);
  const SnapPiece whole{dag.clusters, {}, SharedPositions::None, {}};
  snapper.solve(0, whole);
  std::vector<uint32_t> shifts;
  const std::vector<std::vector<glm::vec3>> snapped = snapper.snap(0, whole, shifts);
  placement.max_shift = snapper.maxShift();
  placement.coarsened_vertices = snapper.coarsenedVertices();
  // Snapping moves a vertex by up to half a cell of the coarsest grid, which can carry it just
  // outside the lod spheres the DAG computed from unsnapped positions. Every lod sphere grows by
  // that much: the same amount everywhere, so siblings still share their spheres exactly and a
  // parent's sphere still contains its children's.
  placement.lod_slack =
      static_cast<float>(quantizationErrorM(storage.position_step_m, placement.max_shift));
  addDagPieceToPackage(dag, 0, 0, snapped, shifts, placement, storage);
  return placement;
}

}  // namespace tw
