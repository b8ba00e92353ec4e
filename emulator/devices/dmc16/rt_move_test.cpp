// The upload store of real-time moves (MSG_RT_UPLOAD_MOVE_*): range rules,
// retries, the last-set rule, gaps.
#include "devices/dmc16/rt_move.h"

#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>

namespace moco::devices {
namespace {

using dmc::AckCode;

TEST(RtMove, ResentSectionOverwritesAndCompletes) {
  RtMove m(100, 4, 8);
  ASSERT_TRUE(m.Begin(0, 9).ok());
  ASSERT_TRUE(m.Axis({1, 0, false, {1, 2, 3, 4, 5}}).ok());
  ASSERT_TRUE(m.Axis({1, 0, false, {9, 2, 3, 4, 5}}).ok());  // a retry with other data
  ASSERT_TRUE(m.Axis({1, 5, false, {6, 7, 8, 9, 10}}).ok());
  ASSERT_TRUE(m.End().ok());
  EXPECT_EQ(m.Position(1, 0), 9);
  EXPECT_EQ(m.Position(1, 9), 10);
  EXPECT_EQ(m.Motors(), std::vector<int>{1});
  EXPECT_TRUE(m.Contains(9));
  EXPECT_FALSE(m.Contains(10));
}

TEST(RtMove, BeginClearsThePreviousMove) {
  RtMove m(100, 4, 8);
  ASSERT_TRUE(m.Begin(0, 9).ok());
  ASSERT_TRUE(m.Axis({1, 0, true, {1}}).ok());
  ASSERT_TRUE(m.End().ok());
  ASSERT_TRUE(m.Begin(5, 6).ok());
  EXPECT_FALSE(m.complete());
  EXPECT_TRUE(m.Motors().empty());
}

TEST(RtMove, TriggersAreMaskedAndZeroWhereAbsent) {
  RtMove m(100, 4, 8);
  ASSERT_TRUE(m.Begin(10, 19).ok());
  ASSERT_TRUE(m.Triggers({0x5, {{2, 0xff}}}).ok());
  ASSERT_TRUE(m.End().ok());
  EXPECT_EQ(m.TriggersAt(12), 0x5u);
  EXPECT_EQ(m.TriggersAt(13), 0u);
  EXPECT_EQ(m.trigger_mask(), 0x5u);
}

// A trigger frame index past the upload: ERR_RANGE (the spec's reading of
// "Frame index (frame - start)"), or, unchecked (dmc-lite), the point is
// dropped and the section taken.
TEST(RtMove, TriggerFramesPastTheUploadAreRefusedOrDropped) {
  for (const bool checked : {true, false}) {
    RtMove m(100, 4, 8);
    m.SetTriggerFramesChecked(checked);
    ASSERT_TRUE(m.Begin(10, 19).ok());
    EXPECT_EQ(m.Triggers({0x3, {{2, 0x1}, {10, 0x2}}}).code,
              checked ? AckCode::kErrRange : AckCode::kOk);
    ASSERT_TRUE(m.End().ok());
    EXPECT_EQ(m.TriggersAt(12), checked ? 0u : 0x1u) << "a refused section sets nothing";
    EXPECT_EQ(m.TriggersAt(19), 0u);
    EXPECT_EQ(m.trigger_mask(), checked ? 0u : 0x3u);
  }
}

TEST(RtMove, FrameCountBoundIsInclusive) {
  RtMove m(10, 1, 0);
  EXPECT_TRUE(m.Begin(0, 9).ok());
  EXPECT_EQ(m.Begin(0, 10).code, AckCode::kErrRange);
  EXPECT_EQ(m.Begin(0xffffffffu, 0xffffffffu).code, AckCode::kOk);
  EXPECT_EQ(m.Dmx({1, 0, true, {1}}).code, AckCode::kErrRange) << "no DMX channels";
}

// Law: sections covering [0, k) plus a last set ending at k give every frame
// a value, and frames >= k hold the last value.
RC_GTEST_PROP(RtMoveLaws, LastSetFillsTheRest, ()) {
  const uint32_t frames = *rc::gen::inRange<uint32_t>(1, 300);
  const uint32_t k = *rc::gen::inRange<uint32_t>(1, frames + 1);
  std::vector<int32_t> values =
      *rc::gen::container<std::vector<int32_t>>(k, rc::gen::arbitrary<int32_t>());
  RtMove m(frames, 1, 0);
  RC_ASSERT(m.Begin(1000, 1000 + frames - 1).ok());
  // Upload in random-sized sections, the final one flagged.
  uint32_t i = 0;
  while (i < k) {
    const uint32_t len = *rc::gen::inRange<uint32_t>(1, k - i + 1);
    RC_ASSERT(m.Axis({1, i, i + len == k,
                      std::vector<int32_t>(values.begin() + i, values.begin() + i + len)})
                  .ok());
    i += len;
  }
  RC_ASSERT(m.End().ok());
  for (uint32_t f = 0; f < frames; ++f) {
    const int32_t expect = f < k ? values[f] : values[k - 1];
    RC_ASSERT(m.Position(1, 1000 + f) == expect);
  }
}

}  // namespace
}  // namespace moco::devices
