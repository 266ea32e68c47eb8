// Byte layout of a ClusterDag for the resume store. Plain sequential fields; the blob store adds
// the checksum and the run hash, so this layer only guards against reading past the end and
// against references out of range.
#include "dag_serialization.h"

#include "byte_packing.h"

namespace tw {
namespace {

constexpr char kMagic[8] = {'T', 'W', 'D', 'A', 'G', '0', '0', '1'};

}  // namespace

std::vector<uint8_t> serializeClusterDag(const ClusterDag& dag) {
  ByteWriter w;
  for (char c : kMagic) w.put(c);
  w.put<uint64_t>(dag.clusters.size());
  for (const DagCluster& c : dag.clusters) {
    w.putArray(c.positions);
    w.putArray(c.indices);
    w.putArray(c.triangle_object_ids);
    w.put(c.level);
    w.put(c.group);
    w.put(c.parent_group);
    w.put(c.error);
    w.put(c.parent_error);
    w.put(c.sphere_center);
    w.put(c.sphere_radius);
    w.put(c.box_min);
    w.put(c.box_max);
    w.put(c.lod_center);
    w.put(c.lod_radius);
    w.put(c.parent_lod_center);
    w.put(c.parent_lod_radius);
  }
  w.put<uint64_t>(dag.groups.size());
  for (const DagGroup& g : dag.groups) {
    w.put(g.level);
    w.putArray(g.children);
    w.putArray(g.clusters);
    w.put(g.error);
    w.put(g.sphere_center);
    w.put(g.sphere_radius);
    w.put(g.method);
  }
  w.putArray(dag.triangles_per_level);
  w.putArray(dag.clusters_per_level);
  w.put(dag.root_triangles);
  w.put(dag.stats);
  return std::move(w.bytes);
}

ClusterDag deserializeClusterDag(std::span<const uint8_t> bytes, const std::string& source) {
  ByteReader r(bytes, source);
  for (char c : kMagic)
    if (r.get<char>() != c) r.fail("not a serialized cluster DAG (bad magic)");
  ClusterDag dag;
  uint64_t clusters = r.get<uint64_t>();
  // Each cluster takes well over 64 bytes: a cheap bound before reserving.
  if (clusters > bytes.size() / 64) r.fail("cluster count " + std::to_string(clusters) +
                                           " exceeds what the bytes can hold");
  dag.clusters.resize(clusters);
  for (DagCluster& c : dag.clusters) {
    c.positions = r.getArray<glm::vec3>();
    c.indices = r.getArray<uint32_t>();
    c.triangle_object_ids = r.getArray<uint32_t>();
    c.level = r.get<uint32_t>();
    c.group = r.get<uint32_t>();
    c.parent_group = r.get<uint32_t>();
    c.error = r.get<float>();
    c.parent_error = r.get<float>();
    c.sphere_center = r.get<glm::vec3>();
    c.sphere_radius = r.get<float>();
    c.box_min = r.get<glm::vec3>();
    c.box_max = r.get<glm::vec3>();
    c.lod_center = r.get<glm::vec3>();
    c.lod_radius = r.get<float>();
    c.parent_lod_center = r.get<glm::vec3>();
    c.parent_lod_radius = r.get<float>();
    if (c.indices.size() % 3 != 0 || c.indices.size() / 3 != c.triangle_object_ids.size())
      r.fail("cluster index and object-id counts disagree");
    for (uint32_t i : c.indices)
      if (i >= c.positions.size()) r.fail("cluster index out of range");
  }
  uint64_t groups = r.get<uint64_t>();
  if (groups > bytes.size() / 16) r.fail("group count " + std::to_string(groups) +
                                         " exceeds what the bytes can hold");
  dag.groups.resize(groups);
  for (DagGroup& g : dag.groups) {
    g.level = r.get<uint32_t>();
    g.children = r.getArray<uint32_t>();
    g.clusters = r.getArray<uint32_t>();
    g.error = r.get<float>();
    g.sphere_center = r.get<glm::vec3>();
    g.sphere_radius = r.get<float>();
    g.method = r.get<GroupMethod>();
    if (uint8_t(g.method) > uint8_t(GroupMethod::Merged)) r.fail("unknown group method");
    for (uint32_t i : g.children)
      if (i >= clusters) r.fail("group child out of range");
    for (uint32_t i : g.clusters)
      if (i >= clusters) r.fail("group cluster out of range");
  }
  for (const DagCluster& c : dag.clusters)
    if ((c.group != kNoGroup && c.group >= groups) ||
        (c.parent_group != kNoGroup && c.parent_group >= groups))
      r.fail("cluster refers to a group out of range");
  dag.triangles_per_level = r.getArray<uint64_t>();
  dag.clusters_per_level = r.getArray<uint32_t>();
  dag.root_triangles = r.get<uint64_t>();
  dag.stats = r.get<DagBuildStats>();
  if (!r.atEnd()) r.fail("trailing bytes after the DAG");
  return dag;
}

}  // namespace tw
