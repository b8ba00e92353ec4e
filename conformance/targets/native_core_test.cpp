// The host Arduino core's board API sets, timed through the native target
// (fixtures/firmware/native_timers/*.cpp): Teensy's IntervalTimer and
// elapsedMicros over USB serial, the ESP32's hw_timer with a portMUX critical
// section and a BluetoothSerial port, TimerOne on an Uno with a receive buffer
// that overflows. Each interrupt at its exact simulated time; each serial byte
// where the board's line puts it.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "conformance/targets/native_target.h"

namespace moco::conformance {
namespace {

std::string Executable(const std::string& which) {
  const std::string all = MOCO_NATIVE_TIMERS;  // "teensy=PATH,uno=PATH,..."
  const size_t at = all.find(which + "=");
  if (at == std::string::npos) return "";
  const size_t from = at + which.size() + 1;
  return all.substr(from, all.find(',', from) - from);
}

// A board watching numbered pins `step` and `dir` as motor 1.
Board Watching(int step, int dir) {
  Board b;
  b.name = "test";
  b.motors.push_back({PinRef{'B', 0, step}, PinRef{'B', 0, dir}, std::nullopt});
  return b;
}

std::string RunFor(Target& t, TimeNs ns) {
  wire::Bytes got;
  const TimeNs end = t.Now() + ns;
  while (t.Now() < end && t.Receive(end, got)) {
  }
  return std::string(got.begin(), got.end());
}

void Send(Target& t, const std::string& text) {
  t.Send(wire::ByteView(reinterpret_cast<const uint8_t*>(text.data()), text.size()));
}

std::vector<TimeNs> Intervals(const PinSignal& s) {
  std::vector<TimeNs> out;
  for (size_t i = 1; i < s.edges.size(); ++i) out.push_back(s.edges[i].t_ns - s.edges[i - 1].t_ns);
  return out;
}

TEST(NativeCore, TeensyIntervalTimerFiresEvery12500NsAndElapsedMicrosKeepsItsPhase) {
  NativeTarget t(NativeSpec{Executable("teensy")});
  ASSERT_EQ(t.WatchPins(Watching(2, 3)), std::nullopt);
  ASSERT_EQ(t.Open(), std::nullopt);
  EXPECT_EQ(t.board(), "teensy40");
  RunFor(t, 10 * sim::kNsPerMs);
  const PinTrace* pins = t.Pins();
  ASSERT_NE(pins, nullptr);
  const PinSignal& fast = pins->signals[static_cast<size_t>(pins->motors[0].step)];
  const PinSignal& slow = pins->signals[static_cast<size_t>(pins->motors[0].dir)];
  ASSERT_GE(fast.edges.size(), 790u);
  for (const TimeNs d : Intervals(fast)) ASSERT_EQ(d, 12500);
  ASSERT_GE(slow.edges.size(), 9u);
  for (const TimeNs d : Intervals(slow)) {
    EXPECT_GE(d, 999 * sim::kNsPerUs);
    EXPECT_LE(d, 1001 * sim::kNsPerUs);
  }
  // USB serial: the answer comes at once, stamped with the time it was asked.
  const TimeNs asked = t.Now();
  Send(t, "?\n");
  const std::string answer = RunFor(t, sim::kNsPerMs);
  EXPECT_EQ(answer, "t " + std::to_string(asked / 1000) + "\r\n");
}

TEST(NativeCore, Esp32HwTimerWaitsOutACriticalSectionAndRunsOnceAfterIt) {
  NativeTarget t(NativeSpec{Executable("esp32")});
  ASSERT_EQ(t.WatchPins(Watching(4, 5)), std::nullopt);
  ASSERT_EQ(t.Open(), std::nullopt);
  EXPECT_EQ(t.board(), "esp32");
  RunFor(t, sim::kNsPerMs);
  Send(t, "c");  // 100 us in a critical section, once the byte is in
  RunFor(t, sim::kNsPerMs);
  const PinTrace* pins = t.Pins();
  ASSERT_NE(pins, nullptr);
  const std::vector<TimeNs> d = Intervals(pins->signals[static_cast<size_t>(pins->motors[0].step)]);
  ASSERT_GT(d.size(), 70u);
  std::vector<TimeNs> odd;
  for (const TimeNs x : d) {
    if (x != 25000) odd.push_back(x);
  }
  // One late edge when the section ends (the alarms it held back collapse
  // into one, as the interrupt flag does), then back on the 25 us grid.
  ASSERT_EQ(odd.size(), 2u);
  EXPECT_GE(odd[0], 100 * sim::kNsPerUs);
  EXPECT_EQ((odd[0] + odd[1]) % 25000, 0);
  // The Serial answer comes at 115200 baud: 10 bytes "ticks 123\n" take 868 us.
  Send(t, "b");
  const std::string answer = RunFor(t, 2 * sim::kNsPerMs);
  EXPECT_EQ(answer.rfind("ticks ", 0), 0u) << answer;
}

TEST(NativeCore, Esp32BluetoothSerialCarriesTheProtocolWhenAsked) {
  NativeTarget t(NativeSpec{Executable("esp32"), arduino::link::Port::kBluetooth});
  ASSERT_EQ(t.Open(), std::nullopt);
  RunFor(t, sim::kNsPerMs);
  Send(t, "\n");
  EXPECT_EQ(RunFor(t, sim::kNsPerMs), "bt echo\r\n");
}

TEST(NativeCore, UnoTimerOneAndAReceiveBufferThatOverflowsWhileTheSketchWaits) {
  NativeTarget t(NativeSpec{Executable("uno")});
  ASSERT_EQ(t.WatchPins(Watching(5, 6)), std::nullopt);
  ASSERT_EQ(t.Open(), std::nullopt);
  RunFor(t, sim::kNsPerMs);  // past Serial.begin()
  Send(t, std::string(100, 'x'));
  // 9600 baud: 100 bytes take 104 ms, all within loop()'s first delay(200);
  // the Uno's buffer keeps 64 of them.
  EXPECT_EQ(RunFor(t, 300 * sim::kNsPerMs), "got 64\r\n");
  bool said = false;
  for (const std::string& c : t.Caveats()) said = said || c.find("36 byte(s)") == 0;
  EXPECT_TRUE(said);
  const PinTrace* pins = t.Pins();
  ASSERT_NE(pins, nullptr);
  for (const TimeNs x : Intervals(pins->signals[static_cast<size_t>(pins->motors[0].step)])) {
    ASSERT_EQ(x, 100 * sim::kNsPerUs);
  }
}

TEST(NativeCore, ASecondCoreSetsUpFirstLoopsAfterEachLoopAndItsTimerShareTheClock) {
  NativeTarget t(NativeSpec{Executable("dual_core")});
  ASSERT_EQ(t.Open(), std::nullopt);
  RunFor(t, sim::kNsPerMs);
  const TimeNs asked = t.Now();
  Send(t, "\n");  // USB serial (the giga board): read at once
  const std::string answer = RunFor(t, sim::kNsPerMs);
  // The second core's timer every 5 us from its setup at time 0: as many ticks
  // as 5 us periods have passed when the line was read (a call or two later).
  const size_t at = answer.find("ticks ");
  ASSERT_NE(at, std::string::npos) << answer;
  EXPECT_EQ(answer.substr(0, at), "order sm loops paired ");
  const long ticks = std::stol(answer.substr(at + 6));
  EXPECT_GE(ticks, asked / 5000);
  EXPECT_LE(ticks, asked / 5000 + 1);
}

// What stops a faulty sketch: each a FirmwareStopped() naming what happened
// and when, Receive() false from then on.
std::string StopOf(char command, int stall_wall_seconds = 20) {
  NativeSpec spec{Executable("faulty")};
  spec.stall_wall_seconds = stall_wall_seconds;
  NativeTarget t(spec);
  EXPECT_EQ(t.Open(), std::nullopt);
  RunFor(t, sim::kNsPerMs);
  EXPECT_EQ(t.FirmwareStopped(), std::nullopt);
  Send(t, std::string(1, command));
  wire::Bytes got;
  EXPECT_FALSE(t.Receive(t.Now() + sim::kNsPerSecond, got));
  EXPECT_FALSE(t.Send(wire::Bytes{'x'}));
  const auto fault = t.FirmwareFaulted();
  EXPECT_TRUE(fault.has_value());
  return t.FirmwareStopped().value_or("");
}

TEST(NativeCore, ALoopThatNeverCallsTheCoreIsStoppedAfterItsWallTimeLimit) {
  const std::string why = StopOf('s', 1);
  EXPECT_NE(why.find("answered no grant of time for 1 s"), std::string::npos) << why;
  EXPECT_NE(why.find("calls nothing of the core"), std::string::npos) << why;
}

TEST(NativeCore, ACrashEndsTheFirmwareWithWhatKilledIt) {
  const std::string why = StopOf('n');
  EXPECT_NE(why.find("the sketch stopped at a bad memory access (SIGSEGV) at 0.00"),
            std::string::npos)
      << why;
}

TEST(NativeCore, ADivisionByZeroIsAFaultOfItsOwnKind) {
  NativeTarget t(NativeSpec{Executable("faulty")});
  ASSERT_EQ(t.Open(), std::nullopt);
  RunFor(t, sim::kNsPerMs);
  Send(t, "z");
  wire::Bytes got;
  EXPECT_FALSE(t.Receive(t.Now() + sim::kNsPerSecond, got));
  const auto fault = t.FirmwareFaulted();
  ASSERT_TRUE(fault.has_value());
  EXPECT_EQ(fault->kind, FirmwareFaultKind::kDivisionByZero);
  EXPECT_NE(fault->what.find("a division by zero (SIGFPE)"), std::string::npos) << fault->what;
  // A restart clears it: the next run starts without a fault.
  t.Restart();
  EXPECT_EQ(t.FirmwareFaulted(), std::nullopt);
}

TEST(NativeCore, AnExitEndsTheFirmwareWithItsStatus) {
  const std::string why = StopOf('q');
  EXPECT_NE(why.find("exited with status 0"), std::string::npos) << why;
}

}  // namespace
}  // namespace moco::conformance
