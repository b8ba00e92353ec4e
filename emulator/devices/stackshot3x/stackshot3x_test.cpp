// The emulated StackShot 3X against stackshot-protocol.txt section 2 (every
// CC_ command and its error replies), section 3 (DfMoco dialect), ERRATA
// part 3 and FACTS "StackShot", in virtual time; plus protocol laws.
#include "devices/stackshot3x/stackshot3x.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>

#include "devices/registry.h"
#include "devices/stackshot3x/stackshot3x_test_support.h"

namespace moco::devices {
namespace {

using stackshot::Action;
using stackshot::Command;
using stackshot::Units;
using testing::Read;
using testing::SsBench;
using testing::Write;
constexpr sim::TimeNs kMs = sim::kNsPerMs;
constexpr sim::TimeNs kSec = sim::kNsPerSecond;
constexpr double kStepsPerMm = 3200 / 2.0;  // default profile: 3200 steps per 2 mm revolution

float PositionIn(SsBench& b, Command c, uint8_t axis, Units u) {
  const auto r = b.AskRead(Read(c, axis, stackshot::UnitsQuery{u}));
  const auto* v = std::get_if<stackshot::UnitsF32>(&r.payload);
  return v ? v->value.value() : NAN;
}
float Current(SsBench& b, uint8_t axis = 0, Units u = Units::kSteps) {
  return PositionIn(b, Command::kRailPositionCurrent, axis, u);
}
uint32_t StatusBits(SsBench& b, uint8_t axis = 0, Command c = Command::kRailStatus) {
  const auto r = b.AskRead(Read(c, axis));
  const auto* v = std::get_if<stackshot::RailStatus>(&r.payload);
  return v ? v->bits : 0xDEAD;
}
stackshot::HostCommand Move(uint8_t axis, stackshot::Direction d, Units u, bool backlash,
                            float dist) {
  return Write(Command::kRailMove, axis, stackshot::RailMove{d, u, backlash, dist});
}
constexpr auto kFwd = stackshot::Direction::kForward;
constexpr auto kBack = stackshot::Direction::kBack;

// --- identity, ping, unsupported ---------------------------------------------------

TEST(Stackshot3xTest, IdentityComesFromTheProfile) {
  Stackshot3xProfile prof;
  prof.software_string = "SS3X test 9.9";
  prof.software_id = 0x01020304;
  prof.hardware_id = 0x0A;
  prof.bootloader_id = 0x0B;
  SsBench b(prof);
  EXPECT_EQ(std::get<stackshot::Text>(b.AskRead(Read(Command::kSoftwareString)).payload).text,
            "SS3X test 9.9");
  EXPECT_EQ(std::get<stackshot::U32Value>(b.AskRead(Read(Command::kSoftwareId)).payload).value,
            0x01020304u);
  EXPECT_EQ(std::get<stackshot::U32Value>(b.AskRead(Read(Command::kHardwareId)).payload).value,
            0x0Au);
  EXPECT_EQ(std::get<stackshot::U32Value>(b.AskRead(Read(Command::kBootloaderId)).payload).value,
            0x0Bu);
}

TEST(Stackshot3xTest, PingAnswersXorFFAndReservedZeroAlsoAtTableId) {
  SsBench b;
  auto p = b.Ask(Read(Command::kPing, 0, stackshot::PingRequest{0x5A}));
  EXPECT_EQ(p.action, static_cast<uint8_t>(Action::kRspOk));
  EXPECT_EQ(p.data, (wire::Bytes{0xA5, 0x00}));
  auto t = Read(Command::kPing, 0, stackshot::PingRequest{0x01});
  t.command = stackshot::kPingTableId;
  p = b.Ask(t);
  EXPECT_EQ(p.command, stackshot::kPingTableId);
  EXPECT_EQ(p.data, (wire::Bytes{0xFE, 0x00}));
}

TEST(Stackshot3xTest, ChecksumReplyIsDelayedAndLaterPacketsWait) {
  SsBench b;
  b.Send(Read(Command::kSoftwareChecksum));
  b.Send(Read(Command::kPing, 0, stackshot::PingRequest{0}));
  b.RunFor(249 * kMs);
  EXPECT_TRUE(b.Replies().empty());
  b.RunFor(2 * kMs);
  auto r = b.Replies();
  ASSERT_EQ(r.size(), 2u);
  EXPECT_EQ(r[0].command, stackshot::Id(Command::kSoftwareChecksum));
  EXPECT_EQ(r[0].data, (wire::Bytes{0x1E, 0x0F, 0x3C, 0x5A}));
  EXPECT_EQ(r[1].command, stackshot::Id(Command::kPing));
}

TEST(Stackshot3xTest, UnsupportedCommandsAndActions) {
  SsBench b;
  EXPECT_EQ(b.Status({0x1234, Action::kRead, 0, false, false, stackshot::Unknown{}}),
            Action::kUnsupportedCmd);
  EXPECT_EQ(b.Status(Write(Command::kWad, 0, stackshot::Raw{{1, 2}})), Action::kUnsupportedCmd);
  EXPECT_EQ(b.Status(Read(Command::kNandAccess, 0, stackshot::Raw{})), Action::kUnsupportedCmd);
  EXPECT_EQ(b.Status(Write(Command::kWifi, 0, stackshot::Raw{})), Action::kUnsupportedCmd);
  // CC_SOFTWARE_ID is read only.
  EXPECT_EQ(b.Status(Write(Command::kSoftwareId, 0, stackshot::U32Value{1})),
            Action::kUnsupportedAction);
  // A length the layout does not allow.
  wire::Bytes bad = {0x55, 0x10, 0x81, 0x01, 0x02, 0x05, 0x06, 0x00};
  b.Feed(bad);
  auto r = b.Replies();
  ASSERT_EQ(r.size(), 1u);
  EXPECT_EQ(r[0].action, static_cast<uint8_t>(Action::kBadParam));
  EXPECT_EQ(b.Status(Write(Command::kReflash)), Action::kFailed);
}

TEST(Stackshot3xTest, ChecksumByteIsNeverVerified) {
  SsBench b;
  // The spec's example "0x55 10 02 00 00 CK" with the constants known hosts send.
  for (const int ck : {0x69, 0x00, 0x13}) {
    b.Feed({0x55, 0x10, 0x05, 0x10, 0x00, static_cast<uint8_t>(ck)});
    auto r = b.Replies();
    ASSERT_EQ(r.size(), 1u);
    EXPECT_EQ(r[0].action & 0x0F, static_cast<uint8_t>(Action::kRspOk));
    EXPECT_EQ(r[0].axis, 1);  // the upper nibble is echoed
  }
}

TEST(Stackshot3xTest, PartialPacketIsDroppedAfterTheInterFrameGap) {
  SsBench b;
  b.Feed({0x55, 0x11, 0x0B});
  b.RunFor(3 * kMs);
  b.Send(Read(Command::kPing, 0, stackshot::PingRequest{7}));
  auto r = b.Replies();
  ASSERT_EQ(r.size(), 1u);
  EXPECT_EQ(r[0].data, (wire::Bytes{0xF8, 0}));
}

// --- moves ----------------------------------------------------------------------------

TEST(Stackshot3xTest, MoveIsRelativeToTargetAndBusyWhileMoving) {
  SsBench b;
  EXPECT_EQ(b.Status(Move(0, kFwd, Units::kMm, false, 1.0f)), Action::kRspOk);
  EXPECT_FLOAT_EQ(PositionIn(b, Command::kRailPositionTarget, 0, Units::kMm), 1.0f);
  EXPECT_EQ(StatusBits(b) & stackshot::kRailStatusMoving, stackshot::kRailStatusMoving);
  EXPECT_EQ(b.Status(Move(0, kFwd, Units::kMm, false, 1.0f)), Action::kBusy);
  EXPECT_EQ(b.Status(Write(Command::kRailPositionZero)), Action::kBusy);
  b.RunFor(2 * kSec);
  EXPECT_EQ(StatusBits(b), 0u);
  EXPECT_FLOAT_EQ(Current(b), 1600.0f);
  EXPECT_NEAR(Current(b, 0, Units::kMils), 1000.0f / 25.4f, 1e-3);
  EXPECT_EQ(b.Status(Move(0, kFwd, Units::kSteps, false, 400.0f)), Action::kRspOk);
  b.RunFor(2 * kSec);
  EXPECT_FLOAT_EQ(Current(b), 2000.0f);
  // Other axes did not move.
  EXPECT_FLOAT_EQ(Current(b, 1), 0.0f);
  EXPECT_FLOAT_EQ(Current(b, 2), 0.0f);
}

TEST(Stackshot3xTest, MoveRejectsBadParameters) {
  SsBench b;
  EXPECT_EQ(b.Status(Move(3, kFwd, Units::kMm, false, 1.0f)), Action::kBadParam);
  EXPECT_EQ(b.Status(Move(0, static_cast<stackshot::Direction>(2), Units::kMm, false, 1)),
            Action::kBadParam);
  EXPECT_EQ(b.Status(Move(0, kFwd, Units::kDegrees, false, 1)), Action::kBadParam);
  EXPECT_EQ(b.Status(Move(0, kFwd, Units::kMm, false, NAN)), Action::kBadParam);
  EXPECT_EQ(b.Status(Move(0, kFwd, Units::kMm, false, -1)), Action::kBadParam);
  EXPECT_EQ(b.Status(Move(0, kFwd, Units::kMm, false, 1e30f)), Action::kBadParam);
  EXPECT_EQ(
      b.Status(Write(Command::kRailConfigBacklash, 0, stackshot::UnitsF32{Units::kMm, 1e30f})),
      Action::kBadParam);
  auto at = [](float d, float f) {
    return Write(Command::kRailMoveAtSpeed, 0, stackshot::RailMoveAtSpeed{kFwd, Units::kMm, d, f});
  };
  EXPECT_EQ(b.Status(at(1, 0)), Action::kBadParam);
  EXPECT_EQ(b.Status(at(1, 1.5f)), Action::kBadParam);
}

TEST(Stackshot3xTest, MoveAtSpeedIsRelativeToTheImmediatePosition) {
  SsBench b;
  ASSERT_EQ(b.Status(Move(1, kFwd, Units::kSteps, false, 10000)), Action::kRspOk);
  b.RunFor(1 * kSec);
  const float mid = Current(b, 1);
  ASSERT_GT(mid, 0);
  ASSERT_LT(mid, 10000);
  ASSERT_EQ(b.Status(Write(Command::kRailMoveAtSpeed, 1,
                           stackshot::RailMoveAtSpeed{kFwd, Units::kSteps, 100.0f, 0.5f})),
            Action::kRspOk);
  b.RunFor(5 * kSec);
  // From where it was when the command arrived (within the braking distance).
  EXPECT_NEAR(Current(b, 1), mid + 100, 4000);
  EXPECT_LT(Current(b, 1), 10000);
  EXPECT_FLOAT_EQ(Current(b, 1), PositionIn(b, Command::kRailPositionTarget, 1, Units::kSteps));
}

TEST(Stackshot3xTest, BacklashTakeUpOnReversalDoesNotMoveTheRail) {
  SsBench b;
  ASSERT_EQ(b.Status(Move(0, kFwd, Units::kMm, true, 1.0f)), Action::kRspOk);
  b.RunFor(2 * kSec);
  ASSERT_EQ(b.Status(Move(0, kBack, Units::kMm, true, 0.5f)), Action::kRspOk);
  b.RunFor(2 * kSec);
  // Default backlash 0.1 mm = 160 steps: the motor turned 160 steps more.
  EXPECT_FLOAT_EQ(Current(b), 800.0f);
  EXPECT_EQ(b.dev->rig()->motor(1).Position(), 1600 - 800 - 160);
  // Same direction again: no take-up.
  ASSERT_EQ(b.Status(Move(0, kBack, Units::kMm, true, 0.5f)), Action::kRspOk);
  b.RunFor(2 * kSec);
  EXPECT_FLOAT_EQ(Current(b), 0.0f);
  EXPECT_EQ(b.dev->rig()->motor(1).Position(), -160);
  // Reversal without compensation: motor and rail move alike.
  ASSERT_EQ(b.Status(Move(0, kFwd, Units::kMm, false, 0.5f)), Action::kRspOk);
  b.RunFor(2 * kSec);
  EXPECT_FLOAT_EQ(Current(b), 800.0f);
  EXPECT_EQ(b.dev->rig()->motor(1).Position(), 640);
}

TEST(Stackshot3xTest, ZeroStopAndStopRamp) {
  SsBench b;
  ASSERT_EQ(b.Status(Move(0, kFwd, Units::kMm, false, 1.0f)), Action::kRspOk);
  b.RunFor(2 * kSec);
  EXPECT_EQ(b.Status(Write(Command::kRailPositionZero)), Action::kRspOk);
  EXPECT_FLOAT_EQ(Current(b), 0.0f);
  EXPECT_FLOAT_EQ(PositionIn(b, Command::kRailPositionTarget, 0, Units::kSteps), 0.0f);
  ASSERT_EQ(b.Status(Move(0, kFwd, Units::kMm, false, 5.0f)), Action::kRspOk);
  b.RunFor(1 * kSec);
  EXPECT_EQ(b.Status(Write(Command::kRailStop)), Action::kRspOk);
  EXPECT_EQ(StatusBits(b) & 1, 0u);  // stopped dead
  ASSERT_EQ(b.Status(Move(0, kFwd, Units::kMm, false, 5.0f)), Action::kRspOk);
  b.RunFor(1 * kSec);
  EXPECT_EQ(b.Status(Write(Command::kRailStopRamp)), Action::kRspOk);
  EXPECT_EQ(StatusBits(b) & 1, 1u);  // still ramping down
  b.RunFor(1 * kSec);
  EXPECT_EQ(StatusBits(b) & 1, 0u);
  EXPECT_EQ(b.Status(Write(Command::kRailStop, 3)), Action::kBadParam);
}

TEST(Stackshot3xTest, UserAbortedIsStickyUntilRead) {
  SsBench b;
  ASSERT_EQ(b.Status(Move(2, kFwd, Units::kMm, false, 5.0f)), Action::kRspOk);
  b.RunFor(500 * kMs);
  b.dev->UserAbort();
  EXPECT_EQ(StatusBits(b, 2), stackshot::kRailStatusUserAborted);
  EXPECT_EQ(StatusBits(b, 2), 0u);
  EXPECT_EQ(StatusBits(b, 3), 0xDEADu);  // axis 3 -> BAD_PARAM, no data
}

// --- shutter --------------------------------------------------------------------------

TEST(Stackshot3xTest, ShutterFirePulsesAndStatusBit) {
  SsBench b;
  const sim::TimeNs t0 = b.sched.Now();
  ASSERT_EQ(b.Status(Write(Command::kRailShutterFire, 0, stackshot::ShutterFire{3, 0.1f, 0.2f})),
            Action::kRspOk);
  EXPECT_EQ(StatusBits(b), stackshot::kRailStatusShutter);
  EXPECT_EQ(b.Status(Write(Command::kRailShutterFire, 0, stackshot::ShutterFire{1, 0.1f, 0.1f})),
            Action::kBusy);
  EXPECT_EQ(b.Status(Write(Command::kRailShutterFire, 2, stackshot::ShutterFire{1, 0.1f, 0.1f})),
            Action::kBadParam);
  b.RunFor(2 * kSec);
  const auto& p = b.dev->ShutterPulses();
  ASSERT_EQ(p.size(), 3u);
  for (size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(p[i].on_ns - t0, static_cast<sim::TimeNs>(i) * 300 * kMs);
    EXPECT_EQ(p[i].off_ns - p[i].on_ns, 100 * kMs);
  }
  EXPECT_EQ(StatusBits(b), 0u);
  // Out-of-bound times are bounded, not refused.
  ASSERT_EQ(b.Status(Write(Command::kRailShutterFire, 1, stackshot::ShutterFire{0, 0.0f, -1.0f})),
            Action::kRspOk);
  b.RunFor(kSec);
  ASSERT_EQ(p.size(), 4u);
  EXPECT_EQ(p[3].output, 1);
  EXPECT_EQ(p[3].off_ns - p[3].on_ns, 1 * kMs);
}

// --- stack runs -----------------------------------------------------------------------

TEST(Stackshot3xTest, StackRunSettlesShootsAndReturns) {
  SsBench b;
  ASSERT_EQ(b.Status(Write(Command::kRailConfigSettleTime, 0, stackshot::F32Value{0.5f})),
            Action::kRspOk);
  ASSERT_EQ(b.Status(Write(Command::kRailConfigNumPulses, 0, stackshot::U16Value{2})),
            Action::kRspOk);
  ASSERT_EQ(b.Status(Write(Command::kRailConfigPulseTime, 0, stackshot::F32Value{0.1f})),
            Action::kRspOk);
  ASSERT_EQ(b.Status(Write(Command::kRailConfigPulseTime, 0, stackshot::F32Value{0.2f}, true)),
            Action::kRspOk);
  ASSERT_EQ(b.Status(Write(Command::kRailConfigOffTime, 0, stackshot::F32Value{0.3f})),
            Action::kRspOk);
  ASSERT_EQ(b.Status(Write(Command::kRailConfigToffFinal, 0, stackshot::BoolValue{false})),
            Action::kRspOk);
  ASSERT_EQ(b.Status(Write(Command::kRailConfigAutoReturn, 0, stackshot::BoolValue{true})),
            Action::kRspOk);
  stackshot::RailStack s;
  s.num_steps = 3;
  s.x_start = 0;
  s.x_end = 3200;
  const sim::TimeNs t0 = b.sched.Now();
  ASSERT_EQ(b.Status(Write(Command::kRailStack, 0, s)), Action::kRspOk);
  EXPECT_EQ(b.Status(Move(0, kFwd, Units::kMm, false, 1)), Action::kBusy);
  EXPECT_EQ(StatusBits(b, 0, Command::kRailStackStatus) & 1, 1u);
  b.RunFor(30 * kSec);
  const auto& p = b.dev->ShutterPulses();
  ASSERT_EQ(p.size(), 6u);
  // Frame 0 is at the start: settle, then pulse 1 (0.1 s), off 0.3 s, pulse 2 (0.2 s).
  EXPECT_EQ(p[0].on_ns - t0, 500 * kMs);
  EXPECT_EQ(p[0].off_ns - p[0].on_ns, 100 * kMs);
  EXPECT_EQ(p[1].on_ns - p[0].off_ns, 300 * kMs);
  EXPECT_EQ(p[1].off_ns - p[1].on_ns, 200 * kMs);
  // Between frames: a 1 mm move (>= 0.5 s at 2 mm/s) and the settle time.
  EXPECT_GE(p[2].on_ns - p[1].off_ns, 1000 * kMs);
  EXPECT_EQ(b.dev->StackFramesShot(), 3u);
  EXPECT_FALSE(b.dev->StackRunning());
  EXPECT_EQ(
      std::get<stackshot::U32Value>(b.AskRead(Read(Command::kRailStackPosition)).payload).value,
      3u);
  EXPECT_FLOAT_EQ(Current(b), 0.0f);  // auto-return
  EXPECT_EQ(StatusBits(b, 0, Command::kRailStackStatus), 0u);
  s.num_steps = 0;
  EXPECT_EQ(b.Status(Write(Command::kRailStack, 0, s)), Action::kBadParam);
}

// Where `axis` stood at each shot of the stack now running (sampled every ms
// while the shutter fires), until the stack ends.
std::vector<int64_t> ShotPositions(SsBench& b, int axis) {
  std::vector<int64_t> at;
  bool firing = false;
  for (int ms = 0; ms < 120000 && b.dev->StackRunning(); ++ms) {
    b.RunFor(kMs);
    const bool now = b.dev->ShutterFiring();
    if (now && !firing) at.push_back(b.dev->RailPosition(axis));
    firing = now;
  }
  return at;
}

TEST(Stackshot3xTest, StackModesPlaceTheFramesByModeAndDistance) {
  // CC_RAIL_STACK "setting_mode_t The operating mode for this stack" with
  // comm_rail_mode_t, "Number of steps", "Distance" (motor steps, as the
  // positions are).
  SsBench b;
  ASSERT_EQ(b.Status(Write(Command::kRailConfigSettleTime, 0, stackshot::F32Value{0.1f})),
            Action::kRspOk);
  {
    SCOPED_TRACE("AUTO_DIST: a frame every `distance` from start to end, the last on the end");
    stackshot::RailStack s;
    s.mode = static_cast<uint32_t>(stackshot::RailMode::kAutoDist);
    s.num_steps = 99;  // not used in this mode
    s.distance = 300;
    s.x_start = 0;
    s.x_end = 1000;
    ASSERT_EQ(b.Status(Write(Command::kRailStack, 0, s)), Action::kRspOk);
    EXPECT_EQ(ShotPositions(b, 0), (std::vector<int64_t>{0, 300, 600, 900, 1000}));
    EXPECT_EQ(b.dev->StackFramesShot(), 5u);
  }
  {
    SCOPED_TRACE("TOTAL_DISTANCE: the addressed axis covers `distance` from where it stands");
    stackshot::RailStack s;
    s.mode = static_cast<uint32_t>(stackshot::RailMode::kTotalDistance);
    s.num_steps = 3;
    s.distance = 1600;
    ASSERT_EQ(b.Status(Write(Command::kRailStack, 1, s)), Action::kRspOk);
    EXPECT_EQ(ShotPositions(b, 1), (std::vector<int64_t>{0, 800, 1600}));
  }
  {
    SCOPED_TRACE("DISTANCE_PER_STEP: `distance` between frames (negative: backwards)");
    stackshot::RailStack s;
    s.mode = static_cast<uint32_t>(stackshot::RailMode::kDistancePerStep);
    s.num_steps = 3;
    s.distance = static_cast<uint32_t>(-400);
    ASSERT_EQ(b.Status(Write(Command::kRailStack, 0, s)), Action::kRspOk);  // X stands at 1000
    EXPECT_EQ(ShotPositions(b, 0), (std::vector<int64_t>{1000, 600, 200}));
  }
  // The other side: requests the mode cannot run.
  stackshot::RailStack s;
  s.mode = static_cast<uint32_t>(stackshot::RailMode::kAutoDist);
  s.x_end = 1000;
  s.distance = 0;
  EXPECT_EQ(b.Status(Write(Command::kRailStack, 0, s)), Action::kBadParam);
  s.mode = static_cast<uint32_t>(stackshot::RailMode::kTotalDistance);
  s.num_steps = 3;
  EXPECT_EQ(b.Status(Write(Command::kRailStack, 0, s)), Action::kBadParam);  // no distance
  s.mode = static_cast<uint32_t>(stackshot::RailMode::kDistancePerStep);
  s.distance = 0x7FFFFFFF;  // beyond any rail (and past int64 if multiplied naively)
  s.num_steps = 0xFFFFFFFF;
  EXPECT_EQ(b.Status(Write(Command::kRailStack, 0, s)), Action::kBadParam);
  s.num_steps = 3;
  s.mode = static_cast<uint32_t>(stackshot::RailMode::kManual);
  s.distance = 100;
  EXPECT_EQ(b.Status(Write(Command::kRailStack, 0, s)), Action::kBadParam);
  EXPECT_FALSE(b.dev->StackRunning());
}

TEST(Stackshot3xTest, StackPanoFieldsHoldTheFreeAxisAtTheFrameStartThenMoveItToTheStop) {
  SsBench b;
  ASSERT_EQ(b.Status(Write(Command::kRailConfigSettleTime, 0, stackshot::F32Value{0.1f})),
            Action::kRspOk);
  stackshot::RailStack s;
  s.mode = static_cast<uint32_t>(stackshot::RailMode::kAutoStep);
  s.num_steps = 2;
  s.x_end = 800;
  s.pano_start_steps = 1000;
  s.pano_stop_steps = 2000;
  ASSERT_EQ(b.Status(Write(Command::kRailStack, 0, s)), Action::kRspOk);
  // Y, the first axis the stack leaves alone, is the pano axis.
  std::vector<int64_t> y_at_shots;
  bool firing = false;
  for (int ms = 0; ms < 60000 && b.dev->StackRunning(); ++ms) {
    b.RunFor(kMs);
    const bool now = b.dev->ShutterFiring();
    if (now && !firing) y_at_shots.push_back(b.dev->RailPosition(1));
    firing = now;
  }
  EXPECT_EQ(y_at_shots, (std::vector<int64_t>{1000, 1000}));
  EXPECT_EQ(b.dev->RailPosition(1), 2000);
  EXPECT_EQ(b.dev->RailPosition(0), 800);
  // The other side: a pano frame with every axis stacking has no axis to use.
  s.y_end = 100;
  s.z_end = 100;
  EXPECT_EQ(b.Status(Write(Command::kRailStack, 0, s)), Action::kBadParam);
}

TEST(Stackshot3xTest, TheEStopEndsAStackRunWithoutAnotherShot) {
  SsBench b;
  ASSERT_EQ(b.Status(Write(Command::kRailConfigSettleTime, 0, stackshot::F32Value{0.5f})),
            Action::kRspOk);
  stackshot::RailStack s;
  s.num_steps = 5;
  s.x_start = 0;
  s.x_end = 6400;
  ASSERT_EQ(b.Status(Write(Command::kRailStack, 0, s)), Action::kRspOk);
  // Frame 0 shot at the start; then the rail moves towards frame 1.
  b.RunFor(1500 * kMs);
  ASSERT_TRUE(b.dev->StackRunning());
  const size_t shots = b.dev->ShutterPulses().size();
  ASSERT_GE(shots, 1u);
  const sim::TimeNs pressed = b.sched.Now();
  b.dev->rig()->EngageEStop();
  EXPECT_FALSE(b.dev->StackRunning());
  b.RunFor(30 * kSec);
  // No shot after the e-stop, the rail stays where it halted.
  EXPECT_EQ(b.dev->ShutterPulses().size(), shots);
  for (const auto& p : b.dev->ShutterPulses()) EXPECT_LT(p.on_ns, pressed);
  EXPECT_EQ(StatusBits(b, 0, Command::kRailStackStatus), 0u);
  EXPECT_EQ(StatusBits(b) & 1, 0u);  // not moving
  // Released, the unit takes a new stack.
  b.dev->rig()->ReleaseEStop();
  ASSERT_EQ(b.Status(Write(Command::kRailStack, 0, s)), Action::kRspOk);
  EXPECT_TRUE(b.dev->StackRunning());
}

// --- configuration --------------------------------------------------------------------

TEST(Stackshot3xTest, U8AndBoolConfigRangesAndRoundTrips) {
  SsBench b;
  struct Case {
    Command c;
    uint8_t lo, hi;
  };
  for (const Case k :
       {Case{Command::kRailConfigBacklight, 1, 10}, Case{Command::kRailConfigTorque, 1, 10},
        Case{Command::kRailConfigHoldingTorque, 0, 10}}) {
    SCOPED_TRACE(stackshot::CommandName(stackshot::Id(k.c)));
    EXPECT_EQ(b.Status(Write(k.c, 0, stackshot::U8Value{k.hi})), Action::kRspOk);
    EXPECT_EQ(std::get<stackshot::U8Value>(b.AskRead(Read(k.c)).payload).value, k.hi);
    EXPECT_EQ(b.Status(Write(k.c, 0, stackshot::U8Value{static_cast<uint8_t>(k.hi + 1)})),
              Action::kBadParam);
    if (k.lo > 0) {
      EXPECT_EQ(b.Status(Write(k.c, 0, stackshot::U8Value{static_cast<uint8_t>(k.lo - 1)})),
                Action::kBadParam);
    }
  }
  for (Command c : {Command::kRailConfigShutterDisable, Command::kRailConfigAutoReturn,
                    Command::kRailConfigToffFinal, Command::kRailConfigPolarity}) {
    EXPECT_EQ(b.Status(Write(c, 1, stackshot::BoolValue{true})), Action::kRspOk);
    EXPECT_TRUE(std::get<stackshot::BoolValue>(b.AskRead(Read(c, 1)).payload).value);
  }
  EXPECT_EQ(b.Status(Write(Command::kRailConfigTorque, 3, stackshot::U8Value{5})),
            Action::kBadParam);
  EXPECT_EQ(b.Status(Write(Command::kRailConfigNumSteps, 0, stackshot::U16Value{0})),
            Action::kBadParam);
  EXPECT_EQ(b.Status(Write(Command::kRailConfigNumSteps, 2, stackshot::U16Value{300})),
            Action::kRspOk);
  EXPECT_EQ(
      std::get<stackshot::U16Value>(b.AskRead(Read(Command::kRailConfigNumSteps, 2)).payload).value,
      300);
  EXPECT_EQ(b.Status(Write(Command::kRailConfigNumPulses, 2, stackshot::U16Value{2})),
            Action::kBadParam);
}

TEST(Stackshot3xTest, EnumConfigRanges) {
  SsBench b;
  EXPECT_EQ(
      b.Status(Write(Command::kRailConfigUnits, 0, stackshot::EnumValue<Units>{Units::kDegrees})),
      Action::kBadParam);
  EXPECT_EQ(
      b.Status(Write(Command::kRailConfigUnits, 0, stackshot::EnumValue<Units>{Units::kSteps})),
      Action::kRspOk);
  EXPECT_EQ(b.Status(Write(
                Command::kRailConfigMode, 0,
                stackshot::EnumValue<stackshot::RailMode>{static_cast<stackshot::RailMode>(8)})),
            Action::kBadParam);
  EXPECT_EQ(b.Status(Write(Command::kRailConfigGlobalMode, 0,
                           stackshot::EnumValue<stackshot::GlobalMode>{
                               stackshot::GlobalMode::kMotionReserved})),
            Action::kBadParam);
  EXPECT_EQ(b.Status(Write(Command::kRailConfigGlobalMode, 0,
                           stackshot::EnumValue<stackshot::GlobalMode>{
                               static_cast<stackshot::GlobalMode>(13)})),
            Action::kBadParam);
  EXPECT_EQ(b.Status(Write(Command::kRailConfigShutter, 0,
                           stackshot::EnumValue<stackshot::ShutterSetting>{
                               static_cast<stackshot::ShutterSetting>(4)})),
            Action::kBadParam);
  EXPECT_EQ(
      b.Status(Write(Command::kRailConfigIoMode, 0,
                     stackshot::EnumValue<stackshot::IoMode>{static_cast<stackshot::IoMode>(3)})),
      Action::kBadParam);
  EXPECT_EQ(b.Status(Write(Command::kRailConfigIoDir, 0,
                           stackshot::EnumValue<stackshot::Direction>{kBack})),
            Action::kRspOk);
  EXPECT_EQ(b.Status(Write(Command::kRailConfigAxis, 0, stackshot::U8Value{5})), Action::kBadParam);
}

TEST(Stackshot3xTest, FloatAndUnitsConfigRoundTripsAndRanges) {
  SsBench b;
  EXPECT_EQ(b.Status(Write(Command::kRailConfigSettleTime, 0, stackshot::F32Value{-1.0f})),
            Action::kBadParam);
  EXPECT_EQ(b.Status(Write(Command::kRailConfigSettleTime, 0, stackshot::F32Value{NAN})),
            Action::kBadParam);
  EXPECT_EQ(b.Status(Write(Command::kRailConfigPulseTime, 1, stackshot::F32Value{0.0f})),
            Action::kBadParam);
  EXPECT_EQ(b.Status(Write(Command::kRailConfigPulseTime, 2, stackshot::F32Value{0.5f})),
            Action::kBadParam);
  EXPECT_EQ(b.Status(Write(Command::kRailConfigRampTime, 0, stackshot::F32Value{11.0f})),
            Action::kBadParam);
  EXPECT_EQ(b.Status(Write(Command::kRailConfigRotaryRatio, 0, stackshot::F32Value{0.0f})),
            Action::kBadParam);
  EXPECT_EQ(b.Status(Write(Command::kRailConfigTimelapse, 0, stackshot::F32Value{12.5f})),
            Action::kRspOk);
  EXPECT_EQ(
      std::get<stackshot::F32Value>(b.AskRead(Read(Command::kRailConfigTimelapse)).payload).value,
      stackshot::F32(12.5f));
  // Speed written in mm/s reads back in mils/s; above the axis maximum (8000 steps/s = 5 mm/s) is
  // refused.
  EXPECT_EQ(b.Status(Write(Command::kRailConfigSpeed, 1, stackshot::UnitsF32{Units::kMm, 2.54f})),
            Action::kRspOk);
  const auto r = b.AskRead(Read(Command::kRailConfigSpeed, 1, stackshot::UnitsQuery{Units::kMils}));
  EXPECT_NEAR(std::get<stackshot::UnitsF32>(r.payload).value.value(), 100.0f, 1e-3);
  EXPECT_EQ(b.Status(Write(Command::kRailConfigSpeed, 1, stackshot::UnitsF32{Units::kMm, 5.01f})),
            Action::kBadParam);
  EXPECT_EQ(
      b.Status(Write(Command::kRailConfigSpeedMove, 1, stackshot::UnitsF32{Units::kSteps, 8000})),
      Action::kRspOk);
  EXPECT_EQ(
      b.Status(Write(Command::kRailConfigBacklash, 0, stackshot::UnitsF32{Units::kMm, -0.1f})),
      Action::kBadParam);
  EXPECT_EQ(
      b.Status(Write(Command::kRailConfigDistancePerRev, 0, stackshot::UnitsF32{Units::kSteps, 2})),
      Action::kBadParam);
  // Distance per revolution changes the steps per mm: 4 mm/rev -> 800 steps/mm.
  EXPECT_EQ(
      b.Status(Write(Command::kRailConfigDistancePerRev, 0, stackshot::UnitsF32{Units::kMm, 4})),
      Action::kRspOk);
  ASSERT_EQ(b.Status(Move(0, kFwd, Units::kMm, false, 1)), Action::kRspOk);
  b.RunFor(3 * kSec);
  EXPECT_FLOAT_EQ(Current(b), 800.0f);
  EXPECT_EQ(b.Status(Write(Command::kRailConfigName, 0, stackshot::Text{std::string(33, 'a')})),
            Action::kBadParam);
  EXPECT_EQ(std::get<stackshot::Text>(b.AskRead(Read(Command::kRailConfigName)).payload).text,
            "\xFF");
  EXPECT_EQ(b.Status(Write(Command::kRailConfigName, 0, stackshot::Text{"bugs"})), Action::kRspOk);
  EXPECT_EQ(std::get<stackshot::Text>(b.AskRead(Read(Command::kRailConfigName)).payload).text,
            "bugs");
}

TEST(Stackshot3xTest, SaveAndLoadSlots) {
  SsBench b;
  EXPECT_EQ(b.Status(Write(Command::kRailConfigLoad, 0, stackshot::U8Value{4})), Action::kFailed);
  EXPECT_EQ(b.Status(Write(Command::kRailConfigSave, 0, stackshot::U8Value{11})),
            Action::kBadParam);
  EXPECT_EQ(b.Status(Write(Command::kRailConfigBacklight, 0, stackshot::U8Value{9})),
            Action::kRspOk);
  EXPECT_EQ(b.Status(Write(Command::kRailConfigSave, 0, stackshot::U8Value{4})), Action::kRspOk);
  EXPECT_EQ(b.Status(Write(Command::kRailConfigBacklight, 0, stackshot::U8Value{2})),
            Action::kRspOk);
  EXPECT_EQ(b.Status(Write(Command::kRailConfigLoad, 0, stackshot::U8Value{4})), Action::kRspOk);
  EXPECT_EQ(
      std::get<stackshot::U8Value>(b.AskRead(Read(Command::kRailConfigBacklight)).payload).value,
      9);
}

TEST(Stackshot3xTest, SerialNumberIsWriteOnceAndNvmPersistsThroughPowerCycleAndReset) {
  SsBench b;
  EXPECT_EQ(std::get<stackshot::U32Value>(b.AskRead(Read(Command::kSerialNumber)).payload).value,
            0xFFFFFFFFu);
  EXPECT_EQ(b.Status(Write(Command::kSerialNumber, 0, stackshot::U32Value{1234})), Action::kRspOk);
  EXPECT_EQ(b.Status(Write(Command::kSerialNumber, 0, stackshot::U32Value{99})), Action::kFailed);
  EXPECT_EQ(std::get<stackshot::U32Value>(
                b.AskRead(Read(Command::kNvmAccess, 0, stackshot::NvmRead{7})).payload)
                .value,
            0xFFFFFFFFu);
  EXPECT_EQ(b.Status(Write(Command::kNvmAccess, 0, stackshot::NvmWrite{7, 0xCAFE})),
            Action::kRspOk);
  EXPECT_EQ(b.Status(Write(Command::kNvmAccess, 0, stackshot::NvmWrite{128, 1})),
            Action::kBadParam);
  EXPECT_EQ(b.Status(Read(Command::kNvmAccess, 0, stackshot::NvmRead{128})), Action::kBadParam);
  EXPECT_EQ(b.Status(Write(Command::kRailConfigAxis, 0, stackshot::U8Value{2})), Action::kRspOk);
  EXPECT_EQ(std::get<stackshot::U32Value>(
                b.AskRead(Read(Command::kNvmAccess, 0, stackshot::NvmRead{0})).payload)
                .value,
            2u);
  EXPECT_EQ(b.Status(Write(Command::kRailConfigBacklight, 0, stackshot::U8Value{8})),
            Action::kRspOk);
  EXPECT_EQ(b.Status(Write(Command::kRailConfigSave, 0, stackshot::U8Value{0})), Action::kRspOk);
  EXPECT_EQ(b.Status(Write(Command::kRailConfigBacklight, 0, stackshot::U8Value{3})),
            Action::kRspOk);
  ASSERT_EQ(b.Status(Move(0, kFwd, Units::kMm, false, 1)), Action::kRspOk);
  b.RunFor(2 * kSec);
  for (int cycle = 0; cycle < 2; ++cycle) {
    if (cycle == 0) {
      b.dev->PowerOff();
      b.dev->PowerOn();
    } else {
      EXPECT_EQ(b.Status(Write(Command::kReset)), Action::kRspOk);
    }
    SCOPED_TRACE(cycle);
    EXPECT_EQ(std::get<stackshot::U32Value>(b.AskRead(Read(Command::kSerialNumber)).payload).value,
              1234u);
    EXPECT_EQ(b.Status(Write(Command::kSerialNumber, 0, stackshot::U32Value{5})), Action::kFailed);
    EXPECT_EQ(std::get<stackshot::U32Value>(
                  b.AskRead(Read(Command::kNvmAccess, 0, stackshot::NvmRead{7})).payload)
                  .value,
              0xCAFEu);
    EXPECT_EQ(std::get<stackshot::U8Value>(b.AskRead(Read(Command::kRailConfigAxis)).payload).value,
              2);
    // The power-on configuration (slot 0), not the unsaved change.
    EXPECT_EQ(
        std::get<stackshot::U8Value>(b.AskRead(Read(Command::kRailConfigBacklight)).payload).value,
        8);
    EXPECT_FLOAT_EQ(Current(b), 0.0f);  // position is volatile
  }
}

TEST(Stackshot3xTest, LogEntriesUntilBadParam) {
  SsBench b;
  ASSERT_EQ(b.Status(Write(Command::kRailConfigSave, 0, stackshot::U8Value{2})), Action::kRspOk);
  std::vector<std::string> entries;
  for (uint32_t i = 0; i < 100; ++i) {
    const stackshot::Packet p = b.Ask(Read(Command::kLog, 0, stackshot::LogRequest{i, 1}));
    if (p.action == static_cast<uint8_t>(Action::kBadParam)) break;
    auto r = stackshot::DecodeDevicePacket(p, stackshot::ReplyContext{Action::kRead});
    ASSERT_TRUE(r.ok());
    entries.push_back(std::get<stackshot::Text>(r->payload).text);
  }
  ASSERT_EQ(entries.size(), 2u);
  EXPECT_NE(entries[0].find("power on"), std::string::npos);
  EXPECT_NE(entries[1].find("slot 2"), std::string::npos);
}

// --- Bezier motion --------------------------------------------------------------------

stackshot::MotionConfig Ramp(float t_end, float y_end) {
  stackshot::MotionConfig m;
  m.axis_type = stackshot::AxisType::kRail;
  m.curves[0].p = {stackshot::BezierPoint{0.0f, 0.0f}, stackshot::BezierPoint{t_end / 3, 0.0f},
                   stackshot::BezierPoint{2 * t_end / 3, y_end},
                   stackshot::BezierPoint{t_end, y_end}};
  return m;
}

TEST(Stackshot3xTest, MotionConfigRefusesInvalidCurvesAndStartNeedsACurve) {
  SsBench b;
  EXPECT_EQ(b.Status(Write(Command::kMotionStart, 0, stackshot::MotionStart{true, false, false})),
            Action::kFailed);
  auto m = Ramp(2, 1);
  m.curves[0].p[0].x = 0.5f;  // curve 0 must start at time 0
  EXPECT_EQ(b.Status(Write(Command::kMotionConfig, 0, m)), Action::kBadParam);
  m = Ramp(2, 1);
  m.curves[0].p[1].x = 3.0f;  // P1.x beyond P3.x
  EXPECT_EQ(b.Status(Write(Command::kMotionConfig, 0, m)), Action::kBadParam);
  EXPECT_EQ(b.Status(Write(Command::kMotionConfig, 3, Ramp(2, 1))), Action::kBadParam);
  m = Ramp(2, 0);
  for (auto& pt : m.curves[0].p) pt.y = 1e30f;  // standing still, far off
  EXPECT_EQ(b.Status(Write(Command::kMotionConfig, 0, m)), Action::kBadParam);
  EXPECT_EQ(b.Status(Write(Command::kMotionStart, 0, stackshot::MotionStart{true, false, false})),
            Action::kFailed);
  EXPECT_EQ(b.Status(Write(Command::kMotionStart, 0, stackshot::MotionStart{})), Action::kBadParam);
}

TEST(Stackshot3xTest, APositionJumpBetweenCurvesIsAcceptedAndTravelledAtFullSpeed) {
  // Section 2 CC_MOTION_CONFIG lists time continuity ("P0.x must match the
  // previous curves P3.x"), not position continuity.
  SsBench b;
  stackshot::MotionConfig jump = Ramp(1, 1);  // 0 -> 1 mm over 1 s
  jump.curves[1].p = {stackshot::BezierPoint{1.0f, 3.0f}, stackshot::BezierPoint{1.3f, 3.0f},
                      stackshot::BezierPoint{1.7f, 4.0f}, stackshot::BezierPoint{2.0f, 4.0f}};
  ASSERT_EQ(b.Status(Write(Command::kMotionConfig, 0, jump)), Action::kRspOk);
  // The other side: a time gap between the curves breaks the requirement.
  stackshot::MotionConfig gap = jump;
  gap.curves[1].p[0].x = 1.5f;
  EXPECT_EQ(b.Status(Write(Command::kMotionConfig, 0, gap)), Action::kBadParam);
  // The accepted set stays configured and plays: 1 mm, a 2 mm traverse at
  // 8000 steps/s (3200 steps: 0.4 s plus the ramp), then 3 -> 4 mm.
  ASSERT_EQ(b.Status(Write(Command::kMotionStart, 0, stackshot::MotionStart{true, false, false})),
            Action::kRspOk);
  b.RunFor(999 * kMs);
  EXPECT_NEAR(Current(b), kStepsPerMm, 2);
  b.RunFor(800 * kMs);
  EXPECT_EQ(StatusBits(b) & 1, 1u);
  EXPECT_GE(Current(b), 3 * kStepsPerMm);  // the traverse is done, the second curve plays
  b.RunFor(2 * kSec);
  EXPECT_FLOAT_EQ(Current(b), static_cast<float>(4 * kStepsPerMm));
  EXPECT_EQ(StatusBits(b) & 1, 0u);
}

TEST(Stackshot3xTest, ACurveFasterThanTheAxisIsAcceptedAndPlayedWithinItsMaximumSpeed) {
  // "Limits should be applied to prevent sudden velocity changes which may
  // result in loss of steps": advice on the curve, not a requirement for
  // acceptance. The unit applies the axis's limit by slowing the curve down.
  SsBench b;
  const stackshot::MotionConfig fast = Ramp(0.1f, 2);  // 2 mm in 0.1 s: peaks near 48000 steps/s
  ASSERT_EQ(b.Status(Write(Command::kMotionConfig, 0, fast)), Action::kRspOk);
  ASSERT_EQ(b.Status(Write(Command::kMotionStart, 0, stackshot::MotionStart{true, false, false})),
            Action::kRspOk);
  int64_t last = b.dev->RailPosition(0);
  double fastest = 0;
  for (int ms = 0; ms < 2000; ++ms) {
    b.RunFor(kMs);
    const int64_t now = b.dev->RailPosition(0);
    fastest = std::max(fastest, static_cast<double>(now - last) / 0.001);
    last = now;
  }
  EXPECT_LE(fastest, 8000 + 1000);  // within the maximum (one step of sampling slack)
  EXPECT_GT(fastest, 8000 * 0.9);   // and no slower than needed
  EXPECT_EQ(b.dev->RailPosition(0), static_cast<int64_t>(2 * kStepsPerMm));
  // The other side: a curve whose speed is unbounded (a vertical tangent:
  // P1 at P0's time, another position) has no speed to slow down to.
  stackshot::MotionConfig vertical = Ramp(1, 1);
  vertical.curves[0].p[1] = stackshot::BezierPoint{0.0f, 1.0f};
  EXPECT_EQ(b.Status(Write(Command::kMotionConfig, 0, vertical)), Action::kBadParam);
}

TEST(Stackshot3xTest, MotionStartPlaysTheCurve) {
  SsBench b;
  ASSERT_EQ(b.Status(Write(Command::kMotionConfig, 1, Ramp(2, 1))), Action::kRspOk);
  ASSERT_EQ(b.Status(Write(Command::kMotionStart, 0, stackshot::MotionStart{false, true, false})),
            Action::kRspOk);
  b.RunFor(999 * kMs);
  EXPECT_NEAR(Current(b, 1), 0.5 * kStepsPerMm, 2);  // symmetric ease: half way at half time
  EXPECT_EQ(StatusBits(b, 1) & 1, 1u);
  b.RunFor(1100 * kMs);
  EXPECT_FLOAT_EQ(Current(b, 1), static_cast<float>(kStepsPerMm));
  EXPECT_EQ(StatusBits(b, 1) & 1, 0u);
}

TEST(Stackshot3xTest, RemainingConfigValuesAndBusyReplies) {
  SsBench b;
  // Total distance written in mils reads back in mm; per axis.
  EXPECT_EQ(b.Status(Write(Command::kRailConfigTotalDistance, 2,
                           stackshot::UnitsF32{Units::kMils, 1000.0f})),
            Action::kRspOk);
  const auto td =
      b.AskRead(Read(Command::kRailConfigTotalDistance, 2, stackshot::UnitsQuery{Units::kMm}));
  EXPECT_NEAR(std::get<stackshot::UnitsF32>(td.payload).value.value(), 25.4f, 1e-4);
  EXPECT_EQ(b.Status(Write(Command::kRailConfigDistancePerStep, 0,
                           stackshot::UnitsF32{Units::kSteps, 0.0f})),
            Action::kBadParam);
  EXPECT_EQ(b.Status(Write(Command::kRailConfigDistancePerStep, 0,
                           stackshot::UnitsF32{Units::kSteps, 16.0f})),
            Action::kRspOk);
  const auto dps =
      b.AskRead(Read(Command::kRailConfigDistancePerStep, 0, stackshot::UnitsQuery{Units::kMm}));
  EXPECT_FLOAT_EQ(std::get<stackshot::UnitsF32>(dps.payload).value.value(), 0.01f);
  EXPECT_EQ(b.Status(Write(Command::kRailConfigRotaryDegrees, 1, stackshot::F32Value{361.0f})),
            Action::kBadParam);
  EXPECT_EQ(b.Status(Write(Command::kRailConfigRotaryBacklash, 1, stackshot::F32Value{2.5f})),
            Action::kRspOk);
  EXPECT_EQ(
      std::get<stackshot::F32Value>(b.AskRead(Read(Command::kRailConfigRotaryBacklash, 1)).payload)
          .value,
      stackshot::F32(2.5f));
  EXPECT_EQ(
      b.Status(Write(Command::kRailConfigMode, 0,
                     stackshot::EnumValue<stackshot::RailMode>{stackshot::RailMode::kRotary})),
      Action::kRspOk);
  EXPECT_EQ(b.Status(Write(Command::kClose)), Action::kRspOk);
  // While an axis moves: stack, motion start and load are BUSY.
  ASSERT_EQ(b.Status(Write(Command::kRailConfigSave, 0, stackshot::U8Value{1})), Action::kRspOk);
  ASSERT_EQ(b.Status(Write(Command::kMotionConfig, 0, Ramp(2, 1))), Action::kRspOk);
  ASSERT_EQ(b.Status(Move(0, kFwd, Units::kMm, false, 2)), Action::kRspOk);
  stackshot::RailStack st;
  st.num_steps = 2;
  st.y_end = 100;
  EXPECT_EQ(b.Status(Write(Command::kRailStack, 0, st)), Action::kBusy);
  EXPECT_EQ(b.Status(Write(Command::kMotionStart, 0, stackshot::MotionStart{true, false, false})),
            Action::kBusy);
  EXPECT_EQ(b.Status(Write(Command::kRailConfigLoad, 0, stackshot::U8Value{1})), Action::kBusy);
  b.RunFor(3 * kSec);
  // STOP on an axis of a running stack abandons the stack.
  ASSERT_EQ(b.Status(Write(Command::kRailStack, 0, st)), Action::kRspOk);
  EXPECT_TRUE(b.dev->StackRunning());
  EXPECT_EQ(b.Status(Write(Command::kRailStop, 1)), Action::kRspOk);
  EXPECT_FALSE(b.dev->StackRunning());
  EXPECT_EQ(StatusBits(b, 0, Command::kRailStackStatus), 0u);
}

TEST(Stackshot3xTest, BytesAfterResetReachTheRestartedControllerUnlessItBoots) {
  for (const int64_t boot_ms : {0, 100}) {
    SCOPED_TRACE(boot_ms);
    Stackshot3xProfile prof;
    prof.boot_delay_ms = boot_ms;
    SsBench b(prof);
    b.RunFor(200 * kMs);
    wire::Bytes stream;
    stackshot::EncodeHostCommand(Write(Command::kReset), stream);
    stackshot::EncodeHostCommand(Read(Command::kPing, 0, stackshot::PingRequest{3}), stream);
    b.Feed(stream);
    b.RunFor(200 * kMs);
    const auto r = b.Replies();
    ASSERT_EQ(r.size(), boot_ms == 0 ? 2u : 1u);
    EXPECT_EQ(r[0].command, stackshot::Id(Command::kReset));
    EXPECT_TRUE(b.dev->Ready());
  }
}

TEST(Stackshot3xTest, PanelModeIsThePowerOnModeSerialModeIsNot) {
  SsBench b;
  ASSERT_EQ(b.Status(Write(Command::kRailConfigBacklight, 0, stackshot::U8Value{7})),
            Action::kRspOk);
  ASSERT_EQ(b.Status(Write(Command::kRailConfigSave, 0, stackshot::U8Value{0})), Action::kRspOk);
  b.dev->SetGlobalModeFromPanel(stackshot::GlobalMode::kMotionDfMoco);
  b.dev->PowerOff();
  b.dev->PowerOn();
  ASSERT_TRUE(b.dev->InDfmocoMode());
  EXPECT_EQ(b.dev->config().backlight, 7);  // the rest of slot 0 is kept
  b.dev->SetGlobalModeFromPanel(stackshot::GlobalMode::kAdvanced);
  b.dev->PowerOff();
  b.dev->PowerOn();
  EXPECT_FALSE(b.dev->InDfmocoMode());
  // Over serial: until the power goes.
  ASSERT_EQ(b.Status(Write(
                Command::kRailConfigGlobalMode, 0,
                stackshot::EnumValue<stackshot::GlobalMode>{stackshot::GlobalMode::kMotionDfMoco})),
            Action::kRspOk);
  EXPECT_TRUE(b.dev->InDfmocoMode());
  b.dev->PowerOff();
  b.dev->PowerOn();
  EXPECT_FALSE(b.dev->InDfmocoMode());
}

// --- DfMoco mode ----------------------------------------------------------------------

std::string Text(SsBench& b) {
  const wire::Bytes out = b.sink.Take();
  return std::string(out.begin(), out.end());
}
void Line(SsBench& b, std::string_view l) {
  const std::string s = std::string(l) + "\r\n";
  b.Feed(wire::Bytes(s.begin(), s.end()));
}

// Every switch of the line is announced (Device::SetLineSwitchListener):
// the binary mode write after its acknowledgement, a power-on in a mode the
// NVM keeps, the panel, and the way back.
TEST(Stackshot3xTest, EverySwitchOfTheLineIsAnnouncedAfterTheBytesBeforeIt) {
  SsBench b;
  std::vector<std::pair<wire::Protocol, uint32_t>> heard;
  size_t bytes_before = 0;
  b.dev->SetLineSwitchListener([&](const LineSwitch& s) {
    heard.emplace_back(s.protocol, s.line.serial.baud);
    bytes_before = b.sink.bytes().size();
  });
  b.Send(Write(Command::kRailConfigGlobalMode, 0,
               stackshot::EnumValue<stackshot::GlobalMode>{stackshot::GlobalMode::kMotionDfMoco}));
  b.RunFor(sim::kNsPerMs);
  ASSERT_EQ(heard.size(), 1u);
  EXPECT_EQ(heard[0], std::make_pair(wire::Protocol::kStackshotDfmoco, 57600u));
  EXPECT_EQ(bytes_before, b.sink.bytes().size()) << "announced after the acknowledgement";
  EXPECT_GT(bytes_before, 0u);
  // Not saved: the power-on speaks binary again, and says so.
  b.dev->PowerOff();
  b.dev->PowerOn();
  ASSERT_EQ(heard.size(), 2u);
  EXPECT_EQ(heard[1], std::make_pair(wire::Protocol::kStackshot, 38400u));
  // The panel's mode is the power-on mode: announced when set, and not again
  // at a power-on that speaks as before.
  b.dev->SetGlobalModeFromPanel(stackshot::GlobalMode::kMotionDfMoco);
  b.dev->PowerOff();
  b.dev->PowerOn();
  ASSERT_EQ(heard.size(), 3u);
  EXPECT_EQ(heard[2].first, wire::Protocol::kStackshotDfmoco);
}

TEST(Stackshot3xTest, TheRegistryStartsAUnitInDfmocoModeAndItAnnouncesItAtPowerOn) {
  const DeviceModel* m = FindDeviceModel("stackshot3x");
  ASSERT_NE(m, nullptr);
  EXPECT_EQ(LineFor(*m, wire::Protocol::kDfmoco), wire::Protocol::kStackshotDfmoco);
  EXPECT_EQ(LineFor(*m, wire::Protocol::kStackshot), wire::Protocol::kStackshot);
  EXPECT_EQ(LineFor(*m, wire::Protocol::kDmc), std::nullopt);
  sim::Scheduler sched;
  testing::RecordingSink sink(sched);
  MemoryStateStore nvm;
  auto dev = CreateDevice("stackshot3x", "", sched, sink, &nvm,
                          DeviceStart{wire::Protocol::kStackshotDfmoco});
  std::vector<wire::Protocol> heard;
  dev->SetLineSwitchListener([&](const LineSwitch& s) { heard.push_back(s.protocol); });
  dev->PowerOn();
  ASSERT_EQ(heard.size(), 1u);
  EXPECT_EQ(heard[0], wire::Protocol::kStackshotDfmoco);
  EXPECT_EQ(dev->Line().serial.baud, 57600u);
  EXPECT_THROW(
      CreateDevice("dmc16", "", sched, sink, nullptr, DeviceStart{wire::Protocol::kDfmoco}),
      std::invalid_argument);
}

TEST(Stackshot3xTest, OverWifiTheLineNeverSwitchesSoNothingIsAnnounced) {
  SsBench b;
  b.dev->PowerOff();
  Device& device = *b.dev;
  device.SetHostLink(HostLink::kWifi);  // through the device interface, as serve does
  b.dev->PowerOn();
  int heard = 0;
  b.dev->SetLineSwitchListener([&](const LineSwitch&) { ++heard; });
  b.dev->SetGlobalModeFromPanel(stackshot::GlobalMode::kMotionDfMoco);
  EXPECT_TRUE(b.dev->InDfmocoMode());
  EXPECT_EQ(heard, 0);
}

TEST(Stackshot3xTest, DfmocoModeSpeaksTheStackshotDialect) {
  SsBench b;
  EXPECT_EQ(b.dev->Line().serial.baud, 38400u);
  ASSERT_EQ(b.Status(Write(
                Command::kRailConfigGlobalMode, 0,
                stackshot::EnumValue<stackshot::GlobalMode>{stackshot::GlobalMode::kMotionDfMoco})),
            Action::kRspOk);
  EXPECT_EQ(b.dev->Line().serial.baud, 57600u);
  Text(b);
  Line(b, "hi");
  EXPECT_EQ(Text(b), "hi 1 3 1.2.6\r\n");
  Line(b, "mm 2 5000");
  EXPECT_EQ(Text(b), "mm 2 0\r\n");
  Line(b, "ms");
  EXPECT_EQ(Text(b), "ms 010\r\n");
  b.RunFor(600 * kMs);
  const std::string periodic = Text(b);
  EXPECT_EQ(periodic.rfind("mm 2 ", 0), 0u) << periodic;
  b.RunFor(5 * kSec);
  EXPECT_EQ(Text(b), "mm 2 4375\r\n");  // reported while moving, not after
  Line(b, "mp *");
  EXPECT_EQ(Text(b), "mp 1 0\r\nmp 2 5000\r\nmp 3 0\r\n");
  Line(b, "zm 2");
  EXPECT_EQ(Text(b), "mp 2 0\r\n");
  Line(b, "np 3 42");
  EXPECT_EQ(Text(b), "mp 3 42\r\n");
  Line(b, "pr 1 99999");
  EXPECT_EQ(Text(b), "pr 1 8000\r\n");
  Line(b, "mm 4 10");
  EXPECT_EQ(Text(b), "parse error\r\n");
  Line(b, "sa");
  EXPECT_EQ(Text(b), "sa\r\n");
  // A binary packet is not understood in this mode.
  b.Send(Read(Command::kPing, 0, stackshot::PingRequest{1}));
  EXPECT_TRUE(b.Replies().empty());
  // Set over serial and not saved: a power cycle comes back in binary mode.
  b.dev->PowerOff();
  b.dev->PowerOn();
  EXPECT_EQ(b.dev->Line().serial.baud, 38400u);
  EXPECT_EQ(b.Ask(Read(Command::kPing, 0, stackshot::PingRequest{1})).data, (wire::Bytes{0xFE, 0}));
  // The panel switches both ways.
  b.dev->SetGlobalModeFromPanel(stackshot::GlobalMode::kMotionDfMoco);
  Line(b, "hi");
  EXPECT_EQ(Text(b), "hi 1 3 1.2.6\r\n");
  b.dev->SetGlobalModeFromPanel(stackshot::GlobalMode::kAdvanced);
  EXPECT_EQ(b.Ask(Read(Command::kPing, 0, stackshot::PingRequest{2})).data, (wire::Bytes{0xFD, 0}));
}

// --- laws -------------------------------------------------------------------------------

// A request built from the command table with random action, axis and data;
// mostly with a data length the command's layout accepts (found by trying
// the layouts' lengths), sometimes any length or an unknown command id.
rc::Gen<stackshot::Packet> GenRequest() {
  return rc::gen::exec([] {
    const auto cmds = stackshot::AllCommands();
    stackshot::Packet p;
    p.command = cmds[*rc::gen::inRange<size_t>(0, cmds.size())].id;
    if (*rc::gen::inRange(0, 10) == 0) p.command = *rc::gen::arbitrary<uint16_t>();
    p.action = static_cast<uint8_t>(*rc::gen::inRange(0, 2));
    p.axis = static_cast<uint8_t>(*rc::gen::inRange(0, 4));
    p.sub_item = *rc::gen::arbitrary<bool>();
    p.data = *rc::gen::container<wire::Bytes>(stackshot::kMotionConfigBytes,
                                              rc::gen::arbitrary<uint8_t>());
    // Small values keep enumerations, slots and registers mostly in range.
    if (*rc::gen::arbitrary<bool>()) {
      for (uint8_t& b : p.data) b = static_cast<uint8_t>(b % 4);
    }
    size_t len = *rc::gen::inRange<size_t>(0, 16);
    if (*rc::gen::inRange(0, 5) != 0) {
      for (size_t candidate : {0, 1, 2, 3, 4, 5, 7, 10, 44, 48, 132}) {
        stackshot::Packet trial = p;
        trial.data.resize(candidate);
        if (stackshot::DecodeHostPacket(trial).ok()) {
          len = candidate;
          break;
        }
      }
    }
    p.data.resize(len);
    // A switch to DfMoco mode changes the language of every later byte.
    if (p.command == stackshot::Id(Command::kRailConfigGlobalMode) && !p.data.empty() &&
        p.data[0] == static_cast<uint8_t>(stackshot::GlobalMode::kMotionDfMoco)) {
      p.data[0] = 0;
    }
    p.checksum = *rc::gen::arbitrary<uint8_t>();
    return p;
  });
}

RC_GTEST_PROP(Stackshot3xLaws, EveryRequestGetsExactlyOneLegalReply, ()) {
  SsBench b;
  const auto requests = *rc::gen::container<std::vector<stackshot::Packet>>(
      *rc::gen::inRange<size_t>(1, 12), GenRequest());
  int ok_replies = 0;
  for (const stackshot::Packet& p : requests) {
    wire::Bytes bytes;
    RC_ASSERT(stackshot::EncodePacket(p, bytes));
    b.Feed(bytes);
    b.RunFor(300 * kMs);
    const auto replies = b.Replies();
    RC_ASSERT(replies.size() == 1u);
    RC_ASSERT(replies[0].command == p.command);
    RC_ASSERT(replies[0].axis == p.axis);
    RC_ASSERT(replies[0].action >= static_cast<uint8_t>(Action::kRspOk));
    RC_ASSERT(replies[0].action <= static_cast<uint8_t>(Action::kBusy));
    RC_ASSERT(stackshot::ChecksumMatches(replies[0], stackshot::kDefaultChecksum));
    ok_replies += replies[0].action == static_cast<uint8_t>(Action::kRspOk) ? 1 : 0;
  }
  RC_CLASSIFY(ok_replies > 0, "some request succeeded");
}

RC_GTEST_PROP(Stackshot3xLaws, AnyChunkingGivesTheSameOutput, ()) {
  const auto requests = *rc::gen::container<std::vector<stackshot::Packet>>(
      *rc::gen::inRange<size_t>(1, 10), GenRequest());
  wire::Bytes stream;
  for (const auto& p : requests) {
    RC_LOG() << stackshot::Describe(p) << "\n";
    RC_ASSERT(stackshot::EncodePacket(p, stream));
  }
  SsBench whole;
  whole.Feed(stream);
  whole.RunFor(5 * kSec);
  SsBench chunked;
  size_t at = 0;
  while (at < stream.size()) {
    const size_t n = *rc::gen::inRange<size_t>(1, stream.size() - at + 1);
    chunked.Feed(wire::Bytes(stream.begin() + static_cast<ptrdiff_t>(at),
                             stream.begin() + static_cast<ptrdiff_t>(at + n)));
    at += n;
  }
  chunked.RunFor(5 * kSec);
  RC_ASSERT(whole.sink.bytes() == chunked.sink.bytes());
}

// --- the link, slot 0, read forms and the store-less unit --------------------------

// A host packet as raw bytes (forms the typed encoder does not make).
wire::Bytes RawHost(Command c, Action a, wire::Bytes data, uint8_t axis = 0) {
  stackshot::Packet p;
  p.command = stackshot::Id(c);
  p.action = static_cast<uint8_t>(a);
  p.axis = axis;
  p.data = std::move(data);
  stackshot::Seal(p, stackshot::ChecksumAlgorithm::kNegatedSum);
  wire::Bytes out;
  stackshot::EncodePacket(p, out);
  return out;
}

TEST(Stackshot3xTest, OverWifiAPacketSplitAcrossSegmentsFarApartIsStillAnswered) {
  // ERRATA 3.6: the 2 ms gap re-syncs the serial line. A TCP segment boundary
  // is no frame boundary (section 4.2 splits large commands on purpose).
  wire::Bytes ping;
  stackshot::EncodeHostCommand(Read(Command::kPing, 0, stackshot::PingRequest{7}), ping);
  for (const auto link : {Stackshot3x::HostLink::kSerial, Stackshot3x::HostLink::kWifi}) {
    SCOPED_TRACE(link == Stackshot3x::HostLink::kWifi ? "wifi" : "serial");
    SsBench b;
    b.dev->SetHostLink(link);
    b.Feed(wire::Bytes(ping.begin(), ping.begin() + 3));
    b.RunFor(50 * kMs);  // far beyond the 2 ms gap
    b.Feed(wire::Bytes(ping.begin() + 3, ping.end()));
    b.RunFor(kMs);
    const auto r = b.Replies();
    if (link == Stackshot3x::HostLink::kWifi) {
      ASSERT_EQ(r.size(), 1u);
      EXPECT_EQ(r[0].data, (wire::Bytes{0xF8, 0}));
    } else {
      EXPECT_TRUE(r.empty());  // the serial line dropped the partial packet
    }
  }
}

TEST(Stackshot3xTest, OverWifiDfmocoModeIsTakenButTheLinkKeepsTheBinaryProtocol) {
  // Section 3: the DfMoco interface "runs over USB"; section 4.2: over Wi-Fi
  // "The commands are identical" (the binary API).
  SsBench b;
  b.dev->SetHostLink(Stackshot3x::HostLink::kWifi);
  ASSERT_EQ(b.Status(Write(
                Command::kRailConfigGlobalMode, 0,
                stackshot::EnumValue<stackshot::GlobalMode>{stackshot::GlobalMode::kMotionDfMoco})),
            Action::kRspOk);
  EXPECT_TRUE(b.dev->InDfmocoMode());
  EXPECT_FALSE(b.dev->SpeaksDfmoco());
  EXPECT_EQ(b.dev->Line().serial.baud, 38400u);
  EXPECT_EQ(std::get<stackshot::EnumValue<stackshot::GlobalMode>>(
                b.AskRead(Read(Command::kRailConfigGlobalMode)).payload)
                .value,
            stackshot::GlobalMode::kMotionDfMoco);
  Line(b, "hi");
  b.RunFor(10 * kMs);
  EXPECT_TRUE(b.sink.Take().empty());  // no ASCII on Wi-Fi
  EXPECT_EQ(b.Ask(Read(Command::kPing, 0, stackshot::PingRequest{1})).data, (wire::Bytes{0xFE, 0}));
  // The same unit on USB speaks DfMoco in that mode.
  b.dev->SetHostLink(Stackshot3x::HostLink::kSerial);
  EXPECT_TRUE(b.dev->SpeaksDfmoco());
  Line(b, "hi");
  EXPECT_EQ(Text(b), "hi 1 3 1.2.6\r\n");
}

TEST(Stackshot3xTest, LoadOfSlotZeroOnANeverSavedUnitLoadsTheFactoryDefaults) {
  // CC_RAIL_CONFIG_SAVE: slot 0 is the "power on" configuration, which a unit
  // always has; "empty slot" (FAILED) is for the user slots 1-10.
  SsBench b;
  ASSERT_EQ(b.Status(Write(Command::kRailConfigBacklight, 0, stackshot::U8Value{9})),
            Action::kRspOk);
  EXPECT_EQ(b.Status(Write(Command::kRailConfigLoad, 0, stackshot::U8Value{0})), Action::kRspOk);
  EXPECT_EQ(b.dev->config(), Stackshot3xConfig::Defaults(b.dev->profile()));
  for (uint8_t slot = 1; slot <= 10; ++slot) {
    EXPECT_EQ(b.Status(Write(Command::kRailConfigLoad, 0, stackshot::U8Value{slot})),
              Action::kFailed)
        << int{slot};
  }
  // Once saved, slot 0 loads what was saved.
  ASSERT_EQ(b.Status(Write(Command::kRailConfigBacklight, 0, stackshot::U8Value{3})),
            Action::kRspOk);
  ASSERT_EQ(b.Status(Write(Command::kRailConfigSave, 0, stackshot::U8Value{0})), Action::kRspOk);
  ASSERT_EQ(b.Status(Write(Command::kRailConfigBacklight, 0, stackshot::U8Value{7})),
            Action::kRspOk);
  EXPECT_EQ(b.Status(Write(Command::kRailConfigLoad, 0, stackshot::U8Value{0})), Action::kRspOk);
  EXPECT_EQ(b.dev->config().backlight, 3);
}

TEST(Stackshot3xTest, ReadsInTheFormsTheTablesShowAreAnswered) {
  SsBench b;
  // DISTANCE_PER_REV: the read table has no units byte. With units = steps
  // the answer is in mm (a distance per revolution has no steps form).
  ASSERT_EQ(
      b.Status(Write(Command::kRailConfigUnits, 0, stackshot::EnumValue<Units>{Units::kSteps})),
      Action::kRspOk);
  b.Feed(RawHost(Command::kRailConfigDistancePerRev, Action::kRead, {}, 1));
  b.RunFor(kMs);
  auto r = b.Replies();
  ASSERT_EQ(r.size(), 1u);
  ASSERT_EQ(r[0].action, static_cast<uint8_t>(Action::kRspOk));
  auto d = stackshot::DecodeDevicePacket(r[0], stackshot::ReplyContext{Action::kRead});
  ASSERT_TRUE(d.ok());
  const auto& per_rev = std::get<stackshot::UnitsF32>(d->payload);
  EXPECT_EQ(per_rev.units, Units::kMm);
  EXPECT_FLOAT_EQ(per_rev.value.value(), 2.0f);
  // With units = mils, the configured units.
  ASSERT_EQ(
      b.Status(Write(Command::kRailConfigUnits, 0, stackshot::EnumValue<Units>{Units::kMils})),
      Action::kRspOk);
  b.Feed(RawHost(Command::kRailConfigDistancePerRev, Action::kRead, {}));
  b.RunFor(kMs);
  r = b.Replies();
  ASSERT_EQ(r.size(), 1u);
  d = stackshot::DecodeDevicePacket(r[0], stackshot::ReplyContext{Action::kRead});
  ASSERT_TRUE(d.ok());
  EXPECT_EQ(std::get<stackshot::UnitsF32>(d->payload).units, Units::kMils);
  EXPECT_NEAR(std::get<stackshot::UnitsF32>(d->payload).value.value(), 2.0 / 0.0254, 1e-3);
  // An explicit steps byte is still refused.
  b.Feed(RawHost(Command::kRailConfigDistancePerRev, Action::kRead, {2}));
  b.RunFor(kMs);
  r = b.Replies();
  ASSERT_EQ(r.size(), 1u);
  EXPECT_EQ(r[0].action, static_cast<uint8_t>(Action::kBadParam));

  // AUTO_RETURN: the read table lists a bool under Cmd Data; both forms read.
  ASSERT_EQ(b.Status(Write(Command::kRailConfigAutoReturn, 0, stackshot::BoolValue{true})),
            Action::kRspOk);
  for (const wire::Bytes& data : {wire::Bytes{}, wire::Bytes{1}, wire::Bytes{0}}) {
    b.Feed(RawHost(Command::kRailConfigAutoReturn, Action::kRead, data));
    b.RunFor(kMs);
    r = b.Replies();
    ASSERT_EQ(r.size(), 1u);
    EXPECT_EQ(r[0].action, static_cast<uint8_t>(Action::kRspOk)) << data.size();
    EXPECT_EQ(r[0].data, (wire::Bytes{1})) << data.size();
  }

  // MOTION_START: the header says Length 132 for three bools; both lengths start.
  ASSERT_EQ(b.Status(Write(Command::kMotionConfig, 0, Ramp(1, 1))), Action::kRspOk);
  wire::Bytes padded(132, 0);
  padded[0] = 1;
  b.Feed(RawHost(Command::kMotionStart, Action::kWrite, padded));
  b.RunFor(kMs);
  r = b.Replies();
  ASSERT_EQ(r.size(), 1u);
  EXPECT_EQ(r[0].action, static_cast<uint8_t>(Action::kRspOk));
  b.RunFor(2 * kSec);
  EXPECT_FLOAT_EQ(Current(b, 0), static_cast<float>(kStepsPerMm));
  // Any other length is still a length error.
  b.Feed(RawHost(Command::kMotionStart, Action::kWrite, wire::Bytes(4, 1)));
  b.RunFor(kMs);
  r = b.Replies();
  ASSERT_EQ(r.size(), 1u);
  EXPECT_EQ(r[0].action, static_cast<uint8_t>(Action::kBadParam));
}

TEST(Stackshot3xTest, WithoutAStoreResetAndPowerCyclesKeepTheSerialNvmAndSlots) {
  // A real unit keeps its NVM across a reset: so does one embedded with no
  // store (it then lives in the device's memory).
  sim::Scheduler sched;
  testing::RecordingSink sink(sched);
  Stackshot3x dev(sched, sink, {}, nullptr);
  dev.PowerOn();
  auto ask = [&](const stackshot::HostCommand& c) {
    wire::Bytes b;
    stackshot::EncodeHostCommand(c, b);
    dev.OnHostBytes(b);
    sched.RunUntil(sched.Now() + kMs);
    stackshot::PacketDecoder d(true);
    std::vector<stackshot::DecodedPacket> out;
    d.Feed(sink.Take(), out);
    return out.size() == 1 ? static_cast<Action>(out[0].packet.action) : Action::kRead;
  };
  ASSERT_EQ(ask(Write(Command::kSerialNumber, 0, stackshot::U32Value{4242})), Action::kRspOk);
  ASSERT_EQ(ask(Write(Command::kNvmAccess, 0, stackshot::NvmWrite{5, 77})), Action::kRspOk);
  ASSERT_EQ(ask(Write(Command::kRailConfigBacklight, 0, stackshot::U8Value{8})), Action::kRspOk);
  ASSERT_EQ(ask(Write(Command::kRailConfigSave, 0, stackshot::U8Value{3})), Action::kRspOk);
  ASSERT_EQ(ask(Write(Command::kReset)), Action::kRspOk);
  sched.RunUntil(sched.Now() + kSec);
  EXPECT_EQ(dev.SerialNumber(), 4242u);
  EXPECT_EQ(ask(Write(Command::kSerialNumber, 0, stackshot::U32Value{1})), Action::kFailed);
  EXPECT_EQ(ask(Write(Command::kRailConfigLoad, 0, stackshot::U8Value{3})), Action::kRspOk);
  EXPECT_EQ(dev.config().backlight, 8);
  dev.PowerOff();
  dev.PowerOn();
  EXPECT_EQ(dev.SerialNumber(), 4242u);
  EXPECT_EQ(ask(Write(Command::kRailConfigLoad, 0, stackshot::U8Value{3})), Action::kRspOk);
  EXPECT_EQ(dev.State()["serial_number"], 4242u);
}

RC_GTEST_PROP(Stackshot3xLaws, GarbageNeverCrashesAndOnlyLegalPacketsComeOut, ()) {
  SsBench b;
  const auto chunks = *rc::gen::container<std::vector<wire::Bytes>>(
      *rc::gen::inRange<size_t>(1, 8), rc::gen::arbitrary<wire::Bytes>());
  for (const auto& c : chunks) {
    b.Feed(c);
    b.RunFor(*rc::gen::inRange<sim::TimeNs>(0, 10 * kMs));
  }
  b.RunFor(5 * kSec);
  const wire::Bytes out = b.sink.bytes();
  if (b.dev->InDfmocoMode()) return;  // garbage may have switched the dialect
  stackshot::PacketDecoder d(true);
  std::vector<stackshot::DecodedPacket> packets;
  d.Feed(b.sink.Take(), packets);
  RC_ASSERT(d.skipped_total() == 0u);
  RC_ASSERT(d.pending_bytes() == 0u);
  for (const auto& p : packets) RC_ASSERT(p.packet.action >= 2 && p.packet.action <= 8);
}

}  // namespace
}  // namespace moco::devices
