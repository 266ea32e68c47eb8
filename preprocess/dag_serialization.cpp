// Byte layout of a ClusterDag for the resume store. Plain sequential fields; the blob store adds
// the checksum and the run hash, so this layer only guards against reading past the end.
#include "dag_serialization.h"

#include <cstring>
#include <type_traits>

#include "format_error.h"

namespace tw {
namespace {

constexpr char kMagic[8] = {'T', 'W', 'D', 'A', 'G', '0', '0', '1'};

class Writer {
 public:
  template <typename T>
  void value(const T& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    const auto* p = reinterpret_cast<const uint8_t*>(&v);
    bytes.insert(bytes.end(), p, p + sizeof(T));
  }
  template <typename T>
  void array(const std::vector<T>& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    value<uint64_t>(v.size());
    const auto* p = reinterpret_cast<const uint8_t*>(v.data());
    bytes.insert(bytes.end(), p, p + v.size() * sizeof(T));
  }
  std::vector<uint8_t> bytes;
};

class Reader {
 public:
  Reader(std::span<const uint8_t> bytes, const std::string& source)
      : bytes_(bytes), source_(source) {}

  template <typename T>
  T value() {
    static_assert(std::is_trivially_copyable_v<T>);
    need(sizeof(T), "value");
    T v;
    std::memcpy(&v, bytes_.data() + at_, sizeof(T));
    at_ += sizeof(T);
    return v;
  }
  template <typename T>
  std::vector<T> array() {
    uint64_t count = value<uint64_t>();
    if (count > (bytes_.size() - at_) / sizeof(T)) fail("array of " + std::to_string(count) +
                                                        " elements runs past the end");
    std::vector<T> v(count);
    std::memcpy(v.data(), bytes_.data() + at_, count * sizeof(T));
    at_ += count * sizeof(T);
    return v;
  }
  void need(size_t n, const char* what) {
    if (n > bytes_.size() - at_) fail(std::string("truncated ") + what);
  }
  [[noreturn]] void fail(const std::string& reason) const {
    throw FormatError::atByte(source_, at_, reason);
  }
  bool atEnd() const { return at_ == bytes_.size(); }

 private:
  std::span<const uint8_t> bytes_;
  const std::string& source_;
  size_t at_ = 0;
};

}  // namespace

std::vector<uint8_t> serializeClusterDag(const ClusterDag& dag) {
  Writer w;
  for (char c : kMagic) w.value(c);
  w.value<uint64_t>(dag.clusters.size());
  for (const DagCluster& c : dag.clusters) {
    w.array(c.positions);
    w.array(c.indices);
    w.array(c.triangle_object_ids);
    w.value(c.level);
    w.value(c.group);
    w.value(c.parent_group);
    w.value(c.error);
    w.value(c.parent_error);
    w.value(c.sphere_center);
    w.value(c.sphere_radius);
    w.value(c.box_min);
    w.value(c.box_max);
    w.value(c.lod_center);
    w.value(c.lod_radius);
    w.value(c.parent_lod_center);
    w.value(c.parent_lod_radius);
  }
  w.value<uint64_t>(dag.groups.size());
  for (const DagGroup& g : dag.groups) {
    w.value(g.level);
    w.array(g.children);
    w.array(g.clusters);
    w.value(g.error);
    w.value(g.sphere_center);
    w.value(g.sphere_radius);
    w.value(g.method);
  }
  w.array(dag.triangles_per_level);
  w.array(dag.clusters_per_level);
  w.value(dag.root_triangles);
  w.value(dag.stats);
  return std::move(w.bytes);
}

ClusterDag deserializeClusterDag(std::span<const uint8_t> bytes, const std::string& source) {
  Reader r(bytes, source);
  for (char c : kMagic)
    if (r.value<char>() != c) r.fail("not a serialized cluster DAG (bad magic)");
  ClusterDag dag;
  uint64_t clusters = r.value<uint64_t>();
  // Each cluster takes well over 64 bytes: a cheap bound before reserving.
  if (clusters > bytes.size() / 64) r.fail("cluster count " + std::to_string(clusters) +
                                           " exceeds what the bytes can hold");
  dag.clusters.resize(clusters);
  for (DagCluster& c : dag.clusters) {
    c.positions = r.array<glm::vec3>();
    c.indices = r.array<uint32_t>();
    c.triangle_object_ids = r.array<uint32_t>();
    c.level = r.value<uint32_t>();
    c.group = r.value<uint32_t>();
    c.parent_group = r.value<uint32_t>();
    c.error = r.value<float>();
    c.parent_error = r.value<float>();
    c.sphere_center = r.value<glm::vec3>();
    c.sphere_radius = r.value<float>();
    c.box_min = r.value<glm::vec3>();
    c.box_max = r.value<glm::vec3>();
    c.lod_center = r.value<glm::vec3>();
    c.lod_radius = r.value<float>();
    c.parent_lod_center = r.value<glm::vec3>();
    c.parent_lod_radius = r.value<float>();
    if (c.indices.size() % 3 != 0 || c.indices.size() / 3 != c.triangle_object_ids.size())
      r.fail("cluster index and object-id counts disagree");
    for (uint32_t i : c.indices)
      if (i >= c.positions.size()) r.fail("cluster index out of range");
  }
  uint64_t groups = r.value<uint64_t>();
  if (groups > bytes.size() / 16) r.fail("group count " + std::to_string(groups) +
                                         " exceeds what the bytes can hold");
  dag.groups.resize(groups);
  for (DagGroup& g : dag.groups) {
    g.level = r.value<uint32_t>();
    g.children = r.array<uint32_t>();
    g.clusters = r.array<uint32_t>();
    g.error = r.value<float>();
    g.sphere_center = r.value<glm::vec3>();
    g.sphere_radius = r.value<float>();
    g.method = r.value<GroupMethod>();
    for (uint32_t i : g.children)
      if (i >= clusters) r.fail("group child out of range");
    for (uint32_t i : g.clusters)
      if (i >= clusters) r.fail("group cluster out of range");
  }
  for (const DagCluster& c : dag.clusters)
    if ((c.group != kNoGroup && c.group >= groups) ||
        (c.parent_group != kNoGroup && c.parent_group >= groups))
      r.fail("cluster refers to a group out of range");
  dag.triangles_per_level = r.array<uint64_t>();
  dag.clusters_per_level = r.array<uint32_t>();
  dag.root_triangles = r.value<uint64_t>();
  dag.stats = r.value<DagBuildStats>();
  if (!r.atEnd()) r.fail("trailing bytes after the DAG");
  return dag;
}

}  // namespace tw
