// Unit tests of the shared argument parsers (liggghts_mpm/mpm/args.h): what is accepted, what is
// refused, and that nothing is wrapped or clipped.
#include <gtest/gtest.h>

#include <cstdint>
#include <limits>

#include "mpm/args.h"

using mpm::axis_of;
using mpm::parse_double;
using mpm::parse_int;
using mpm::parse_int64;
using mpm::parse_yesno;

TEST(Args, DoubleAccepted) {
  const std::pair<const char *, double> ok[] = {{"1", 1.0},       {"-2.5", -2.5},  {"+.5", 0.5},
                                                {"5.", 5.0},      {"1e-3", 1e-3},  {"2E+6", 2e6},
                                                {"0", 0.0},       {"-0", -0.0},    {"1.7976931348623157e308", 1.7976931348623157e308},
                                                {"2.2250738585072014e-308", 2.2250738585072014e-308}};
  for (const auto &c : ok) {
    double v = -99.0;
    EXPECT_TRUE(parse_double(c.first, v)) << c.first;
    EXPECT_EQ(v, c.second) << c.first;
  }
}

TEST(Args, DoubleRefused) {
  const char *bad[] = {"", " 1", "1 ", "\t1", "1\n", "1x", "1.0.0", "abc", "nan", "NaN", "-nan", "inf", "-inf",
                       "infinity", "0x10", "0x1p3", "1e999", "-1e999", "1e-400", "1e-310", "1,5", "--1", "e5"};
  for (const char *s : bad) {
    double v = 42.0;
    EXPECT_FALSE(parse_double(s, v)) << "'" << s << "'";
    EXPECT_EQ(v, 42.0) << "'" << s << "': the target is left alone";
  }
  double v = 0.0;
  EXPECT_FALSE(parse_double(nullptr, v));
}

TEST(Args, Int64) {
  std::int64_t v = 0;
  EXPECT_TRUE(parse_int64("4294967298", v));
  EXPECT_EQ(v, 4294967298LL);
  EXPECT_TRUE(parse_int64("9223372036854775807", v));
  EXPECT_EQ(v, std::numeric_limits<std::int64_t>::max());
  EXPECT_TRUE(parse_int64("-9223372036854775808", v));
  EXPECT_EQ(v, std::numeric_limits<std::int64_t>::min());
  EXPECT_TRUE(parse_int64("+3", v));
  EXPECT_EQ(v, 3);
  EXPECT_TRUE(parse_int64("007", v));  // base 10, not octal
  EXPECT_EQ(v, 7);
  v = 5;
  const char *bad[] = {"",  "9223372036854775808", "-9223372036854775809", "18446744073709551617", " 1", "1 ",
                       "1x", "1.0", "1e3", "0x10", "nan", "inf", "-", "+"};
  for (const char *s : bad) {
    EXPECT_FALSE(parse_int64(s, v)) << "'" << s << "'";
    EXPECT_EQ(v, 5) << s;
  }
}

TEST(Args, IntRange) {
  int v = 0;
  EXPECT_TRUE(parse_int("2147483647", v));
  EXPECT_EQ(v, 2147483647);
  EXPECT_TRUE(parse_int("-2147483648", v));
  EXPECT_EQ(v, -2147483647 - 1);
  v = 9;
  // 2^31 and 2^32 + 2 would wrap to -2^31 and 2 in a 32-bit int: refused
  EXPECT_FALSE(parse_int("2147483648", v));
  EXPECT_FALSE(parse_int("4294967298", v));
  EXPECT_FALSE(parse_int("-2147483649", v));
  EXPECT_EQ(v, 9);
  EXPECT_TRUE(parse_int("8", v, 1, 8));
  EXPECT_EQ(v, 8);
  EXPECT_FALSE(parse_int("9", v, 1, 8));
  EXPECT_FALSE(parse_int("0", v, 1, 8));
  EXPECT_FALSE(parse_int("-3", v, 0));
  EXPECT_EQ(v, 8);
}

TEST(Args, YesNoAndAxis) {
  bool b = false;
  EXPECT_TRUE(parse_yesno("yes", b));
  EXPECT_TRUE(b);
  EXPECT_TRUE(parse_yesno("no", b));
  EXPECT_FALSE(b);
  for (const char *s : {"Yes", "y", "1", "true", "", " yes", "no "}) EXPECT_FALSE(parse_yesno(s, b)) << s;
  EXPECT_FALSE(parse_yesno(nullptr, b));
  EXPECT_EQ(axis_of("x"), 0);
  EXPECT_EQ(axis_of("y"), 1);
  EXPECT_EQ(axis_of("z"), 2);
  for (const char *s : {"", "X", "w", "xy", " x", "x "}) EXPECT_EQ(axis_of(s), -1) << s;
  EXPECT_EQ(axis_of(nullptr), -1);
}
