// PackageView: maps a .twk read-only and validates everything before handing out spans.
//
// Order of checks: identity (magic, version, struct sizes) first so a wrong file gets the most
// useful message, then sizes and the section table, then checksums, then records and references.
// Every offset is compared in 64-bit arithmetic against what remains, never added blindly.
#include "package_view.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>
#include <xxhash.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <future>
#include <limits>
#include <utility>
#include <vector>

#include "section_codec.h"

namespace tw {
namespace {

using namespace pkg;

bool finite(float v) { return std::isfinite(v); }
bool allFinite(const float* v, int n) {
  for (int i = 0; i < n; ++i)
    if (!std::isfinite(v[i])) return false;
  return true;
}
// a + b <= limit without overflow.
bool fits(uint64_t a, uint64_t b, uint64_t limit) { return a <= limit && b <= limit - a; }

std::string str(uint64_t v) { return std::to_string(v); }

template <typename T>
uint64_t fieldOffset(const T& record, const void* field) {
  return static_cast<uint64_t>(static_cast<const uint8_t*>(field) -
                               reinterpret_cast<const uint8_t*>(&record));
}

}  // namespace

uint64_t packageHeaderChecksum(const PackageHeader& header, std::span<const SectionEntry> table) {
  PackageHeader copy = header;
  copy.header_checksum = 0;
  XXH3_state_t* state = XXH3_createState();
  XXH3_64bits_reset(state);
  XXH3_64bits_update(state, &copy, sizeof(copy));
  if (!table.empty()) XXH3_64bits_update(state, table.data(), table.size_bytes());
  uint64_t hash = XXH3_64bits_digest(state);
  XXH3_freeState(state);
  return hash;
}

uint64_t packageSectionChecksum(std::span<const uint8_t> bytes) {
  static const uint8_t kEmpty = 0;
  return XXH3_64bits(bytes.empty() ? &kEmpty : bytes.data(), bytes.size());
}

PackageView PackageView::open(const std::filesystem::path& path, Verify verify) {
  PackageView view;
  view.name_ = path.string();
  view.fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (view.fd_ < 0)
    throw FormatError(view.name_, std::string("cannot open: ") + std::strerror(errno));
  struct stat st {};
  if (::fstat(view.fd_, &st) != 0 || !S_ISREG(st.st_mode))
    throw FormatError(view.name_, "not a regular file");  // ~PackageView closes the file
  view.size_ = static_cast<uint64_t>(st.st_size);
  if (view.size_ < sizeof(PackageHeader))
    throw FormatError::atByte(
        view.name_, view.size_,
        "file is too small for a package header (" + str(view.size_) + " bytes)");
  view.validate(verify);
  return view;
}

PackageView::PackageView(PackageView&& other) noexcept { *this = std::move(other); }

PackageView& PackageView::operator=(PackageView&& other) noexcept {
  if (this != &other) {
    release();
    name_ = std::move(other.name_);
    fd_ = std::exchange(other.fd_, -1);
    size_ = std::exchange(other.size_, 0);
    header_ = other.header_;
    sections_ = std::move(other.sections_);
    clusters_ = other.clusters_;
    groups_ = other.groups_;
    pages_ = other.pages_;
    instances_ = other.instances_;
    profiles_ = other.profiles_;
    objects_ = other.objects_;
    layers_ = other.layers_;
    strings_ = other.strings_;
    visibility_ = other.visibility_;
    visibility_cells_ = std::exchange(other.visibility_cells_, VisibilityView());
    stored_ = std::move(other.stored_);
    decompressed_ = std::move(other.decompressed_);
  }
  return *this;
}

PackageView::~PackageView() { release(); }

void PackageView::release() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

void PackageView::readFileBytes(uint64_t offset, uint64_t bytes, uint8_t* out) const {
  uint64_t done = 0;
  while (done < bytes) {
    const ssize_t n = ::pread(fd_, out + done, size_t(bytes - done), off_t(offset + done));
    if (n < 0 && errno == EINTR) continue;
    if (n < 0)
      fail(offset + done, std::string("cannot read: ") + std::strerror(errno));
    if (n == 0)
      fail(offset + done, "the file ends here, before the " + str(bytes) + " bytes at byte " +
                              str(offset) + " (it was truncated after it was opened)");
    done += uint64_t(n);
  }
}

uint64_t PackageView::offsetOf(const void* p) const {
  const auto* byte = static_cast<const uint8_t*>(p);
  const auto* header = reinterpret_cast<const uint8_t*>(&header_);
  if (byte >= header && byte < header + sizeof(header_)) return uint64_t(byte - header);
  for (size_t i = 0; i < decompressed_.size(); ++i) {
    const std::vector<uint8_t>& d = decompressed_[i];
    if (!d.empty() && byte >= d.data() && byte < d.data() + d.size()) return sections_[i].offset;
  }
  for (size_t i = 0; i < stored_.size(); ++i) {
    const std::vector<uint8_t>& d = stored_[i];
    if (!d.empty() && byte >= d.data() && byte < d.data() + d.size())
      return sections_[i].offset + uint64_t(byte - d.data());
  }
  return 0;
}

void PackageView::fail(uint64_t offset, const std::string& reason) const {
  throw FormatError::atByte(name_, offset, reason);
}

glm::dvec3 PackageView::origin() const {
  return glm::dvec3(header_.origin[0], header_.origin[1], header_.origin[2]);
}

// Open-time validation, in the order each step needs the one before: the header and section
// table, the sections' checksums, the compressed tables, then every record and reference.
void PackageView::validate(Verify verify) {
  readFileBytes(0, sizeof(PackageHeader), reinterpret_cast<uint8_t*>(&header_));
  validateHeader();
  validateSectionTable();
  readSections();
  verifySectionChecksums(verify);
  decompressSections();
  mapSections();
  validateNamedRecords();
  validateInstances();
  validatePages();
  validateGroups();
  validateClusters();
  validateVisibility();
  if (verify == Verify::All) verifyAll();
}

// Identity, record sizes, the section table's extent and checksum, and the header's values.
void PackageView::validateHeader() {
  const PackageHeader& h = header_;
  auto at = [&](const void* field) { return fieldOffset(h, field); };

  // Identity.
  if (std::memcmp(h.magic, kMagic, sizeof(kMagic)) != 0)
    fail(0, "not a TeraWalk package (bad magic)");
  if (h.version != kVersion)
    fail(at(&h.version), "unsupported package version " + str(h.version) + " (this build reads " +
                             str(kVersion) + ")");
  if (h.header_bytes != sizeof(PackageHeader))
    fail(at(&h.header_bytes),
         "header size " + str(h.header_bytes) + " != " + str(sizeof(PackageHeader)));
  if (h.section_entry_bytes != sizeof(SectionEntry))
    fail(at(&h.section_entry_bytes),
         "section entry size " + str(h.section_entry_bytes) + " != " + str(sizeof(SectionEntry)));
  struct SizeCheck {
    const uint32_t* field;
    uint32_t expected;
    const char* what;
  };
  const SizeCheck sizes[] = {
      {&h.cluster_record_bytes, sizeof(ClusterRecord), "cluster record"},
      {&h.group_record_bytes, sizeof(GroupRecord), "group record"},
      {&h.page_record_bytes, sizeof(PageRecord), "page record"},
      {&h.instance_record_bytes, sizeof(InstanceRecord), "instance record"},
      {&h.object_record_bytes, sizeof(ObjectRecord), "object record"},
      {&h.layer_record_bytes, sizeof(LayerRecord), "layer record"},
      {&h.encoded_cluster_header_bytes, sizeof(EncodedClusterHeader), "encoded cluster header"},
  };
  for (const SizeCheck& s : sizes)
    if (*s.field != s.expected)
      fail(at(s.field), std::string(s.what) + " size " + str(*s.field) + " != " + str(s.expected) +
                            " (built with a different format layout)");
  if (h.file_bytes != size_)
    fail(at(&h.file_bytes), "header says the file has " + str(h.file_bytes) + " bytes but it has " +
                                str(size_) + " (truncated or extended)");
  if ((h.flags & ~kKnownHeaderFlags) != 0) fail(at(&h.flags), "unknown header flags");
  if (h.section_count < kSectionCount || h.section_count > 4096)
    fail(at(&h.section_count), "section count " + str(h.section_count) + " is out of range");
  if (sectionTableEnd() > size_) fail(size_, "section table runs past the end of the file");
  sections_.resize(h.section_count);
  readFileBytes(sizeof(PackageHeader), sections_.size() * sizeof(SectionEntry),
         reinterpret_cast<uint8_t*>(sections_.data()));
  if (packageHeaderChecksum(h, sections_) != h.header_checksum)
    fail(at(&h.header_checksum), "header checksum mismatch (header or section table is corrupt)");

  // Header values.
  if (h.reserved0 != 0 || h.reserved1 != 0 || h.reserved3 != 0)
    fail(at(&h.reserved0), "reserved header fields are not zero");
  for (uint64_t r : h.reserved2)
    if (r != 0) fail(at(&h.reserved2), "reserved header fields are not zero");
  for (double o : h.origin)
    if (!std::isfinite(o)) fail(at(&h.origin), "origin is not finite");
  if (!(h.position_step_m >= kMinPositionStepM && h.position_step_m <= kMaxPositionStepM))
    fail(at(&h.position_step_m), "position step is outside [1e-9, 1] m");
  if (!allFinite(h.bounds_min, 3) || !allFinite(h.bounds_max, 3))
    fail(at(&h.bounds_min), "bounds are not finite");
}

uint64_t PackageView::sectionTableEnd() const {
  return sizeof(PackageHeader) + uint64_t{header_.section_count} * sizeof(SectionEntry);
}

// Every entry's type, record size, alignment, extent and count; no two sections overlap.
void PackageView::validateSectionTable() {
  const PackageHeader& h = header_;
  const uint64_t table_end = sectionTableEnd();
  for (uint32_t i = 0; i < h.section_count; ++i) {
    const SectionEntry& e = sections_[i];
    const uint64_t entry_at = sizeof(PackageHeader) + uint64_t{i} * sizeof(SectionEntry);
    const std::string what =
        i < kSectionCount ? std::string(kSectionNames[i]) + " section" : "section " + str(i);
    if (i < kSectionCount) {
      if (e.type != i) fail(entry_at, what + ": table entry has type " + str(e.type));
      if (e.record_bytes != kSectionRecordBytes[i])
        fail(entry_at + 4,
             what + ": record size " + str(e.record_bytes) + " != " + str(kSectionRecordBytes[i]));
    } else if (e.record_bytes == 0) {
      fail(entry_at + 4, what + ": record size is 0");
    }
    if (i < kSectionCount && e.stored_bytes != 0 && !sectionMayBeCompressed(i))
      fail(entry_at + 40, what + ": stored compressed, but it must be read in place");
    if (e.offset % kSectionAlignment != 0)
      fail(entry_at + 8,
           what + ": offset " + str(e.offset) + " is not a multiple of " + str(kSectionAlignment));
    if (e.offset < table_end || !fits(e.offset, storedBytes(e), size_))
      fail(entry_at + 8, what + ": bytes [" + str(e.offset) + ", +" + str(storedBytes(e)) +
                             ") are not inside the file after the section table");
    if (e.count > e.bytes / e.record_bytes || e.count * e.record_bytes != e.bytes)
      fail(entry_at + 24, what + ": " + str(e.bytes) + " bytes do not hold " + str(e.count) +
                              " records of " + str(e.record_bytes));
    if (i < kSectionCount && e.count >= kNone)
      fail(entry_at + 24, what + ": too many records for 32-bit indices");
  }
  {
    std::vector<uint32_t> order;
    for (uint32_t i = 0; i < h.section_count; ++i)
      if (storedBytes(sections_[i]) > 0) order.push_back(i);
    std::sort(order.begin(), order.end(),
              [&](uint32_t a, uint32_t b) { return sections_[a].offset < sections_[b].offset; });
    for (size_t k = 1; k < order.size(); ++k) {
      const SectionEntry& prev = sections_[order[k - 1]];
      const SectionEntry& cur = sections_[order[k]];
      if (cur.offset < prev.offset + storedBytes(prev))
        fail(cur.offset, "section " + str(order[k]) + " overlaps section " + str(order[k - 1]));
    }
  }
}

// Every section but the page data, read into memory as stored: the view never reads the tables
// from the file again, so whatever happens to the file after open (truncated, overwritten in
// place) cannot change a validated record.
void PackageView::readSections() {
  stored_.assign(sections_.size(), {});
  for (uint32_t i = 0; i < sections_.size(); ++i) {
    if (i == static_cast<uint32_t>(SectionType::PageData)) continue;
    stored_[i].resize(storedBytes(sections_[i]));
    readFileBytes(sections_[i].offset, stored_[i].size(), stored_[i].data());
  }
}

std::span<const uint8_t> PackageView::storedSection(uint32_t i) const {
  return std::span<const uint8_t>(stored_[i]);
}

// XXH3-64 of the file's bytes [offset, offset + bytes), read in chunks.
uint64_t PackageView::fileChecksum(uint64_t offset, uint64_t bytes) const {
  if (bytes == 0) return packageSectionChecksum({});
  XXH3_state_t* state = XXH3_createState();
  XXH3_64bits_reset(state);
  std::vector<uint8_t> chunk(std::min<uint64_t>(bytes, uint64_t(4) << 20));
  try {
    for (uint64_t done = 0; done < bytes;) {
      const uint64_t n = std::min<uint64_t>(chunk.size(), bytes - done);
      readFileBytes(offset + done, n, chunk.data());
      XXH3_64bits_update(state, chunk.data(), size_t(n));
      done += n;
    }
  } catch (...) {
    XXH3_freeState(state);
    throw;
  }
  const uint64_t hash = XXH3_64bits_digest(state);
  XXH3_freeState(state);
  return hash;
}

// The page data and unknown sections are checked only by a full verification (docs/verify.md).
void PackageView::verifySectionChecksums(Verify verify) const {
  const PackageHeader& h = header_;
  for (uint32_t i = 0; i < h.section_count; ++i) {
    if (i == static_cast<uint32_t>(SectionType::PageData) && verify != Verify::All) continue;
    if (i >= kSectionCount && verify != Verify::All) continue;
    const SectionEntry& e = sections_[i];
    const uint64_t sum = i == static_cast<uint32_t>(SectionType::PageData)
                             ? fileChecksum(e.offset, storedBytes(e))
                             : packageSectionChecksum(storedSection(i));
    if (sum != e.checksum)
      fail(e.offset, (i < kSectionCount ? std::string(kSectionNames[i]) : "section " + str(i)) +
                         " section checksum mismatch");
  }
}

// Compressed tables, once their frames passed the checksum: each on a thread of its own (the
// instance and object tables of a large model are tens of MB each, and this is start-up), the
// first problem in table order reported.
void PackageView::decompressSections() {
  decompressed_.assign(kSectionCount, {});
  std::vector<std::future<std::string>> problems(kSectionCount);
  for (uint32_t i = 0; i < kSectionCount; ++i)
    if (sections_[i].stored_bytes != 0)
      problems[i] = std::async(std::launch::async, [this, i, frame = storedSection(i)] {
        return decompressSection(frame, sections_[i].bytes, decompressed_[i]);
      });
  std::vector<std::string> results(kSectionCount);
  for (uint32_t i = 0; i < kSectionCount; ++i)
    if (problems[i].valid()) results[i] = problems[i].get();  // all joined before any throw
  for (uint32_t i = 0; i < kSectionCount; ++i)
    if (!results[i].empty())
      fail(sections_[i].offset, std::string(kSectionNames[i]) + " section " + results[i]);
}

std::span<const uint8_t> PackageView::sectionBytes(SectionType type) const {
  const uint32_t i = static_cast<uint32_t>(type);
  if (sections_[i].stored_bytes != 0) return std::span<const uint8_t>(decompressed_[i]);
  return std::span<const uint8_t>(stored_[i]);
}

// The record spans over the tables read at open (or decompressed).
void PackageView::mapSections() {
  auto records = [&]<typename T>(SectionType type, std::span<const T>& out) {
    const SectionEntry& e = sections_[static_cast<uint32_t>(type)];
    out = std::span<const T>(reinterpret_cast<const T*>(sectionBytes(type).data()), e.count);
  };
  records(SectionType::Clusters, clusters_);
  records(SectionType::Groups, groups_);
  records(SectionType::Pages, pages_);
  records(SectionType::Instances, instances_);
  records(SectionType::Profiles, profiles_);
  records(SectionType::Objects, objects_);
  records(SectionType::Layers, layers_);
  auto strings = sectionBytes(SectionType::Strings);
  strings_ = std::string_view(reinterpret_cast<const char*>(strings.data()), strings.size());
  visibility_ = sectionBytes(SectionType::Visibility);
}

// Layers and objects: names and keys inside the string pool, layers in range, known flags.
void PackageView::validateNamedRecords() const {
  auto checkString = [&](const void* record, uint64_t offset, uint64_t bytes, const char* what) {
    if (bytes > kMaxStringBytes || !fits(offset, bytes, strings_.size()))
      fail(offsetOf(record), std::string(what) + " [" + str(offset) + ", +" + str(bytes) +
                                 ") is not inside the string pool");
  };
  checkString(&header_.database_path_offset, header_.database_path_offset,
              header_.database_path_bytes, "database path");
  for (const LayerRecord& l : layers_) checkString(&l, l.name_offset, l.name_bytes, "layer name");
  for (const ObjectRecord& o : objects_) {
    if (o.layer >= layers_.size())
      fail(offsetOf(&o.layer), "object layer " + str(o.layer) + " is out of range (" +
                                   str(layers_.size()) + " layers)");
    checkString(&o, o.name_offset, o.name_bytes, "object name");
    checkString(&o, o.db_key_offset, o.db_key_bytes, "object database key");
    if ((o.flags & ~kKnownObjectFlags) != 0) fail(offsetOf(&o.flags), "object flags has unknown bits");
    if (!allFinite(o.aabb_min, 3) || !allFinite(o.aabb_max, 3))
      fail(offsetOf(&o.aabb_min), "object bounds are not finite");
  }
}

// Profile points finite; instances of known types and flags, in range, with valid profiles.
void PackageView::validateInstances() const {
  const PackageHeader& h = header_;
  for (const glm::vec2& p : profiles_)
    if (!finite(p.x) || !finite(p.y)) fail(offsetOf(&p), "profile point is not finite");
  for (const InstanceRecord& in : instances_) {
    if (in.type >= kPrimitiveTypeCount)
      fail(offsetOf(&in.type), "unknown primitive type " + str(in.type));
    if (in.flags & ~kKnownInstanceFlags) fail(offsetOf(&in.flags), "unknown instance flags");
    if ((in.flags & (kInstanceSealedRunMember | kInstanceSealedRunCloser)) &&
        !(h.flags & kHeaderSealedRunsMarked))
      fail(offsetOf(&in.flags), "instance has sealed-run flags but the header does not mark them");
    if (in.flags & kInstanceCoveredFaces) {
      if (!(h.flags & kHeaderCoveredFacesMarked))
        fail(offsetOf(&in.flags), "instance has covered-face flags but the header does not mark them");
      if (in.type != static_cast<uint32_t>(PrimitiveType::Box))
        fail(offsetOf(&in.flags), "instance has covered-face flags but is not a box");
    }
    if (in.reserved != 0) fail(offsetOf(&in.reserved), "instance reserved field is not zero");
    if (in.object >= objects_.size())
      fail(offsetOf(&in.object), "instance object " + str(in.object) + " is out of range");
    if (!allFinite(in.origin, 3) || !allFinite(in.linear, 9) || !allFinite(in.params, 6))
      fail(offsetOf(&in), "instance placement or parameters are not finite");
    const bool profiled = in.type == static_cast<uint32_t>(PrimitiveType::Extrusion) ||
                          in.type == static_cast<uint32_t>(PrimitiveType::Revolution);
    const uint32_t min_points = in.type == static_cast<uint32_t>(PrimitiveType::Extrusion) ? 3
                                : profiled                                                 ? 2
                                                                                           : 0;
    if ((!profiled && in.profile_count != 0) || in.profile_count < min_points ||
        in.profile_count > kMaxProfilePoints ||
        !fits(in.profile_first, in.profile_count, profiles_.size()))
      fail(offsetOf(&in.profile_first), "instance profile range is invalid");
  }
}

void PackageView::validatePages() const {
  for (const PageRecord& p : pages_) {
    if (p.codec > static_cast<uint32_t>(PageCodec::Zstd))
      fail(offsetOf(&p.codec), "unknown page codec");
    if (p.raw_bytes > kMaxPageRawBytes)
      fail(offsetOf(&p.raw_bytes), "page raw size is over the limit");
    if (p.codec == static_cast<uint32_t>(PageCodec::None) && p.stored_bytes != p.raw_bytes)
      fail(offsetOf(&p.stored_bytes), "uncompressed page has stored size != raw size");
    if (p.offset % kSectionAlignment != 0 ||
        !fits(p.offset, p.stored_bytes, sections_[static_cast<uint32_t>(SectionType::PageData)].bytes))
      fail(offsetOf(&p.offset), "page bytes [" + str(p.offset) + ", +" + str(p.stored_bytes) +
                                    ") are not inside the page data section");
  }
}

void PackageView::validateGroups() const {
  const PackageHeader& h = header_;
  for (const GroupRecord& g : groups_) {
    if (!fits(g.first_cluster, g.cluster_count, clusters_.size()))
      fail(offsetOf(&g.first_cluster), "group cluster range is invalid");
    if (!allFinite(g.lod_center, 4) || g.lod_radius < 0 || !allFinite(g.aabb_min, 3) ||
        !allFinite(g.aabb_max, 3) || !finite(g.error) || g.error < 0)
      fail(offsetOf(&g), "group bounds or error are not finite and non-negative");
    if (!(g.max_parent_error >= g.error))
      fail(offsetOf(&g.max_parent_error), "group parent error < error");
    if (g.level >= h.level_count || g.reserved != 0)
      fail(offsetOf(&g.level), "group level or reserved field is invalid");
  }
}

// Bounds, errors monotone toward the roots, group links, object ranges, and each kind's own
// fields: a mesh cluster's bytes inside its page, a parametric cluster's instances of one type.
void PackageView::validateClusters() const {
  const PackageHeader& h = header_;
  for (size_t c = 0; c < clusters_.size(); ++c) {
    const ClusterRecord& r = clusters_[c];
    const uint64_t at_c = offsetOf(&r);
    if (!allFinite(r.center, 4) || r.radius < 0 || !allFinite(r.aabb_min, 3) ||
        !allFinite(r.aabb_max, 3) || !allFinite(r.lod_center, 4) || r.lod_radius < 0 ||
        !allFinite(r.parent_lod_center, 4) || r.parent_lod_radius < 0)
      fail(at_c, "cluster " + str(c) + " bounds are not finite");
    for (int a = 0; a < 3; ++a)
      if (r.aabb_min[a] > r.aabb_max[a]) fail(at_c + 16, "cluster " + str(c) + " box is inverted");
    if (!finite(r.error) || r.error < 0)
      fail(at_c + 28, "cluster " + str(c) + " error is not finite and non-negative");
    if (!(r.parent_error >= r.error))
      fail(at_c + 44,
           "cluster " + str(c) + " parent error is smaller than its error (not monotone)");
    if ((r.parent_group == kNone) != std::isinf(r.parent_error))
      fail(at_c + 44, "cluster " + str(c) + " parent error must be infinite exactly for roots");
    if (r.level >= h.level_count)
      fail(at_c + 88, "cluster " + str(c) + " level " + str(r.level) + " >= level count " +
                          str(h.level_count));
    if (r.group != kNone) {
      if (r.group >= groups_.size())
        fail(at_c + 80, "cluster " + str(c) + " group " + str(r.group) + " is out of range");
      const GroupRecord& g = groups_[r.group];
      if (c < g.first_cluster || c - g.first_cluster >= g.cluster_count ||
          uint64_t{g.level} + 1 != r.level || g.error != r.error)
        fail(at_c + 80, "cluster " + str(c) + " is not one of the clusters its group " +
                            str(r.group) + " produced (range, level or error)");
    }
    if (r.parent_group != kNone &&
        (r.parent_group >= groups_.size() || r.level > groups_[r.parent_group].level ||
         groups_[r.parent_group].error != r.parent_error))
      fail(at_c + 84, "cluster " + str(c) + " parent group " + str(r.parent_group) +
                          " is out of range or does not match its parent error and level" +
                          " (a child's level must be <= its parent group's)");
    if ((r.flags & ~kKnownClusterFlags) != 0)
      fail(at_c + 91, "cluster " + str(c) + " has unknown flags");
    if ((r.flags & kClusterFarProxy) &&
        (r.kind != static_cast<uint8_t>(ClusterKind::Mesh) || r.level == 0))
      fail(at_c + 91, "cluster " + str(c) + " is marked a far proxy but is not a coarse mesh cluster");
    if (r.object_min > r.object_max || r.object_max >= objects_.size())
      fail(at_c + 112, "cluster " + str(c) + " object range [" + str(r.object_min) + ", " +
                           str(r.object_max) + "] is invalid (" + str(objects_.size()) +
                           " objects)");
    if (r.kind == static_cast<uint8_t>(ClusterKind::Mesh)) {
      if (r.page >= pages_.size())
        fail(at_c + 92, "cluster " + str(c) + " page " + str(r.page) + " is out of range");
      if (r.page_offset % kClusterAlignment != 0 ||
          r.encoded_bytes < sizeof(EncodedClusterHeader) ||
          !fits(r.page_offset, r.encoded_bytes, pages_[r.page].raw_bytes))
        fail(at_c + 96, "cluster " + str(c) + " bytes [" + str(r.page_offset) + ", +" +
                            str(r.encoded_bytes) + ") are not inside page " + str(r.page));
      if (r.triangle_count == 0 || r.triangle_count > kMaxClusterTriangles || r.vertex_count == 0 ||
          r.vertex_count > kMaxClusterVertices)
        fail(at_c + 104, "cluster " + str(c) + " triangle or vertex count is out of range");
      if (r.instance_first != 0 || r.instance_count != 0)
        fail(at_c + 120, "mesh cluster " + str(c) + " lists instances");
    } else if (r.kind == static_cast<uint8_t>(ClusterKind::Parametric)) {
      if (r.page != kNone || r.page_offset != 0 || r.encoded_bytes != 0 || r.triangle_count != 0 ||
          r.vertex_count != 0)
        fail(at_c + 92, "parametric cluster " + str(c) + " has geometry fields set");
      if (r.instance_count == 0 || !fits(r.instance_first, r.instance_count, instances_.size()))
        fail(at_c + 120, "parametric cluster " + str(c) + " instance range is invalid");
      const uint32_t type = instances_[r.instance_first].type;
      for (uint32_t i = r.instance_first; i < r.instance_first + r.instance_count; ++i) {
        const InstanceRecord& in = instances_[i];
        if (in.type != type || in.object < r.object_min || in.object > r.object_max)
          fail(at_c + 120, "parametric cluster " + str(c) + " instance " + str(i) +
                               " has another type or an object outside the cluster's range");
      }
    } else {
      fail(at_c + 90, "cluster " + str(c) + " has unknown kind " + str(r.kind));
    }
  }
}

void PackageView::validateVisibility() {
  const SectionEntry& e = sections_[static_cast<uint32_t>(SectionType::Visibility)];
  visibility_cells_ = VisibilityView::parse(visibility_, name_, e.offset, clusters_.size());
  if (visibility_cells_.empty()) return;
  const VisibilityHeader& v = visibility_cells_.header();
  if (v.candidate_level >= header_.level_count)
    fail(offsetOf(&v.candidate_level), "visibility: candidate level " + str(v.candidate_level) +
                                           " >= level count " + str(header_.level_count));
  // Candidates are mesh clusters (drawn as occluders, mapped through the DAG) and, when the
  // section says so, parametric clusters.
  const bool parametric = (v.flags & kParametricCandidates) != 0;
  auto checkMesh = [&](std::span<const uint32_t> ids, const char* what) {
    for (const uint32_t& id : ids) {
      const uint8_t kind = clusters_[id].kind;
      if (kind != static_cast<uint8_t>(ClusterKind::Mesh) &&
          !(parametric && kind == static_cast<uint8_t>(ClusterKind::Parametric)))
        fail(offsetOf(&id), std::string("visibility: ") + what + " id " + str(id) +
                                (parametric ? " is neither a mesh nor a parametric cluster"
                                            : " is not a mesh cluster"));
    }
  };
  for (const VisibilityCellRecord& c : visibility_cells_.cells()) {
    checkMesh(visibility_cells_.occluders(c), "occluder");
    checkMesh(visibility_cells_.visible(c), "visible");
  }
  for (const uint32_t& id : visibility_cells_.parametricCandidates())
    if (clusters_[id].kind != static_cast<uint8_t>(ClusterKind::Parametric))
      fail(offsetOf(&id), "visibility: parametric candidate " + str(id) +
                              " is not a parametric cluster");
}

void PackageView::verifyAll() {
  // Gaps between header, table and sections must be zero, so no byte escapes every checksum.
  std::vector<std::pair<uint64_t, uint64_t>> used{
      {0, sizeof(PackageHeader) + sections_.size() * sizeof(SectionEntry)}};
  for (const SectionEntry& e : sections_)
    if (storedBytes(e) > 0) used.push_back({e.offset, e.offset + storedBytes(e)});
  std::sort(used.begin(), used.end());
  uint64_t cursor = 0;
  used.push_back({size_, size_});
  std::vector<uint8_t> gap;
  for (const auto& [begin, end] : used) {
    if (begin > cursor) {
      gap.resize(begin - cursor);
      readFileBytes(cursor, gap.size(), gap.data());
      for (uint64_t b = 0; b < gap.size(); ++b)
        if (gap[b] != 0) fail(cursor + b, "padding between sections is not zero");
    }
    cursor = std::max(cursor, end);
  }

  // Every page decodes, and holds exactly the clusters that point into it.
  std::vector<std::vector<uint32_t>> by_page(pages_.size());
  for (size_t c = 0; c < clusters_.size(); ++c)
    if (clusters_[c].kind == static_cast<uint8_t>(ClusterKind::Mesh))
      by_page[clusters_[c].page].push_back(static_cast<uint32_t>(c));
  std::vector<uint8_t> raw;
  DecodedCluster decoded;
  for (uint32_t p = 0; p < pages_.size(); ++p) {
    if (by_page[p].size() != pages_[p].cluster_count)
      fail(offsetOf(&pages_[p].cluster_count),
           "page " + str(p) + " is referenced by " + str(by_page[p].size()) +
               " clusters but records " + str(pages_[p].cluster_count));
    readPage(p, raw);
    for (uint32_t c : by_page[p]) decodeCluster(c, raw, decoded);
  }
}

std::string_view PackageView::objectName(uint32_t object) const {
  const ObjectRecord& o = objects_[object];
  return strings_.substr(o.name_offset, o.name_bytes);
}

std::string_view PackageView::objectDbKey(uint32_t object) const {
  const ObjectRecord& o = objects_[object];
  return strings_.substr(o.db_key_offset, o.db_key_bytes);
}

std::string_view PackageView::databasePath() const {
  return strings_.substr(header_.database_path_offset, header_.database_path_bytes);
}

std::string_view PackageView::layerName(uint32_t layer) const {
  const LayerRecord& l = layers_[layer];
  return strings_.substr(l.name_offset, l.name_bytes);
}

uint64_t PackageView::pageFileOffset(uint32_t page) const {
  return sections_[static_cast<uint32_t>(SectionType::PageData)].offset + pages_[page].offset;
}

std::span<const uint8_t> PackageView::pageStored(uint32_t page, std::vector<uint8_t>& bytes) const {
  if (page >= pages_.size()) throw std::out_of_range("PackageView::pageStored: no such page");
  bytes.resize(pages_[page].stored_bytes);
  readFileBytes(pageFileOffset(page), bytes.size(), bytes.data());
  return bytes;
}

std::span<const uint8_t> PackageView::loadPage(uint32_t page, std::vector<uint8_t>& scratch) const {
  if (page >= pages_.size()) throw std::out_of_range("PackageView::loadPage: no such page");
  const PageRecord& p = pages_[page];
  const uint64_t at = pageFileOffset(page);
  const bool compressed = p.codec != static_cast<uint32_t>(PageCodec::None);
  // An uncompressed page is read straight into `scratch`; a compressed one into a buffer of the
  // calling thread's, then decompressed into `scratch`.
  thread_local std::vector<uint8_t> compressed_bytes;
  std::vector<uint8_t>& stored = compressed ? compressed_bytes : scratch;
  const std::span<const uint8_t> bytes = pageStored(page, stored);
  if (packageSectionChecksum(bytes) != p.checksum)
    fail(at, "page " + str(page) + " checksum mismatch");
  if (!compressed) return scratch;
  const char* error = decompressPage(bytes, p.raw_bytes, scratch);
  if (compressed_bytes.capacity() > (size_t(16) << 20)) compressed_bytes = {};  // a huge one-off
  if (error) fail(at, "page " + str(page) + ": " + error);
  return scratch;
}

void PackageView::readPage(uint32_t page, std::vector<uint8_t>& raw) const { loadPage(page, raw); }

void PackageView::decodeCluster(uint32_t cluster, std::span<const uint8_t> raw_page,
                                DecodedCluster& out) const {
  if (cluster >= clusters_.size())
    throw std::out_of_range("PackageView::decodeCluster: no such cluster");
  const ClusterRecord& r = clusters_[cluster];
  const uint64_t at = offsetOf(&r);
  if (r.kind != static_cast<uint8_t>(ClusterKind::Mesh))
    throw std::invalid_argument("PackageView::decodeCluster: cluster is not a mesh cluster");
  const PageRecord& p = pages_[r.page];
  if (raw_page.size() != p.raw_bytes)
    throw std::invalid_argument("PackageView::decodeCluster: raw page has the wrong size");
  const uint64_t page_at = pageFileOffset(r.page);
  DecodeStatus status =
      tw::decodeCluster(raw_page.subspan(r.page_offset, r.encoded_bytes), header_.position_step_m,
                        static_cast<uint32_t>(objects_.size()), out);
  if (!status.ok())
    fail(page_at, "cluster " + str(cluster) + " at raw byte " + str(r.page_offset + status.offset) +
                      " of page " + str(r.page) + ": " + status.error);
  if (out.vertices.size() != r.vertex_count || out.triangle_objects.size() != r.triangle_count)
    fail(at, "cluster " + str(cluster) + " record counts do not match its encoded geometry");
  if (out.triangle_objects.front() != r.object_min || out.triangle_objects.back() != r.object_max)
    fail(at, "cluster " + str(cluster) + " object range does not match its encoded geometry");
  const glm::vec3 lo(r.aabb_min[0], r.aabb_min[1], r.aabb_min[2]);
  const glm::vec3 hi(r.aabb_max[0], r.aabb_max[1], r.aabb_max[2]);
  const glm::vec3 center(r.center[0], r.center[1], r.center[2]);
  const float slack = 1e-6f * r.radius;
  for (const glm::vec3& v : out.positions)
    if (glm::any(glm::lessThan(v, lo)) || glm::any(glm::greaterThan(v, hi)) ||
        glm::length(v - center) > r.radius + slack)
      fail(at, "cluster " + str(cluster) + " geometry lies outside its bounds");
}

}  // namespace tw
