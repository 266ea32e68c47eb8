// Fast, locale-independent scanning of numbers and tokens in text formats (OBJ, ASCII PLY/STL).
//
// std::strtod is locale-dependent and slow; these functions parse the plain decimal forms that
// CAD exporters write at several hundred MB/s and report failure instead of guessing.
#pragma once

#include <cstdint>
#include <string_view>

namespace tw::text {

// Skips spaces and tabs at the front of `s`.
inline void skipBlanks(std::string_view& s) {
  size_t i = 0;
  while (i < s.size() && (s[i] == ' ' || s[i] == '\t' || s[i] == '\r')) ++i;
  s.remove_prefix(i);
}

// Removes and returns the next blank-separated token (empty when none is left).
inline std::string_view nextToken(std::string_view& s) {
  skipBlanks(s);
  size_t i = 0;
  while (i < s.size() && s[i] != ' ' && s[i] != '\t' && s[i] != '\r') ++i;
  std::string_view token = s.substr(0, i);
  s.remove_prefix(i);
  return token;
}

// Parses a decimal floating-point number ("-1.5", "2e-3", "inf" and "nan" are rejected) from the
// front of `s`, skipping leading blanks, and removes it. Returns false, leaving `s` unspecified,
// when no number is there or it is followed by something other than a blank, '/' or the end.
bool parseDouble(std::string_view& s, double& out);
bool parseFloat(std::string_view& s, float& out);

// Parses an optionally signed decimal integer the same way. Fails on overflow.
bool parseInt64(std::string_view& s, int64_t& out);

}  // namespace tw::text
