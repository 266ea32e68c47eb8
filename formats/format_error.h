// The one error type for unreadable input: it names the file, where in it, and why.
//
// Readers throw FormatError for anything wrong with the data (never assert on file contents); the
// command line catches it at the boundary and prints what() as a one-line message.
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>

namespace tw {

class FormatError : public std::runtime_error {
 public:
  enum class Where { None, Byte, Line };

  // "file: reason" (an I/O failure with no position, such as a missing file).
  FormatError(const std::string& file, const std::string& reason);
  static FormatError atByte(const std::string& file, uint64_t offset, const std::string& reason);
  static FormatError atLine(const std::string& file, uint64_t line, const std::string& reason);

  const std::string& file() const { return file_; }
  Where where() const { return where_; }
  uint64_t position() const { return position_; }  // byte offset or 1-based line number
  const std::string& reason() const { return reason_; }

 private:
  FormatError(const std::string& file, Where where, uint64_t position, const std::string& reason);

  std::string file_;
  Where where_ = Where::None;
  uint64_t position_ = 0;
  std::string reason_;
};

}  // namespace tw
