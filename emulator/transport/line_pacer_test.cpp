// Tests for serial line pacing (wire/line.h LineSettings): a byte at
// baud B, 8N1, takes 10/B s, and reaches the far end when its stop bit ends.
#include "transport/line_pacer.h"

#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>

#include <vector>

#include "wire/line.h"

namespace moco::transport {
namespace {

using sim::TimeNs;

TEST(LinePacerTest, BytesPerSecondIsBaudOverTenFor8N1) {
  wire::LineSettings line;
  line.baud = 115200;
  EXPECT_EQ(line.BytesPerSecond(), 11520u);
  line.baud = 57600;  // DFMoco
  EXPECT_EQ(line.BytesPerSecond(), 5760u);
  line.baud = 38400;  // StackShot
  EXPECT_EQ(line.BytesPerSecond(), 3840u);
}

TEST(LinePacerTest, UnpacedByteIsDueWhenReady) {
  LinePacer p(0);
  EXPECT_FALSE(p.paced());
  EXPECT_EQ(p.Take(5), 5);
  EXPECT_EQ(p.Take(5), 5);
  EXPECT_EQ(p.DueTime(7), 7);
}

TEST(LinePacerTest, BurstAt115200CompletesOneCharacterTimeApart) {
  // 1e9 / 11520 = 86805.55... ns per byte: byte k of a burst starting at 0
  // ends at ceil((k + 1) * 86805.55...).
  LinePacer p(11520);
  EXPECT_EQ(p.Take(0), 86806);
  EXPECT_EQ(p.Take(0), 173612);  // 173611.1 rounded up
  EXPECT_EQ(p.Take(0), 260417);  // 260416.7 rounded up
  EXPECT_EQ(p.Take(0), 347223);  // 347222.2 rounded up
}

TEST(LinePacerTest, OneSecondOfBytesTakesExactlyOneSecond) {
  LinePacer p(11520);
  TimeNs last = 0;
  for (int i = 0; i < 11520; ++i) last = p.Take(1000);
  EXPECT_EQ(last, 1000 + sim::kNsPerSecond);
  for (int i = 0; i < 11520; ++i) last = p.Take(1000);
  EXPECT_EQ(last, 1000 + 2 * sim::kNsPerSecond);
  // And the next byte is one character time later: no drift after 2 s.
  EXPECT_EQ(p.Take(1000), 1000 + 2 * sim::kNsPerSecond + 86806);
}

TEST(LinePacerTest, ByteReadyOnAnIdleLineStartsANewBurst) {
  LinePacer p(3840);  // 38400 baud: 260416.67 ns per byte
  EXPECT_EQ(p.Take(0), 260417);
  // Ready long after the line went idle: one character time after ready.
  EXPECT_EQ(p.Take(10'000'000), 10'260'417);
  // Ready exactly when the previous byte ended: starts right then.
  EXPECT_EQ(p.Take(10'260'417), 10'520'834);
}

TEST(LinePacerTest, ByteReadyWhileLineBusyWaitsForIt) {
  LinePacer p(5760);  // 57600 baud: 173611.1 ns per byte
  EXPECT_EQ(p.Take(0), 173612);
  // Ready mid-byte: it follows the previous byte back to back.
  EXPECT_EQ(p.Take(100'000), 347223);
}

TEST(LinePacerTest, DueTimeDoesNotChangeState) {
  LinePacer p(11520);
  EXPECT_EQ(p.DueTime(0), 86806);
  EXPECT_EQ(p.DueTime(0), 86806);
  EXPECT_EQ(p.Take(0), 86806);
  EXPECT_EQ(p.DueTime(0), 173612);
  p.Reset();
  EXPECT_EQ(p.DueTime(500), 500 + 86806);
}

// Law: whatever the ready times, consecutive bytes end at least one
// character time apart (rounded down), never before ready + one character
// time (rounded up), and never later than needed.
RC_GTEST_PROP(LinePacerProp, RespectsTheLineRate, ()) {
  const auto bps = *rc::gen::element<uint32_t>(960, 3840, 5760, 11520, 100000);
  const auto gaps = *rc::gen::container<std::vector<TimeNs>>(
      rc::gen::inRange<TimeNs>(0, 2 * sim::kNsPerSecond / bps));
  LinePacer p(bps);
  const TimeNs byte_floor = sim::kNsPerSecond / bps;
  const TimeNs byte_ceil = (sim::kNsPerSecond + bps - 1) / bps;
  TimeNs ready = 0;
  TimeNs prev_due = -1;
  for (TimeNs gap : gaps) {
    ready += gap;
    const TimeNs due = p.Take(ready);
    RC_ASSERT(due >= ready + byte_floor);
    RC_ASSERT(due <= std::max(ready, prev_due) + byte_ceil);
    if (prev_due >= 0) RC_ASSERT(due - prev_due >= byte_floor);
    prev_due = due;
  }
}

}  // namespace
}  // namespace moco::transport
