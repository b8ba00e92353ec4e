// The simavr target running the DFMoco test firmware (fixtures/firmware/dfmoco_avr,
// dfmoco-protocol.txt "Messages"): answers judged on the firmware's clock, motion
// over time, determinism, the simavr 1.6 UDRE quirk (FACTS "simavr"), restart, errors.
#include "conformance/targets/simavr_target.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace moco::conformance {
namespace {

constexpr TimeNs kMs = 1'000'000;
constexpr TimeNs kSecond = 1'000'000'000;
constexpr const char* kHello = "hi 1 4 1.1.0";  // fixtures/firmware/dfmoco_avr/README.md

// 8N1 at UBRR 34 with U2X (57143 baud): 10 bits of 8 * 35 cycles at 16 MHz.
constexpr TimeNs kFrameNs = 10 * 8 * 35 * 1000 / 16;  // 175 us

SimavrSpec FirmwareSpec() { return SimavrSpec{MOCO_DFMOCO_ELF, "", 0}; }

// Lines to and from a target, with the firmware time each chunk of bytes arrived.
class Link {
 public:
  explicit Link(Target& target) : target_(target) {}

  void SendLine(std::string_view line) {
    std::string bytes(line);
    bytes += "\r\n";
    sent_.emplace_back(target_.Now(), bytes);
    ASSERT_TRUE(
        target_.Send(wire::ByteView(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size())));
  }

  // The next complete line (without "\r\n") that arrives before `deadline_ns`.
  std::optional<std::string> ReadLine(TimeNs deadline_ns) {
    for (;;) {
      const size_t end = pending_.find("\r\n");
      if (end != std::string::npos) {
        std::string line = pending_.substr(0, end);
        pending_.erase(0, end + 2);
        return line;
      }
      if (target_.Now() >= deadline_ns) return std::nullopt;
      wire::Bytes chunk;
      if (!target_.Receive(deadline_ns, chunk)) return std::nullopt;
      if (!chunk.empty()) {
        received_.emplace_back(target_.Now(), std::string(chunk.begin(), chunk.end()));
        pending_.append(chunk.begin(), chunk.end());
      }
    }
  }

  // Sends `line` and returns the first reply starting with `prefix` within `within_ns`;
  // other lines (the firmware's unprompted `mp` reports) are kept in `others`.
  std::optional<std::string> Ask(std::string_view line, std::string_view prefix,
                                 TimeNs within_ns = 50 * kMs) {
    SendLine(line);
    const TimeNs deadline = target_.Now() + within_ns;
    while (auto got = ReadLine(deadline)) {
      if (got->rfind(prefix, 0) == 0) return got;
      others.push_back(*got);
    }
    return std::nullopt;
  }

  // Runs the firmware until `until_ns`, keeping whatever lines arrive in `others`.
  void Idle(TimeNs until_ns) {
    while (auto got = ReadLine(until_ns)) others.push_back(*got);
  }

  std::vector<std::string> others;
  const std::vector<std::pair<TimeNs, std::string>>& received() const { return received_; }
  const std::vector<std::pair<TimeNs, std::string>>& sent() const { return sent_; }

 private:
  Target& target_;
  std::string pending_;
  std::vector<std::pair<TimeNs, std::string>> received_;
  std::vector<std::pair<TimeNs, std::string>> sent_;
};

int64_t Position(const std::string& mp_line) {
  int motor = 0;
  long long pos = 0;
  EXPECT_EQ(std::sscanf(mp_line.c_str(), "mp %d %lld", &motor, &pos), 2) << mp_line;
  return pos;
}

TEST(SimavrTarget, BootsAnnouncesItselfAndAnswersHiWithinTheWireTime) {
  SimavrTarget target(FirmwareSpec());
  ASSERT_EQ(target.Open(), std::nullopt);
  EXPECT_TRUE(target.VirtualClock());
  EXPECT_TRUE(target.CanRestart());
  EXPECT_EQ(target.mcu(), "atmega328p");
  EXPECT_EQ(target.frequency_hz(), 16'000'000u);
  EXPECT_EQ(target.Now(), 0);
  Link link(target);

  // The sketch announces itself at start-up (FACTS "DFMoco").
  EXPECT_EQ(link.ReadLine(50 * kMs), kHello);
  EXPECT_EQ(target.FrameCycles(), 2800u);

  const TimeNs asked = target.Now();
  EXPECT_EQ(link.ReadLine(asked + 20 * kMs), std::nullopt) << "nothing unprompted when idle";
  const TimeNs t0 = target.Now();
  link.SendLine("hi");
  EXPECT_EQ(link.ReadLine(t0 + 20 * kMs), kHello);
  const TimeNs took = target.Now() - t0;
  // 4 bytes in and 14 out cannot pass the 57143-baud line faster than 18 frames.
  EXPECT_GE(took, 18 * kFrameNs);
  EXPECT_LE(took, 10 * kMs);
  std::printf("hi answered in %.3f ms of firmware time\n", static_cast<double>(took) / kMs);
}

TEST(SimavrTarget, AnswersTheBasicCommandsInTheSpecFormats) {
  SimavrTarget target(FirmwareSpec());
  ASSERT_EQ(target.Open(), std::nullopt);
  Link link(target);
  ASSERT_EQ(link.ReadLine(50 * kMs), kHello);

  EXPECT_EQ(link.Ask("ms", "ms"), "ms 0000");  // one digit per motor
  EXPECT_EQ(link.Ask("mp 2", "mp"), "mp 2 0");
  EXPECT_EQ(link.Ask("np 2 -150", "np"), "np 2 -150");
  EXPECT_EQ(link.Ask("mp 2", "mp"), "mp 2 -150");
  EXPECT_EQ(link.Ask("mm 2 -150", "m"), "mp 2 -150") << "already there: mp, not mm";
  EXPECT_EQ(link.Ask("zm 2", "zm"), "zm 2");
  EXPECT_EQ(link.Ask("mp 2", "mp"), "mp 2 0");
  EXPECT_EQ(link.Ask("pr 3 50", "pr"), "pr 3 100") << "clamped to 100..20000";
  EXPECT_EQ(link.Ask("pr 3 90000", "pr"), "pr 3 20000");
  EXPECT_EQ(link.Ask("sm 4", "sm"), "sm 4");
  EXPECT_EQ(link.Ask("sa", "sa"), "sa");
  // Bad arguments answer `parse error`; an unknown word gets nothing (FACTS "DFMoco").
  EXPECT_EQ(link.Ask("mm 5 10", "parse"), "parse error");
  EXPECT_EQ(link.Ask("mp", "parse"), "parse error");
  EXPECT_EQ(link.Ask("mm 1 ten", "parse"), "parse error");
  EXPECT_EQ(link.Ask("xy 1 2", ""), std::nullopt);
  // A bare "\n" ends a line too (ERRATA dfmoco 1).
  const std::string lf = "ms\n";
  ASSERT_TRUE(target.Send(wire::ByteView(reinterpret_cast<const uint8_t*>(lf.data()), lf.size())));
  EXPECT_EQ(link.ReadLine(target.Now() + 20 * kMs), "ms 0000");
  EXPECT_TRUE(link.others.empty()) << link.others.front();
}

TEST(SimavrTarget, MoveRunsOverFirmwareTimeAndArrives) {
  SimavrTarget target(FirmwareSpec());
  ASSERT_EQ(target.Open(), std::nullopt);
  Link link(target);
  ASSERT_EQ(link.ReadLine(50 * kMs), kHello);

  const TimeNs start = target.Now();
  EXPECT_EQ(link.Ask("mm 1 1000", "mm"), "mm 1 1000");
  std::vector<int64_t> positions;
  TimeNs arrived = -1;
  for (TimeNs t = start + 100 * kMs; t < start + 5 * kSecond; t += 100 * kMs) {
    link.Idle(t);
    const auto ms = link.Ask("ms", "ms");
    ASSERT_TRUE(ms.has_value());
    const auto mp = link.Ask("mp 1", "mp 1");
    ASSERT_TRUE(mp.has_value());
    positions.push_back(Position(*mp));
    if (*ms == "ms 0000") {
      arrived = target.Now() - start;
      break;
    }
    EXPECT_EQ(*ms, "ms 1000");
  }
  ASSERT_GT(arrived, 0) << "motor 1 never stopped";
  ASSERT_GE(positions.size(), 5u);
  EXPECT_EQ(positions.back(), 1000);
  for (size_t i = 1; i < positions.size(); ++i) EXPECT_LE(positions[i - 1], positions[i]);
  EXPECT_GT(positions[2], 0);
  EXPECT_LT(positions[2], 1000) << "the move takes time";
  // Default pulse rate 5000 steps/s, acceleration 2500 steps/s^2 (FACTS): 1000 steps
  // take at least 2 * sqrt(1000 / 2500) s = 1.265 s.
  EXPECT_GE(arrived, 1265 * kMs);
  EXPECT_LE(arrived, 2 * kSecond);
  // Unprompted position reports while moving and once after the stop (ERRATA dfmoco 4).
  link.Idle(target.Now() + 1100 * kMs);
  ASSERT_FALSE(link.others.empty());
  for (const std::string& l : link.others) EXPECT_EQ(l.rfind("mp 1 ", 0), 0u) << l;
  EXPECT_EQ(link.others.back(), "mp 1 1000");
  std::printf("mm 1 1000 arrived after %.3f s of firmware time\n",
              static_cast<double>(arrived) / kSecond);
}

TEST(SimavrTarget, StopDeceleratesShortOfTheTarget) {
  SimavrTarget target(FirmwareSpec());
  ASSERT_EQ(target.Open(), std::nullopt);
  Link link(target);
  ASSERT_EQ(link.ReadLine(50 * kMs), kHello);
  ASSERT_EQ(link.Ask("mm 3 -100000", "mm"), "mm 3 -100000");
  link.Idle(target.Now() + 1500 * kMs);
  const int64_t at_stop = Position(*link.Ask("mp 3", "mp 3"));
  EXPECT_LT(at_stop, -500);
  EXPECT_EQ(link.Ask("sm 3", "sm"), "sm 3");
  link.Idle(target.Now() + 2500 * kMs);
  EXPECT_EQ(link.Ask("ms", "ms"), "ms 0000");
  const int64_t stopped = Position(*link.Ask("mp 3", "mp 3"));
  EXPECT_LT(stopped, at_stop) << "it decelerates, it does not stop dead";
  EXPECT_GT(stopped, -100000);
}

// Every byte both ways with its firmware time, for one scripted session.
std::pair<std::vector<std::pair<TimeNs, std::string>>, std::vector<std::pair<TimeNs, std::string>>>
ScriptedSession() {
  SimavrTarget target(FirmwareSpec());
  EXPECT_EQ(target.Open(), std::nullopt);
  Link link(target);
  link.ReadLine(50 * kMs);
  link.Ask("pr 2 12000", "pr");
  link.Ask("mm 1 700", "mm");
  link.Ask("mm 2 -3000", "mm");
  for (int i = 0; i < 12; ++i) {
    link.Idle(target.Now() + 73 * kMs);
    link.Ask("ms", "ms");
    link.Ask("mp 2", "mp 2");
  }
  link.Ask("sa", "sa");
  link.Idle(target.Now() + 1500 * kMs);
  link.Ask("np 1 5", "np");
  return {link.sent(), link.received()};
}

TEST(SimavrTarget, TwoRunsGiveTheSameBytesAtTheSameTimes) {
  const auto a = ScriptedSession();
  const auto b = ScriptedSession();
  ASSERT_GT(a.second.size(), 20u);
  EXPECT_EQ(a.first, b.first);
  EXPECT_EQ(a.second, b.second);
}

TEST(SimavrTarget, WithoutTheUdreFixTheFirmwareNeverTransmits) {
  SimavrTarget::Options options;
  options.udre_fix = false;
  SimavrTarget target(FirmwareSpec(), options);
  ASSERT_EQ(target.Open(), std::nullopt);
  Link link(target);
  EXPECT_EQ(link.ReadLine(200 * kMs), std::nullopt) << "no boot announcement";
  link.SendLine("hi");
  EXPECT_EQ(link.ReadLine(target.Now() + 200 * kMs), std::nullopt);
  EXPECT_TRUE(link.received().empty());
  // The same firmware with the fix (the default) talks: see the first test.
}

TEST(SimavrTarget, RestartBootsAFreshCoreAtTimeZero) {
  SimavrTarget target(FirmwareSpec());
  ASSERT_EQ(target.Open(), std::nullopt);
  {
    Link link(target);
    ASSERT_EQ(link.ReadLine(50 * kMs), kHello);
    ASSERT_EQ(link.Ask("np 1 4242", "np"), "np 1 4242");
    ASSERT_EQ(link.Ask("mm 2 90000", "mm"), "mm 2 90000");
    link.Idle(target.Now() + 300 * kMs);
  }
  const TimeNs before = target.Now();
  ASSERT_GT(before, 300 * kMs);
  target.Restart();
  EXPECT_EQ(target.Now(), 0);
  EXPECT_EQ(target.cycles(), 0u);
  Link link(target);
  EXPECT_EQ(link.ReadLine(50 * kMs), kHello);
  EXPECT_EQ(link.Ask("mp 1", "mp"), "mp 1 0");
  EXPECT_EQ(link.Ask("ms", "ms"), "ms 0000");
  EXPECT_TRUE(link.others.empty());
}

TEST(SimavrTarget, TheClockIsCyclesOverTheGivenFrequency) {
  // The same firmware clocked at 8 MHz runs the same cycles: the boot line arrives
  // at the same cycle, twice as late in nanoseconds (and at half the baud rate).
  TimeNs at_ns[2];
  uint64_t at_cycles[2];
  const uint32_t hz[2] = {16'000'000, 8'000'000};
  for (int i = 0; i < 2; ++i) {
    SimavrTarget target(SimavrSpec{MOCO_DFMOCO_ELF, "atmega328p", hz[i]});
    ASSERT_EQ(target.Open(), std::nullopt);
    EXPECT_EQ(target.frequency_hz(), hz[i]);
    Link link(target);
    ASSERT_EQ(link.ReadLine(100 * kMs), kHello);
    at_ns[i] = target.Now();
    at_cycles[i] = target.cycles();
  }
  EXPECT_EQ(at_cycles[0], at_cycles[1]);
  EXPECT_NEAR(static_cast<double>(at_ns[1]), 2.0 * static_cast<double>(at_ns[0]), 1.0);
}

#ifdef MOCO_DFMOCO_MMCU_ELF
TEST(SimavrTarget, TheElfsMmcuSectionNamesTheMcuAndClock) {
  // The same firmware built for 8 MHz, its .mmcu section saying atmega328p at 8 MHz.
  SimavrTarget target(SimavrSpec{MOCO_DFMOCO_MMCU_ELF, "", 0});
  ASSERT_EQ(target.Open(), std::nullopt);
  EXPECT_EQ(target.mcu(), "atmega328p");
  EXPECT_EQ(target.frequency_hz(), 8'000'000u);
  Link link(target);
  EXPECT_EQ(link.ReadLine(100 * kMs), kHello);
  EXPECT_EQ(link.Ask("mp 1", "mp"), "mp 1 0");
  // UBRR (8e6 / 4 / 57600 - 1) / 2 = 16 with U2X: 10 bits of 8 * 17 cycles.
  EXPECT_EQ(target.FrameCycles(), 1360u);

  SimavrTarget clash(SimavrSpec{MOCO_DFMOCO_MMCU_ELF, "atmega2560", 0});
  const auto err = clash.Open();
  ASSERT_TRUE(err.has_value());
  EXPECT_NE(err->find("atmega2560"), std::string::npos) << *err;
  EXPECT_NE(err->find("atmega328p"), std::string::npos) << *err;
}
#endif

TEST(SimavrTarget, RunsFasterThanRealTime) {
  SimavrTarget target(FirmwareSpec());
  ASSERT_EQ(target.Open(), std::nullopt);
  Link link(target);
  ASSERT_EQ(link.ReadLine(50 * kMs), kHello);
  for (int m = 1; m <= 4; ++m) {
    link.Ask("pr " + std::to_string(m) + " 20000", "pr");
    link.Ask("mm " + std::to_string(m) + " " + std::to_string(m * 50000), "mm");
  }
  // Wall time and this process's CPU time (the machine may be shared), printed only.
  struct Stopwatch {
    std::chrono::steady_clock::time_point wall = std::chrono::steady_clock::now();
    std::clock_t cpu = std::clock();
    double WallS() const {
      return std::chrono::duration<double>(std::chrono::steady_clock::now() - wall).count();
    }
    double CpuS() const { return static_cast<double>(std::clock() - cpu) / CLOCKS_PER_SEC; }
  };
  const Stopwatch moving;
  const TimeNs fw0 = target.Now();
  link.Idle(fw0 + 4 * kSecond);
  const double moving_fw_s = static_cast<double>(target.Now() - fw0) / kSecond;
  const double moving_wall_s = moving.WallS(), moving_cpu_s = moving.CpuS();
  EXPECT_EQ(link.Ask("ms", "ms"), "ms 1111") << "still moving, all four";

  link.Ask("sa", "sa");
  link.Idle(target.Now() + 3 * kSecond);
  EXPECT_EQ(link.Ask("ms", "ms"), "ms 0000");
  const Stopwatch idle;
  const TimeNs fw1 = target.Now();
  link.Idle(fw1 + 10 * kSecond);
  const double idle_fw_s = static_cast<double>(target.Now() - fw1) / kSecond;
  std::printf(
      "firmware seconds per wall second: %.1f (per CPU second %.1f) with four motors "
      "stepping at 20 kHz each; %.0f (per CPU second %.0f) idle\n",
      moving_fw_s / moving_wall_s, moving_fw_s / moving_cpu_s, idle_fw_s / idle.WallS(),
      idle_fw_s / std::max(idle.CpuS(), 1e-6));
}

TEST(SimavrTarget, FirmwareThatHaltsEndsTheLink) {
  SimavrTarget target(SimavrSpec{MOCO_HALT_ELF, "", 0});
  ASSERT_EQ(target.Open(), std::nullopt);
  std::string got;
  bool alive = true;
  while (alive && target.Now() < 100 * kMs) {
    wire::Bytes out;
    alive = target.Receive(100 * kMs, out);
    got.append(out.begin(), out.end());
  }
  EXPECT_EQ(got, "bye\r\n") << "every byte sent before the halt arrives";
  EXPECT_FALSE(alive) << "the core halted";
  wire::Bytes out;
  EXPECT_FALSE(target.Receive(200 * kMs, out));
  const std::string hi = "hi\r\n";
  EXPECT_FALSE(target.Send(wire::ByteView(reinterpret_cast<const uint8_t*>(hi.data()), hi.size())));
  EXPECT_NE(target.Name().find("firmware stopped: the core halted"), std::string::npos)
      << target.Name();
  // Restart() brings the firmware back.
  target.Restart();
  EXPECT_EQ(target.Name().find("stopped"), std::string::npos) << target.Name();
  wire::Bytes again;
  while (target.Receive(100 * kMs, again) && target.Now() < 100 * kMs) {
  }
  EXPECT_EQ(std::string(again.begin(), again.end()), "bye\r\n");
}

TEST(SimavrTarget, ErrorsNameTheProblem) {
  SimavrTarget missing(SimavrSpec{"/nonexistent/dir/fw.elf", "", 0});
  const auto err = missing.Open();
  ASSERT_TRUE(err.has_value());
  EXPECT_NE(err->find("/nonexistent/dir/fw.elf"), std::string::npos) << *err;
  EXPECT_NE(err->find("not found"), std::string::npos) << *err;
  wire::Bytes out;
  EXPECT_FALSE(missing.Receive(kMs, out));
  EXPECT_FALSE(missing.Send(wire::ByteView()));

  SimavrTarget unknown(SimavrSpec{MOCO_DFMOCO_ELF, "atmega9999", 0});
  const auto err2 = unknown.Open();
  ASSERT_TRUE(err2.has_value());
  EXPECT_NE(err2->find("atmega9999"), std::string::npos) << *err2;

  // A text file (not this source by __FILE__: that path may be relative to
  // the build folder, and the test runs from the source folder).
  const std::string text_path =
      (std::filesystem::temp_directory_path() / ("moco_not_elf_" + std::to_string(::getpid())))
          .string();
  std::ofstream(text_path) << std::string(256, '#') << "\nnot an ELF at all\n";
  SimavrTarget not_elf(SimavrSpec{text_path, "", 0});
  const auto err3 = not_elf.Open();
  ASSERT_TRUE(err3.has_value());
  EXPECT_NE(err3->find("not an ELF file"), std::string::npos) << *err3;
  std::filesystem::remove(text_path);

  // An ELF for another machine (this test program): simavr 1.6 would crash on it.
  SimavrTarget host_elf(SimavrSpec{"/proc/self/exe", "", 0});
  const auto err4 = host_elf.Open();
  ASSERT_TRUE(err4.has_value());
  EXPECT_NE(err4->find("another machine"), std::string::npos) << *err4;
}

TEST(SimavrTarget, TargetSpecsParseAndBuild) {
  const auto spec =
      ParseTargetSpec(std::string("simavr:") + MOCO_DFMOCO_ELF + "@atmega328p:16000000");
  ASSERT_TRUE(std::holds_alternative<TargetSpec>(spec)) << std::get<std::string>(spec);
  EXPECT_EQ(std::get<TargetSpec>(spec).kind, TargetSpec::Kind::kSimavr);
  auto made = MakeTarget(std::get<TargetSpec>(spec), "", 115200);
  ASSERT_TRUE(std::holds_alternative<std::unique_ptr<Target>>(made));
  Target& target = *std::get<std::unique_ptr<Target>>(made);
  ASSERT_EQ(target.Open(), std::nullopt);
  EXPECT_EQ(target.Name(), std::string("simavr:") + MOCO_DFMOCO_ELF + " @atmega328p 16000000 Hz");

  const auto parsed = ParseSimavrAddress("a/b@c.elf@atmega2560:20000000");
  ASSERT_TRUE(std::holds_alternative<SimavrSpec>(parsed));
  EXPECT_EQ(std::get<SimavrSpec>(parsed).elf_path, "a/b@c.elf");
  EXPECT_EQ(std::get<SimavrSpec>(parsed).mcu, "atmega2560");
  EXPECT_EQ(std::get<SimavrSpec>(parsed).frequency_hz, 20'000'000u);
  for (const char* bad :
       {"simavr:", "simavr:@atmega328p", "simavr:x.elf@", "simavr:x.elf@m:", "simavr:x.elf@m:16MHz",
        "simavr:x.elf@m:0", "simavr:x.elf@m:4294967296"}) {
    EXPECT_TRUE(std::holds_alternative<std::string>(ParseTargetSpec(bad))) << bad;
  }
}

}  // namespace
}  // namespace moco::conformance

namespace moco::conformance {
namespace {

// fixtures/boards/own-dfmoco.json: motor 1 on PD4/PD5, motor 3 on PB0/PB1.
Board OwnBoard() {
  Board b;
  b.name = "own-dfmoco";
  b.motors = {{PinRef{'D', 4}, PinRef{'D', 5}, std::nullopt},
              {PinRef{'D', 6}, PinRef{'D', 7}, std::nullopt},
              {PinRef{'B', 0}, PinRef{'B', 1}, std::nullopt},
              {PinRef{'B', 2}, PinRef{'B', 3}, std::nullopt}};
  return b;
}

// The signed count of rising STEP edges of motor `i` (0-based), DIR high counting up.
int64_t SignedSteps(const PinTrace& t, size_t i) {
  const PinSignal& step = t.signals[static_cast<size_t>(t.motors[i].step)];
  const PinSignal& dir = t.signals[static_cast<size_t>(t.motors[i].dir)];
  int64_t n = 0;
  for (const PinEdge& e : step.edges) {
    if (e.level) n += dir.LevelAt(e.t_ns) ? 1 : -1;
  }
  return n;
}

TEST(SimavrPins, EveryStepIsOnePulseOnItsPinTimedToTheCpuCycleOfThePortWrite) {
  SimavrTarget target(FirmwareSpec());
  ASSERT_EQ(target.WatchPins(OwnBoard()), std::nullopt);
  ASSERT_EQ(target.Open(), std::nullopt);
  Link link(target);
  ASSERT_EQ(link.ReadLine(50 * kMs), kHello);
  EXPECT_EQ(link.Ask("mm 1 300", "mm"), "mm 1 300");
  EXPECT_EQ(link.Ask("mm 3 -200", "mm"), "mm 3 -200");
  link.Idle(target.Now() + 2 * kSecond);
  EXPECT_EQ(Position(*link.Ask("mp 1", "mp 1")), 300);
  EXPECT_EQ(Position(*link.Ask("mp 3", "mp 3")), -200);
  const PinTrace* pins = target.Pins();
  ASSERT_NE(pins, nullptr);
  EXPECT_EQ(SignedSteps(*pins, 0), 300);
  EXPECT_EQ(SignedSteps(*pins, 2), -200);
  EXPECT_EQ(SignedSteps(*pins, 1), 0) << "motor 2 never stepped";
  const PinSignal& step = pins->signals[static_cast<size_t>(pins->motors[0].step)];
  ASSERT_EQ(step.edges.size(), 600u);
  for (size_t k = 0; k < step.edges.size(); ++k) {
    const PinEdge& e = step.edges[k];
    // Time is the cycle over 16 MHz (62.5 ns), rounded down.
    EXPECT_EQ(e.t_ns, static_cast<TimeNs>(e.cycle * 1000 / 16));
    if (k % 2 == 1) {
      // The next 40 kHz tick (400 cycles later) lowers the pin as its ISR's first write;
      // the raise came after that ISR had run every motor's phase accumulator, so a
      // pulse is one tick less that path (about 110 cycles, longer while more motors step).
      const uint64_t high = e.cycle - step.edges[k - 1].cycle;
      EXPECT_GT(high, 200u) << "pulse " << k / 2;
      EXPECT_LT(high, 400u) << "pulse " << k / 2;
    }
  }
}

TEST(SimavrPins, RestartStartsAnEmptyTraceAtTimeZero) {
  SimavrTarget target(FirmwareSpec());
  ASSERT_EQ(target.WatchPins(OwnBoard()), std::nullopt);
  ASSERT_EQ(target.Open(), std::nullopt);
  Link link(target);
  ASSERT_EQ(link.ReadLine(50 * kMs), kHello);
  link.Ask("mm 2 50", "mm");
  link.Idle(target.Now() + 500 * kMs);
  EXPECT_EQ(SignedSteps(*target.Pins(), 1), 50);
  target.Restart();
  EXPECT_EQ(target.Pins()->EdgeCount(), 0u);
  EXPECT_TRUE(target.WatchPins(OwnBoard()).has_value()) << "pins are chosen before Open()";
}

TEST(SimavrPins, APinOnAPortTheMcuLacksIsRefusedAtOpen) {
  SimavrTarget target(FirmwareSpec());
  Board b = OwnBoard();
  b.motors[0].step = PinRef{'L', 0};  // a Mega port; the ATmega328P has B, C and D
  ASSERT_EQ(target.WatchPins(b), std::nullopt);
  const auto err = target.Open();
  ASSERT_TRUE(err.has_value());
  EXPECT_NE(err->find("no port L"), std::string::npos) << *err;
  EXPECT_NE(err->find("m1_step"), std::string::npos) << *err;
}

}  // namespace
}  // namespace moco::conformance
