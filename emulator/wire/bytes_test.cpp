// Tests for the shared byte-order helpers: the spec's own byte-order examples
// (stackshot-protocol.txt section 2, "Byte ordering") and hex round trips.
#include "wire/bytes.h"

#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>

namespace moco::wire {
namespace {

TEST(BytesTest, U32LittleEndianMatchesStackShotExample) {
  Bytes out;
  Writer(out).U32Le(0x12345678u);
  EXPECT_EQ(ToHex(out), "78563412");
}

TEST(BytesTest, F32LittleEndianMatchesStackShotExample) {
  Bytes out;
  Writer(out).F32Le(12345678.0f);
  EXPECT_EQ(ToHex(out), "4e613c4b");
}

TEST(BytesTest, ReaderNeverReadsPastEnd) {
  const Bytes in = {1, 2, 3};
  Reader r(in);
  uint32_t v = 0xdeadbeef;
  EXPECT_FALSE(r.U32Le(v));
  EXPECT_EQ(v, 0xdeadbeefu);
  uint16_t w = 0;
  EXPECT_TRUE(r.U16Le(w));
  EXPECT_EQ(w, 0x0201);
  EXPECT_FALSE(r.U16Le(w));
  uint8_t b = 0;
  EXPECT_TRUE(r.U8(b));
  EXPECT_EQ(b, 3);
  EXPECT_TRUE(r.empty());
}

TEST(BytesTest, FromHexRejectsOddAndNonHex) {
  EXPECT_FALSE(FromHex("abc").has_value());
  EXPECT_FALSE(FromHex("zz").has_value());
  EXPECT_EQ(FromHex("44 46:01-00"), (Bytes{0x44, 0x46, 0x01, 0x00}));
}

RC_GTEST_PROP(BytesProp, HexRoundTrip, (const std::vector<uint8_t>& bytes)) {
  RC_ASSERT(FromHex(ToHex(bytes)) == bytes);
}

RC_GTEST_PROP(BytesProp, IntegersRoundTrip, (uint32_t a, int32_t b, uint16_t c, int16_t d)) {
  Bytes out;
  Writer w(out);
  w.U32Le(a);
  w.I32Le(b);
  w.U16Le(c);
  w.I16Le(d);
  w.U16Be(c);
  Reader r(out);
  uint32_t a2 = 0;
  int32_t b2 = 0;
  uint16_t c2 = 0, c3 = 0;
  int16_t d2 = 0;
  RC_ASSERT(r.U32Le(a2) && r.I32Le(b2) && r.U16Le(c2) && r.I16Le(d2) && r.U16Be(c3));
  RC_ASSERT(a2 == a && b2 == b && c2 == c && d2 == d && c3 == c);
  RC_ASSERT(r.empty());
}

}  // namespace
}  // namespace moco::wire
