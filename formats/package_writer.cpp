// PackageStorage helpers and writePackage: lays out, checksums and atomically writes a .twk.
#include "package_writer.h"

#include <unistd.h>
#include <xxhash.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <initializer_list>
#include <limits>
#include <stdexcept>
#include <string>
#include <variant>

#include "package_view.h"
#include "record_spill.h"
#include "section_codec.h"
#include "tws_format.h"

namespace tw {
namespace {

using namespace pkg;

void setVec3(float out[3], const glm::vec3& v) {
  out[0] = v.x;
  out[1] = v.y;
  out[2] = v.z;
}

uint32_t checkedStringBytes(std::string_view text, const char* what) {
  if (text.size() > kMaxStringBytes)
    throw std::invalid_argument(std::string("package: ") + what + " is longer than " +
                                std::to_string(kMaxStringBytes) + " bytes");
  return static_cast<uint32_t>(text.size());
}

// One output file, removed unless commit() renamed it.
class TempFile {
 public:
  TempFile(const std::filesystem::path& path)
      : path_(path), temp_(path.string() + ".tmp-" + std::to_string(::getpid())) {
    file_ = std::fopen(temp_.c_str(), "wb");
    if (!file_) ioFail("cannot create");
  }
  ~TempFile() {
    if (file_) std::fclose(file_);
    if (!committed_) {
      std::error_code ec;
      std::filesystem::remove(temp_, ec);
    }
  }
  const std::filesystem::path& tempPath() const { return temp_; }

  void write(const void* data, uint64_t bytes) {
    if (bytes > 0 && std::fwrite(data, 1, bytes, file_) != bytes) ioFail("cannot write");
    written_ += bytes;
  }
  // Appends a spill file's bytes in chunks (never all in memory).
  void copyFrom(const RecordSpill& source) {
    source.forEachChunk(4u << 20,
                        [this](std::span<const uint8_t> chunk) { write(chunk.data(), chunk.size()); });
  }
  void padTo(uint64_t offset) {
    static const uint8_t kZeros[kSectionAlignment] = {};
    while (written_ < offset) write(kZeros, std::min<uint64_t>(offset - written_, sizeof(kZeros)));
  }
  void close() {
    bool ok = std::fflush(file_) == 0 && ::fsync(::fileno(file_)) == 0;
    ok = std::fclose(file_) == 0 && ok;
    file_ = nullptr;
    if (!ok) ioFail("cannot finish writing");
  }
  void commit() {
    std::error_code ec;
    std::filesystem::rename(temp_, path_, ec);
    if (ec)
      throw std::runtime_error(path_.string() + ": cannot rename " + temp_.string() + ": " +
                               ec.message());
    committed_ = true;
  }

 private:
  [[noreturn]] void ioFail(const std::string& what) const {
    throw std::runtime_error(path_.string() + ": " + what + " " + temp_.string() + ": " +
                             std::strerror(errno));
  }
  std::filesystem::path path_;
  std::filesystem::path temp_;
  std::FILE* file_ = nullptr;
  uint64_t written_ = 0;
  bool committed_ = false;
};

// One page as the file stores it: zstd when that shrinks it, raw otherwise. Fills the record's
// sizes, codec and checksum (not its offset or cluster count); returns the stored bytes, which
// point into `raw` or `compressed`.
std::span<const uint8_t> storePage(std::span<const uint8_t> raw, const PackageWriteOptions& options,
                                   std::vector<uint8_t>& compressed, PageRecord& p) {
  p.raw_bytes = static_cast<uint32_t>(raw.size());
  compressed.clear();
  if (options.zstd && !raw.empty()) compressPage(raw, options.zstd_level, compressed);
  const bool use_zstd = options.zstd && !raw.empty() && compressed.size() < raw.size();
  std::span<const uint8_t> stored = use_zstd ? std::span<const uint8_t>(compressed) : raw;
  p.codec = static_cast<uint32_t>(use_zstd ? PageCodec::Zstd : PageCodec::None);
  p.stored_bytes = static_cast<uint32_t>(stored.size());
  p.checksum = packageSectionChecksum(stored);
  return stored;
}

}  // namespace

// The page-data section's first bytes, in a file: pages compressed and laid out exactly as
// writePackage lays them out (each at a multiple of kSectionAlignment from the section start,
// zero padding between), with their records and a running XXH3 of the section so far.
class PageSpill {
 public:
  PageSpill(const std::filesystem::path& path, const PackageWriteOptions& options)
      : data_(path, 1, "page data"), options_(options) {}

  void append(std::span<const uint8_t> raw) {
    if (raw.size() > kMaxPageRawBytes)
      throw std::invalid_argument("package: page " + std::to_string(records_.size()) +
                                  " is over the size limit");
    PageRecord p{};
    std::span<const uint8_t> stored = storePage(raw, options_, compressed_, p);
    static const uint8_t kZeros[kSectionAlignment] = {};
    p.offset = alignUp(data_.bytes(), kSectionAlignment);
    data_.append(kZeros, p.offset - data_.bytes());
    data_.appendBytes(stored);
    records_.push_back(p);
    raw_bytes_ += raw.size();
  }
  const RecordSpill& data() const { return data_; }
  const PackageWriteOptions& options() const { return options_; }
  const std::vector<PageRecord>& records() const { return records_; }
  uint64_t bytes() const { return data_.bytes(); }
  uint64_t rawBytes() const { return raw_bytes_; }

 private:
  RecordSpill data_;
  PackageWriteOptions options_;
  std::vector<PageRecord> records_;
  std::vector<uint8_t> compressed_;
  uint64_t raw_bytes_ = 0;
};

// The tables' older records, one file each, and the rule that moves them there: a table's
// in-memory tail goes to its file once it holds tail_bytes.
class TableSpill {
 public:
  TableSpill(const std::filesystem::path& dir, uint64_t tail_limit_bytes)
      : tail_bytes(std::max<uint64_t>(tail_limit_bytes, 1)),
        clusters(dir / "clusters.spill", sizeof(ClusterRecord), "cluster table"),
        groups(dir / "groups.spill", sizeof(GroupRecord), "group table"),
        instances(dir / "instances.spill", sizeof(InstanceRecord), "instance table"),
        profiles(dir / "profiles.spill", sizeof(glm::vec2), "profile table"),
        objects(dir / "objects.spill", sizeof(ObjectRecord), "object table"),
        strings(dir / "strings.spill", 1, "string pool") {}

  template <typename Tail>
  void flushIfFull(Tail& tail, RecordSpill& file) const {
    if (tail.size() * sizeof(tail[0]) < tail_bytes) return;
    file.append(tail.data(), tail.size());
    tail.clear();
  }

  const uint64_t tail_bytes;
  RecordSpill clusters, groups, instances, profiles, objects, strings;
};

void setClusterLod(pkg::ClusterRecord& r, const ClusterLod& lod, const glm::vec3& fallback_center,
                   float fallback_radius) {
  r.error = lod.error;
  r.parent_error = lod.parent_error;
  glm::vec4 sphere = lod.lod_sphere.w > 0.0f ? lod.lod_sphere
                                             : glm::vec4(fallback_center, fallback_radius);
  glm::vec4 parent = lod.parent_lod_sphere.w > 0.0f ? lod.parent_lod_sphere : sphere;
  setVec3(r.lod_center, glm::vec3(sphere));
  r.lod_radius = sphere.w;
  setVec3(r.parent_lod_center, glm::vec3(parent));
  r.parent_lod_radius = parent.w;
  r.group = lod.group;
  r.parent_group = lod.parent_group;
  r.level = lod.level;
}

uint64_t PackageStorage::addString(std::string_view text) {
  uint64_t offset = stringBytes();
  strings.append(text);
  if (tables) tables->flushIfFull(strings, tables->strings);
  return offset;
}

void PackageStorage::setDatabasePath(std::string_view path) {
  database_path_bytes = checkedStringBytes(path, "database path");
  database_path_offset = addString(path);
}

uint32_t PackageStorage::addLayer(const Layer& layer) {
  LayerRecord r{};
  r.name_bytes = checkedStringBytes(layer.name, "layer name");
  r.name_offset = addString(layer.name);
  r.color_rgba = layer.color_rgba;
  layers.push_back(r);
  return static_cast<uint32_t>(layers.size() - 1);
}

uint32_t PackageStorage::addObject(const ObjectInfo& info, const glm::vec3& aabb_min,
                                   const glm::vec3& aabb_max, uint32_t flags) {
  if ((flags & ~kKnownObjectFlags) != 0)
    throw std::invalid_argument("package: object flags has unknown bits");
  ObjectRecord r{};
  r.flags = flags;
  r.id = info.id;
  r.layer = info.layer;
  r.color_rgba = info.color_rgba;
  r.name_bytes = checkedStringBytes(info.name, "object name");
  r.name_offset = addString(info.name);
  r.db_key_bytes = checkedStringBytes(info.db_key, "database key");
  r.db_key_offset = addString(info.db_key);
  setVec3(r.aabb_min, aabb_min);
  setVec3(r.aabb_max, aabb_max);
  const uint32_t index = objectCount();
  objects.push_back(r);
  if (tables) tables->flushIfFull(objects, tables->objects);
  return index;
}

void PackageStorage::placeEncodedCluster(std::span<const uint8_t> encoded, ClusterRecord& record) {
  if (encoded.size() > kMaxPageRawBytes)
    throw std::invalid_argument("package: encoded cluster is larger than a page may be");
  uint64_t offset = pages.empty() ? 0 : alignUp(pages.back().size(), kClusterAlignment);
  if (pages.empty() || (!pages.back().empty() && offset + encoded.size() > target_page_bytes) ||
      offset + encoded.size() > kMaxPageRawBytes) {
    if (spill && !pages.empty()) {  // the open page is complete: out of memory with it
      spill->append(pages.back());
      pages.clear();
    }
    pages.emplace_back();
    pages.back().reserve(target_page_bytes);
    offset = 0;
  }
  std::vector<uint8_t>& page = pages.back();
  page.resize(offset, 0);
  page.insert(page.end(), encoded.begin(), encoded.end());
  record.page = pageCount() - 1;
  record.page_offset = static_cast<uint32_t>(offset);
  record.encoded_bytes = static_cast<uint32_t>(encoded.size());
}

void PackageStorage::spillPagesTo(const std::filesystem::path& spill_path,
                                  const PackageWriteOptions& options) {
  if (spill || !pages.empty())
    throw std::logic_error("package: spillPagesTo must be called before any page exists");
  spill = std::make_shared<PageSpill>(spill_path, options);
}

uint32_t PackageStorage::pageCount() const {
  return static_cast<uint32_t>((spill ? spill->records().size() : 0) + pages.size());
}

uint64_t PackageStorage::spilledPageBytes() const { return spill ? spill->bytes() : 0; }

void PackageStorage::spillTablesTo(const std::filesystem::path& dir, uint64_t tail_bytes) {
  if (tables || !clusters.empty() || !groups.empty() || !instances.empty() ||
      !profile_points.empty() || !objects.empty() || !strings.empty())
    throw std::logic_error("package: spillTablesTo must be called before any record exists");
  std::filesystem::create_directories(dir);
  tables = std::make_shared<TableSpill>(dir, tail_bytes);
}

uint32_t PackageStorage::clusterCount() const {
  return static_cast<uint32_t>((tables ? tables->clusters.count() : 0) + clusters.size());
}
uint32_t PackageStorage::groupCount() const {
  return static_cast<uint32_t>((tables ? tables->groups.count() : 0) + groups.size());
}
uint32_t PackageStorage::instanceCount() const {
  return static_cast<uint32_t>((tables ? tables->instances.count() : 0) + instances.size());
}
uint64_t PackageStorage::profilePointCount() const {
  return (tables ? tables->profiles.count() : 0) + profile_points.size();
}
uint32_t PackageStorage::objectCount() const {
  return static_cast<uint32_t>((tables ? tables->objects.count() : 0) + objects.size());
}
uint64_t PackageStorage::stringBytes() const {
  return (tables ? tables->strings.count() : 0) + strings.size();
}

namespace {

// Records [first, first + count) of a table split into a spilled head and an in-memory tail.
template <typename Record>
void readSplit(const RecordSpill* head, const std::vector<Record>& tail, uint64_t first,
               uint64_t count, Record* out) {
  const uint64_t spilled = head ? head->count() : 0;
  if (first > spilled + tail.size() || count > spilled + tail.size() - first)
    throw std::out_of_range("package: record index out of range");
  if (first < spilled) {
    const uint64_t n = std::min(count, spilled - first);
    head->read(first, n, out);
    out += n;
    first += n;
    count -= n;
  }
  std::copy_n(tail.begin() + ptrdiff_t(first - spilled), count, out);
}

}  // namespace

ClusterRecord PackageStorage::clusterRecord(uint32_t index) const {
  ClusterRecord r;
  readSplit(tables ? &tables->clusters : nullptr, clusters, index, 1, &r);
  return r;
}

InstanceRecord PackageStorage::instanceRecord(uint32_t index) const {
  InstanceRecord r;
  readSplit(tables ? &tables->instances : nullptr, instances, index, 1, &r);
  return r;
}

void PackageStorage::readProfilePoints(uint64_t first, uint32_t count,
                                       std::vector<glm::vec2>& out) const {
  out.resize(count);
  readSplit(tables ? &tables->profiles : nullptr, profile_points, first, count, out.data());
}

uint32_t PackageStorage::appendCluster(const ClusterRecord& record) {
  const uint32_t index = clusterCount();
  clusters.push_back(record);
  if (tables) tables->flushIfFull(clusters, tables->clusters);
  return index;
}

uint32_t PackageStorage::appendGroup(const GroupRecord& record) {
  const uint32_t index = groupCount();
  groups.push_back(record);
  if (tables) tables->flushIfFull(groups, tables->groups);
  return index;
}

uint32_t PackageStorage::addMeshCluster(const ClusterGeometryInput& geometry, const ClusterLod& lod,
                                        bool optimize) {
  std::vector<uint8_t> encoded;
  ClusterEncodeOptions options;
  options.position_step_m = position_step_m;
  options.optimize = optimize;
  EncodedClusterInfo info = encodeCluster(geometry, options, encoded);

  ClusterRecord r{};
  setVec3(r.center, info.center);
  r.radius = info.radius;
  setVec3(r.aabb_min, info.aabb_min);
  setVec3(r.aabb_max, info.aabb_max);
  setClusterLod(r, lod, info.center, info.radius);
  r.kind = static_cast<uint8_t>(ClusterKind::Mesh);
  r.triangle_count = info.triangle_count;
  r.vertex_count = info.vertex_count;
  r.object_min = info.object_min;
  r.object_max = info.object_max;
  placeEncodedCluster(encoded, r);
  return appendCluster(r);
}

namespace {

// Fills the type, flags, params and profile of `r` from the primitive (tws parameter layout).
struct InstanceFiller {
  InstanceRecord& r;
  std::vector<glm::vec2>& profiles;
  void operator()(const Cylinder& c) {
    set(PrimitiveType::Cylinder, {c.radius, c.height}, c.capped);
  }
  void operator()(const Cone& c) {
    set(PrimitiveType::Cone, {c.radius_bottom, c.radius_top, c.height}, c.capped);
  }
  void operator()(const Sphere& s) { set(PrimitiveType::Sphere, {s.radius}, false); }
  void operator()(const TorusSegment& t) {
    set(PrimitiveType::TorusSegment, {t.major_radius, t.minor_radius, t.sweep_rad}, false);
  }
  void operator()(const Box& b) {
    set(PrimitiveType::Box, {b.half_extents.x, b.half_extents.y, b.half_extents.z}, false);
  }
  void operator()(const Extrusion& e) {
    set(PrimitiveType::Extrusion, {e.height}, false);
    profile(e.profile);
  }
  void operator()(const Revolution& v) {
    set(PrimitiveType::Revolution, {v.sweep_rad}, false);
    profile(v.profile);
  }
  void set(PrimitiveType type, std::initializer_list<float> params, bool capped) {
    r.type = static_cast<uint32_t>(type);
    r.flags = capped ? kInstanceCapped : 0;
    std::copy(params.begin(), params.end(), r.params);
  }
  void profile(const std::vector<glm::vec2>& points) {
    if (points.size() > kMaxProfilePoints)
      throw std::invalid_argument("package: profile has more than 65536 points");
    r.profile_first = static_cast<uint32_t>(profiles.size());
    r.profile_count = static_cast<uint32_t>(points.size());
    profiles.insert(profiles.end(), points.begin(), points.end());
  }
};

}  // namespace

void instanceBounds(const InstanceRecord& in, std::span<const glm::vec2> profile_points,
                    glm::vec3& aabb_min, glm::vec3& aabb_max) {
  const float* p = in.params;
  glm::vec3 lo(0.0f), hi(0.0f);
  switch (static_cast<PrimitiveType>(in.type)) {
    case PrimitiveType::Cylinder:
      lo = {-p[0], -p[0], 0.0f};
      hi = {p[0], p[0], p[1]};
      break;
    case PrimitiveType::Cone: {
      float r = std::max(p[0], p[1]);
      lo = {-r, -r, 0.0f};
      hi = {r, r, p[2]};
      break;
    }
    case PrimitiveType::Sphere:
      lo = glm::vec3(-p[0]);
      hi = glm::vec3(p[0]);
      break;
    case PrimitiveType::TorusSegment: {  // the whole torus: conservative for any sweep
      float r = p[0] + p[1];
      lo = {-r, -r, -p[1]};
      hi = {r, r, p[1]};
      break;
    }
    case PrimitiveType::Box:
      lo = {-p[0], -p[1], -p[2]};
      hi = {p[0], p[1], p[2]};
      break;
    case PrimitiveType::Extrusion:
    case PrimitiveType::Revolution: {
      const bool extrusion = in.type == static_cast<uint32_t>(PrimitiveType::Extrusion);
      glm::vec2 pmin(std::numeric_limits<float>::max()), pmax(-std::numeric_limits<float>::max());
      for (uint32_t i = 0; i < in.profile_count; ++i) {
        pmin = glm::min(pmin, profile_points[in.profile_first + i]);
        pmax = glm::max(pmax, profile_points[in.profile_first + i]);
      }
      if (in.profile_count == 0) pmin = pmax = glm::vec2(0.0f);
      if (extrusion) {
        lo = {pmin.x, pmin.y, 0.0f};
        hi = {pmax.x, pmax.y, p[0]};
      } else {  // (radius, z) profile revolved about +Z
        lo = {-pmax.x, -pmax.x, pmin.y};
        hi = {pmax.x, pmax.x, pmax.y};
      }
      break;
    }
  }
  const glm::mat3 linear(in.linear[0], in.linear[1], in.linear[2], in.linear[3], in.linear[4],
                         in.linear[5], in.linear[6], in.linear[7], in.linear[8]);
  const glm::vec3 origin(in.origin[0], in.origin[1], in.origin[2]);
  aabb_min = glm::vec3(std::numeric_limits<float>::max());
  aabb_max = glm::vec3(-std::numeric_limits<float>::max());
  for (int corner = 0; corner < 8; ++corner) {
    glm::vec3 local(corner & 1 ? hi.x : lo.x, corner & 2 ? hi.y : lo.y, corner & 4 ? hi.z : lo.z);
    glm::vec3 world = origin + linear * local;
    aabb_min = glm::min(aabb_min, world);
    aabb_max = glm::max(aabb_max, world);
  }
}

namespace {

// The record of `primitive` placed by `transform` relative to `origin`; its profile points, if
// any, are appended to `profiles` (profile_first counts from the vector's start).
InstanceRecord makeInstanceRecord(const Primitive& primitive, const Transform& transform,
                                  uint32_t object, const glm::dvec3& origin,
                                  std::vector<glm::vec2>& profiles) {
  if (std::string problem = tws::primitiveProblem(primitive); !problem.empty())
    throw std::invalid_argument("package: " + problem);
  InstanceRecord r{};
  glm::vec3 at(transform.origin - origin);
  setVec3(r.origin, at);
  const float* m = &transform.linear[0][0];
  std::copy(m, m + 9, r.linear);
  r.object = object;
  std::visit(InstanceFiller{r, profiles}, primitive);
  return r;
}

}  // namespace

pkg::InstanceRecord placedInstanceRecord(const Primitive& primitive, const Transform& transform,
                                         uint32_t object, const glm::dvec3& origin) {
  std::vector<glm::vec2> profiles;
  InstanceRecord r = makeInstanceRecord(primitive, transform, object, origin, profiles);
  r.profile_first = r.profile_count = 0;
  return r;
}

uint32_t PackageStorage::addInstance(const Primitive& primitive, const Transform& transform,
                                     uint32_t object, uint32_t role_flags) {
  if (role_flags & ~kInstanceSearchedFlags)
    throw std::invalid_argument("package: instance role flags has unknown bits");
  if ((role_flags & kInstanceCoveredFaces) && !std::holds_alternative<Box>(primitive))
    throw std::invalid_argument("package: covered faces on an instance that is not a box");
  const uint64_t profile_base = profilePointCount() - profile_points.size();
  InstanceRecord r = makeInstanceRecord(primitive, transform, object, origin, profile_points);
  r.flags |= role_flags;
  r.profile_first = static_cast<uint32_t>(profile_base + r.profile_first);
  if (r.profile_count == 0) r.profile_first = 0;
  const uint32_t index = instanceCount();
  instances.push_back(r);
  if (tables) {
    tables->flushIfFull(instances, tables->instances);
    tables->flushIfFull(profile_points, tables->profiles);
  }
  return index;
}

uint32_t PackageStorage::addParametricCluster(uint32_t first_instance, uint32_t count,
                                              const ClusterLod& lod) {
  const uint32_t total = instanceCount();
  if (count == 0 || first_instance > total || count > total - first_instance)
    throw std::invalid_argument("package: parametric cluster instance range is invalid");
  ClusterRecord r{};
  glm::vec3 lo(std::numeric_limits<float>::max()), hi(-std::numeric_limits<float>::max());
  r.object_min = ~0u;
  std::vector<InstanceRecord> range(count);
  readSplit(tables ? &tables->instances : nullptr, instances, first_instance, count, range.data());
  std::vector<glm::vec2> points;
  for (InstanceRecord in : range) {
    if (in.type != range[0].type)
      throw std::invalid_argument("package: a parametric cluster mixes primitive types");
    if (in.profile_count > 0) {  // its own points, rebased so the bounds read them at 0
      readProfilePoints(in.profile_first, in.profile_count, points);
      in.profile_first = 0;
    }
    glm::vec3 bmin, bmax;
    instanceBounds(in, points, bmin, bmax);
    lo = glm::min(lo, bmin);
    hi = glm::max(hi, bmax);
    r.object_min = std::min(r.object_min, in.object);
    r.object_max = std::max(r.object_max, in.object);
  }
  setVec3(r.aabb_min, lo);
  setVec3(r.aabb_max, hi);
  glm::vec3 center = (lo + hi) * 0.5f;
  float radius = std::nextafter(glm::length(hi - lo) * 0.5f, std::numeric_limits<float>::max());
  setVec3(r.center, center);
  r.radius = radius;
  setClusterLod(r, lod, center, radius);
  r.kind = static_cast<uint8_t>(ClusterKind::Parametric);
  r.page = kNone;
  r.instance_first = first_instance;
  r.instance_count = count;
  return appendCluster(r);
}

PackageWriteStats writePackage(const PackageStorage& storage, const std::filesystem::path& path,
                               const PackageWriteOptions& options) {
  PackageWriteStats stats;

  // Pages: compress each, keep the raw bytes when compression does not help. Spilled pages are
  // already stored: the section is the spill file's bytes followed by `page_data`.
  const PageSpill* spill = storage.spill.get();
  if (spill && (spill->options().zstd != options.zstd ||
                (options.zstd && spill->options().zstd_level != options.zstd_level)))
    throw std::invalid_argument("writePackage: options differ from the page spill's");
  const uint64_t spilled_bytes = spill ? spill->bytes() : 0;
  std::vector<PageRecord> page_records;
  if (spill) {
    page_records = spill->records();
    stats.page_raw_bytes = spill->rawBytes();
  }
  const size_t first_memory_page = page_records.size();
  page_records.resize(first_memory_page + storage.pages.size());
  const TableSpill* tables = storage.tables.get();
  // One pass over the cluster records (spilled ones first, in chunks): clusters per page and the
  // header's aggregates.
  PackageHeader h{};
  glm::vec3 lo(std::numeric_limits<float>::max()), hi(-std::numeric_limits<float>::max());
  auto visit_cluster = [&](const ClusterRecord& c) {
    if (c.kind == static_cast<uint8_t>(ClusterKind::Mesh) && c.page < page_records.size())
      ++page_records[c.page].cluster_count;
    lo = glm::min(lo, glm::vec3(c.aabb_min[0], c.aabb_min[1], c.aabb_min[2]));
    hi = glm::max(hi, glm::vec3(c.aabb_max[0], c.aabb_max[1], c.aabb_max[2]));
    h.level_count = std::max<uint32_t>(h.level_count, c.level + 1u);
    h.max_cluster_triangles = std::max(h.max_cluster_triangles, c.triangle_count);
    if (c.level == 0) h.total_triangles += c.triangle_count;
  };
  if (tables)
    tables->clusters.forEachChunk(4u << 20, [&](std::span<const uint8_t> chunk) {
      for (size_t at = 0; at < chunk.size(); at += sizeof(ClusterRecord)) {
        ClusterRecord c;
        std::memcpy(&c, chunk.data() + at, sizeof c);
        visit_cluster(c);
      }
    });
  for (const ClusterRecord& c : storage.clusters) visit_cluster(c);
  std::vector<uint8_t> page_data;
  std::vector<uint8_t> compressed;
  for (size_t i = 0; i < storage.pages.size(); ++i) {
    const std::vector<uint8_t>& raw = storage.pages[i];
    const size_t index = first_memory_page + i;
    if (raw.size() > kMaxPageRawBytes)
      throw std::invalid_argument("package: page " + std::to_string(index) +
                                  " is over the size limit");
    stats.page_raw_bytes += raw.size();
    PageRecord& p = page_records[index];
    p.offset = alignUp(spilled_bytes + page_data.size(), kSectionAlignment);
    page_data.resize(p.offset - spilled_bytes, 0);
    std::span<const uint8_t> stored = storePage(raw, options, compressed, p);
    page_data.insert(page_data.end(), stored.begin(), stored.end());
  }

  // Header.
  std::memcpy(h.magic, kMagic, sizeof(kMagic));
  h.version = kVersion;
  h.minor_version = kMinorVersion;
  h.flags = (storage.sealed_runs_marked ? kHeaderSealedRunsMarked : 0) |
            (storage.covered_faces_marked ? kHeaderCoveredFacesMarked : 0);
  h.header_bytes = sizeof(PackageHeader);
  h.section_entry_bytes = sizeof(SectionEntry);
  h.section_count = kSectionCount;
  h.input_hash = storage.input_hash;
  h.database_path_offset = storage.database_path_offset;
  h.database_path_bytes = storage.database_path_bytes;
  h.cluster_record_bytes = sizeof(ClusterRecord);
  h.group_record_bytes = sizeof(GroupRecord);
  h.page_record_bytes = sizeof(PageRecord);
  h.instance_record_bytes = sizeof(InstanceRecord);
  h.object_record_bytes = sizeof(ObjectRecord);
  h.layer_record_bytes = sizeof(LayerRecord);
  h.encoded_cluster_header_bytes = sizeof(EncodedClusterHeader);
  for (int a = 0; a < 3; ++a) h.origin[a] = storage.origin[a];
  h.position_step_m = storage.position_step_m;
  h.target_page_bytes = storage.target_page_bytes;
  if (storage.clusterCount() == 0) lo = hi = glm::vec3(0.0f);
  setVec3(h.bounds_min, lo);
  setVec3(h.bounds_max, hi);

  // Sections, in file order == table order: a spilled head (a file) then an in-memory tail.
  struct Piece {
    const RecordSpill* head;
    const void* tail;
    uint64_t tail_count;
  };
  const Piece pieces[kSectionCount] = {
      {tables ? &tables->clusters : nullptr, storage.clusters.data(), storage.clusters.size()},
      {tables ? &tables->groups : nullptr, storage.groups.data(), storage.groups.size()},
      {nullptr, page_records.data(), page_records.size()},
      {tables ? &tables->instances : nullptr, storage.instances.data(), storage.instances.size()},
      {tables ? &tables->profiles : nullptr, storage.profile_points.data(),
       storage.profile_points.size()},
      {tables ? &tables->objects : nullptr, storage.objects.data(), storage.objects.size()},
      {nullptr, storage.layers.data(), storage.layers.size()},
      {tables ? &tables->strings : nullptr, storage.strings.data(), storage.strings.size()},
      {nullptr, storage.visibility.data(), storage.visibility.size()},
      {spill ? &spill->data() : nullptr, page_data.data(), page_data.size()},
  };
  SectionEntry table[kSectionCount] = {};
  std::vector<uint8_t> frames[kSectionCount];  // compressed tables, written instead of records
  uint64_t cursor = sizeof(PackageHeader) + sizeof(table);
  for (uint32_t i = 0; i < kSectionCount; ++i) {
    SectionEntry& e = table[i];
    const Piece& piece = pieces[i];
    const uint64_t head_bytes = piece.head ? piece.head->bytes() : 0;
    const std::span<const uint8_t> tail(static_cast<const uint8_t*>(piece.tail),
                                        size_t(piece.tail_count * kSectionRecordBytes[i]));
    e.type = i;
    e.record_bytes = kSectionRecordBytes[i];
    e.bytes = head_bytes + tail.size();
    e.count = e.bytes / kSectionRecordBytes[i];
    e.offset = alignUp(cursor, kSectionAlignment);
    if (options.compress_tables && sectionMayBeCompressed(i) && e.bytes > 0) {
      SectionCompressor compressor(e.bytes, options.zstd_level);
      if (piece.head) piece.head->forEachChunk(4u << 20, [&](std::span<const uint8_t> chunk) {
        compressor.add(chunk);
      });
      compressor.add(tail);
      frames[i] = compressor.finish();
      if (frames[i].size() >= e.bytes) frames[i] = {};  // did not shrink: stored as it is
    }
    if (!frames[i].empty()) {
      e.stored_bytes = frames[i].size();
      e.checksum = packageSectionChecksum(frames[i]);
    } else {
      e.checksum = piece.head ? piece.head->checksumWith(tail) : packageSectionChecksum(tail);
    }
    cursor = e.offset + storedBytes(e);
    stats.section_bytes[i] = storedBytes(e);
  }
  h.file_bytes = cursor;
  h.header_checksum = packageHeaderChecksum(h, table);
  stats.file_bytes = cursor;

  TempFile out(path);
  out.write(&h, sizeof(h));
  out.write(table, sizeof(table));
  for (uint32_t i = 0; i < kSectionCount; ++i) {
    out.padTo(table[i].offset);
    if (!frames[i].empty()) {
      out.write(frames[i].data(), frames[i].size());
      continue;
    }
    const Piece& piece = pieces[i];
    if (piece.head) out.copyFrom(*piece.head);
    out.write(piece.tail, piece.tail_count * kSectionRecordBytes[i]);
  }
  out.close();
  // The view's checks are the definition of a valid package: refuse to publish anything else.
  try {
    PackageView::open(out.tempPath(), PackageView::Verify::Headers);
  } catch (const FormatError& e) {
    throw std::invalid_argument("writePackage: storage is inconsistent: " + e.reason());
  }
  out.commit();
  return stats;
}

}  // namespace tw
