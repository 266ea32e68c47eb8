// Formats FormatError messages as "file: byte N: reason" or "file:LINE: reason".
#include "format_error.h"

namespace tw {
namespace {

std::string describe(const std::string& file, FormatError::Where where, uint64_t position,
                     const std::string& reason) {
  // Built with append() rather than operator+ chains, which GCC 12 flags with a false -Wrestrict.
  std::string out = file;
  switch (where) {
    case FormatError::Where::Byte:
      out.append(": byte ").append(std::to_string(position));
      break;
    case FormatError::Where::Line:
      out.append(":").append(std::to_string(position));
      break;
    case FormatError::Where::None:
      break;
  }
  out.append(": ").append(reason);
  return out;
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
