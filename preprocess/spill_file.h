// The bricking's spill files: what the out-of-core passes write to the work directory and read
// back (bricks of triangles, objects, their bounds, parametrics), each a header, its records and
// a trailer written last with the record count, the content size and an XXH3-64 of the content.
// A missing or wrong trailer means a killed run or a damaged file, and the reader says so with
// the file and the offset; a run that resumes checks every file it reuses this way.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "file_reader.h"

namespace tw {

enum class SpillKind : uint32_t { Brick = 1, Objects = 2, ObjectBounds = 3, Parametrics = 4 };

// Appends records through a caller-sized buffer; the file is opened only to flush, so thousands
// of bricks never hold thousands of descriptors. Throws std::runtime_error naming the file when
// it cannot be created or written.
class SpillWriter {
 public:
  SpillWriter(std::filesystem::path path, SpillKind kind);
  ~SpillWriter();
  SpillWriter(const SpillWriter&) = delete;
  SpillWriter& operator=(const SpillWriter&) = delete;

  void append(const void* data, size_t bytes);
  void countRecord() { ++records_; }
  void reserve(size_t bytes) { buffer_.reserve(bytes); }
  size_t buffered() const { return buffer_.size(); }
  // Writes the buffer out; `release` gives its memory back too.
  void flush(bool release);
  // Flushes and appends the trailer; the file is complete only after this.
  void finish();
  uint64_t records() const { return records_; }
  uint64_t bytesWritten() const { return bytes_written_; }
  const std::filesystem::path& path() const { return path_; }

 private:
  struct Checksum;
  std::filesystem::path path_;
  std::vector<uint8_t> buffer_;
  std::unique_ptr<Checksum> checksum_;
  uint64_t records_ = 0, content_bytes_ = 0, bytes_written_ = 0;
};

// Bounds-checked reading of a spill file's content; finish() verifies the checksum. Every
// failure is a FormatError naming the file and the offset.
class SpillReader {
 public:
  SpillReader(const std::filesystem::path& path, SpillKind kind);
  ~SpillReader();
  SpillReader(const SpillReader&) = delete;
  SpillReader& operator=(const SpillReader&) = delete;

  uint64_t records() const { return record_count_; }
  uint64_t contentRemaining() const;
  void read(void* out, size_t bytes);
  template <typename T>
  T readValue() {
    T value;
    read(&value, sizeof value);
    return value;
  }
  // After the last record: no bytes left and the checksum matches.
  void finish();
  [[noreturn]] void fail(const std::string& reason) const { reader_.fail(reason); }
  const std::string& name() const { return reader_.name(); }
  uint64_t offset() const { return reader_.offset(); }

 private:
  struct Checksum;
  FileReader reader_;
  uint64_t record_count_ = 0, expected_checksum_ = 0;
  std::unique_ptr<Checksum> checksum_;
};

}  // namespace tw
