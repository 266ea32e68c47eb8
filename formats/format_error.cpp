// Formats FormatError messages as "file: byte N: reason" or "file:LINE: reason".
#include "format_error.h"

namespace tw {
namespace {

std::string describe(const std::string& file, FormatError::Where where, uint64_t position,
                     const std::string& reason) {
  switch (where) {
    case FormatError::Where::Byte:
      return file + ": byte " + std::to_string(position) + ": " + reason;
    case FormatError::Where::Line:
      return file + ":" + std::to_string(position) + ": " + reason;
    case FormatError::Where::None:
      break;
  }
  return file + ": " + reason;
}

}  // namespace

FormatError::FormatError(const std::string& file, Where where, uint64_t position,
                         const std::string& reason)
    : std::runtime_error(describe(file, where, position, reason)),
      file_(file),
      where_(where),
      position_(position),
      reason_(reason) {}

FormatError::FormatError(const std::string& file, const std::string& reason)
    : FormatError(file, Where::None, 0, reason) {}

FormatError FormatError::atByte(const std::string& file, uint64_t offset,
                                const std::string& reason) {
  return FormatError(file, Where::Byte, offset, reason);
}

FormatError FormatError::atLine(const std::string& file, uint64_t line,
                                const std::string& reason) {
  return FormatError(file, Where::Line, line, reason);
}

}  // namespace tw
