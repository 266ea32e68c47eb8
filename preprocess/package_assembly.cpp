// DAG -> package records: parallel cluster encoding, sequential placement. See
// package_assembly.h for the contract.
#include "package_assembly.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <unordered_map>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "position_key.h"

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

// The shift encodeCluster will pick (page_codec.cpp, same arithmetic): the smallest one from
// `min_shift` whose cells hold the cluster's extent in 16 bits and its grid origin in int32.
// Returns kMaxPositionShift + 1 when none does (the encoder then refuses the cluster).
uint32_t requiredShift(const std::vector<glm::vec3>& positions, double step, uint32_t min_shift) {
  double lo[3], hi[3];
  for (int a = 0; a < 3; ++a) {
    lo[a] = std::numeric_limits<double>::max();
    hi[a] = -std::numeric_limits<double>::max();
  }
  for (const glm::vec3& p : positions)
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], double(p[a]));
      hi[a] = std::max(hi[a], double(p[a]));
    }
  for (uint32_t shift = min_shift; shift <= kMaxPositionShift; ++shift) {
    const double cell = std::ldexp(step, int(shift));
    bool fits = true;
    for (int a = 0; a < 3 && fits; ++a) {
      double glo = std::nearbyint(lo[a] / cell), ghi = std::nearbyint(hi[a] / cell);
      fits = glo >= -2147483648.0 && glo <= 2147483647.0 && ghi - glo <= 65535.0;
    }
    if (fits) return shift;
  }
  return kMaxPositionShift + 1;
}

// Positions as the package will hold them: each vertex snapped to the grid of the coarsest
// shift among all clusters that use it (clusters of different levels share locked border
// vertices, and clusters pick their shift by extent). A vertex on the grid of shift S is
// quantized exactly by every cluster of shift <= S (cells are nested powers of two of the step),
// so every cluster decodes a shared vertex to the same point and cuts stay closed after
// quantization. A vertex moves by at most half a cell of that coarsest shift.
struct SnappedDag {
  std::vector<std::vector<glm::vec3>> positions;  // per cluster
  std::vector<uint32_t> shifts;                   // per cluster
  uint32_t max_shift = 0;
  uint64_t coarsened_vertices = 0;  // welded vertices snapped coarser than their finest cluster
};

SnappedDag snapToSharedGrids(const ClusterDag& dag, double step) {
  const size_t n = dag.clusters.size();
  SnappedDag out;
  out.positions.resize(n);
  out.shifts.assign(n, 0);
  std::unordered_map<PositionKey, uint32_t, PositionHash> weld;
  std::vector<std::vector<uint32_t>> global(n);
  for (size_t c = 0; c < n; ++c) {
    const DagCluster& cl = dag.clusters[c];
    global[c].resize(cl.positions.size());
    for (size_t v = 0; v < cl.positions.size(); ++v)
      global[c][v] =
          weld.emplace(positionKeyOf(cl.positions[v]), uint32_t(weld.size())).first->second;
  }
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 64), [&](const auto& range) {
    for (size_t c = range.begin(); c != range.end(); ++c)
      out.shifts[c] = requiredShift(dag.clusters[c].positions, step, 0);
  });
  std::vector<uint32_t> finest(weld.size(), kMaxPositionShift + 1);
  for (size_t c = 0; c < n; ++c)
    for (uint32_t g : global[c]) finest[g] = std::min(finest[g], out.shifts[c]);
  std::vector<uint32_t> vertex_shift(weld.size());
  // Snapping can widen a cluster past its shift; then its shift grows and the snap is redone.
  // Shifts only grow and are bounded, so this ends (in practice after one or two rounds).
  for (bool changed = true; changed;) {
    std::fill(vertex_shift.begin(), vertex_shift.end(), 0u);
    for (size_t c = 0; c < n; ++c)
      for (uint32_t g : global[c]) vertex_shift[g] = std::max(vertex_shift[g], out.shifts[c]);
    std::vector<uint8_t> grew(n, 0);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 64), [&](const auto& range) {
      for (size_t c = range.begin(); c != range.end(); ++c) {
        const DagCluster& cl = dag.clusters[c];
        std::vector<glm::vec3>& snapped = out.positions[c];
        snapped.resize(cl.positions.size());
        for (size_t v = 0; v < cl.positions.size(); ++v) {
          const double cell = std::ldexp(step, int(vertex_shift[global[c][v]]));
          for (int a = 0; a < 3; ++a)
            snapped[v][a] = float(std::nearbyint(double(cl.positions[v][a]) / cell) * cell);
        }
        const uint32_t shift = requiredShift(snapped, step, out.shifts[c]);
        if (shift > kMaxPositionShift) continue;  // the encoder reports it
        if (shift != out.shifts[c]) {
          out.shifts[c] = shift;
          grew[c] = 1;
        }
      }
    });
    changed = std::find(grew.begin(), grew.end(), uint8_t{1}) != grew.end();
  }
  for (size_t g = 0; g < vertex_shift.size(); ++g) {
    out.max_shift = std::max(out.max_shift, vertex_shift[g]);
    out.coarsened_vertices += vertex_shift[g] > finest[g];
  }
  return out;
}

}  // namespace

DagPlacement addDagToPackage(const ClusterDag& dag, PackageStorage& storage) {
  DagPlacement placement;
  placement.first_cluster = uint32_t(storage.clusters.size());
  placement.first_group = uint32_t(storage.groups.size());
  if (uint64_t(storage.clusters.size()) + dag.clusters.size() >= kNone ||
      uint64_t(storage.groups.size()) + dag.groups.size() >= kNone)
    throw std::invalid_argument("addDagToPackage: too many clusters or groups for the format");

  // Check the DAG before writing anything that depends on it.
  const size_t object_count = storage.objects.size();
  for (size_t c = 0; c < dag.clusters.size(); ++c) {
    const DagCluster& cl = dag.clusters[c];
    if (cl.level > std::numeric_limits<uint16_t>::max())
      throw std::invalid_argument("addDagToPackage: cluster level above 65535");
    for (uint32_t id : cl.triangle_object_ids)
      if (id >= object_count)
        throw std::invalid_argument("addDagToPackage: cluster " + std::to_string(c) +
                                    " has object id " + std::to_string(id) + " but storage has " +
                                    std::to_string(object_count) + " objects");
  }
  for (size_t g = 0; g < dag.groups.size(); ++g) {
    const std::vector<uint32_t>& made = dag.groups[g].clusters;
    for (size_t i = 1; i < made.size(); ++i)
      if (made[i] != made[0] + i)
        throw std::invalid_argument("addDagToPackage: group " + std::to_string(g) +
                                    " produced clusters that are not contiguous");
  }

  const SnappedDag snapped = snapToSharedGrids(dag, storage.position_step_m);
  placement.max_shift = snapped.max_shift;
  placement.coarsened_vertices = snapped.coarsened_vertices;
  // Snapping moves a vertex by up to half a cell of the coarsest grid, which can carry it just
  // outside the lod spheres the DAG computed from unsnapped positions. Every lod sphere grows by
  // that much: the same amount everywhere, so siblings still share their spheres exactly and a
  // parent's sphere still contains its children's.
  const float lod_slack =
      static_cast<float>(quantizationErrorM(storage.position_step_m, snapped.max_shift));
  placement.lod_slack = lod_slack;
  ClusterEncodeOptions encode_options;
  encode_options.position_step_m = storage.position_step_m;
  std::vector<std::vector<uint8_t>> encoded;
  std::vector<EncodedClusterInfo> infos;
  for (size_t batch = 0; batch < dag.clusters.size(); batch += kEncodeBatch) {
    const size_t count = std::min(kEncodeBatch, dag.clusters.size() - batch);
    encoded.assign(count, {});
    infos.assign(count, {});
    tbb::parallel_for(tbb::blocked_range<size_t>(0, count, 16),
                      [&](const tbb::blocked_range<size_t>& range) {
                        for (size_t i = range.begin(); i != range.end(); ++i) {
                          const DagCluster& cl = dag.clusters[batch + i];
                          ClusterGeometryInput geometry;
                          geometry.positions = snapped.positions[batch + i];
                          geometry.indices = cl.indices;
                          geometry.triangle_objects = cl.triangle_object_ids;
                          ClusterEncodeOptions options = encode_options;
                          options.min_shift = snapped.shifts[batch + i];
                          infos[i] = encodeCluster(geometry, options, encoded[i]);
                        }
                      });
    for (size_t i = 0; i < count; ++i) {
      const DagCluster& cl = dag.clusters[batch + i];
      const EncodedClusterInfo& info = infos[i];
      if (info.shift != snapped.shifts[batch + i])
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
      r.triangle_count = info.triangle_count;
      r.vertex_count = info.vertex_count;
      r.object_min = info.object_min;
      r.object_max = info.object_max;
      storage.placeEncodedCluster(encoded[i], r);
      storage.clusters.push_back(r);
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
      const ClusterRecord& cr = storage.clusters[placement.first_cluster + c];
      lo = glm::min(lo, glm::vec3(cr.aabb_min[0], cr.aabb_min[1], cr.aabb_min[2]));
      hi = glm::max(hi, glm::vec3(cr.aabb_max[0], cr.aabb_max[1], cr.aabb_max[2]));
    }
    if (boxed.empty()) lo = hi = g.sphere_center;
    setVec3(r.aabb_min, lo);
    setVec3(r.aabb_max, hi);
    r.max_parent_error = g.error;
    for (uint32_t c : g.clusters)
      r.max_parent_error = std::max(r.max_parent_error, dag.clusters[c].parent_error);
    r.first_cluster = g.clusters.empty() ? 0 : placement.first_cluster + g.clusters[0];
    r.cluster_count = uint32_t(g.clusters.size());
    storage.groups.push_back(r);
  }
  return placement;
}

}  // namespace tw
