// Out-of-core parametric clustering: see parametric_external_sort.h.
//
// Pass 1 streams the items for the cube the Morton codes live in and the count per type (which
// fixes every cluster boundary in advance). Pass 2 streams them again into one arena of the
// budget's size: records grow from its front, sort keys from its back; when they meet, the keys
// are sorted and the records written in that order as a run file. The runs are then merged k
// ways (in several merges when their read buffers would not fit the budget at once), and the
// final merge feeds PackageStorage directly, cutting clusters as the counts dictate. When
// everything fits, the arena is sorted in place and no file is written.
//
// Run file (native byte order: a run never leaves the process that wrote it):
//   header  : char[8] "TWPSRUN1", u64 record count, u32 largest profile in bytes, u32 0
//   records : in (type, morton, input index) order, each
//             u8 type, u64 morton, u32 input index, u32 object, f64 origin[3], f32 linear[9],
//             the type's parameters (kParamBytes), then for extrusions and revolutions
//             u32-counted profile points (f32 x, y)
//   trailer : u64 checksum of everything before it
#include "parametric_external_sort.h"

#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <deque>
#include <limits>
#include <memory>
#include <new>
#include <queue>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <variant>
#include <vector>

#include "file_reader.h"
#include "format_error.h"
#include "package_format.h"

namespace tw {
namespace {

constexpr uint32_t kTypeCount = uint32_t(std::variant_size_v<Primitive>);
constexpr uint32_t kExtrusionType = uint32_t(pkg::PrimitiveType::Extrusion);
constexpr uint32_t kRevolutionType = uint32_t(pkg::PrimitiveType::Revolution);
static_assert(std::is_same_v<std::variant_alternative_t<kExtrusionType, Primitive>, Extrusion>);
static_assert(std::is_same_v<std::variant_alternative_t<kRevolutionType, Primitive>, Revolution>);

// Record layout (see the file comment).
constexpr size_t kHeadBytes = 1 + 8 + 4 + 4 + 3 * 8 + 9 * 4;  // type .. linear: 77
constexpr std::array<size_t, kTypeCount> kParamBytes = {
    2 * 4 + 1,  // Cylinder: radius, height, capped
    3 * 4 + 1,  // Cone: radius_bottom, radius_top, height, capped
    4,          // Sphere: radius
    3 * 4,      // TorusSegment: major, minor, sweep
    3 * 4,      // Box: half extents
    4 + 4,      // Extrusion: height, point count
    4 + 4,      // Revolution: sweep, point count
};
constexpr size_t kMaxFixedBytes = kHeadBytes + 3 * 4 + 1;
constexpr size_t kMinRecordBytes = kHeadBytes + 4;
constexpr char kRunMagic[8] = {'T', 'W', 'P', 'S', 'R', 'U', 'N', '1'};
constexpr size_t kRunHeaderBytes = 8 + 8 + 4 + 4;
constexpr size_t kRunTrailerBytes = 8;

// I/O buffers: under 64 KiB a disk spends its time seeking between runs; over a few MiB nothing
// is gained.
constexpr uint64_t kMinIoBufferBytes = 64u << 10;
constexpr uint64_t kMaxIoBufferBytes = 4u << 20;
constexpr uint64_t kMinBudgetBytes = 1u << 20;
// Runs open at once: far below the usual limit of 1024 open files, and a 256-way merge already
// takes a terabyte of data to a single merge at a 4 GiB budget.
constexpr size_t kMaxFanIn = 256;

size_t fixedBytes(uint32_t type) { return kHeadBytes + kParamBytes[type]; }
bool hasProfile(uint32_t type) { return type == kExtrusionType || type == kRevolutionType; }

// The clustering order: type, then Morton code, then input order (so keys are unique).
struct SortKey {
  uint32_t type = 0;
  uint32_t index = 0;
  uint64_t morton = 0;
  bool operator<(const SortKey& o) const {
    if (type != o.type) return type < o.type;
    if (morton != o.morton) return morton < o.morton;
    return index < o.index;
  }
};

// A key in the arena, pointing at its record there.
struct ArenaKey {
  SortKey key;
  uint64_t offset;
};
static_assert(sizeof(ArenaKey) == 24 && alignof(ArenaKey) <= 8);

// A 64-bit running checksum over the run bytes, fed in the same pieces by writer and reader.
// Each 8-byte word goes through a bijection of the state, so any change confined to one word is
// always caught; wider damage slips through with probability about 2^-64.
class RunningHash {
 public:
  void add(const void* data, size_t bytes) {
    const auto* p = static_cast<const uint8_t*>(data);
    for (; bytes >= 8; p += 8, bytes -= 8) {
      uint64_t w;
      std::memcpy(&w, p, 8);
      mix(w);
    }
    if (bytes > 0) {
      uint64_t w = 0;
      std::memcpy(&w, p, bytes);
      mix(w ^ (uint64_t(bytes) << 56));
    }
  }
  uint64_t value() const { return state_ ^ (state_ >> 31); }

 private:
  void mix(uint64_t w) {
    state_ = (state_ ^ w) * 0x9e3779b97f4a7c15ull;
    state_ ^= state_ >> 29;
  }
  uint64_t state_ = 0x243f6a8885a308d3ull;
};

template <typename T>
uint8_t* put(uint8_t* p, const T& value) {
  std::memcpy(p, &value, sizeof(T));
  return p + sizeof(T);
}
template <typename T>
const uint8_t* get(const uint8_t* p, T& value) {
  std::memcpy(&value, p, sizeof(T));
  return p + sizeof(T);
}

// Profile of an extrusion or revolution, else null.
const std::vector<glm::vec2>* profileOf(const Primitive& primitive) {
  if (const auto* e = std::get_if<Extrusion>(&primitive)) return &e->profile;
  if (const auto* r = std::get_if<Revolution>(&primitive)) return &r->profile;
  return nullptr;
}

uint64_t recordBytes(const ParametricItem& item) {
  const auto* profile = profileOf(item.primitive);
  return fixedBytes(uint32_t(item.primitive.index())) +
         (profile ? profile->size() * sizeof(glm::vec2) : 0);
}

// Calls `f` on each parameter of a primitive in record order: floats, then the capped flag
// (bool) or the profile (its point count goes in the fixed part, its points after it).
template <typename T, typename F>
void forEachField(T& p, F&& f) {
  using U = std::remove_const_t<T>;
  if constexpr (std::is_same_v<U, Cylinder>) {
    f(p.radius), f(p.height), f(p.capped);
  } else if constexpr (std::is_same_v<U, Cone>) {
    f(p.radius_bottom), f(p.radius_top), f(p.height), f(p.capped);
  } else if constexpr (std::is_same_v<U, Sphere>) {
    f(p.radius);
  } else if constexpr (std::is_same_v<U, TorusSegment>) {
    f(p.major_radius), f(p.minor_radius), f(p.sweep_rad);
  } else if constexpr (std::is_same_v<U, Box>) {
    f(p.half_extents.x), f(p.half_extents.y), f(p.half_extents.z);
  } else if constexpr (std::is_same_v<U, Extrusion>) {
    f(p.height), f(p.profile);
  } else {
    static_assert(std::is_same_v<U, Revolution>);
    f(p.sweep_rad), f(p.profile);
  }
}

// Writes the fixed part of the record (fixedBytes(key.type) bytes) to `out`. The profile, if
// any, follows it (profileOf).
void encodeFixed(const SortKey& key, const ParametricItem& item, uint8_t* out) {
  uint8_t* p = out;
  p = put(p, uint8_t(key.type));
  p = put(p, key.morton);
  p = put(p, key.index);
  p = put(p, item.object);
  for (int a = 0; a < 3; ++a) p = put(p, item.transform.origin[a]);
  for (int c = 0; c < 3; ++c)
    for (int r = 0; r < 3; ++r) p = put(p, item.transform.linear[c][r]);
  std::visit(
      [&](const auto& primitive) {
        forEachField(primitive, [&](const auto& field) {
          using F = std::decay_t<decltype(field)>;
          if constexpr (std::is_same_v<F, bool>) p = put(p, uint8_t(field));
          else if constexpr (std::is_same_v<F, float>) p = put(p, field);
          else p = put(p, uint32_t(field.size()));  // the profile
        });
      },
      item.primitive);
}

// `T` in `primitive`, keeping its allocations when it already holds one (profiles are reused).
template <typename T>
T& alternative(Primitive& primitive) {
  if (auto* t = std::get_if<T>(&primitive)) return *t;
  return primitive.emplace<T>();
}

struct DecodedFixed {
  std::vector<glm::vec2>* profile = nullptr;  // to be filled with profile_count points
  uint32_t profile_count = 0;
  const char* problem = nullptr;              // set when the bytes cannot be a record
};

// Reads the parameters of primitive type `type` (< kTypeCount) from `p` into `primitive`.
template <size_t I = 0>
void decodeParams(uint32_t type, const uint8_t* p, Primitive& primitive, DecodedFixed& out) {
  if constexpr (I < kTypeCount) {
    if (type != I) return decodeParams<I + 1>(type, p, primitive, out);
    auto& alt = alternative<std::variant_alternative_t<I, Primitive>>(primitive);
    forEachField(alt, [&](auto& field) {
      using F = std::decay_t<decltype(field)>;
      if constexpr (std::is_same_v<F, bool>) {
        uint8_t flag;
        p = get(p, flag);
        field = flag != 0;
        if (flag > 1) out.problem = "capped flag is neither 0 nor 1";
      } else if constexpr (std::is_same_v<F, float>) {
        p = get(p, field);
      } else {
        p = get(p, out.profile_count);
        out.profile = &field;
      }
    });
  }
}

// Reads the fixed part of a record whose first byte (the type) is < kTypeCount.
DecodedFixed decodeFixed(const uint8_t* in, SortKey& key, ParametricItem& item) {
  DecodedFixed out;
  const uint8_t* p = in;
  uint8_t type;
  p = get(p, type);
  key.type = type;
  p = get(p, key.morton);
  p = get(p, key.index);
  p = get(p, item.object);
  for (int a = 0; a < 3; ++a) p = get(p, item.transform.origin[a]);
  for (int c = 0; c < 3; ++c)
    for (int r = 0; r < 3; ++r) p = get(p, item.transform.linear[c][r]);
  decodeParams(type, p, item.primitive, out);
  if (key.morton >> 63) out.problem = "Morton code has more than 63 bits";
  if (out.profile_count > pkg::kMaxProfilePoints) out.problem = "profile has too many points";
  return out;
}

// Box centres through the package's own instance conversion in a scratch storage with the
// package's origin, exactly as clusterPrimitives does (bad parameters throw here).
class CentreFinder {
 public:
  explicit CentreFinder(const glm::dvec3& origin) { scratch_.origin = origin; }
  glm::vec3 centre(const ParametricItem& item) {
    const uint32_t i = scratch_.addInstance(item.primitive, item.transform, item.object);
    glm::vec3 box_lo, box_hi;
    instanceBounds(scratch_.instances[i], scratch_.profile_points, box_lo, box_hi);
    scratch_.instances.clear();  // the scratch is ours and in memory; keep it small
    scratch_.profile_points.clear();
    return 0.5f * (box_lo + box_hi);
  }

 private:
  PackageStorage scratch_;
};

// A run file on disk, removed when this goes (success or exception).
struct RunFile {
  std::filesystem::path path;
  uint64_t count = 0;               // records
  uint32_t max_profile_bytes = 0;   // largest profile of a record
  uint64_t bytes = 0;               // file size once written

  explicit RunFile(std::filesystem::path p) : path(std::move(p)) {}
  ~RunFile() {
    std::error_code ec;
    std::filesystem::remove(path, ec);
  }
  RunFile(const RunFile&) = delete;
  RunFile& operator=(const RunFile&) = delete;
};
using RunPtr = std::unique_ptr<RunFile>;

// Names run files, unique per process and call, and creates the work directory on first use.
class RunNamer {
 public:
  explicit RunNamer(std::filesystem::path dir) : dir_(std::move(dir)) {
    static std::atomic<uint64_t> calls{0};
    prefix_ = "twps-" + std::to_string(::getpid()) + "-" + std::to_string(calls++) + "-";
  }
  RunPtr next() {
    if (!created_) {
      std::error_code ec;
      std::filesystem::create_directories(dir_, ec);
      if (ec)
        throw std::runtime_error("parametric sort: cannot create work directory " +
                                 dir_.string() + ": " + ec.message());
      created_ = true;
    }
    return std::make_unique<RunFile>(dir_ / (prefix_ + std::to_string(count_++) + ".run"));
  }

 private:
  std::filesystem::path dir_;
  std::string prefix_;
  uint64_t count_ = 0;
  bool created_ = false;
};

// Writes one run file through a buffer of its own.
class RunWriter {
 public:
  RunWriter(RunFile& run, uint64_t count, uint32_t max_profile_bytes, size_t buffer_bytes)
      : run_(run), count_(count) {
    run_.count = count;
    run_.max_profile_bytes = max_profile_bytes;
    file_ = std::fopen(run_.path.c_str(), "wb");
    if (!file_) ioFail("create");
    std::setvbuf(file_, nullptr, _IONBF, 0);  // buffered here
    buffer_.reserve(buffer_bytes);
    uint8_t header[kRunHeaderBytes];
    uint8_t* p = header;
    std::memcpy(p, kRunMagic, 8);
    p += 8;
    p = put(p, count);
    p = put(p, max_profile_bytes);
    put(p, uint32_t(0));
    append(header, sizeof header);
  }
  ~RunWriter() {
    if (file_) std::fclose(file_);
  }
  RunWriter(const RunWriter&) = delete;
  RunWriter& operator=(const RunWriter&) = delete;

  void write(const uint8_t* fixed, size_t fixed_bytes, const void* profile, size_t profile_bytes) {
    append(fixed, fixed_bytes);
    if (profile_bytes > 0) append(profile, profile_bytes);
    ++written_;
  }

  // Appends the checksum and closes the file; returns its size.
  uint64_t finish() {
    if (written_ != count_)
      throw std::logic_error("parametric sort: run record count differs from its header");
    const uint64_t sum = hash_.value();
    flushBuffer();
    if (std::fwrite(&sum, 1, sizeof sum, file_) != sizeof sum) ioFail("write");
    bytes_ += sizeof sum;
    std::FILE* f = file_;
    file_ = nullptr;
    if (std::fclose(f) != 0) ioFail("close");
    run_.bytes = bytes_;
    return bytes_;
  }

 private:
  void append(const void* data, size_t bytes) {
    hash_.add(data, bytes);
    if (buffer_.size() + bytes > buffer_.capacity()) flushBuffer();
    if (bytes >= buffer_.capacity()) {  // a large profile goes straight out
      if (std::fwrite(data, 1, bytes, file_) != bytes) ioFail("write");
      bytes_ += bytes;
      return;
    }
    const auto* p = static_cast<const uint8_t*>(data);
    buffer_.insert(buffer_.end(), p, p + bytes);
  }
  void flushBuffer() {
    if (buffer_.empty()) return;
    if (std::fwrite(buffer_.data(), 1, buffer_.size(), file_) != buffer_.size()) ioFail("write");
    bytes_ += buffer_.size();
    buffer_.clear();
  }
  [[noreturn]] void ioFail(const char* what) {
    const int error = errno;
    throw std::runtime_error("parametric sort: cannot " + std::string(what) + " run file " +
                             run_.path.string() + ": " + std::strerror(error));
  }

  RunFile& run_;
  uint64_t count_;
  std::FILE* file_ = nullptr;
  std::vector<uint8_t> buffer_;
  RunningHash hash_;
  uint64_t written_ = 0;
  uint64_t bytes_ = 0;
};

// Reads one run file back record by record through a bounded buffer, checking everything it
// can: the file should be exactly what RunWriter wrote, but it is a file.
class RunReader {
 public:
  RunReader(const RunFile& run, size_t buffer_bytes, uint64_t total_items)
      : reader_(run.path, buffer_bytes), total_items_(total_items) {
    if (reader_.size() != run.bytes)
      reader_.failAt(std::min(reader_.size(), run.bytes),
                     "run file is " + std::to_string(reader_.size()) + " bytes, " +
                         std::to_string(run.bytes) + " were written");
    if (reader_.size() < kRunHeaderBytes + kRunTrailerBytes)
      reader_.failAt(0, "too short for a run file");
    uint8_t header[kRunHeaderBytes];
    reader_.read(header, sizeof header);
    hash_.add(header, sizeof header);
    if (std::memcmp(header, kRunMagic, 8) != 0) reader_.failAt(0, "not a parametric run file");
    get(header + 8, count_);
    get(header + 16, max_profile_bytes_);
    if (count_ != run.count)
      reader_.failAt(8, "run holds " + std::to_string(count_) + " records, " +
                            std::to_string(run.count) + " were written");
    if (count_ > (reader_.size() - kRunHeaderBytes - kRunTrailerBytes) / kMinRecordBytes)
      reader_.failAt(8, "record count " + std::to_string(count_) + " cannot fit in the file");
    if (max_profile_bytes_ != run.max_profile_bytes)
      reader_.failAt(16, "largest profile " + std::to_string(max_profile_bytes_) +
                             " bytes, expected " + std::to_string(run.max_profile_bytes));
  }

  // Advances to the next record; false at the end of the run (after checking its checksum).
  bool next() {
    if (read_ == count_) {
      if (!finished_) finish();
      return false;
    }
    record_offset_ = reader_.offset();
    reader_.read(fixed_.data(), 1);
    const uint32_t type = fixed_[0];
    if (type >= kTypeCount) fail("primitive type " + std::to_string(type) + " is out of range");
    fixed_bytes_ = fixedBytes(type);
    reader_.read(fixed_.data() + 1, fixed_bytes_ - 1);
    hash_.add(fixed_.data(), fixed_bytes_);
    SortKey key;
    const DecodedFixed decoded = decodeFixed(fixed_.data(), key, item_);
    if (decoded.problem) fail(decoded.problem);
    if (key.index >= total_items_)
      fail("item index " + std::to_string(key.index) + " is out of range");
    if (read_ > 0 && !(key_ < key)) fail("records are not in sort order");
    key_ = key;
    profile_ = nullptr;
    profile_bytes_ = 0;
    if (decoded.profile) {
      const uint64_t bytes = uint64_t(decoded.profile_count) * sizeof(glm::vec2);
      if (bytes > max_profile_bytes_ || bytes > reader_.remaining())
        fail("profile of " + std::to_string(decoded.profile_count) + " points cannot be here");
      decoded.profile->resize(decoded.profile_count);
      reader_.read(decoded.profile->data(), bytes);
      hash_.add(decoded.profile->data(), bytes);
      profile_ = decoded.profile->data();
      profile_bytes_ = bytes;
    }
    ++read_;
    return true;
  }

  const SortKey& key() const { return key_; }
  const ParametricItem& item() const { return item_; }
  // The current record's bytes, for copying it into another run unchanged.
  const uint8_t* fixedData() const { return fixed_.data(); }
  size_t fixedSize() const { return fixed_bytes_; }
  const void* profileData() const { return profile_; }
  size_t profileSize() const { return profile_bytes_; }

  [[noreturn]] void fail(const std::string& reason) const {
    reader_.failAt(record_offset_, "record " + std::to_string(read_) + ": " + reason);
  }

 private:
  void finish() {
    finished_ = true;
    const uint64_t at = reader_.offset();
    const uint64_t stored = reader_.readValue<uint64_t>();
    if (stored != hash_.value()) reader_.failAt(at, "checksum mismatch: the run file is damaged");
    if (!reader_.atEnd()) reader_.fail("unexpected bytes after the checksum");
  }

  FileReader reader_;
  uint64_t total_items_;
  uint64_t count_ = 0;
  uint32_t max_profile_bytes_ = 0;
  uint64_t read_ = 0;
  bool finished_ = false;
  RunningHash hash_;
  uint64_t record_offset_ = 0;
  std::array<uint8_t, kMaxFixedBytes> fixed_{};
  size_t fixed_bytes_ = 0;
  SortKey key_;
  ParametricItem item_;
  const void* profile_ = nullptr;
  size_t profile_bytes_ = 0;
};

// Memory a reader takes besides its buffer and its largest profile.
constexpr uint64_t kReaderOverheadBytes = sizeof(RunReader) + sizeof(RunFile) + 64;

// Collects items in clustering order and, when a cluster's precomputed size is reached, adds its
// instances widest first and closes it: per type, ceil(n / max) runs of sizes n * r / runs apart,
// as clusterPrimitives cuts and orders them.
// The role flags options.instance_role_flags gives the item of input index `index` (none when
// it is empty; its size was checked against the item count).
uint32_t roleFlags(const ParametricSortOptions& options, uint32_t index) {
  return options.instance_role_flags.empty() ? 0u : options.instance_role_flags[index];
}

class ClusterCutter {
 public:
  ClusterCutter(const std::array<uint64_t, kTypeCount>& counts, uint32_t max_per_cluster,
                PackageStorage& storage)
      : counts_(counts), max_per_cluster_(max_per_cluster), storage_(storage) {}

  void add(uint32_t type, const ParametricItem& item, uint32_t role_flags) {
    if (int64_t(type) != type_) {
      if (int64_t(type) < type_ || (type_ >= 0 && pos_ != counts_[type_]) || type >= kTypeCount ||
          counts_[type] == 0)
        throw std::logic_error("parametric sort: items reached the clusters out of order");
      type_ = type;
      n_ = counts_[type];
      runs_ = (n_ + max_per_cluster_ - 1) / max_per_cluster_;
      pos_ = begin_ = 0;
      r_ = 0;
      end_ = n_ / runs_;  // n * 1 / runs
    }
    if (pos_ >= n_)
      throw std::logic_error("parametric sort: more items of a type than counted");
    // Refused here, as the item arrives, so its run is named; added when its cluster is whole.
    (void)placedInstanceRecord(item.primitive, item.transform, item.object, storage_.origin);
    if (role_flags & ~pkg::kInstanceSearchedFlags)
      throw std::invalid_argument("parametric sort: unknown instance role flags");
    pending_.push_back({item, role_flags, parametricShowWidth(item.primitive, item.transform)});
    ++pos_;
    if (pos_ == end_) {
      // Widest first, ties in arrival (Morton) order: clusterPrimitives' order.
      std::stable_sort(pending_.begin(), pending_.end(),
                       [](const Pending& a, const Pending& b) { return a.width > b.width; });
      for (size_t k = 0; k < pending_.size(); ++k) {
        const Pending& p = pending_[k];
        const uint32_t instance =
            storage_.addInstance(p.item.primitive, p.item.transform, p.item.object, p.role_flags);
        if (k == 0) first_ = instance;
        else if (uint64_t(instance) != first_ + k)
          throw std::logic_error("parametric sort: storage did not append instances contiguously");
      }
      pending_.clear();
      storage_.addParametricCluster(first_, uint32_t(end_ - begin_), ClusterLod{});
      ++clusters_;
      ++r_;
      begin_ = end_;
      end_ = n_ * (r_ + 1) / runs_;
    }
  }

  // Checks every counted item arrived.
  void finish() const {
    uint64_t expected = 0, seen = 0;
    for (uint32_t t = 0; t < kTypeCount; ++t) {
      expected += counts_[t];
      if (int64_t(t) < type_) seen += counts_[t];
    }
    if (type_ >= 0) seen += pos_;
    if (seen != expected)
      throw std::logic_error("parametric sort: " + std::to_string(seen) + " of " +
                             std::to_string(expected) + " items reached the clusters");
  }
  uint32_t clusters() const { return clusters_; }

 private:
  std::array<uint64_t, kTypeCount> counts_;
  uint64_t max_per_cluster_;
  PackageStorage& storage_;
  int64_t type_ = -1;
  uint64_t n_ = 0, runs_ = 0, r_ = 0, pos_ = 0, begin_ = 0, end_ = 0;
  uint64_t first_ = 0;
  uint32_t clusters_ = 0;
  // The items of the cluster being filled, added once it is whole.
  struct Pending {
    ParametricItem item;
    uint32_t role_flags;
    float width;
  };
  std::vector<Pending> pending_;
};

// k-way merge of `readers` (each not yet advanced) by key; `emit(reader)` gets each record.
template <typename Emit>
void mergeReaders(std::vector<std::unique_ptr<RunReader>>& readers, Emit&& emit) {
  auto later = [&](uint32_t a, uint32_t b) { return readers[b]->key() < readers[a]->key(); };
  std::priority_queue<uint32_t, std::vector<uint32_t>, decltype(later)> heap(later);
  for (uint32_t i = 0; i < readers.size(); ++i)
    if (readers[i]->next()) heap.push(i);
  SortKey last;
  bool any = false;
  while (!heap.empty()) {
    const uint32_t i = heap.top();
    heap.pop();
    RunReader& reader = *readers[i];
    if (any && !(last < reader.key()))
      reader.fail("item " + std::to_string(reader.key().index) + " is in two runs");
    last = reader.key();
    any = true;
    emit(reader);
    if (reader.next()) heap.push(i);
  }
}

struct PassOne {
  uint64_t items = 0;
  std::array<uint64_t, kTypeCount> counts{};
  glm::vec3 lo{std::numeric_limits<float>::max()};
  glm::vec3 hi{-std::numeric_limits<float>::max()};
  uint64_t record_bytes = 0;       // all records, profiles included
  uint32_t max_profile_bytes = 0;  // largest single profile
};

PassOne scanItems(const ParametricStream& stream, const glm::dvec3& origin) {
  PassOne one;
  CentreFinder finder(origin);
  stream([&](std::span<const ParametricItem> batch) {
    for (const ParametricItem& item : batch) {
      if (++one.items >= std::numeric_limits<uint32_t>::max())
        throw std::invalid_argument("addParametricClustersOutOfCore: too many items");
      const glm::vec3 c = finder.centre(item);
      one.lo = glm::min(one.lo, c);
      one.hi = glm::max(one.hi, c);
      ++one.counts[item.primitive.index()];
      one.record_bytes += recordBytes(item);
      if (const auto* profile = profileOf(item.primitive))
        one.max_profile_bytes =
            std::max(one.max_profile_bytes, uint32_t(profile->size() * sizeof(glm::vec2)));
    }
  });
  return one;
}

uint64_t roundUp8(uint64_t n) { return (n + 7) & ~uint64_t(7); }

[[noreturn]] void streamChanged(const std::string& what) {
  throw std::invalid_argument("addParametricClustersOutOfCore: the stream gave different items on "
                              "its second pass (" + what + ")");
}

}  // namespace

ParametricSortStats addParametricClustersOutOfCore(const ParametricStream& stream,
                                                   const ParametricSortOptions& options,
                                                   PackageStorage& storage) {
  if (options.max_per_cluster == 0)
    throw std::invalid_argument("addParametricClustersOutOfCore: max_per_cluster must be > 0");
  if (options.memory_budget_bytes < kMinBudgetBytes)
    throw std::invalid_argument("addParametricClustersOutOfCore: memory_budget_bytes must be at "
                                "least 1 MiB");
  if (options.work_dir.empty())
    throw std::invalid_argument("addParametricClustersOutOfCore: work_dir is empty");
  const uint64_t budget = options.memory_budget_bytes;
  ParametricSortStats stats;

  // Pass 1: bounds of the centres, counts, sizes. Bad parameters throw before anything is added.
  const PassOne one = scanItems(stream, storage.origin);
  stats.items = one.items;
  if (!options.instance_role_flags.empty() && options.instance_role_flags.size() != one.items)
    throw std::invalid_argument("addParametricClustersOutOfCore: " +
                                std::to_string(options.instance_role_flags.size()) +
                                " role flags for " + std::to_string(one.items) + " items");
  const glm::vec3 lo = one.lo, hi = one.hi;
  // One scale for all axes, as clusterPrimitives.
  const glm::vec3 extent(std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z, 1e-30f}));

  // Pass 2 into the arena: records up from 0, keys down from the end.
  const uint64_t all_bytes = roundUp8(one.record_bytes) + one.items * sizeof(ArenaKey);
  const bool in_memory = all_bytes + one.max_profile_bytes <= budget;
  const uint64_t writer_bytes = std::clamp(budget / 16, kMinIoBufferBytes, kMaxIoBufferBytes);
  const uint64_t arena_bytes = in_memory ? all_bytes : (budget - writer_bytes) & ~uint64_t(7);
  stats.peak_held_bytes = arena_bytes + (in_memory ? one.max_profile_bytes : writer_bytes);
  auto arena = std::make_unique_for_overwrite<uint8_t[]>(arena_bytes);
  uint64_t used = 0, key_count = 0;
  uint32_t run_max_profile = 0;
  auto arenaKeys = [&] {
    return std::launder(
        reinterpret_cast<ArenaKey*>(arena.get() + arena_bytes - key_count * sizeof(ArenaKey)));
  };
  auto sortArena = [&] {
    ArenaKey* keys = arenaKeys();
    std::sort(keys, keys + key_count,
              [](const ArenaKey& a, const ArenaKey& b) { return a.key < b.key; });
    return keys;
  };

  RunNamer namer(options.work_dir);
  std::deque<RunPtr> runs;
  auto flushRun = [&] {
    const ArenaKey* keys = sortArena();
    RunPtr run = namer.next();
    RunWriter writer(*run, key_count, run_max_profile, writer_bytes);
    for (uint64_t k = 0; k < key_count; ++k) {
      const uint8_t* record = arena.get() + keys[k].offset;
      const size_t fixed = fixedBytes(keys[k].key.type);
      uint32_t points = 0;
      if (hasProfile(keys[k].key.type)) get(record + fixed - 4, points);
      writer.write(record, fixed, record + fixed, size_t(points) * sizeof(glm::vec2));
    }
    stats.run_bytes += writer.finish();
    runs.push_back(std::move(run));
    ++stats.runs;
    used = key_count = 0;
    run_max_profile = 0;
  };

  std::array<uint64_t, kTypeCount> counts2{};
  uint64_t items2 = 0;
  {
    CentreFinder finder(storage.origin);
    stream([&](std::span<const ParametricItem> batch) {
      for (const ParametricItem& item : batch) {
        const uint32_t type = uint32_t(item.primitive.index());
        if (items2 >= one.items || ++counts2[type] > one.counts[type]) streamChanged("more items");
        const SortKey key{type, uint32_t(items2++), parametricMortonCode((finder.centre(item) - lo) / extent)};
        const uint64_t bytes = recordBytes(item);
        auto fits = [&] {
          return roundUp8(used + bytes) + (key_count + 1) * sizeof(ArenaKey) <= arena_bytes;
        };
        if (!fits()) {
          if (in_memory) streamChanged("larger items");
          flushRun();
          if (!fits()) throw std::logic_error("parametric sort: an item does not fit the arena");
        }
        uint8_t* record = arena.get() + used;
        encodeFixed(key, item, record);
        if (const auto* profile = profileOf(item.primitive)) {
          const size_t profile_bytes = profile->size() * sizeof(glm::vec2);
          if (profile_bytes > 0)
            std::memcpy(record + fixedBytes(type), profile->data(), profile_bytes);
          run_max_profile = std::max(run_max_profile, uint32_t(profile_bytes));
        }
        ++key_count;
        new (arena.get() + arena_bytes - key_count * sizeof(ArenaKey)) ArenaKey{key, used};
        used += bytes;
      }
    });
  }
  if (items2 != one.items) streamChanged("fewer items");

  ClusterCutter cutter(one.counts, options.max_per_cluster, storage);
  if (runs.empty()) {
    // Everything fit: sort in place and feed the storage from the arena.
    const ArenaKey* keys = sortArena();
    ParametricItem item;
    for (uint64_t k = 0; k < key_count; ++k) {
      SortKey key;
      const uint8_t* record = arena.get() + keys[k].offset;
      const DecodedFixed decoded = decodeFixed(record, key, item);
      if (decoded.profile) {
        decoded.profile->resize(decoded.profile_count);
        std::memcpy(decoded.profile->data(), record + fixedBytes(key.type),
                    decoded.profile_count * sizeof(glm::vec2));
      }
      cutter.add(key.type, item, roleFlags(options, key.index));
    }
    cutter.finish();
    stats.clusters = cutter.clusters();
    return stats;
  }
  if (key_count > 0) flushRun();
  arena.reset();

  // Merge. Each reader needs a buffer and room for its largest profile; when all of them do not
  // fit the budget, the oldest runs that do (at least two) are merged into a new run at the back,
  // so data is rewritten about log_k(runs) times.
  auto need = [](const RunFile& run) {
    return kMinIoBufferBytes + run.max_profile_bytes + kReaderOverheadBytes;
  };
  while (true) {
    uint64_t total_need = 0;
    for (const RunPtr& run : runs) total_need += need(*run);
    size_t group = runs.size();
    bool final_merge = (total_need <= budget && runs.size() <= kMaxFanIn) || runs.size() <= 2;
    if (!final_merge) {
      uint64_t sum = kMinIoBufferBytes;  // the output's buffer
      group = 0;
      while (group < runs.size() && group < kMaxFanIn && sum + need(*runs[group]) <= budget)
        sum += need(*runs[group++]);
      group = std::max<size_t>(group, 2);
    }
    const uint64_t buffers = group + (final_merge ? 0 : 1);
    uint64_t fixed_part = 0, count = 0;
    uint32_t max_profile = 0;
    for (size_t i = 0; i < group; ++i) {
      fixed_part += runs[i]->max_profile_bytes + kReaderOverheadBytes;
      count += runs[i]->count;
      max_profile = std::max(max_profile, runs[i]->max_profile_bytes);
    }
    // FileReader never takes less than 4 KiB.
    const uint64_t buffer_bytes = std::clamp<uint64_t>(
        budget > fixed_part ? (budget - fixed_part) / buffers : 0, 4096, kMaxIoBufferBytes);
    stats.peak_held_bytes = std::max(stats.peak_held_bytes, fixed_part + buffers * buffer_bytes);
    ++stats.merges;

    std::vector<std::unique_ptr<RunReader>> readers;
    readers.reserve(group);
    for (size_t i = 0; i < group; ++i)
      readers.push_back(std::make_unique<RunReader>(*runs[i], buffer_bytes, one.items));
    if (final_merge) {
      // Records reach the storage before their run's checksum is checked (at its end), so a
      // damaged record that the storage or the cutter refuses is reported as what it is.
      mergeReaders(readers, [&](const RunReader& r) {
        try {
          cutter.add(r.key().type, r.item(), roleFlags(options, r.key().index));
        } catch (const std::logic_error& e) {  // std::invalid_argument included
          r.fail(std::string("refused (damaged run?): ") + e.what());
        }
      });
      break;
    }
    RunPtr merged = namer.next();
    RunWriter writer(*merged, count, max_profile, buffer_bytes);
    mergeReaders(readers, [&](const RunReader& r) {
      writer.write(r.fixedData(), r.fixedSize(), r.profileData(), r.profileSize());
    });
    stats.run_bytes += writer.finish();
    readers.clear();
    for (size_t i = 0; i < group; ++i) runs.pop_front();  // removes the files
    runs.push_back(std::move(merged));
  }
  cutter.finish();
  stats.clusters = cutter.clusters();
  return stats;
}

}  // namespace tw
