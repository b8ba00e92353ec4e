// Tests for the strict numeric command-line options (cli_numbers.h): every
// text that is not one finite number within the range is refused, with the
// option and the range named; the range's edges are accepted.
#include "cli_numbers.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <limits>
#include <vector>

namespace moco::cli {
namespace {

TEST(ParseNumber, UnsignedTakesOnlyDecimalDigitsThatFit) {
  EXPECT_EQ(ParseNumber<uint64_t>("0"), 0u);
  EXPECT_EQ(ParseNumber<uint64_t>("18446744073709551615"), UINT64_MAX);
  for (const char* bad : {"", "-1", "+1", "18446744073709551616", "1e23", "1.0", " 1", "1 ", "0x10",
                          "nan", "inf", "1x"}) {
    EXPECT_FALSE(ParseNumber<uint64_t>(bad).has_value()) << bad;
  }
}

TEST(ParseNumber, SignedTakesAMinusSign) {
  EXPECT_EQ(ParseNumber<int64_t>("-5"), -5);
  EXPECT_FALSE(ParseNumber<int64_t>("99999999999999999999").has_value());
  EXPECT_FALSE(ParseNumber<int>("--5").has_value());
}

TEST(ParseNumber, FloatingPointMustBeFinite) {
  EXPECT_EQ(ParseNumber<double>("2.5"), 2.5);
  EXPECT_EQ(ParseNumber<double>("1e3"), 1000.0);
  for (const char* bad : {"nan", "NaN", "inf", "-inf", "infinity", "1e400", "", "1.5s", "."}) {
    EXPECT_FALSE(ParseNumber<double>(bad).has_value()) << bad;
  }
}

// Parses `args` (after the program name) with one option --x in [lo, hi].
template <class T>
std::string ParseError(std::vector<std::string> args, T lo, T hi, T& value) {
  CLI::App app;
  AddNumber(&app, "--x", value, lo, hi, "x");
  std::vector<const char*> argv{"prog"};
  for (const std::string& a : args) argv.push_back(a.c_str());
  try {
    app.parse(static_cast<int>(argv.size()), const_cast<char**>(argv.data()));
  } catch (const CLI::ParseError& e) {
    return e.what();
  }
  return "";
}

TEST(AddNumber, OutOfRangeNamesTheOptionAndTheRange) {
  double seconds = 10;
  const std::string e = ParseError<double>({"--x", "nan"}, 0.0, 86400.0, seconds);
  EXPECT_NE(e.find("--x"), std::string::npos) << e;
  EXPECT_NE(e.find("0..86400"), std::string::npos) << e;
  EXPECT_EQ(seconds, 10);
  EXPECT_NE(ParseError<double>({"--x", "86400.5"}, 0.0, 86400.0, seconds), "");
  EXPECT_EQ(ParseError<double>({"--x", "86400"}, 0.0, 86400.0, seconds), "");
  EXPECT_EQ(seconds, 86400);
  uint64_t seed = 1;
  for (const char* bad : {"-1", "18446744073709551616", "1e23"}) {
    const std::string m = ParseError<uint64_t>({"--x", bad}, 0, UINT64_MAX, seed);
    EXPECT_NE(m.find("0..18446744073709551615"), std::string::npos) << bad << ": " << m;
    EXPECT_EQ(seed, 1u) << bad;
  }
  EXPECT_EQ(ParseError<uint64_t>({"--x", "18446744073709551615"}, 0, UINT64_MAX, seed), "");
  EXPECT_EQ(seed, UINT64_MAX);
}

TEST(AddNumber, AbsentOptionKeepsTheDefault) {
  int steps = 40;
  EXPECT_EQ(ParseError<int>({}, 1, 100000, steps), "");
  EXPECT_EQ(steps, 40);
}

}  // namespace
}  // namespace moco::cli
