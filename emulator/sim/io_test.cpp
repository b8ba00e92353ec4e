// Tests for GIO debounce, camera lines and DMX ramps (dmc-v2-protocol.txt
// MSG_GIO_OUT, MSG_GIO_IN, MSG_GIO_CAM, MSG_DMX). Virtual time only.
#include "sim/io.h"

#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>

#include <cmath>
#include <vector>

namespace moco::sim {
namespace {

constexpr TimeNs kMs = kNsPerMs;

struct InputEvent {
  uint32_t inputs;
  uint32_t changed;
  TimeNs time;
};

TEST(GioPortTest, OutputsAreStored) {
  Scheduler s;
  GioPort gio(s, 10 * kMs);
  gio.SetOutputs(0x80000001u);
  EXPECT_EQ(gio.outputs(), 0x80000001u);
}

TEST(GioPortTest, ChangeReportedAfterTheLevelHeldForTheDebounceTime) {
  Scheduler s;
  std::vector<InputEvent> ev;
  GioPort gio(s, 10 * kMs, [&](uint32_t in, uint32_t ch, TimeNs t) { ev.push_back({in, ch, t}); });
  s.RunUntil(100 * kMs);
  gio.SetRawInput(3, true);
  s.RunUntil(109 * kMs);
  EXPECT_EQ(gio.inputs(), 0u);
  EXPECT_TRUE(ev.empty());
  s.RunUntil(110 * kMs);
  ASSERT_EQ(ev.size(), 1u);
  EXPECT_EQ(ev[0].inputs, 0x8u);
  EXPECT_EQ(ev[0].changed, 0x8u);
  EXPECT_EQ(ev[0].time, 110 * kMs);
  EXPECT_EQ(gio.inputs(), 0x8u);
}

TEST(GioPortTest, GlitchShorterThanDebounceIsNeverSeen) {
  Scheduler s;
  std::vector<InputEvent> ev;
  GioPort gio(s, 10 * kMs, [&](uint32_t in, uint32_t ch, TimeNs t) { ev.push_back({in, ch, t}); });
  gio.SetRawInput(0, true);
  s.RunUntil(9 * kMs);
  gio.SetRawInput(0, false);
  s.RunUntil(1000 * kMs);
  EXPECT_TRUE(ev.empty());
  EXPECT_EQ(gio.inputs(), 0u);
}

TEST(GioPortTest, BouncingRestartsTheDebounceFromTheLastChange) {
  Scheduler s;
  std::vector<InputEvent> ev;
  GioPort gio(s, 10 * kMs, [&](uint32_t in, uint32_t ch, TimeNs t) { ev.push_back({in, ch, t}); });
  gio.SetRawInput(5, true);
  s.RunUntil(4 * kMs);
  gio.SetRawInput(5, false);
  s.RunUntil(6 * kMs);
  gio.SetRawInput(5, true);  // held from 6 ms on
  s.RunUntil(1000 * kMs);
  ASSERT_EQ(ev.size(), 1u);
  EXPECT_EQ(ev[0].time, 16 * kMs);
  EXPECT_EQ(gio.raw_inputs(), 0x20u);
}

// Law: the debounced inputs change only where the raw level held for the
// whole debounce time, and then exactly debounce_ns after the last change.
RC_GTEST_PROP(GioPortProp, DebounceMatchesAReferenceModel,
              (const std::vector<std::pair<uint8_t, bool>>& changes)) {
  const TimeNs debounce = 10 * kMs;
  Scheduler s;
  std::vector<InputEvent> ev;
  GioPort gio(s, debounce, [&](uint32_t in, uint32_t ch, TimeNs t) { ev.push_back({in, ch, t}); });
  // One input; each change happens gap ms after the previous one.
  std::vector<std::pair<TimeNs, bool>> raw;  // (time, level)
  TimeNs t = 0;
  for (const auto& [gap, level] : changes) {
    t += (gap % 25) * kMs;
    s.RunUntil(t);
    gio.SetRawInput(0, level);
    raw.push_back({t, level});
  }
  s.RunUntil(t + 1000 * kMs);
  // Reference: a level is accepted when it held for at least debounce (a
  // change at exactly that instant comes after the acceptance), and it
  // differs from the last accepted level.
  std::vector<std::pair<TimeNs, bool>> want;
  bool stable = false;
  bool last_raw = false;
  for (size_t i = 0; i < raw.size(); ++i) {
    if (raw[i].second == last_raw) continue;  // not a change
    last_raw = raw[i].second;
    TimeNs next = kTimeNever;
    for (size_t j = i + 1; j < raw.size(); ++j) {
      if (raw[j].second != last_raw) {
        next = raw[j].first;
        break;
      }
    }
    if (next == kTimeNever || next - raw[i].first >= debounce) {
      if (last_raw != stable) {
        stable = last_raw;
        want.push_back({raw[i].first + debounce, stable});
      }
    }
  }
  RC_ASSERT(ev.size() == want.size());
  for (size_t i = 0; i < ev.size(); ++i) {
    RC_ASSERT(ev[i].time == want[i].first);
    RC_ASSERT(((ev[i].inputs & 1u) != 0) == want[i].second);
  }
}

TEST(CameraPortTest, ExposeOpensAndClosesAtTheRightTimes) {
  Scheduler s;
  CameraPort cam(s);
  s.RunUntil(5 * kMs);
  EXPECT_EQ(cam.Expose(250 * kMs), 255 * kMs);
  EXPECT_TRUE(cam.level(CameraPort::kShutter));
  s.RunUntilIdle();
  EXPECT_FALSE(cam.level(CameraPort::kShutter));
  const std::vector<CameraPort::Edge> want = {{5 * kMs, CameraPort::kShutter, true},
                                              {255 * kMs, CameraPort::kShutter, false}};
  EXPECT_EQ(cam.Trace(), want);
  EXPECT_EQ(cam.exposures(), 1u);
}

TEST(CameraPortTest, GioCamFlagsDriveShutterAndMeter) {
  Scheduler s;
  CameraPort cam(s, 3);
  cam.SetFlags(0x2);  // GIO_CAM_METER
  EXPECT_TRUE(cam.level(CameraPort::kMeter));
  EXPECT_FALSE(cam.level(CameraPort::kShutter));
  s.RunUntil(1 * kMs);
  cam.SetFlags(0x3);
  s.RunUntil(2 * kMs);
  cam.SetFlags(0x0);
  const auto trace = cam.Trace();  // capacity 3: the oldest of 4 dropped
  ASSERT_EQ(trace.size(), 3u);
  EXPECT_EQ(cam.dropped(), 1u);
  EXPECT_EQ(trace[0], (CameraPort::Edge{1 * kMs, CameraPort::kShutter, true}));
  EXPECT_EQ(trace[1], (CameraPort::Edge{2 * kMs, CameraPort::kShutter, false}));
  EXPECT_EQ(trace[2], (CameraPort::Edge{2 * kMs, CameraPort::kMeter, false}));
}

TEST(CameraPortTest, SettingTheShutterCancelsAPendingClose) {
  Scheduler s;
  CameraPort cam(s);
  cam.Expose(100 * kMs);
  s.RunUntil(50 * kMs);
  cam.Set(CameraPort::kShutter, false);
  cam.Set(CameraPort::kShutter, true);  // bulb, held open
  s.RunUntil(500 * kMs);
  EXPECT_TRUE(cam.level(CameraPort::kShutter));
}

TEST(DmxTest, ImmediateSetAndChannelRange) {
  Scheduler s;
  DmxUniverse dmx(s, 100);
  EXPECT_TRUE(dmx.Set(1, 200));
  EXPECT_TRUE(dmx.Set(512, 7));
  EXPECT_FALSE(dmx.Set(0, 1));
  EXPECT_FALSE(dmx.Set(513, 1));
  EXPECT_EQ(dmx.Value(1), 200);
  EXPECT_EQ(dmx.Value(512), 7);
  EXPECT_FALSE(dmx.Adjusting());
}

TEST(DmxTest, RampReachesTargetAtTheComputedTimeAndReportsAdjusting) {
  Scheduler s;
  std::vector<TimeNs> settled;
  DmxUniverse dmx(s, 100, [&](TimeNs t) { settled.push_back(t); });  // 100 units/s
  dmx.Set(10, 50);
  s.RunUntil(1000 * kMs);
  ASSERT_TRUE(dmx.RampTo(10, 250));  // 200 units: 2 s
  EXPECT_TRUE(dmx.Adjusting());
  EXPECT_EQ(dmx.ReachTime(10), 3000 * kMs);
  s.RunUntil(1500 * kMs);
  EXPECT_EQ(dmx.Value(10), 100);  // 50 + 100 * 0.5
  s.RunUntil(2999 * kMs);
  EXPECT_EQ(dmx.Value(10), 249);
  EXPECT_TRUE(dmx.Adjusting());
  s.RunUntil(3000 * kMs);
  EXPECT_EQ(dmx.Value(10), 250);
  EXPECT_FALSE(dmx.Adjusting());
  EXPECT_EQ(settled, std::vector<TimeNs>{3000 * kMs});
}

TEST(DmxTest, RampDownAndRetargetFromTheCurrentValue) {
  Scheduler s;
  DmxUniverse dmx(s, 40);
  dmx.Set(1, 200);
  dmx.RampTo(1, 0);  // 5 s
  s.RunUntil(1000 * kMs);
  EXPECT_EQ(dmx.Value(1), 160);
  dmx.RampTo(1, 180);  // from 160: 0.5 s
  EXPECT_EQ(dmx.ReachTime(1), 1500 * kMs);
  s.RunUntil(1250 * kMs);
  EXPECT_EQ(dmx.Value(1), 170);
  s.RunUntilIdle();
  EXPECT_EQ(dmx.Value(1), 180);
}

TEST(DmxTest, MsgDmxAppliesConsecutiveChannelsAndDropsPast512) {
  Scheduler s;
  DmxUniverse dmx(s, 255);
  EXPECT_TRUE(dmx.Apply(false, 511, {1, 2, 3}));
  EXPECT_EQ(dmx.Value(511), 1);
  EXPECT_EQ(dmx.Value(512), 2);
  EXPECT_FALSE(dmx.Apply(false, 0, {1}));
  EXPECT_TRUE(dmx.Apply(true, 1, {255, 255}));
  EXPECT_TRUE(dmx.Adjusting());
  s.RunUntilIdle();
  EXPECT_EQ(s.Now(), 1000 * kMs);
  EXPECT_FALSE(dmx.Adjusting());
}

// Law: a ramp is monotonic, moves at most rate units per second, and is on
// target exactly from ReachTime on.
RC_GTEST_PROP(DmxProp, RampIsMonotonicBoundedAndArrivesOnTime,
              (uint8_t from, uint8_t to, uint16_t rate_raw)) {
  const double rate = 1 + rate_raw % 1000;
  Scheduler s;
  DmxUniverse dmx(s, rate);
  dmx.Set(7, from);
  dmx.RampTo(7, to);
  const TimeNs reach = dmx.ReachTime(7);
  RC_ASSERT(reach == static_cast<TimeNs>(std::ceil(std::abs(to - from) / rate * 1e9)));
  int prev = from;
  for (int i = 0; i <= 64; ++i) {
    const TimeNs t = reach * i / 64;
    const int v = dmx.ValueAt(7, t);
    const bool monotonic = to >= from ? v >= prev : v <= prev;
    RC_ASSERT(monotonic);
    const bool bounded = std::abs(v - from) <= rate * static_cast<double>(t) / 1e9 + 1e-9;
    RC_ASSERT(bounded);
    prev = v;
  }
  RC_ASSERT(dmx.ValueAt(7, reach) == to);
  if (reach > 0) RC_ASSERT(dmx.ValueAt(7, reach - 1) != to);
}

}  // namespace
}  // namespace moco::sim
