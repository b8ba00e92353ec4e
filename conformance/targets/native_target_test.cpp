// The native target (native_target.h) against the DFMoco test firmware built
// for the host Arduino core (fixtures/firmware/dfmoco_avr/dfmoco.c, board
// "uno"): the firmware's clock and line, determinism, restarts, refusals and
// crashes; the DFMoco suite with its pins judged gives the verdicts the same
// source gives under simavr; each planted pin fault fails its rule alone.
#include "conformance/targets/native_target.h"

#include <gtest/gtest.h>

#include <map>
#include <set>
#include <string>
#include <vector>

#include "conformance/protocols/dfmoco/dfmoco_pin_proofs_testing.h"
#ifdef MOCO_HAVE_SIMAVR
#include "conformance/targets/simavr_target.h"
#endif

namespace moco::conformance {
namespace {

std::string Text(const wire::Bytes& b) { return std::string(b.begin(), b.end()); }

// Receives until `want` has arrived or `limit_ns` of firmware time has passed.
std::string ReceiveUntil(Target& t, const std::string& want, TimeNs limit_ns) {
  wire::Bytes got;
  const TimeNs end = t.Now() + limit_ns;
  while (Text(got).find(want) == std::string::npos && t.Now() < end) {
    if (!t.Receive(end, got)) break;
  }
  return Text(got);
}

TEST(NativeTarget, TheFirmwareGreetsOnItsOwnClockAtItsBaud) {
  NativeTarget t(NativeSpec{MOCO_DFMOCO_NATIVE});
  ASSERT_EQ(t.Open(), std::nullopt);
  EXPECT_EQ(t.board(), "uno");
  EXPECT_EQ(ReceiveUntil(t, "\r\n", sim::kNsPerSecond), "hi 1 4 1.1.0\r\n");
  // 14 bytes at 57142 baud (the AVR build's rate), ten bits each, back to back.
  const TimeNs frame_ns = (10 * sim::kNsPerSecond + 57142 - 1) / 57142;
  EXPECT_GE(t.Now(), 14 * frame_ns);
  EXPECT_LT(t.Now(), 14 * frame_ns + 100 * sim::kNsPerUs);
  // The host's bytes are paced at the same rate.
  const TimeNs before = t.SentBy();
  ASSERT_TRUE(t.Send(wire::Bytes{'h', 'i', '\r', '\n'}));
  EXPECT_EQ(t.SentBy(), std::max(before, t.Now()) + 4 * frame_ns);
  EXPECT_EQ(ReceiveUntil(t, "\r\n", sim::kNsPerSecond), "hi 1 4 1.1.0\r\n");
  EXPECT_EQ(t.FirmwareStopped(), std::nullopt);
}

// Every byte of the answers and the time each arrived, for one run of `lines`.
std::vector<std::pair<TimeNs, std::string>> Play(const std::vector<std::string>& lines) {
  NativeTarget t(NativeSpec{MOCO_DFMOCO_NATIVE});
  EXPECT_EQ(t.Open(), std::nullopt);
  std::vector<std::pair<TimeNs, std::string>> seen;
  for (const std::string& line : lines) {
    t.Send(wire::Bytes(line.begin(), line.end()));
    wire::Bytes got;
    const TimeNs end = t.Now() + 300 * sim::kNsPerMs;
    while (t.Now() < end && t.Receive(end, got)) {
      if (!got.empty()) seen.push_back({t.Now(), Text(got)});
      got.clear();
    }
  }
  return seen;
}

TEST(NativeTarget, TwoRunsOfTheSameTrafficAreTheSameToTheNanosecond) {
  const std::vector<std::string> lines = {"hi\r\n", "mm 1 2000\r\n", "mp 1\r\n", "sa\r\n",
                                          "ms\r\n"};
  const auto first = Play(lines);
  const auto second = Play(lines);
  ASSERT_GT(first.size(), 10u);
  EXPECT_EQ(first, second);
}

TEST(NativeTarget, RestartStartsTheFirmwareAgainAtTimeZero) {
  NativeTarget t(NativeSpec{MOCO_DFMOCO_NATIVE});
  ASSERT_EQ(t.Open(), std::nullopt);
  EXPECT_EQ(ReceiveUntil(t, "\r\n", sim::kNsPerSecond), "hi 1 4 1.1.0\r\n");
  const TimeNs first = t.Now();
  t.Restart();
  EXPECT_LT(t.Now(), first);
  EXPECT_EQ(ReceiveUntil(t, "\r\n", sim::kNsPerSecond), "hi 1 4 1.1.0\r\n");
  EXPECT_EQ(t.Now(), first);
}

TEST(NativeTarget, WhatIsNotFirmwareForTheTargetIsRefusedNamingTheFix) {
  auto error = [](const std::string& path) {
    NativeTarget t(NativeSpec{path});
    return t.Open().value_or("");
  };
  EXPECT_NE(error("/nonexistent/fw").find("cannot be read"), std::string::npos);
  EXPECT_NE(error("/tmp").find("not a regular file"), std::string::npos);
  EXPECT_NE(error("/bin/true").find("mococheck-build-native"), std::string::npos);
  const std::string not_built = error("/bin/sleep");  // exits at once without arguments
  EXPECT_NE(not_built.find("did not introduce itself"), std::string::npos) << not_built;
}

TEST(NativeTarget, AddressesNameTheProtocolPort) {
  const auto spec = ParseNativeAddress("./fw@bluetooth");
  ASSERT_TRUE(std::holds_alternative<NativeSpec>(spec));
  EXPECT_EQ(std::get<NativeSpec>(spec).path, "./fw");
  EXPECT_EQ(std::get<NativeSpec>(spec).port, arduino::link::Port::kBluetooth);
  const auto bad = ParseNativeAddress("./fw@usb");
  ASSERT_TRUE(std::holds_alternative<std::string>(bad));
  EXPECT_NE(std::get<std::string>(bad).find("@bluetooth"), std::string::npos);
  EXPECT_TRUE(std::holds_alternative<std::string>(ParseNativeAddress("@serial")));
}

RunReport RunNative(const std::string& path) {
  NativeTarget t(NativeSpec{path});
  return RunOwnDfmocoWithPins(t);
}

TEST(NativeDfmoco, TheSuiteGivesTheVerdictsTheSameSourceGivesUnderSimavr) {
  const RunReport native = RunNative(MOCO_DFMOCO_NATIVE);
  EXPECT_EQ(ExitCode(native), 0) << ConsoleReport(native, false);
  std::map<std::string, Status> native_status;
  for (const auto& [id, s] : native.rules) native_status[id] = s.status;
  for (const char* rule : {"DFM-PIN-001", "DFM-PIN-002", "DFM-PIN-003", "DFM-PIN-004",
                           "DFM-PIN-005", "DFM-PIN-006", "DFM-PIN-007"}) {
    EXPECT_EQ(native_status[rule], Status::kPass) << rule;
  }
#ifdef MOCO_DFMOCO_ELF
  SimavrTarget avr(SimavrSpec{MOCO_DFMOCO_ELF, "", 0});
  const RunReport simavr = RunOwnDfmocoWithPins(avr);
  std::map<std::string, Status> simavr_status;
  for (const auto& [id, s] : simavr.rules) simavr_status[id] = s.status;
  EXPECT_EQ(native_status, simavr_status) << ConsoleReport(native, false) << "\n---\n"
                                          << ConsoleReport(simavr, false);
#endif
}

void ExpectOnly(const char* path, const std::string& rule, bool must) {
  ExpectOnlyRuleFailed(RunNative(path), rule, must);
}

TEST(NativePinProofs, AStepCountedButNeverPulsedIsCaughtByPin001) {
  ExpectOnly(MOCO_NATIVE_FAULT_LOST_STEP, "DFM-PIN-001", true);
}
TEST(NativePinProofs, AMovingPositionReportingTheDestinationIsCaughtByPin002) {
  ExpectOnly(MOCO_NATIVE_FAULT_REPORT_TARGET, "DFM-PIN-002", true);
}
TEST(NativePinProofs, AStepPulseShorterThanTheDriverNeedsIsCaughtByPin003) {
  ExpectOnly(MOCO_NATIVE_FAULT_SHORT_PULSE, "DFM-PIN-003", true);
}
TEST(NativePinProofs, DirWrittenWithTheStepEdgeIsCaughtByPin004) {
  ExpectOnly(MOCO_NATIVE_FAULT_DIR_WITH_STEP, "DFM-PIN-004", true);
}
TEST(NativePinProofs, StepsFasterThanTheBoardsMaximumAreCaughtByPin005) {
  ExpectOnly(MOCO_NATIVE_FAULT_OVERSPEED, "DFM-PIN-005", true);
}
TEST(NativePinProofs, AMoveStartingAtFullSpeedIsCaughtByPin006) {
  ExpectOnly(MOCO_NATIVE_FAULT_NO_RAMP, "DFM-PIN-006", false);
}
TEST(NativePinProofs, DirFlippedAtSpeedIsCaughtByPin007) {
  ExpectOnly(MOCO_NATIVE_FAULT_REVERSE_AT_SPEED, "DFM-PIN-007", false);
}

}  // namespace
}  // namespace moco::conformance
