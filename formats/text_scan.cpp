// Number scanning for text formats. Short mantissas (the common case: "18.860") are computed
// exactly in integer arithmetic and scaled once; long ones fall back to std::from_chars.
#include "text_scan.h"

#include <charconv>
#include <cmath>
#include <limits>

namespace tw::text {
namespace {

inline bool isDigit(char c) { return static_cast<unsigned char>(c - '0') < 10; }
inline bool isEndOfNumber(std::string_view s, size_t i) {
  return i >= s.size() || s[i] == ' ' || s[i] == '\t' || s[i] == '\r' || s[i] == '/';
}

constexpr double kPow10[] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,  1e8,  1e9,  1e10,
                             1e11, 1e12, 1e13, 1e14, 1e15, 1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};

}  // namespace

bool parseDouble(std::string_view& s, double& out) {
  skipBlanks(s);
  size_t i = 0;
  bool negative = false;
  if (i < s.size() && (s[i] == '-' || s[i] == '+')) negative = s[i++] == '-';
  uint64_t mantissa = 0;
  int digits = 0;      // significant digits accumulated in mantissa
  int exponent = 0;    // decimal exponent applied to mantissa
  bool any_digit = false;
  bool exact = true;
  while (i < s.size() && isDigit(s[i])) {
    any_digit = true;
    if (digits < 19) {
      mantissa = mantissa * 10 + static_cast<uint64_t>(s[i] - '0');
      if (mantissa) ++digits;
    } else {
      ++exponent;
      exact = false;
    }
    ++i;
  }
  if (i < s.size() && s[i] == '.') {
    ++i;
    while (i < s.size() && isDigit(s[i])) {
      any_digit = true;
      if (digits < 19) {
        mantissa = mantissa * 10 + static_cast<uint64_t>(s[i] - '0');
        if (mantissa) ++digits;
        --exponent;
      } else {
        exact = false;
      }
      ++i;
    }
  }
  if (!any_digit) return false;
  if (i < s.size() && (s[i] == 'e' || s[i] == 'E')) {
    ++i;
    bool exp_negative = false;
    if (i < s.size() && (s[i] == '-' || s[i] == '+')) exp_negative = s[i++] == '-';
    if (i >= s.size() || !isDigit(s[i])) return false;
    int e = 0;
    while (i < s.size() && isDigit(s[i])) {
      if (e < 100000) e = e * 10 + (s[i] - '0');
      ++i;
    }
    exponent += exp_negative ? -e : e;
  }
  if (!isEndOfNumber(s, i)) return false;
  double value;
  if (exact && mantissa < (uint64_t{1} << 53) && exponent >= -22 && exponent <= 22) {
    value = static_cast<double>(mantissa);
    value = exponent < 0 ? value / kPow10[-exponent] : value * kPow10[exponent];
  } else {
    // Rare: many digits or a large exponent. Let the standard library round correctly.
    const char* begin = s.data() + (s[0] == '+' ? 1 : 0);
    auto result = std::from_chars(begin, s.data() + i, value);
    if (result.ec == std::errc::result_out_of_range) {
      value = exponent < 0 ? 0.0 : std::numeric_limits<double>::infinity();
      if (negative) value = -value;
    } else if (result.ec != std::errc()) {
      return false;
    }
    s.remove_prefix(i);
    out = value;
    return std::isfinite(value);
  }
  out = negative ? -value : value;
  s.remove_prefix(i);
  return true;
}

bool parseFloat(std::string_view& s, float& out) {
  double d;
  if (!parseDouble(s, d)) return false;
  if (std::fabs(d) > static_cast<double>(std::numeric_limits<float>::max())) return false;
  out = static_cast<float>(d);
  return true;
}

bool parseInt64(std::string_view& s, int64_t& out) {
  skipBlanks(s);
  size_t i = 0;
  bool negative = false;
  if (i < s.size() && (s[i] == '-' || s[i] == '+')) negative = s[i++] == '-';
  if (i >= s.size() || !isDigit(s[i])) return false;
  // Checked before each step: value * 10 + digit must stay within int64 (testing after the
  // step missed wraps of the uint64 itself: 18446744073709551624 read as 8).
  constexpr uint64_t kMax = static_cast<uint64_t>(std::numeric_limits<int64_t>::max());
  uint64_t value = 0;
  while (i < s.size() && isDigit(s[i])) {
    const uint64_t digit = static_cast<uint64_t>(s[i] - '0');
    if (value > (kMax - digit) / 10) return false;
    value = value * 10 + digit;
    ++i;
  }
  if (!isEndOfNumber(s, i)) return false;
  out = negative ? -static_cast<int64_t>(value) : static_cast<int64_t>(value);
  s.remove_prefix(i);
  return true;
}

}  // namespace tw::text
