// Buffered, bounds-checked sequential reading of a file of any size.
//
// Every reader in formats/ goes through FileReader so that memory stays bounded by one buffer,
// every read past the end becomes a FormatError naming the file and byte offset, and throughput is
// limited by the disk rather than by per-call overhead.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "format_error.h"

namespace tw {

class FileReader {
 public:
  static constexpr size_t kDefaultBufferBytes = size_t{1} << 20;

  // Opens `path`; throws FormatError if it cannot be opened. The buffer is `buffer_bytes`, or
  // less for a file smaller than that.
  explicit FileReader(const std::filesystem::path& path, size_t buffer_bytes = kDefaultBufferBytes);
  ~FileReader();
  FileReader(const FileReader&) = delete;
  FileReader& operator=(const FileReader&) = delete;

  const std::string& name() const { return name_; }
  uint64_t size() const { return size_; }
  uint64_t offset() const { return offset_; }  // bytes consumed so far
  uint64_t remaining() const { return size_ - offset_; }
  bool atEnd() const { return offset_ >= size_; }

  // Copies exactly `bytes` bytes; throws FormatError "unexpected end of file" if fewer remain.
  void read(void* out, size_t bytes);
  template <typename T>
  T readValue() {
    T value;
    read(&value, sizeof(T));
    return value;
  }
  // Skips `bytes` bytes; throws FormatError if fewer remain.
  void skip(uint64_t bytes);
  // Moves to an absolute offset within the file; throws FormatError if it is past the end.
  void seek(uint64_t offset);

  // Returns a view of up to `max_bytes` contiguous buffered bytes without consuming them. The view
  // is valid until the next call on this reader. Returns an empty view only at end of file.
  std::string_view peek(size_t max_bytes);
  // Consumes `bytes` bytes previously returned by peek().
  void consume(size_t bytes);

  // Reads one text line (without its end: "\n", "\r\n" or a lone "\r"); returns false at end
  // of file. The view is valid until the next call. Lines longer than the buffer throw FormatError. line() is the 1-based
  // number of the line last returned.
  bool readLine(std::string_view& line);
  uint64_t line() const { return line_; }

  [[noreturn]] void fail(const std::string& reason) const;               // at the current offset
  [[noreturn]] void failAt(uint64_t offset, const std::string& reason) const;
  [[noreturn]] void failAtLine(const std::string& reason) const;         // at line()

 private:
  void refill();
  bool findLineEnd(size_t& length, size_t& consumed) const;

  std::FILE* file_ = nullptr;
  std::string name_;
  uint64_t size_ = 0;
  uint64_t offset_ = 0;         // file offset of buffer_[begin_]
  std::vector<char> buffer_;
  size_t begin_ = 0;            // first unconsumed byte in buffer_
  size_t end_ = 0;              // one past the last valid byte in buffer_
  uint64_t line_ = 0;
};

}  // namespace tw
