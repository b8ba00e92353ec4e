// Ms, Hex, HexBytes and ParseHex32 (format.h).
#include "base/format.h"

#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>

#include <cstdint>
#include <vector>

namespace moco::base {
namespace {

TEST(Ms, NanosecondsAsMillisecondsWithTheGivenDecimals) {
  EXPECT_EQ(Ms(12'345'678), "12.3 ms");
  EXPECT_EQ(Ms(12'345'678, 3), "12.346 ms");
  EXPECT_EQ(Ms(0), "0.0 ms");
  EXPECT_EQ(Ms(-1'500'000), "-1.5 ms");
  EXPECT_EQ(Ms(2'000'000, 0), "2 ms");
}

TEST(Hex, ZeroPaddedToAtLeastTheDigitsGiven) {
  EXPECT_EQ(Hex(0x7ff, 4), "0x07ff");
  EXPECT_EQ(Hex(0, 2), "0x00");
  EXPECT_EQ(Hex(0xdeadbeef, 8), "0xdeadbeef");
  EXPECT_EQ(Hex(0x12345, 4), "0x12345");
  EXPECT_EQ(Hex(0xAB, 2), "0xab");
}

TEST(HexBytes, TwoLowerCaseDigitsAByte) {
  const std::vector<uint8_t> bytes = {0x44, 0x46, 0x01, 0x00, 0xff};
  EXPECT_EQ(HexBytes(bytes), "44460100ff");
  EXPECT_EQ(HexBytes({}), "");
}

TEST(ParseHex32, ReadsPrefixedHexOfUpToEightDigits) {
  EXPECT_EQ(ParseHex32("0x0403"), 0x0403u);
  EXPECT_EQ(ParseHex32("0XfFfFfFfF"), 0xffffffffu);
  EXPECT_EQ(ParseHex32("0x0"), 0u);
  EXPECT_EQ(ParseHex32("0x"), std::nullopt);
  EXPECT_EQ(ParseHex32("403"), std::nullopt);
  EXPECT_EQ(ParseHex32("0xZZ"), std::nullopt);
  EXPECT_EQ(ParseHex32("0x123456789"), std::nullopt);
  EXPECT_EQ(ParseHex32(""), std::nullopt);
}

RC_GTEST_PROP(ParseHex32Property, ReadsBackWhatHexWrote, (uint32_t v)) {
  RC_ASSERT(ParseHex32(Hex(v, 8)) == std::optional<uint32_t>(v));
  RC_ASSERT(ParseHex32(Hex(v, 1)) == std::optional<uint32_t>(v));
}

}  // namespace
}  // namespace moco::base
