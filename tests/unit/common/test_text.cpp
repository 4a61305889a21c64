// The one strict number parser and the one fixed-point formatter.
#include <carenav/common/text.h>

#include <gtest/gtest.h>

#include <cmath>

using carenav::NonFinite;
using carenav::parseNumber;

TEST(ParseNumber, WholeTextOrNothing) {
  EXPECT_EQ(parseNumber("1.5"), 1.5);
  EXPECT_EQ(parseNumber("-2e3"), -2000.0);
  EXPECT_EQ(parseNumber("  7"), 7.0);  // strtod skips leading blanks
  for (const char* bad : {"", " ", "1.5x", "1.5 ", "x", "1,5", "--1", "1e400", "1e-400"})
    EXPECT_FALSE(parseNumber(bad).has_value()) << "'" << bad << "'";
}

TEST(ParseNumber, NonFiniteOnlyWhenAllowed) {
  for (const char* t : {"inf", "-inf", "nan", "NaN", "infinity"}) {
    EXPECT_FALSE(parseNumber(t).has_value()) << t;
    const auto v = parseNumber(t, NonFinite::Allow);
    ASSERT_TRUE(v.has_value()) << t;
    EXPECT_FALSE(std::isfinite(*v)) << t;
  }
  EXPECT_FALSE(parseNumber("1e400", NonFinite::Allow).has_value());  // out of range, not inf
  EXPECT_EQ(parseNumber("1e400", NonFinite::Saturate), HUGE_VAL);    // as strtod saturates
  EXPECT_FALSE(parseNumber("1e400x", NonFinite::Saturate).has_value());
}

TEST(FormatFixed, Digits) {
  EXPECT_EQ(carenav::formatFixed(1.23456), "1.235");
  EXPECT_EQ(carenav::formatFixed(2, 0), "2");
  EXPECT_EQ(carenav::formatFixed(-0.5, 1), "-0.5");
}
