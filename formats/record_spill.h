// RecordSpill: an append-only file of fixed-size records that keeps a running XXH3-64 of its
// bytes. The package writer's tables (clusters, groups, instances, objects, strings) and its page
// data leave memory through it as the preprocessor fills them, so the memory a build needs does
// not grow with the model: the package section is later the file's bytes followed by whatever is
// still in memory, and its checksum is the running hash continued over that tail.
#pragma once

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <span>

struct XXH3_state_s;  // xxhash.h, kept out of this header

namespace tw {

class RecordSpill {
 public:
  // Creates (or truncates) `path`. `what` names the table in error messages ("cluster table").
  // Throws std::runtime_error naming the file when it cannot be created.
  RecordSpill(const std::filesystem::path& path, uint32_t record_bytes, const char* what);
  ~RecordSpill();
  RecordSpill(const RecordSpill&) = delete;
  RecordSpill& operator=(const RecordSpill&) = delete;

  // Appends `count` records (count * record_bytes bytes). Throws std::runtime_error on I/O failure.
  void append(const void* records, uint64_t count);
  // Appends raw bytes (record_bytes must be 1).
  void appendBytes(std::span<const uint8_t> bytes) { append(bytes.data(), bytes.size()); }

  uint64_t count() const { return bytes_ / record_bytes_; }
  uint64_t bytes() const { return bytes_; }
  uint32_t recordBytes() const { return record_bytes_; }
  const std::filesystem::path& path() const { return path_; }

  // Copies records [first, first + count) into `out` (count * record_bytes bytes). Throws
  // std::out_of_range past the end, std::runtime_error on I/O failure.
  void read(uint64_t first, uint64_t count, void* out) const;
  // Calls `fn` with the file's bytes in order, in chunks of at most `chunk_bytes` (a multiple of
  // the record size, at least one record).
  void forEachChunk(uint64_t chunk_bytes,
                    const std::function<void(std::span<const uint8_t>)>& fn) const;
  // XXH3-64 (seed 0) of the file's bytes followed by `tail`.
  uint64_t checksumWith(std::span<const uint8_t> tail) const;
  // Makes everything appended visible to other readers of the file.
  void flush() const;

 private:
  [[noreturn]] void ioFail(const char* what) const;

  std::filesystem::path path_;
  uint32_t record_bytes_;
  const char* what_;
  std::FILE* file_ = nullptr;
  XXH3_state_s* hash_ = nullptr;
  uint64_t bytes_ = 0;
};

}  // namespace tw
