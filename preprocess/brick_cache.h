// The resume store of the preprocessor: finished per-brick results kept on disk in the work dir
// (<output>.work/, next to the output), so that a killed run restarted with --resume and the same
// arguments redoes only the bricks that were not finished and produces the same package.
//
// Each blob is written to a temporary name and renamed into place, with a header holding the key,
// the run hash and an XXH3 checksum of the payload. A blob whose run hash differs (other inputs or
// options), whose checksum fails, or which is truncated counts as absent: never trusted, redone.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

#include "scene_bricking.h"

namespace tw {

// Hash of everything that affects the output: input paths, sizes and modification times, and the
// options the caller adds. Order matters.
class RunHash {
 public:
  RunHash();
  ~RunHash();
  RunHash(const RunHash&) = delete;
  RunHash& operator=(const RunHash&) = delete;

  // Adds the path as given, the file size and the modification time (missing file: path only).
  void addFile(const std::filesystem::path& path);
  void addBytes(const void* data, size_t bytes);
  void addString(std::string_view s);
  template <typename T>
  void addValue(const T& value) {  // plain values only (no padding)
    addBytes(&value, sizeof value);
  }
  // The options of brickScene that change its output (the effective brick limit, the tolerance).
  void addBrickingOptions(const BrickingOptions& options);
  uint64_t digest() const;

 private:
  struct State;
  State* state_;
};

class BrickCache {
 public:
  // Blobs live in work_dir/"brick-cache"; the directory is created on the first store.
  BrickCache(std::filesystem::path work_dir, uint64_t run_hash);

  // has() reads and verifies the whole blob: true exactly when load() would return a value.
  bool has(uint32_t key) const;
  // The payload, or nullopt if the blob is missing, truncated, damaged or from another run.
  std::optional<std::vector<uint8_t>> load(uint32_t key) const;
  // Atomically replaces the blob for `key`. Throws std::runtime_error on I/O failure.
  void store(uint32_t key, std::span<const uint8_t> bytes);
  // Removes every blob (keeps the work dir).
  void clear();

  std::filesystem::path blobPath(uint32_t key) const;
  uint64_t runHash() const { return run_hash_; }

 private:
  std::filesystem::path dir_;
  uint64_t run_hash_;
};

// The description as bytes (for the resume store) and back. Deserialization checks every count
// against the bytes present and throws FormatError naming `source` otherwise.
std::vector<uint8_t> serializeBrickedScene(const BrickedScene& scene);
BrickedScene deserializeBrickedScene(std::span<const uint8_t> bytes,
                                     const std::filesystem::path& work_dir,
                                     const std::string& source = "bricked scene");

// The key reserved for the "bricking pass complete" marker: the BrickedScene description.
constexpr uint32_t kBrickedSceneKey = 0xffffffffu;
// The key of the seams between the bricks (BrickSeams::serialize), stored after the bricking.
constexpr uint32_t kBrickSeamsKey = 0xfffffffeu;

// Stores the description after brickScene has finished (its spill files complete).
void storeBrickedScene(BrickCache& cache, const BrickedScene& scene);
// The stored description if present and valid and every spill file it names passes the cheap
// integrity check (verifyBrickedScene without checksums; loadBrick still verifies them).
std::optional<BrickedScene> loadBrickedScene(const BrickCache& cache,
                                             const std::filesystem::path& work_dir);

// "<output>.work": where the driver keeps spill files and the cache.
std::filesystem::path workDirFor(const std::filesystem::path& output);
// Removes the work dir and everything in it; returns false (and leaves what it could not
// remove) on failure. Never throws.
bool removeWorkDir(const std::filesystem::path& work_dir);

}  // namespace tw
