// Number scanning used by every text reader: exact on common forms, strict on garbage.
#include <gtest/gtest.h>

#include <limits>

#include <cmath>
#include <cstdlib>
#include <string>

#include "text_scan.h"

namespace tw::text {
namespace {

double parsed(std::string s) {
  std::string_view v = s;
  double d = NAN;
  EXPECT_TRUE(parseDouble(v, d)) << s;
  return d;
}

bool rejects(std::string s) {
  std::string_view v = s;
  double d;
  return !parseDouble(v, d);
}

TEST(TextScan, ParsesCommonDecimalForms) {
  EXPECT_EQ(parsed("18.860"), 18.86);
  EXPECT_EQ(parsed("-7.988"), -7.988);
  EXPECT_EQ(parsed("+3"), 3.0);
  EXPECT_EQ(parsed("0.000123"), 0.000123);
  EXPECT_EQ(parsed("1e3"), 1000.0);
  EXPECT_EQ(parsed("2.5E-2"), 0.025);
  EXPECT_EQ(parsed(".5"), 0.5);
  EXPECT_EQ(parsed("5."), 5.0);
  EXPECT_EQ(parsed("   42"), 42.0);
}

TEST(TextScan, MatchesStrtodOnLongAndExtremeInputs) {
  for (const char* s : {"3.14159265358979323846264338327950288", "123456789012345678901234",
                        "1e-300", "6.02214076e23", "-0.1000000000000000055511151231257827"}) {
    EXPECT_EQ(parsed(s), std::strtod(s, nullptr)) << s;
  }
}

TEST(TextScan, RejectsGarbage) {
  EXPECT_TRUE(rejects(""));
  EXPECT_TRUE(rejects("-"));
  EXPECT_TRUE(rejects("abc"));
  EXPECT_TRUE(rejects("1.2.3"));
  EXPECT_TRUE(rejects("1e"));
  EXPECT_TRUE(rejects("1x"));
  EXPECT_TRUE(rejects("nan"));
  EXPECT_TRUE(rejects("1e999"));
}

TEST(TextScan, ConsumesOneNumberAndStopsAtSeparators) {
  std::string_view v = "1.5 -2 3e1/7";
  double a, b, c;
  ASSERT_TRUE(parseDouble(v, a));
  ASSERT_TRUE(parseDouble(v, b));
  ASSERT_TRUE(parseDouble(v, c));
  EXPECT_EQ(a, 1.5);
  EXPECT_EQ(b, -2.0);
  EXPECT_EQ(c, 30.0);
  EXPECT_EQ(v, "/7");
}

TEST(TextScan, FloatRangeIsChecked) {
  std::string_view v = "1e39";
  float f;
  EXPECT_FALSE(parseFloat(v, f));
}

TEST(TextScan, IntegersIncludingNegativeAndOverflow) {
  std::string_view v = " -12 7/8 ";
  int64_t a, b;
  ASSERT_TRUE(parseInt64(v, a));
  ASSERT_TRUE(parseInt64(v, b));
  EXPECT_EQ(a, -12);
  EXPECT_EQ(b, 7);
  std::string_view big = "99999999999999999999";
  EXPECT_FALSE(parseInt64(big, a));
  std::string_view frac = "3.5";
  EXPECT_FALSE(parseInt64(frac, a));
}

// Numbers past int64 that wrap the uint64 accumulator itself (2^64 + 8 and 2^64 + 3) are refused,
// not read as 8 and 3; the largest int64 still reads.
TEST(TextScan, IntegersThatWrapSixtyFourBitsAreRefused) {
  int64_t a = 0;
  for (std::string_view wrapping : {"18446744073709551624", "18446744073709551619",
                                    "9223372036854775808", "-9223372036854775809"}) {
    std::string_view v = wrapping;
    EXPECT_FALSE(parseInt64(v, a)) << wrapping << " read as " << a;
  }
  std::string_view largest = "9223372036854775807";
  ASSERT_TRUE(parseInt64(largest, a));
  EXPECT_EQ(a, std::numeric_limits<int64_t>::max());
  std::string_view negative = "-9223372036854775807";
  ASSERT_TRUE(parseInt64(negative, a));
  EXPECT_EQ(a, -std::numeric_limits<int64_t>::max());
}

TEST(TextScan, Tokens) {
  std::string_view v = "  usemtl  steel grey\r";
  EXPECT_EQ(nextToken(v), "usemtl");
  EXPECT_EQ(nextToken(v), "steel");
  EXPECT_EQ(nextToken(v), "grey");
  EXPECT_EQ(nextToken(v), "");
}

}  // namespace
}  // namespace tw::text
