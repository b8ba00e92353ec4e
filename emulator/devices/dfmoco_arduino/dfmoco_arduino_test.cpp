// The emulated DFMoco sketch against dfmoco-protocol.txt and FACTS.md "DFMoco",
// in virtual time: every command and error reply per dialect, framing, the
// periodic `mp` reports, the outgoing queue, go-motion, power cycling, and
// properties (any chunking, every answerable request answered, garbage safe).
#include "devices/dfmoco_arduino/dfmoco_arduino.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>

#include "devices/dfmoco_arduino/dfmoco_test_support.h"
#include "sim/planner_dfmoco.h"
#include "sim/step_trace.h"
#include "wire/dfmoco_sketch_reader.h"

namespace moco::devices {
namespace {

using sim::kNsPerMs;
using sim::kNsPerSecond;
using sim::TimeNs;
using testing::Bench;
using testing::TimedLine;
using Texts = std::vector<std::string>;

constexpr TimeNs kSec = kNsPerSecond;
constexpr TimeNs kMs = kNsPerMs;

DfmocoProfile Profile(DfmocoBoard board, DfmocoFirmware firmware) {
  DfmocoProfile p;
  p.board = board;
  p.firmware = firmware;
  return p;
}

// A bench past the boot `hi`, at t = 1 s.
Bench& Settled(Bench& b) {
  b.RunUntil(kSec);
  b.TakeLines();
  return b;
}

// Sends `line` at the bench's current time and returns what the device says
// within `window`.
Texts Ask(Bench& b, std::string_view line, TimeNs window = 20 * kMs) {
  b.Line(line);
  b.RunFor(window);
  return b.TakeTexts();
}

// Byte-time arithmetic of a 57600 8N1 line: 5760 bytes per second.
TimeNs BytesTime(uint64_t bytes) {
  return static_cast<TimeNs>((bytes * 1'000'000'000 + 5759) / 5760);
}

class DfmocoDialects : public ::testing::TestWithParam<DfmocoFirmware> {};

// ---------------------------------------------------------------------------------------
// Boot and identity

struct BootCase {
  DfmocoBoard board;
  DfmocoFirmware firmware;
  const char* hello;  // FACTS: `hi 2 4 2.0.0`, `hi 1 4 1.3.0`, ...
};

class DfmocoBoot : public ::testing::TestWithParam<BootCase> {};

TEST_P(DfmocoBoot, SendsHiUnpromptedAtPowerOnAndOnRequest) {
  Bench b(Profile(GetParam().board, GetParam().firmware));
  ASSERT_EQ(b.sink.chunks.size(), 1u);
  EXPECT_EQ(b.sink.chunks[0].t_ns, 0);
  EXPECT_EQ(b.sink.chunks[0].bytes, std::string(GetParam().hello) + "\r\n");
  Settled(b);
  EXPECT_EQ(Ask(b, "hi"), Texts{GetParam().hello});
}

INSTANTIATE_TEST_SUITE_P(
    BoardsAndVersions, DfmocoBoot,
    ::testing::Values(BootCase{DfmocoBoard::kUno, DfmocoFirmware::k2_0_0, "hi 2 4 2.0.0"},
                      BootCase{DfmocoBoard::kMega, DfmocoFirmware::k2_0_0, "hi 2 8 2.0.0"},
                      BootCase{DfmocoBoard::kUno, DfmocoFirmware::k1_3_1, "hi 1 4 1.3.1"},
                      BootCase{DfmocoBoard::kMega, DfmocoFirmware::k1_3_1, "hi 1 8 1.3.1"},
                      BootCase{DfmocoBoard::kUno, DfmocoFirmware::k1_3_0, "hi 1 4 1.3.0"},
                      BootCase{DfmocoBoard::kMega, DfmocoFirmware::k1_3_0, "hi 1 8 1.3.0"},
                      BootCase{DfmocoBoard::kUno, DfmocoFirmware::k1_2_7, "hi 1 4 1.2.7"},
                      BootCase{DfmocoBoard::kMega, DfmocoFirmware::k1_2_7, "hi 1 8 1.2.7"}));

TEST(DfmocoArduino, IdentityAndLine) {
  Bench b;
  EXPECT_EQ(b.dev.Model(), "dfmoco");
  const wire::LineSettings line = b.dev.Line().serial;
  EXPECT_EQ(line.baud, 57600u);
  EXPECT_EQ(line.data_bits, 8);
  EXPECT_EQ(line.stop_bits, 1);
  EXPECT_EQ(line.parity, 'N');
  ASSERT_NE(b.dev.rig(), nullptr);
  EXPECT_EQ(b.dev.rig()->motor_count(), 4);
  EXPECT_EQ(b.dev.gio(), nullptr);
}

TEST(DfmocoArduino, BootDelayLosesEarlyBytesThenAnnounces) {
  DfmocoProfile p;
  p.boot_delay_ms = 1600;
  Bench b(p);
  EXPECT_TRUE(b.dev.Powered());
  EXPECT_FALSE(b.dev.Running());
  b.RunUntil(kSec);
  b.Line("ms");  // the bootloader has the line: lost
  b.RunUntil(1600 * kMs);
  const std::vector<TimedLine> lines = b.TakeLines();
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_EQ(lines[0].text, "hi 2 4 2.0.0");
  EXPECT_EQ(lines[0].t_ns, 1600 * kMs);
  EXPECT_EQ(Ask(b, "ms"), Texts{"ms 0000"});
}

TEST(DfmocoArduino, PoweredOffIsSilentAndDeaf) {
  Bench b({}, /*power_on=*/false);
  b.Line("hi");
  b.RunUntil(5 * kSec);
  EXPECT_TRUE(b.sink.chunks.empty());
  EXPECT_FALSE(b.dev.Powered());
}

TEST(DfmocoArduino, PowerOffDropsStateAndCancelsTimers) {
  Bench b;
  Settled(b);
  Ask(b, "pr 1 1000");
  Ask(b, "np 2 777");
  Ask(b, "mm 1 50000");
  ASSERT_TRUE(b.dev.MotorMoving(1));
  b.dev.PowerOff();
  EXPECT_EQ(b.sched.PendingCount(), 0u);
  b.Line("ms");
  b.RunFor(3 * kSec);
  EXPECT_TRUE(b.TakeLines().empty());
  b.dev.PowerOn();
  b.RunFor(10 * kMs);
  EXPECT_EQ(b.TakeTexts(), Texts{"hi 2 4 2.0.0"});
  EXPECT_EQ(Ask(b, "ms"), Texts{"ms 0000"});
  EXPECT_EQ(Ask(b, "mp 1"), Texts{"mp 1 0"});
  EXPECT_EQ(Ask(b, "mp 2"), Texts{"mp 2 0"});
  EXPECT_EQ(b.dev.PulseRate(1), 5000);
}

TEST(DfmocoArduino, PowerOffForgetsAPartialLine) {
  Bench b;
  Settled(b);
  b.Host("m");
  b.dev.PowerOff();
  b.dev.PowerOn();
  b.TakeLines();
  EXPECT_EQ(Ask(b, "s"), Texts{});  // "s" alone: not "ms"
}

TEST(DfmocoArduino, ResetOnOpenRebootsLikeAnUno) {
  DfmocoProfile p;
  p.reset_on_open = true;
  Bench b(p);
  Settled(b);
  Ask(b, "np 1 42");
  b.dev.OnHostLink(true);
  b.RunFor(10 * kMs);
  EXPECT_EQ(b.TakeTexts(), Texts{"hi 2 4 2.0.0"});
  EXPECT_EQ(Ask(b, "mp 1"), Texts{"mp 1 0"});
  b.dev.OnHostLink(false);
  b.RunFor(10 * kMs);
  EXPECT_TRUE(b.TakeLines().empty());
}

TEST(DfmocoArduino, NoResetOnOpenByDefault) {
  Bench b;
  Settled(b);
  Ask(b, "np 1 42");
  b.dev.OnHostLink(true);
  EXPECT_EQ(Ask(b, "mp 1"), Texts{"mp 1 42"});
}

// ---------------------------------------------------------------------------------------
// Framing

TEST(DfmocoArduino, OnlyCrLfEndsALine) {
  Bench b;
  Settled(b);
  b.Host("ms\n");
  b.RunFor(20 * kMs);
  EXPECT_TRUE(b.TakeLines().empty()) << "a bare \\n completes nothing";
  b.Host("\r");
  b.RunFor(20 * kMs);
  EXPECT_TRUE(b.TakeLines().empty()) << "a \\r waits for its \\n";
  b.Host("\n");
  b.RunFor(20 * kMs);
  EXPECT_EQ(b.TakeTexts(), Texts{"ms 0000"});
  // The discarded \n joins the bytes around it into one line.
  b.Host("m\ns\r\n");
  b.RunFor(20 * kMs);
  EXPECT_EQ(b.TakeTexts(), Texts{"ms 0000"});
}

TEST(DfmocoArduino, EveryLineOutEndsInCrLf) {
  Bench b;
  Settled(b);
  Ask(b, "mm 1 3000", 3 * kSec);
  for (const testing::RecordingSink::Chunk& c : b.sink.chunks) {
    ASSERT_GE(c.bytes.size(), 2u);
    EXPECT_EQ(c.bytes.substr(c.bytes.size() - 2), "\r\n") << c.bytes;
    EXPECT_EQ(c.bytes.find("\r\n"), c.bytes.size() - 2) << "one line per write";
  }
}

TEST(DfmocoArduino, UnknownCommandsGetNoReply) {
  Bench b;
  Settled(b);
  for (const char* line : {"xx", "xx 1 2", "", "m", "MS", "MM 1 2", " mm 1 2", "xmm 1 2", "hello",
                           "mz 1", "\x01\x02"}) {
    EXPECT_EQ(Ask(b, line), Texts{}) << "line \"" << line << "\"";
  }
}

// ---------------------------------------------------------------------------------------
// Commands, one by one (FACTS "DFMoco")

TEST(DfmocoArduino, MotorStatusHasOneDigitPerMotor) {
  Bench uno;
  EXPECT_EQ(Ask(Settled(uno), "ms"), Texts{"ms 0000"});
  Bench mega(Profile(DfmocoBoard::kMega, DfmocoFirmware::k2_0_0));
  EXPECT_EQ(Ask(Settled(mega), "ms"), Texts{"ms 00000000"});
  Ask(mega, "mm 7 100");
  EXPECT_EQ(Ask(mega, "ms"), Texts{"ms 00000010"});
}

TEST(DfmocoArduino, MoveAnswersTargetOrPositionWhenAlreadyThere) {
  Bench b;
  Settled(b);
  EXPECT_EQ(Ask(b, "mm 2 300"), Texts{"mm 2 300"});
  EXPECT_EQ(Ask(b, "ms"), Texts{"ms 0100"});
  EXPECT_EQ(Ask(b, "mm 2 300"), Texts{"mm 2 300"}) << "still moving: a new move";
  b.RunFor(3 * kSec);
  b.TakeLines();
  EXPECT_EQ(Ask(b, "ms"), Texts{"ms 0000"});
  EXPECT_EQ(Ask(b, "mp 2"), Texts{"mp 2 300"});
  EXPECT_EQ(Ask(b, "mm 2 300"), Texts{"mp 2 300"}) << "already there";
  EXPECT_EQ(Ask(b, "mm 2 -40"), Texts{"mm 2 -40"});
  b.RunFor(3 * kSec);
  EXPECT_EQ(b.dev.rig()->motor(2).Position(), -40);
}

TEST(DfmocoArduino, PositionQuery) {
  Bench b;
  Settled(b);
  EXPECT_EQ(Ask(b, "mp 3"), Texts{"mp 3 0"});
  EXPECT_EQ(Ask(b, "mp 4"), Texts{"mp 4 0"});
}

TEST(DfmocoArduino, NewPositionAnswersMp) {
  Bench b;
  Settled(b);
  EXPECT_EQ(Ask(b, "np 4 -12345"), Texts{"mp 4 -12345"});  // FACTS: mp, not np
  EXPECT_EQ(Ask(b, "mp 4"), Texts{"mp 4 -12345"});
  EXPECT_EQ(Ask(b, "mm 4 -12345"), Texts{"mp 4 -12345"});
  EXPECT_EQ(b.dev.rig()->motor(4).Position(), -12345);
}

TEST(DfmocoArduino, ZeroAnswersMpZeroTwice) {
  Bench b;
  Settled(b);  // t = 1 s; reports fall at 1.5 s, 2.5 s, ...
  Ask(b, "np 1 500");
  b.Line("zm 1");
  b.RunUntil(1400 * kMs);
  EXPECT_EQ(b.TakeTexts(), Texts{"mp 1 0"});
  b.RunUntil(4 * kSec);
  const std::vector<TimedLine> later = b.TakeLines();
  ASSERT_EQ(later.size(), 1u);
  EXPECT_EQ(later[0].text, "mp 1 0");
  EXPECT_EQ(later[0].t_ns, 1500 * kMs) << "the second comes with the next report";
  EXPECT_EQ(b.dev.rig()->motor(1).Position(), 0);
}

TEST(DfmocoArduino, ZeroWhileMovingStopsDeadOnZero) {
  Bench b;
  Settled(b);
  Ask(b, "mm 1 100000", 500 * kMs);
  ASSERT_TRUE(b.dev.MotorMoving(1));
  b.Line("zm 1");
  b.RunFor(5 * kMs);
  EXPECT_EQ(b.TakeTexts(), Texts{"mp 1 0"});
  EXPECT_FALSE(b.dev.MotorMoving(1));
  b.RunFor(3 * kSec);
  EXPECT_EQ(b.dev.rig()->motor(1).Position(), 0);
}

TEST(DfmocoArduino, StopMotorDeceleratesFromTheLoadedChunkSpeedAndReportsTheChunkEnd) {
  Bench b;
  Settled(b);
  // pr 5000: accel 2500 steps/s^2. `mm` at t = 1 s is planned by the update
  // at 1.05 s, whose chunk steps during 1.10 .. 1.15 s: the position counter
  // after the update at t holds x(t - 1 s), the steps trail it by two chunks.
  b.Line("mm 1 100000");
  b.RunUntil(3010 * kMs);
  b.TakeLines();
  b.Line("sm 1");
  b.RunFor(5 * kMs);
  // The counter after the update at 3.00 s: x(2.0) = 5000, 4999 in the
  // sketch's single precision; `mp` reports it at once.
  const Texts replies = b.TakeTexts();
  ASSERT_EQ(replies.size(), 2u);
  EXPECT_EQ(replies[0], "sm 1");
  EXPECT_EQ(replies[1], "mp 1 4999");
  // stopMotor: the loaded chunk is 4999 - 4753 = 246 steps, speed 246 * 65.6,
  // v = 20 * speed / 65.536 = 4924.8 steps/s; braking at 2500 steps/s^2 covers
  // int(v^2 / 5000) more: the destination 9849 is computed once.
  EXPECT_EQ(b.dev.State()["motors"][0]["target_steps"], 9849);
  // It decelerates over about 2 s, not at once.
  const int64_t at_stop = b.dev.rig()->motor(1).Position();
  b.RunUntil(3500 * kMs);
  EXPECT_GT(b.dev.rig()->motor(1).Position(), at_stop + 2000);
  b.RunUntil(4900 * kMs);
  EXPECT_TRUE(b.dev.MotorMoving(1));
  b.RunUntil(5300 * kMs);
  EXPECT_FALSE(b.dev.MotorMoving(1));
  EXPECT_EQ(b.dev.rig()->motor(1).Position(), 9849);
}

TEST(DfmocoArduino, StopOnAMotorAtRest) {
  Bench b;
  Settled(b);
  EXPECT_EQ(Ask(b, "sm 3"), (Texts{"sm 3", "mp 3 0"}));
}

TEST(DfmocoArduino, StopAllDeceleratesEveryMotorFromItsLoadedChunk) {
  Bench b;
  Settled(b);
  b.Line("mm 1 100000");
  b.Line("mm 3 -100000");
  b.RunUntil(3010 * kMs);
  b.TakeLines();
  EXPECT_EQ(Ask(b, "sa", 0), Texts{"sa"});
  EXPECT_TRUE(b.dev.MotorMoving(1));
  EXPECT_TRUE(b.dev.MotorMoving(3));
  b.RunUntil(6 * kSec);
  b.TakeLines();
  EXPECT_EQ(Ask(b, "ms"), Texts{"ms 0000"});
  // Motor 1 as in the `sm` case: 4999 + int(4924.8^2 / 5000) = 9849. The
  // direction pins start forward, so motor 3's first chunk only turns its pin
  // and its ramp runs one chunk behind: counter -4753, loaded chunk 241 steps
  // (v = 4824.7), -4753 - 4655 = -9408.
  EXPECT_EQ(b.dev.rig()->motor(1).Position(), 9849);
  EXPECT_EQ(b.dev.rig()->motor(3).Position(), -9408);
}

TEST(DfmocoArduino, PulseRateIsClampedTo100Through20000) {
  Bench b;
  Settled(b);
  EXPECT_EQ(Ask(b, "pr 1 20000"), Texts{"pr 1 20000"});
  EXPECT_EQ(Ask(b, "pr 1 25000"), Texts{"pr 1 20000"});
  EXPECT_EQ(Ask(b, "pr 2 99"), Texts{"pr 2 100"});
  EXPECT_EQ(Ask(b, "pr 2 -7"), Texts{"pr 2 100"});
  EXPECT_EQ(Ask(b, "pr 3 1234"), Texts{"pr 3 1234"});
  EXPECT_EQ(b.dev.PulseRate(4), 5000) << "default";
}

TEST(DfmocoArduino, PulseRateSetsSpeedAndHalfAsMuchAccelerationStepsTrailingThePlanByTwoChunks) {
  Bench b;
  Settled(b);
  // pr 1000: 1000 steps/s, 500 steps/s^2. 4000 steps: 2 s up (1000 steps),
  // 2 s cruise (2000 steps), 2 s down. Planned from the update at 1.05 s, the
  // steps follow x(t - 1.1 s) (the chunk an update plans steps one chunk later).
  b.Line("pr 1 1000");
  b.Line("mm 1 4000");
  b.RunUntil(2 * kSec);
  EXPECT_EQ(b.dev.rig()->motor(1).Position(), 202);  // int(250 * 0.9^2)
  b.RunUntil(5 * kSec);
  EXPECT_EQ(b.dev.rig()->motor(1).Position(), 2899);  // 1000 + 1000 * 1.9, single precision
  b.RunUntil(6950 * kMs);
  EXPECT_TRUE(b.dev.MotorMoving(1));
  b.RunUntil(7150 * kMs);  // the sketch plans a chunk ahead of the steps
  EXPECT_FALSE(b.dev.MotorMoving(1));
  EXPECT_EQ(b.dev.rig()->motor(1).Position(), 4000);
}

TEST(DfmocoArduino, StepsNeverExceed20kHzAndFallOn25usTicksAcrossEveryPlanningWindow) {
  Bench b;
  Settled(b);
  Ask(b, "pr 1 20000");
  // 30000 steps at 20000 steps/s take about 2.5 s: longer than one planning
  // window (2 s), so the steps must run on seamlessly when it is extended.
  TimeNs last = -1;
  int64_t edges = 0;
  int64_t gaps_over_a_chunk = 0;
  sim::StepTrace trace(b.dev.rig()->motor(1), 16, 0, sim::kTimeNever, [&](const sim::StepEdge& e) {
    EXPECT_EQ(e.time_ns % sim::kDfmocoTickNs, 0);
    if (last >= 0) {
      EXPECT_GE(e.time_ns - last, 2 * sim::kDfmocoTickNs);
      if (e.time_ns - last > sim::kDfmocoChunkNs) ++gaps_over_a_chunk;
    }
    last = e.time_ns;
    ++edges;
  });
  Ask(b, "mm 1 30000", 6 * kSec);
  trace.Sync();
  EXPECT_EQ(edges, 30000);
  EXPECT_EQ(gaps_over_a_chunk, 0) << "no pause where a window ends";
  EXPECT_EQ(b.dev.rig()->motor(1).Position(), 30000);
}

// jm: toward the destination a short way at a time (the host repeats it).
TEST(DfmocoArduino, JogMovesTowardTheDestinationAndStopsIfNotRepeated) {
  Bench b;
  Settled(b);
  EXPECT_EQ(Ask(b, "jm 1 100000"), Texts{"jm 1"});
  EXPECT_TRUE(b.dev.MotorMoving(1));
  b.RunFor(5 * kSec);
  // pr 5000 (2500 steps/s^2): half a second of speeding up reaches 1250 steps/s
  // after int(312.5) = 312 steps; braking from there: int(312 + 312.5) = 624.
  EXPECT_FALSE(b.dev.MotorMoving(1));
  EXPECT_EQ(b.dev.rig()->motor(1).Position(), 624);
}

TEST(DfmocoArduino, RepeatedJogKeepsGoingAndStopsAtTheDestination) {
  Bench b;
  Settled(b);
  for (int i = 0; i < 40; ++i) {  // 4 s of jogging, a `jm` every 100 ms
    EXPECT_EQ(Ask(b, "jm 2 -3000", 100 * kMs).front(), "jm 2");
  }
  b.RunFor(5 * kSec);
  EXPECT_EQ(b.dev.rig()->motor(2).Position(), -3000);
}

TEST(DfmocoArduino, JogVelocityScalesSpeedOnProtocol2) {
  Bench b;
  Settled(b);
  // 50 %: 2500 steps/s max, 1250 steps/s^2; half a second reaches 625 steps/s
  // after int(156.25) = 156 steps; braking at the same 1250 steps/s^2 takes
  // 156.25 more (jogMotor): int(156 + 156.25) = 312.
  EXPECT_EQ(Ask(b, "jm 1 100000 5000"), Texts{"jm 1"});
  b.RunFor(5 * kSec);
  EXPECT_EQ(b.dev.rig()->motor(1).Position(), 312);
}

TEST(DfmocoArduino, JogVelocityZeroStops) {
  Bench b;
  Settled(b);
  Ask(b, "mm 1 100000", 2 * kSec);
  EXPECT_EQ(Ask(b, "jm 1 100000 0"), Texts{"jm 1"});
  b.RunFor(5 * kSec);
  EXPECT_FALSE(b.dev.MotorMoving(1));
  EXPECT_LT(b.dev.rig()->motor(1).Position(), 10000);
}

TEST(DfmocoArduino, JogAgainstTheMotionStops) {
  Bench b;
  Settled(b);
  Ask(b, "mm 1 100000", 2 * kSec);  // 2500 steps/s after 1 s
  EXPECT_EQ(Ask(b, "jm 1 -100000"), Texts{"jm 1"});
  b.RunFor(5 * kSec);
  EXPECT_FALSE(b.dev.MotorMoving(1));
  EXPECT_GT(b.dev.rig()->motor(1).Position(), 0) << "stopped, did not reverse";
}

TEST_P(DfmocoDialects, JogVelocityArgumentOnlyFromProtocol2) {
  Bench b(Profile(DfmocoBoard::kUno, GetParam()));
  Settled(b);
  const bool v2 = GetParam() == DfmocoFirmware::k2_0_0;
  EXPECT_EQ(Ask(b, "jm 1 1000 5000"), Texts{v2 ? "jm 1" : "parse error"});
  EXPECT_EQ(Ask(b, "jm 2 1000"), Texts{"jm 2"});
  EXPECT_EQ(Ask(b, "jm 2 1000 10001"), Texts{"parse error"});
}

TEST_P(DfmocoDialects, CommandsAnswerAlike) {
  Bench b(Profile(DfmocoBoard::kMega, GetParam()));
  Settled(b);
  EXPECT_EQ(Ask(b, "ms"), Texts{"ms 00000000"});
  EXPECT_EQ(Ask(b, "pr 8 300"), Texts{"pr 8 300"});
  EXPECT_EQ(Ask(b, "np 8 10"), Texts{"mp 8 10"});
  EXPECT_EQ(Ask(b, "mm 8 20"), Texts{"mm 8 20"});
  EXPECT_EQ(Ask(b, "sm 5"), (Texts{"sm 5", "mp 5 0"}));
  EXPECT_EQ(Ask(b, "im 6 5"), Texts{"im 6"});
  EXPECT_EQ(Ask(b, "sa"), Texts{"sa"});
  EXPECT_EQ(Ask(b, "mm 9 1"), Texts{"parse error"});
  EXPECT_EQ(Ask(b, "go"), Texts{"parse error"});
}

INSTANTIATE_TEST_SUITE_P(Versions, DfmocoDialects,
                         ::testing::Values(DfmocoFirmware::k1_2_7, DfmocoFirmware::k1_3_0,
                                           DfmocoFirmware::k1_3_1, DfmocoFirmware::k2_0_0));

TEST(DfmocoArduino, InchMovesTwoStepsFromThePositionAndClampsOnlyTheDestination) {
  Bench b;
  Settled(b);
  // inchMotor: direction = sign(target - destination); the motion is always
  // position +- 2 (movePosition[1]); only the destination is clamped to the target.
  EXPECT_EQ(Ask(b, "im 1 5", 200 * kMs), Texts{"im 1"});
  EXPECT_EQ(b.dev.rig()->motor(1).Position(), 2);
  Ask(b, "im 1 5", 200 * kMs);
  EXPECT_EQ(b.dev.rig()->motor(1).Position(), 4);
  Ask(b, "im 1 5", 200 * kMs);
  EXPECT_EQ(b.dev.rig()->motor(1).Position(), 6) << "two steps, past the target";
  EXPECT_EQ(b.dev.State()["motors"][0]["target_steps"], 5) << "the destination is clamped";
  // The target is not above the destination (5): the inch goes down.
  Ask(b, "im 1 5", 200 * kMs);
  EXPECT_EQ(b.dev.rig()->motor(1).Position(), 4);
  Ask(b, "im 1 -100", 200 * kMs);
  EXPECT_EQ(b.dev.rig()->motor(1).Position(), 2);
}

TEST(DfmocoArduino, InchWhileMovingStops) {
  Bench b;
  Settled(b);
  Ask(b, "mm 1 100000", 2 * kSec);
  EXPECT_EQ(Ask(b, "im 1 100000"), Texts{"im 1"});
  b.RunFor(5 * kSec);
  EXPECT_FALSE(b.dev.MotorMoving(1));
  EXPECT_LT(b.dev.rig()->motor(1).Position(), 10000);
}

// ---------------------------------------------------------------------------------------
// Error replies

TEST_P(DfmocoDialects, ParseErrors) {
  Bench b(Profile(DfmocoBoard::kUno, GetParam()));
  Settled(b);
  for (const char* line : {"mm 1",
                           "mm 1 2 3",
                           "mm 5 10",
                           "mm 0 10",
                           "mm -1 10",
                           "mp",
                           "mp 1 2",
                           "mp 5",
                           "sm",
                           "sm 0",
                           "pr 1",
                           "pr 9 100",
                           "zm",
                           "zm 5",
                           "np 1",
                           "np 1 x",
                           "im 1",
                           "im 5 1",
                           "jm 1",
                           "jm 1 5 10001",
                           "jm 1 5 -1",
                           "go",
                           "go 1",
                           "bf 1000 500",
                           "bf 1000 500 1 0 0",
                           "bf 1000 500 5 0 0 0",
                           "bf 0 500 1 0 0 0",
                           "bf -5 500 1 0 0 0"}) {
    EXPECT_EQ(Ask(b, line), Texts{"parse error"}) << "line \"" << line << "\"";
  }
  EXPECT_EQ(Ask(b, "ms"), Texts{"ms 0000"}) << "nothing moved";
}

// processUserMessage, byte by byte (wire/dfmoco_sketch_reader.h): an argument
// starts at a digit or '-' after a space, later digits append with 32-bit
// wrap-around, other bytes are skipped, the sign applies at a space or the
// line end right after a digit.
TEST(DfmocoArduino, NumbersAreReadAsTheSketchReadsThemByteByByte) {
  Bench b;
  Settled(b);
  EXPECT_EQ(Ask(b, "mm 1 --5"), Texts{"mm 1 -5"}) << "the second '-' is skipped";
  b.RunFor(3 * kSec);
  b.TakeLines();
  EXPECT_EQ(b.dev.rig()->motor(1).Position(), -5);
  EXPECT_EQ(Ask(b, "np 2 99999999999"), Texts{"mp 2 1215752191"}) << "wraps in 32 bits";
  EXPECT_EQ(Ask(b, "np 2 4294967295"), Texts{"mp 2 -1"});
  EXPECT_EQ(Ask(b, "np 2 1.5"), Texts{"mp 2 15"}) << "the '.' is skipped";
  EXPECT_EQ(Ask(b, "np 2 -7x"), Texts{"mp 2 7"}) << "no digit before the end: no sign";
  EXPECT_EQ(Ask(b, "np 2 -7 "), Texts{"mp 2 -7"});
  EXPECT_EQ(Ask(b, "np 2 -"), Texts{"mp 2 0"});
  EXPECT_EQ(Ask(b, "np  2   30"), Texts{"mp 2 30"}) << "any run of spaces";
  EXPECT_EQ(Ask(b, "np 2 30\rxyz"), Texts{"mp 2 30"}) << "a bare '\\r' ends the arguments";
}

TEST(DfmocoArduino, ANonNumberIsNoArgumentAtAll) {
  Bench b;
  Settled(b);
  // "x" does not start an argument: `mm 1 x` has one argument, a parse error.
  EXPECT_EQ(Ask(b, "mm 1 x"), Texts{"parse error"});
  EXPECT_EQ(Ask(b, "np 1 x"), Texts{"parse error"});
  EXPECT_EQ(Ask(b, "mm 1 x 40"), Texts{"mm 1 40"});
  b.RunFor(3 * kSec);
  b.TakeLines();
  EXPECT_EQ(b.dev.rig()->motor(1).Position(), 40);
}

TEST(DfmocoArduino, WordsWithoutArgumentsIgnoreTheRestOfTheLine) {
  Bench b;
  Settled(b);
  // hi, ms, sa and go take no arguments: the sketch skips to the line end.
  EXPECT_EQ(Ask(b, "ms 1"), Texts{"ms 0000"});
  EXPECT_EQ(Ask(b, "ms\t"), Texts{"ms 0000"});
  EXPECT_EQ(Ask(b, "msx 1 2 3"), Texts{"ms 0000"});
  EXPECT_EQ(Ask(b, "hi 7"), Texts{"hi 2 4 2.0.0"});
  EXPECT_EQ(Ask(b, "sa 1"), Texts{"sa"});
}

TEST(DfmocoArduino, SketchReaderDropsADigitBeforeTheFirstArgument) {
  // Reading: the sketch would write in front of its argument array.
  EXPECT_EQ(dfmoco::ReadLineAsSketch("mm5 1").kind, dfmoco::SketchReading::Kind::kNothing);
  const dfmoco::SketchReading r = dfmoco::ReadLineAsSketch("jm 3 -100 2500");
  ASSERT_EQ(r.kind, dfmoco::SketchReading::Kind::kCommand);
  EXPECT_EQ(r.CanonicalLine(), "jm 3 -100 2500");
  std::string forty = "mm";
  for (int i = 0; i < 40; ++i) forty += " -1";
  EXPECT_EQ(dfmoco::ReadLineAsSketch(forty).kind, dfmoco::SketchReading::Kind::kTooManyArgs);
  forty.resize(forty.size() - 3);
  EXPECT_EQ(dfmoco::ReadLineAsSketch(forty).args.size(), 39u) << "39 arguments fit";
}

TEST_P(DfmocoDialects, FortyArgumentsAreTooMany) {
  Bench b(Profile(DfmocoBoard::kUno, GetParam()));
  Settled(b);
  std::string forty = "bf";
  for (int i = 0; i < 40; ++i) forty += " 1";
  EXPECT_EQ(Ask(b, forty), Texts{"error: too many args"});
  std::string thirty_eight = "bf 1000 500";
  for (int i = 0; i < 9; ++i) thirty_eight += " 1 0 0 0";
  EXPECT_EQ(Ask(b, thirty_eight), Texts{"bf 1000"}) << "38 arguments fit";
  std::string many = "mm";
  for (int i = 0; i < 300; ++i) many += " 12";
  EXPECT_EQ(Ask(b, many), Texts{"error: too many args"}) << "past the line buffer too";
  EXPECT_EQ(Ask(b, "ms"), Texts{"ms 0000"});
}

// ---------------------------------------------------------------------------------------
// Periodic position reports

TEST(DfmocoArduino, MpEverySecondWhileMovingAndOnceAfterTheStop) {
  Bench b;
  Settled(b);
  // Planned from the update at 1.05 s: 2 s up to 5000 steps/s (5000 steps),
  // 2 s cruise (10000), 2 s down (5000), 20000 in the counter at t = 7 s.
  EXPECT_EQ(Ask(b, "mm 1 20000", 0), Texts{"mm 1 20000"});
  b.RunUntil(10 * kSec);
  const std::vector<TimedLine> lines = b.TakeLines();
  // Reports fall 0.5 s + k s after boot and carry the position counter: after
  // the update at t it holds x(tau), tau = t - 1 s, in single precision:
  //   tau 0.5: 1250 tau^2 = 312.5     tau 1.5: 2812.5
  //   tau 2.5: 5000 + 5000 (tau - 2) = 7500     tau 3.5: 12500
  //   tau 4.5: 15000 + 5000 (tau - 4) - 1250 (tau - 4)^2 = 17187.5
  //   tau 5.5: 19687.5, and after the stop at 7 s: 20000 at 7.5 s.
  const std::vector<std::pair<TimeNs, std::string>> want = {
      {1500 * kMs, "mp 1 312"},   {2500 * kMs, "mp 1 2812"},  {3500 * kMs, "mp 1 7499"},
      {4500 * kMs, "mp 1 12499"}, {5500 * kMs, "mp 1 17187"}, {6500 * kMs, "mp 1 19687"},
      {7500 * kMs, "mp 1 20000"}};
  ASSERT_EQ(lines.size(), want.size());
  for (size_t i = 0; i < want.size(); ++i) {
    EXPECT_EQ(lines[i].t_ns, want[i].first) << i;
    EXPECT_EQ(lines[i].text, want[i].second) << i;
  }
  EXPECT_EQ(b.sched.PendingCount(), 0u) << "quiet once everything is reported";
}

TEST(DfmocoArduino, ShortMoveGetsOneReportAfterItStops) {
  Bench b;
  Settled(b);
  b.RunUntil(1600 * kMs);  // just after a report tick
  b.Line("mm 2 100");      // 100 steps take 2 * sqrt(100 / 2500) = 0.4 s
  b.RunUntil(5 * kSec);
  const std::vector<TimedLine> lines = b.TakeLines();
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_EQ(lines[0].text, "mm 2 100");
  EXPECT_EQ(lines[1].text, "mp 2 100");
  EXPECT_EQ(lines[1].t_ns, 2500 * kMs) << "lags the stop until the next tick";
}

TEST(DfmocoArduino, EveryMovingMotorIsReported) {
  Bench b(Profile(DfmocoBoard::kMega, DfmocoFirmware::k2_0_0));
  Settled(b);
  b.Line("mm 2 5000");
  b.Line("mm 8 -5000");
  b.RunUntil(1600 * kMs);
  const std::vector<TimedLine> lines = b.TakeLines();
  ASSERT_EQ(lines.size(), 4u);
  EXPECT_EQ(lines[2].text.rfind("mp 2 ", 0), 0u);
  EXPECT_EQ(lines[3].text.rfind("mp 8 -", 0), 0u);
  EXPECT_EQ(lines[2].t_ns, 1500 * kMs);
  EXPECT_EQ(lines[3].t_ns, 1500 * kMs + BytesTime(lines[2].text.size() + 2));
}

TEST(DfmocoArduino, ReportedPositionLeadsTheSteps) {
  Bench b;
  Settled(b);
  Ask(b, "mm 1 -20000", 2 * kSec + 10 * kMs);
  const int64_t now = b.dev.rig()->motor(1).Position();
  const int64_t reported = b.dev.ReportedPosition(1);
  // The counter holds the end of the chunk planned at 3.00 s, which steps
  // during 3.05 .. 3.10 s: two chunks ahead of the steps.
  EXPECT_EQ(reported, b.dev.rig()->motor(1).PositionAt(3100 * kMs));
  EXPECT_LT(reported, now);
  EXPECT_EQ(Ask(b, "mp 1", 0), Texts{"mp 1 " + std::to_string(reported)});
}

// ---------------------------------------------------------------------------------------
// The outgoing queue and the UART

TEST(DfmocoArduino, FullQueueDropsSilently) {
  Bench b;
  Settled(b);
  std::string burst;
  for (int i = 0; i < 30; ++i) burst += "mp 1\r\n";
  b.Host(burst);
  b.RunFor(kSec);
  const std::vector<TimedLine> lines = b.TakeLines();
  // 16 outstanding at most: one in the transmit buffer, 15 in the ring.
  ASSERT_EQ(lines.size(), 16u);
  for (size_t k = 0; k < lines.size(); ++k) {
    EXPECT_EQ(lines[k].text, "mp 1 0");
    // "mp 1 0\r\n" is 8 bytes: back to back at 5760 bytes/s.
    EXPECT_EQ(lines[k].t_ns, kSec + BytesTime(8 * k)) << k;
  }
  EXPECT_EQ(b.dev.DroppedMessages(), 14u);
  EXPECT_EQ(b.dev.State()["tx_queue"]["dropped"], 14);
  EXPECT_EQ(Ask(b, "ms"), Texts{"ms 0000"}) << "answers again once drained";
}

TEST(DfmocoArduino, ParseErrorBypassesTheQueue) {
  Bench b;
  Settled(b);
  std::string burst;
  for (int i = 0; i < 20; ++i) burst += "mp 2\r\n";
  burst += "mm 2\r\n";
  b.Host(burst);
  b.RunFor(kSec);
  const std::vector<TimedLine> lines = b.TakeLines();
  ASSERT_EQ(lines.size(), 17u);
  EXPECT_EQ(lines[0].text, "mp 2 0");
  EXPECT_EQ(lines[1].text, "parse error");
  EXPECT_EQ(lines[1].t_ns, kSec) << "written at once, ahead of the waiting messages";
  EXPECT_EQ(lines[2].t_ns, kSec + BytesTime(8 + 13)) << "the queue waits for the line";
  EXPECT_EQ(b.dev.DroppedMessages(), 4u);
}

TEST(DfmocoArduino, HostFloodingAtLineRateOverflowsTheQueue) {
  Bench b;
  Settled(b);
  // The host sends "mp 1\r\n" (6 bytes) back to back for 1 s at 5760 bytes/s:
  // 960 requests; each answer "mp 1 0\r\n" is 8 bytes, so at most 720 + 16 fit.
  const int requests = 960;
  for (int k = 0; k < requests; ++k) {
    b.sched.At(kSec + BytesTime(6 * static_cast<uint64_t>(k + 1)), [&b] { b.Line("mp 1"); });
  }
  b.RunUntil(4 * kSec);
  const size_t answered = b.TakeLines().size();
  EXPECT_GT(b.dev.DroppedMessages(), 0u);
  EXPECT_EQ(answered + b.dev.DroppedMessages(), static_cast<size_t>(requests));
  EXPECT_LE(answered, 720u + 16u + 1u);
  EXPECT_GE(answered, 720u - 2u) << "the line stays busy";
}

TEST(DfmocoArduino, MpTextIsTakenWhenTransmitted) {
  Bench b;
  Settled(b);
  // Queue behind a long burst: the mp reports where the motor is when it
  // finally leaves, not when it was asked for. Asked at 1.03 s (counter 0),
  // it leaves after 137 bytes, past the update at 1.05 s that plans the first
  // chunk: int(1250 * 0.05^2) = 3.
  b.RunUntil(1030 * kMs);
  std::string burst;
  for (int i = 0; i < 14; ++i) burst += "ms\r\n";
  burst += "mm 1 1000\r\nmp 1\r\n";
  b.Host(burst);
  EXPECT_EQ(b.dev.ReportedPosition(1), 0);
  b.RunUntil(1400 * kMs);  // before the first periodic report
  const std::vector<TimedLine> lines = b.TakeLines();
  ASSERT_EQ(lines.size(), 16u);
  EXPECT_EQ(lines[14].text, "mm 1 1000");
  const TimedLine& mp = lines[15];
  EXPECT_EQ(mp.t_ns, 1030 * kMs + BytesTime(14 * 9 + 11));
  EXPECT_GT(mp.t_ns, 1050 * kMs);
  EXPECT_EQ(mp.text, "mp 1 3");
}

// ---------------------------------------------------------------------------------------
// Go-motion

TEST(DfmocoArduino, GoMotionPrepositionsThenRunsWithOneSecondRamps) {
  Bench b;
  Settled(b);
  // p0 1000, p1 2000, p2 3000, blur 500, exposure 1000 ms: the exposure runs
  // 1500 -> 2000 -> 2500 at 1000 steps/s; ramps start at 1000 and end at 3000.
  EXPECT_EQ(Ask(b, "bf 1000 500 1 1000 2000 3000"), Texts{"bf 1000"});
  EXPECT_EQ(b.dev.go_motion_state(), DfmocoArduino::GoMotionState::kArmed);
  EXPECT_EQ(Ask(b, "ms"), Texts{"ms 1000"}) << "pre-positioning";
  EXPECT_EQ(Ask(b, "go"), Texts{"parse error"}) << "refused while moving";
  b.RunUntil(2900 * kMs);
  b.TakeLines();
  EXPECT_EQ(Ask(b, "ms", 0), Texts{"ms 0000"});
  EXPECT_EQ(b.dev.rig()->motor(1).Position(), 1000);
  b.RunUntil(3 * kSec + 10'000);  // 10 us past: the move starts at the next 25 us tick
  EXPECT_EQ(Ask(b, "go", 0), Texts{"go"});
  const TimeNs t0 = 3 * kSec + 25'000;
  EXPECT_EQ(b.dev.go_motion_state(), DfmocoArduino::GoMotionState::kRunning);
  const sim::StepperMotor& m = b.dev.rig()->motor(1);
  // Half-way up the ramp: 1000 + (1000 steps/s / 1 s) / 2 * (0.5 s)^2 = 1125.
  EXPECT_NEAR(static_cast<double>(m.PositionAt(t0 + 500 * kMs)), 1125, 1.0);
  EXPECT_NEAR(static_cast<double>(m.PositionAt(t0 + kSec)), 1500, 1.0) << "exposure opens";
  EXPECT_NEAR(static_cast<double>(m.PositionAt(t0 + 1500 * kMs)), 2000, 1.0) << "p1 mid-way";
  EXPECT_NEAR(static_cast<double>(m.PositionAt(t0 + 2 * kSec)), 2500, 1.0) << "exposure ends";
  // Constant speed through the exposure.
  const double v =
      static_cast<double>(m.PositionAt(t0 + 1900 * kMs) - m.PositionAt(t0 + 1100 * kMs)) / 0.8;
  EXPECT_NEAR(v, 1000, 3);
  EXPECT_EQ(m.CurrentPlan().EndNs(), t0 + 3 * kSec);
  b.RunUntil(t0 + 2950 * kMs);
  b.TakeLines();
  EXPECT_EQ(Ask(b, "ms", 0), Texts{"ms 1000"});
  b.RunUntil(t0 + 3010 * kMs);
  EXPECT_EQ(Ask(b, "ms", 0), Texts{"ms 0000"});
  EXPECT_EQ(m.Position(), 3000);
  EXPECT_EQ(b.dev.go_motion_state(), DfmocoArduino::GoMotionState::kArmed);
}

TEST(DfmocoArduino, GoMotionReportsPositionsOnItsOwnChunkClock) {
  Bench b;
  Settled(b);
  Ask(b, "bf 1000 500 1 1000 2000 3000", 0);
  b.RunUntil(3 * kSec + 10'000);
  b.TakeLines();
  EXPECT_EQ(Ask(b, "go", 0), Texts{"go"});
  const TimeNs t0 = 3 * kSec + 25'000;
  b.RunUntil(3700 * kMs);
  const std::vector<TimedLine> lines = b.TakeLines();
  ASSERT_EQ(lines.size(), 1u);  // the 3.5 s report
  EXPECT_EQ(lines[0].t_ns, 3500 * kMs);
  // The chunk in progress at 3.5 s started at t0 + 450 ms and ends at t0 + 500 ms.
  EXPECT_EQ(lines[0].text,
            "mp 1 " + std::to_string(b.dev.rig()->motor(1).PositionAt(t0 + 500 * kMs)));
}

TEST(DfmocoArduino, GoMotionMovesSeveralMotorsTogether) {
  Bench b;
  Settled(b);
  // Motor 2 holds still for the exposure (p0 = p1 = p2): it has no ramp at all.
  EXPECT_EQ(Ask(b, "bf 200 1000 1 0 100 400 3 -50 -50 -50"), Texts{"bf 1000"});
  b.RunUntil(3 * kSec);
  EXPECT_EQ(b.dev.rig()->motor(1).Position(), -500);  // 0 - 1000 / 2
  EXPECT_EQ(b.dev.rig()->motor(3).Position(), -50);
  b.TakeLines();
  EXPECT_EQ(Ask(b, "go", 0), Texts{"go"});
  b.RunUntil(10 * kSec);
  EXPECT_EQ(b.dev.rig()->motor(1).Position(), 1900);  // 400 + 3000 / 2
  EXPECT_EQ(b.dev.rig()->motor(3).Position(), -50);
}

TEST(DfmocoArduino, BlurRefusedWhileMoving) {
  Bench b;
  Settled(b);
  Ask(b, "mm 2 5000");
  EXPECT_EQ(Ask(b, "bf 1000 500 1 0 10 20"), Texts{"parse error"});
  EXPECT_EQ(b.dev.go_motion_state(), DfmocoArduino::GoMotionState::kIdle);
}

TEST_P(DfmocoDialects, TooFastBlurIsRefusedFrom131) {
  Bench b(Profile(DfmocoBoard::kUno, GetParam()));
  Settled(b);
  // 2000 steps in 50 ms = 40000 steps/s, over the 20000 limit.
  const bool refuses = GetParam() == DfmocoFirmware::k1_3_1 || GetParam() == DfmocoFirmware::k2_0_0;
  EXPECT_EQ(Ask(b, "bf 100 1000 1 0 2000 4000"), Texts{refuses ? "bf -1" : "bf 1000"});
  if (refuses) {
    EXPECT_EQ(Ask(b, "ms"), Texts{"ms 0000"}) << "nothing moves";
    EXPECT_EQ(Ask(b, "go"), Texts{"parse error"}) << "not armed";
    EXPECT_EQ(b.dev.State()["go_motion"]["last_bf_reply"], -1);
  } else {
    EXPECT_EQ(Ask(b, "ms"), Texts{"ms 1000"}) << "pre-positions to 0 - 40000 / 2";
    b.RunFor(30 * kSec);
    EXPECT_EQ(b.dev.rig()->motor(1).Position(), -20000);
  }
  // A feasible move is accepted after a refusal.
  b.RunFor(30 * kSec);
  b.TakeLines();
  EXPECT_EQ(Ask(b, "bf 1000 500 2 0 10 20"), Texts{"bf 1000"});
}

// ---------------------------------------------------------------------------------------
// State snapshot

TEST(DfmocoArduino, StateShowsPositionsMotionRatesAndQueue) {
  Bench b;
  Settled(b);
  Ask(b, "pr 2 800");
  Ask(b, "np 3 -9");
  Ask(b, "mm 1 10000", 500 * kMs);
  const nlohmann::json s = b.dev.State();
  EXPECT_EQ(s["model"], "dfmoco");
  EXPECT_EQ(s["board"], "uno");
  EXPECT_EQ(s["firmware"], "2.0.0");
  EXPECT_EQ(s["powered"], true);
  ASSERT_EQ(s["motors"].size(), 4u);
  EXPECT_EQ(s["motors"][0]["moving"], true);
  EXPECT_EQ(s["motors"][0]["target_steps"], 10000);
  EXPECT_EQ(s["motors"][0]["position_steps"], b.dev.rig()->motor(1).Position());
  EXPECT_EQ(s["motors"][0]["reported_position_steps"], b.dev.ReportedPosition(1));
  EXPECT_EQ(s["motors"][1]["pulse_rate_steps_per_s"], 800);
  EXPECT_EQ(s["motors"][2]["position_steps"], -9);
  EXPECT_EQ(s["go_motion"]["state"], "idle");
  EXPECT_EQ(s["tx_queue"]["capacity"], 16);
  EXPECT_EQ(s["tx_queue"]["dropped"], 0);
}

// ---------------------------------------------------------------------------------------
// Properties

// A line a Dragonframe-like host might send, or a malformed one.
rc::Gen<std::string> HostLine(int motors) {
  using rc::gen::element;
  using rc::gen::inRange;
  const auto motor = inRange(0, motors + 2);
  const auto pos = inRange(-3000, 3000);
  return rc::gen::oneOf(
      element<std::string>("hi", "ms", "sa", "go", "", "xx 1", "mm 1", "bf 1000 500"),
      rc::gen::map(rc::gen::tuple(element<std::string>("mm", "np", "im", "jm", "pr"), motor, pos),
                   [](const auto& t) {
                     return std::get<0>(t) + " " + std::to_string(std::get<1>(t)) + " " +
                            std::to_string(std::get<2>(t));
                   }),
      rc::gen::map(
          rc::gen::tuple(element<std::string>("mp", "sm", "zm"), motor),
          [](const auto& t) { return std::get<0>(t) + " " + std::to_string(std::get<1>(t)); }),
      rc::gen::map(rc::gen::tuple(inRange(1, 3000), inRange(0, 1001), motor, pos, pos, pos),
                   [](const auto& t) {
                     const auto& [e, bl, m, p0, p1, p2] = t;
                     return "bf " + std::to_string(e) + " " + std::to_string(bl) + " " +
                            std::to_string(m) + " " + std::to_string(p0) + " " +
                            std::to_string(p1) + " " + std::to_string(p2);
                   }));
}

// Every line the device writes is a reply the protocol knows, for this device.
bool LegalDeviceLine(const std::string& line, const dfmoco::Dialect& dialect) {
  const wire::Result<dfmoco::DeviceReply> r = dfmoco::ParseDeviceLine(line, dialect);
  if (!r.ok()) return false;
  if (dfmoco::FormatDevice(*r) != line + "\r\n") return false;  // canonical spelling
  if (const auto* ms = std::get_if<dfmoco::MotorStatusReply>(&*r)) {
    return ms->moving.size() == static_cast<size_t>(dialect.motor_count);
  }
  if (const auto* hi = std::get_if<dfmoco::HelloReply>(&*r)) {
    return *hi == dfmoco::HelloFor(dialect);
  }
  if (const auto* bf = std::get_if<dfmoco::BlurReply>(&*r)) {
    return bf->value == 1000 || bf->value == -1;
  }
  if (std::holds_alternative<dfmoco::NewPositionReply>(*r) ||
      std::holds_alternative<dfmoco::ZeroReply>(*r)) {
    return false;  // the sketch answers those with mp
  }
  const auto motor = std::visit(
      [](const auto& v) -> std::optional<int32_t> {
        if constexpr (requires { v.motor; }) {
          return v.motor;
        } else {
          return std::nullopt;
        }
      },
      *r);
  return !motor || dfmoco::MotorInRange(*motor, dialect);
}

// ---------------------------------------------------------------------------------------
// Motion as the DFMoco 2.0.0 sketch plans it (FACTS "Jog", "Inch", "Stop";
// measured on the real Uno sketch under simavr: 312, 79, 2385)

// The motor's steps and the sketch's position counter agree once at rest.
int64_t RestingPosition(Bench& b, int motor) {
  b.RunFor(10 * kSec);
  EXPECT_FALSE(b.dev.MotorMoving(motor));
  EXPECT_EQ(b.dev.State()["motors"][motor - 1]["position_steps"].get<int64_t>(),
            b.dev.ReportedPosition(motor));
  return b.dev.ReportedPosition(motor);
}

TEST(DfmocoSketchMotion, JogDestinationIsHalfASecondOfAccelAndCruisePlusBrakingThenSmStopsThere) {
  for (const TimeNs phase : {0 * kMs, 10 * kMs, 49 * kMs}) {
    Bench b;
    Settled(b);
    b.RunFor(phase);
    // jm at 50 %: 2500 steps/s, 1250 steps/s^2 from rest: 0.5 s of
    // acceleration covers int(156.25) = 156, braking from 625 steps/s 156.25
    // more: destination int(156 + 156.25) = 312.
    EXPECT_EQ(Ask(b, "jm 2 100000 5000"), (Texts{"jm 2"}));
    b.RunFor(kSec - 20 * kMs);
    const Texts sm = Ask(b, "sm 2");
    EXPECT_NE(std::find(sm.begin(), sm.end(), "sm 2"), sm.end());
    EXPECT_EQ(RestingPosition(b, 2), 312) << "phase " << phase;
  }
}

TEST(DfmocoSketchMotion, RepeatedJogExtendsTheDestinationFromTheLoadedChunkSpeed) {
  Bench b;
  Settled(b);
  (void)Ask(b, "jm 1 100000");  // 100 %: int(312.5) = 312, int(312 + 312.5) = 624
  const int32_t first = b.dev.State()["motors"][0]["target_steps"].get<int32_t>();
  EXPECT_EQ(first, 624);
  b.RunFor(300 * kMs);
  (void)Ask(b, "jm 1 100000");
  const int32_t second = b.dev.State()["motors"][0]["target_steps"].get<int32_t>();
  EXPECT_GT(second, first);
  EXPECT_EQ(RestingPosition(b, 1), second);
}

TEST(DfmocoSketchMotion, InchDirectionIsAgainstTheDestinationNotThePositionAfterNp) {
  Bench b;
  Settled(b);
  EXPECT_EQ(Ask(b, "np 3 77"), (Texts{"mp 3 77"}));
  // Destination still 0: 50 > 0 inches up, two steps from the position.
  EXPECT_EQ(Ask(b, "im 3 50"), (Texts{"im 3"}));
  EXPECT_EQ(RestingPosition(b, 3), 79);
}

TEST(DfmocoSketchMotion, InchMovesTwoStepsWithinOneChunk) {
  Bench b;
  Settled(b);
  (void)Ask(b, "im 1 10", 0);
  // Planned after the next boundary, stepped in the chunk after it.
  b.RunFor(160 * kMs);
  EXPECT_EQ(b.dev.State()["motors"][0]["position_steps"].get<int64_t>(), 2);
  EXPECT_EQ(RestingPosition(b, 1), 2);
}

TEST(DfmocoSketchMotion, InchWhileTheLoadedChunkStepsStopsInstead) {
  Bench b;
  Settled(b);
  (void)Ask(b, "mm 1 100000");
  b.RunFor(kSec);
  (void)Ask(b, "im 1 200000");
  const int64_t end = RestingPosition(b, 1);
  EXPECT_GT(end, 0);
  EXPECT_LT(end, 100000);
}

TEST(DfmocoSketchMotion, StopDeceleratesFromTheLoadedChunkSpeedAndEndsOnTheIntegerComputedOnce) {
  for (const TimeNs phase : {0 * kMs, 25 * kMs, 49 * kMs}) {
    Bench b;
    Settled(b);
    b.RunFor(phase);
    EXPECT_EQ(Ask(b, "pr 4 20000", 0), (Texts{"pr 4 20000"}));
    EXPECT_EQ(Ask(b, "mm 4 30000"), (Texts{"mm 4 30000"}));
    b.RunFor(500 * kMs - 20 * kMs);
    // Loaded chunk: 238 steps, speed 238 * 65.6 = 15612.8, v = 4764.6
    // steps/s from position 1250: int(1250 + v^2 / 20000) = 2385.
    const Texts sa = Ask(b, "sa");
    EXPECT_NE(std::find(sa.begin(), sa.end(), "sa"), sa.end());
    EXPECT_EQ(b.dev.State()["motors"][3]["target_steps"].get<int32_t>(), 2385);
    EXPECT_EQ(RestingPosition(b, 4), 2385) << "phase " << phase;
  }
}

TEST(DfmocoSketchMotion, SecondZmAnswerComesWithTheNextReportTickCarryingThePositionThen) {
  Bench b;
  Settled(b);  // t = 1 s; report ticks at 0.5 s + k s
  b.RunFor(100 * kMs);
  EXPECT_EQ(Ask(b, "zm 1"), (Texts{"mp 1 0"}));
  (void)Ask(b, "mm 1 400");
  const std::vector<TimedLine> lines = [&] {
    b.RunUntil(1500 * kMs + kMs);
    return b.TakeLines();
  }();
  ASSERT_FALSE(lines.empty());
  EXPECT_EQ(lines.front().t_ns, 1500 * kMs);
  EXPECT_NE(lines.front().text, "mp 1 0");  // the motor moved meanwhile
  EXPECT_EQ(lines.front().text.rfind("mp 1 ", 0), 0u);
}

TEST(DfmocoSketchMotion, LongMovePlansAWindowAheadAndStillArrives) {
  Bench b;
  Settled(b);
  (void)Ask(b, "pr 1 20000", 0);
  (void)Ask(b, "mm 1 2147483647");
  EXPECT_LT(b.dev.rig()->motor(1).HeapBytes(), 64u * 1024);
  b.RunFor(60 * kSec);
  EXPECT_TRUE(b.dev.MotorMoving(1));
  const int64_t p = b.dev.ReportedPosition(1);
  EXPECT_NEAR(static_cast<double>(p), 20000.0 * 60, 20000.0 * 2);
  (void)Ask(b, "mm 1 0");
  b.RunFor(80 * kSec);
  EXPECT_EQ(RestingPosition(b, 1), 0);
}

RC_GTEST_PROP(DfmocoArduinoProps, AnyChunkingGivesTheSameReplies, ()) {
  const auto lines = *rc::gen::container<std::vector<std::string>>(HostLine(4));
  std::string bytes;
  for (const std::string& l : lines) bytes += l + "\r\n";
  const auto cuts =
      *rc::gen::container<std::vector<size_t>>(rc::gen::inRange<size_t>(0, bytes.size() + 1));

  Bench whole;
  Settled(whole);
  whole.Host(bytes);
  whole.RunUntil(30 * kSec);

  Bench pieces;
  Settled(pieces);
  std::vector<size_t> at = cuts;
  at.push_back(0);
  at.push_back(bytes.size());
  std::sort(at.begin(), at.end());
  for (size_t i = 0; i + 1 < at.size(); ++i) pieces.Host(bytes.substr(at[i], at[i + 1] - at[i]));
  pieces.RunUntil(30 * kSec);

  RC_ASSERT(whole.sink.chunks == pieces.sink.chunks);
}

// Every well-formed request with a valid motor, sent to an idle line, is answered.
RC_GTEST_PROP(DfmocoArduinoProps, EveryAnswerableRequestIsAnswered, ()) {
  const bool mega = *rc::gen::arbitrary<bool>();
  const DfmocoFirmware fw = *rc::gen::element(DfmocoFirmware::k1_2_7, DfmocoFirmware::k1_3_0,
                                              DfmocoFirmware::k1_3_1, DfmocoFirmware::k2_0_0);
  Bench b(Profile(mega ? DfmocoBoard::kMega : DfmocoBoard::kUno, fw));
  Settled(b);
  const int n = b.dev.rig()->motor_count();
  const bool v2 = fw == DfmocoFirmware::k2_0_0;
  const int steps = *rc::gen::inRange(1, 25);
  for (int i = 0; i < steps; ++i) {
    const int m = *rc::gen::inRange(1, n + 1);
    const int p = *rc::gen::inRange(-5000, 5000);
    const std::string ms = std::to_string(m);
    const std::string ps = std::to_string(p);
    std::string line;
    std::vector<std::string> accept;  // any one of these answers the request
    switch (*rc::gen::inRange(0, 12)) {
      case 0:
        line = "hi";
        accept = {dfmoco::FormatDevice(dfmoco::HelloFor(b.dev.dialect()))};
        accept[0].resize(accept[0].size() - 2);
        break;
      case 1:
        line = "ms";
        accept = {"ms "};
        break;
      case 2:
        line = "mm " + ms + " " + ps;
        accept = {"mm " + ms + " " + ps, "mp " + ms + " " + ps};
        break;
      case 3:
        line = "mp " + ms;
        accept = {"mp " + ms + " "};
        break;
      case 4:
        line = "sm " + ms;
        accept = {"sm " + ms};
        break;
      case 5:
        line = "sa";
        accept = {"sa"};
        break;
      case 6: {
        const int v = *rc::gen::inRange(0, 10001);
        line = "jm " + ms + " " + ps + (v2 ? " " + std::to_string(v) : "");
        accept = {"jm " + ms};
        break;
      }
      case 7:
        line = "im " + ms + " " + ps;
        accept = {"im " + ms};
        break;
      case 8: {
        const int r = *rc::gen::inRange(-100, 30000);
        line = "pr " + ms + " " + std::to_string(r);
        accept = {"pr " + ms + " " + std::to_string(std::clamp(r, 100, 20000))};
        break;
      }
      case 9:
        line = "zm " + ms;
        accept = {"mp " + ms + " 0"};
        break;
      case 10:
        line = "np " + ms + " " + ps;
        accept = {"mp " + ms + " " + ps};
        break;
      default:
        // bf at rest: prepared or (from 1.3.1) refused; while moving: parse
        // error. Which one depends on the motors when the line arrives (below).
        line = "bf 500 500 " + ms + " 0 " + ps + " 0";
        break;
    }
    b.RunFor(50 * kMs);  // the line is idle again
    b.TakeLines();
    auto any_moving = [&] {
      return b.dev.State()["motors"].dump().find("\"moving\":true") != std::string::npos;
    };
    const bool moving_before = any_moving();
    b.Line(line);
    b.RunFor(20 * kMs);
    if (accept.empty()) {
      // A motor that stops while the line is in flight may leave either answer.
      const bool moving_after = any_moving();
      if (moving_before) accept.push_back("parse error");
      if (!moving_before || !moving_after) {
        accept.push_back("bf 1000");
        accept.push_back("bf -1");
      }
    }
    const std::vector<TimedLine> got = b.TakeLines();
    const bool answered = std::any_of(got.begin(), got.end(), [&](const TimedLine& l) {
      return std::any_of(accept.begin(), accept.end(), [&](const std::string& a) {
        return a.back() == ' ' ? l.text.rfind(a, 0) == 0 : l.text == a;
      });
    });
    RC_ASSERT(answered);
    b.RunFor(static_cast<TimeNs>(*rc::gen::inRange(0, 3000)) * kMs);
  }
}

// What the sketch reads from any line, written back as a canonical line, reads
// the same again; and at most 39 arguments are ever read.
RC_GTEST_PROP(DfmocoArduinoProps, SketchReadingOfItsCanonicalLineIsTheSame, ()) {
  const auto token = rc::gen::oneOf(
      rc::gen::element<std::string>("\r", " ", "  ", "-", "--", "mm", "np", "ms", "jm", "bf", "x",
                                    "1", "9", "0", "99999999999", "2147483648", "4294967296", "."),
      rc::gen::map(rc::gen::arbitrary<char>(), [](char c) { return std::string(1, c); }));
  std::string line;
  for (const std::string& t : *rc::gen::container<std::vector<std::string>>(token)) line += t;
  const dfmoco::SketchReading r = dfmoco::ReadLineAsSketch(line);
  RC_ASSERT(r.args.size() < dfmoco::kMaxArgs);
  if (r.kind != dfmoco::SketchReading::Kind::kCommand) {
    RC_ASSERT(r.CanonicalLine().empty());
    return;
  }
  const dfmoco::SketchReading again = dfmoco::ReadLineAsSketch(r.CanonicalLine());
  RC_ASSERT(again.kind == dfmoco::SketchReading::Kind::kCommand);
  RC_ASSERT(again.word == r.word);
  RC_ASSERT(again.args == r.args);
}

// Random bytes never crash the device and never make it say anything but
// whole, legal reply lines.
RC_GTEST_PROP(DfmocoArduinoProps, GarbageGetsOnlyLegalLines, ()) {
  const bool mega = *rc::gen::arbitrary<bool>();
  Bench b(Profile(mega ? DfmocoBoard::kMega : DfmocoBoard::kUno, DfmocoFirmware::k2_0_0));
  Settled(b);
  const auto token = rc::gen::oneOf(
      rc::gen::element<std::string>("\r", "\n", "\r\n", " ", "-", "mm", "mp", "ms", "np", "zm",
                                    "sm", "sa", "jm", "im", "pr", "bf", "go", "hi", "1", "2", "9",
                                    "0", "45", "500", "1000", "*"),
      rc::gen::map(rc::gen::arbitrary<char>(), [](char c) { return std::string(1, c); }));
  const auto chunks = *rc::gen::container<std::vector<std::vector<std::string>>>(
      rc::gen::container<std::vector<std::string>>(token));
  for (const auto& chunk : chunks) {
    std::string bytes;
    for (const std::string& t : chunk) bytes += t;
    b.Host(bytes);
    b.RunFor(static_cast<TimeNs>(*rc::gen::inRange(0, 500)) * kMs);
  }
  b.RunFor(40 * kSec);
  const std::string out = b.sink.All();
  RC_ASSERT(out.empty() || out.substr(out.size() - 2) == "\r\n");
  size_t start = 0;
  while (start < out.size()) {
    const size_t end = out.find("\r\n", start);
    RC_ASSERT(end != std::string::npos);
    const std::string line = out.substr(start, end - start);
    RC_ASSERT(LegalDeviceLine(line, b.dev.dialect()));
    start = end + 2;
  }
}

RC_GTEST_PROP(DfmocoArduinoProps, UniformRandomBytesAreSafe, ()) {
  Bench b;
  Settled(b);
  const auto bytes = *rc::gen::container<std::string>(rc::gen::arbitrary<char>());
  b.Host(bytes);
  b.RunFor(10 * kSec);
  const std::string out = b.sink.All();
  size_t start = 0;
  while (start < out.size()) {
    const size_t end = out.find("\r\n", start);
    RC_ASSERT(end != std::string::npos);
    RC_ASSERT(LegalDeviceLine(out.substr(start, end - start), b.dev.dialect()));
    start = end + 2;
  }
}

}  // namespace
}  // namespace moco::devices
