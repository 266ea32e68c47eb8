// The resume store: checksummed, run-stamped blobs written atomically into the work dir.
#include "brick_cache.h"

#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <string>

#define XXH_INLINE_ALL
#include <xxhash.h>

#include "byte_packing.h"
#include "file_reader.h"
#include "format_error.h"

namespace tw {
namespace {

constexpr uint32_t kBlobMagic = 0x43425754u;  // "TWBC"
constexpr uint32_t kBlobVersion = 3;  // 2: vertex-clustered groups (GroupMethod::Merged); 3: rims
                                      // welded across bricks first (cross_brick_weld.h)

struct BlobHeader {
  uint32_t magic, version, key, reserved;
  uint64_t run_hash, payload_bytes, checksum;  // XXH3-64 of the payload
};
static_assert(sizeof(BlobHeader) == 40);

uint64_t payloadChecksum(std::span<const uint8_t> bytes) {
  static const uint8_t kEmpty = 0;
  return XXH3_64bits(bytes.empty() ? &kEmpty : bytes.data(), bytes.size());
}

}  // namespace

struct RunHash::State {
  XXH3_state_t xxh;
};

RunHash::RunHash() : state_(new State) { XXH3_64bits_reset(&state_->xxh); }
RunHash::~RunHash() { delete state_; }

void RunHash::addBytes(const void* data, size_t bytes) {
  XXH3_64bits_update(&state_->xxh, data, bytes);
}

void RunHash::addString(std::string_view s) {
  addValue(static_cast<uint64_t>(s.size()));  // length first: "ab"+"c" differs from "a"+"bc"
  addBytes(s.data(), s.size());
}

void RunHash::addFile(const std::filesystem::path& path) {
  addString(path.string());
  std::error_code ec;
  uint64_t size = std::filesystem::file_size(path, ec);
  addValue(ec ? uint64_t{0} : size);
  auto time = std::filesystem::last_write_time(path, ec);
  int64_t ticks = ec ? 0 : static_cast<int64_t>(time.time_since_epoch().count());
  addValue(ticks);
}

void RunHash::addBrickingOptions(const BrickingOptions& options) {
  addString("bricking-v1");
  addValue(effectiveMaxBrickTriangles(options));
  addValue(options.nurbs_tolerance);
  addValue(options.position_step_m);
  // Only when set, so that a run without exclusions keeps the hash it always had.
  for (const std::string& name : options.exclude_layers) addString("exclude-layer:" + name);
  if (options.up != UpAxis::Auto) addString(std::string("up:") + upAxisName(options.up));
  if (!options.cad.primitives) addString("cad-primitives:off");
  if (options.cad.tolerance_m > 0.0) {
    addString("cad-tolerance");
    addValue(options.cad.tolerance_m);
  }
  if (!options.cad.conforming_bspline) addString("cad-bspline:brepmesh");
}

uint64_t RunHash::digest() const { return XXH3_64bits_digest(&state_->xxh); }

BrickCache::BrickCache(std::filesystem::path work_dir, uint64_t run_hash)
    : dir_(std::move(work_dir) / "brick-cache"), run_hash_(run_hash) {}

std::filesystem::path BrickCache::blobPath(uint32_t key) const {
  char name[32];
  std::snprintf(name, sizeof name, "%08x.blob", key);
  return dir_ / name;
}

bool BrickCache::has(uint32_t key) const { return load(key).has_value(); }

std::optional<std::vector<uint8_t>> BrickCache::load(uint32_t key) const {
  const auto path = blobPath(key);
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return std::nullopt;
  try {
    FileReader reader(path);
    auto header = reader.readValue<BlobHeader>();
    if (header.magic != kBlobMagic || header.version != kBlobVersion || header.key != key ||
        header.run_hash != run_hash_ || header.payload_bytes != reader.remaining())
      return std::nullopt;
    std::vector<uint8_t> payload(static_cast<size_t>(header.payload_bytes));
    reader.read(payload.data(), payload.size());
    if (payloadChecksum(payload) != header.checksum) return std::nullopt;
    return payload;
  } catch (const FormatError&) {
    return std::nullopt;  // unreadable or truncated: absent, the work is redone
  }
}

void BrickCache::store(uint32_t key, std::span<const uint8_t> bytes) {
  std::filesystem::create_directories(dir_);
  const auto path = blobPath(key);
  const auto temp = path.string() + ".tmp-" + std::to_string(::getpid());
  BlobHeader header{kBlobMagic,   kBlobVersion,          key, 0, run_hash_,
                    bytes.size(), payloadChecksum(bytes)};
  std::FILE* f = std::fopen(temp.c_str(), "wb");
  if (!f) throw std::runtime_error(temp + ": cannot create: " + std::strerror(errno));
  bool ok = std::fwrite(&header, sizeof header, 1, f) == 1 &&
            (bytes.empty() || std::fwrite(bytes.data(), 1, bytes.size(), f) == bytes.size());
  ok = std::fflush(f) == 0 && ok;
  // The rename must not overtake the data after a power cut; a kill alone would not need this.
  ok = ::fsync(::fileno(f)) == 0 && ok;
  ok = std::fclose(f) == 0 && ok;
  if (!ok) {
    int err = errno;
    std::remove(temp.c_str());
    throw std::runtime_error(temp + ": cannot write: " + std::strerror(err));
  }
  std::error_code ec;
  std::filesystem::rename(temp, path, ec);
  if (ec) {
    std::remove(temp.c_str());
    throw std::runtime_error(path.string() + ": cannot rename into place: " + ec.message());
  }
}

void BrickCache::clear() {
  std::error_code ec;
  std::filesystem::remove_all(dir_, ec);
}

std::vector<uint8_t> serializeBrickedScene(const BrickedScene& scene) {
  ByteWriter w;
  w.put(uint32_t{0x53425754u});  // "TWBS"
  w.put(uint32_t{4});  // 3: triangles_repeated; 4: stored_coordinate_extent
  w.put(scene.origin);
  w.put(scene.max_brick_triangles);
  w.put(scene.grid);
  w.put(static_cast<uint64_t>(scene.bricks.size()));
  for (const auto& b : scene.bricks) {
    w.put(b.index), w.put(b.bounds_min), w.put(b.bounds_max), w.put(b.triangle_count);
    w.putString(b.file);
  }
  w.put(static_cast<uint64_t>(scene.layers.size()));
  for (const auto& l : scene.layers) w.putString(l.name), w.put(l.color_rgba);
  w.putString(scene.objects_file);
  w.putString(scene.object_bounds_file);
  w.put(scene.object_count);
  w.putString(scene.parametrics_file);
  w.put(scene.parametric_count);
  w.put(scene.triangle_count);
  w.put(scene.triangles_turned);
  w.put(scene.triangles_repeated);
  w.put(scene.stored_coordinate_extent);
  const BrickingStats& st = scene.stats;
  for (uint64_t v : {st.buffer_cap_bytes, st.peak_buffered_bytes, st.flushes,
                     st.spill_bytes_written, st.object_table_bytes})
    w.put(v);
  for (uint32_t v : {st.grid_cells, st.cells_split, st.split_passes}) w.put(v);
  return std::move(w.bytes);
}

BrickedScene deserializeBrickedScene(std::span<const uint8_t> bytes,
                                     const std::filesystem::path& work_dir,
                                     const std::string& source) {
  ByteReader r(bytes, source);
  if (r.get<uint32_t>() != 0x53425754u) r.fail("not a bricked scene description (bad magic)");
  if (r.get<uint32_t>() != 4) r.fail("unsupported bricked scene version");
  BrickedScene scene;
  scene.work_dir = work_dir;
  scene.origin = r.get<glm::dvec3>();
  scene.max_brick_triangles = r.get<uint64_t>();
  scene.grid = r.get<glm::uvec3>();
  auto bricks = r.get<uint64_t>();
  // Each brick takes at least 48 bytes: bound the count by what is there before reserving.
  if (bricks > r.remaining() / 48) r.fail("brick count " + std::to_string(bricks) + " too large");
  scene.bricks.resize(bricks);
  uint64_t sum = 0;
  for (uint64_t i = 0; i < bricks; ++i) {
    BrickInfo& b = scene.bricks[i];
    b.index = r.get<uint32_t>();
    if (b.index != i) r.fail("brick index out of order");
    b.bounds_min = r.get<glm::vec3>();
    b.bounds_max = r.get<glm::vec3>();
    b.triangle_count = r.get<uint64_t>();
    b.file = r.getString();
    // A file name, never a path: the description must not reach outside the work dir.
    if (b.file.empty() || b.file.find('/') != std::string::npos || b.file == "..")
      r.fail("bad brick file name");
    sum += b.triangle_count;
  }
  auto layers = r.get<uint64_t>();
  if (layers > r.remaining() / 8) r.fail("layer count " + std::to_string(layers) + " too large");
  scene.layers.resize(layers);
  for (auto& l : scene.layers) l.name = r.getString(), l.color_rgba = r.get<uint32_t>();
  scene.objects_file = r.getString();
  scene.object_bounds_file = r.getString();
  scene.object_count = r.get<uint64_t>();
  scene.parametrics_file = r.getString();
  scene.parametric_count = r.get<uint64_t>();
  scene.triangle_count = r.get<uint64_t>();
  if (scene.triangle_count != sum) r.fail("triangle total differs from the sum over bricks");
  scene.triangles_turned = r.get<uint64_t>();
  scene.triangles_repeated = r.get<uint64_t>();
  scene.stored_coordinate_extent = r.get<double>();
  if (!(scene.stored_coordinate_extent >= 0.0 && std::isfinite(scene.stored_coordinate_extent)))
    r.fail("stored coordinate extent is not a finite non-negative number");
  for (const std::string* f :
       {&scene.objects_file, &scene.object_bounds_file, &scene.parametrics_file})
    if (f->empty() || f->find('/') != std::string::npos || *f == "..")
      r.fail("bad spill file name");
  BrickingStats& st = scene.stats;
  for (uint64_t* v : {&st.buffer_cap_bytes, &st.peak_buffered_bytes, &st.flushes,
                      &st.spill_bytes_written, &st.object_table_bytes})
    *v = r.get<uint64_t>();
  for (uint32_t* v : {&st.grid_cells, &st.cells_split, &st.split_passes}) *v = r.get<uint32_t>();
  if (r.remaining() != 0) r.fail("unexpected bytes after the description");
  return scene;
}

void storeBrickedScene(BrickCache& cache, const BrickedScene& scene) {
  cache.store(kBrickedSceneKey, serializeBrickedScene(scene));
}

std::optional<BrickedScene> loadBrickedScene(const BrickCache& cache,
                                             const std::filesystem::path& work_dir) {
  auto bytes = cache.load(kBrickedSceneKey);
  if (!bytes) return std::nullopt;
  try {
    BrickedScene scene = deserializeBrickedScene(*bytes, work_dir);
    if (!verifyBrickedScene(scene, false)) return std::nullopt;
    return scene;
  } catch (const FormatError&) {
    return std::nullopt;
  }
}

std::filesystem::path workDirFor(const std::filesystem::path& output) {
  return std::filesystem::path(output.string() + ".work");
}

bool removeWorkDir(const std::filesystem::path& work_dir) {
  std::error_code ec;
  std::filesystem::remove_all(work_dir, ec);
  return !ec;
}

}  // namespace tw
