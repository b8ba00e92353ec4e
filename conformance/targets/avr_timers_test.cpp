// The timer model of the simavr target (avr_timers.h; ATmega328P datasheet
// 15-18, ATmega2560 datasheet 16-20): the timer test firmware
// (fixtures/firmware/timer_modes_avr) configures one timer per case over USART0
// and toggles a pin from each enabled timer interrupt; the pin's edge-to-edge
// times, in CPU cycles, must be the datasheet's periods exactly.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "conformance/core/report.h"
#include "conformance/core/run_report.h"
#include "conformance/targets/simavr_target.h"

namespace moco::conformance {
namespace {

constexpr const char* kElf328p = MOCO_TIMER_MODES_328P_ELF;
constexpr const char* kElf2560 = MOCO_TIMER_MODES_2560_ELF;

// Interrupt-enable bits of TIMSKn (the same on every timer of both MCUs).
constexpr uint8_t kToie = 1 << 0, kOcieA = 1 << 1, kOcieB = 1 << 2, kOcieC = 1 << 3, kIcie = 1 << 5;
// The firmware's pins: PC0 overflow, PC1..PC3 compare A..C, PC4 input capture.
enum Pin { kPinTov = 0, kPinA, kPinB, kPinC, kPinIcf };

// Data-space addresses of a timer's registers (ATmega328P 16.11/15.9/18.11 and
// ATmega2560 17.11 register summaries; Timer0-2 are at the same addresses on both).
struct TimerRegs {
  bool wide;
  uint16_t tccra, tccrb, tcnt, ocra, ocrb, ocrc, icr, timsk, tifr;
};
TimerRegs Regs(int timer) {
  switch (timer) {
    case 0:
      return {false, 0x44, 0x45, 0x46, 0x47, 0x48, 0, 0, 0x6E, 0x35};
    case 2:
      return {false, 0xB0, 0xB1, 0xB2, 0xB3, 0xB4, 0, 0, 0x70, 0x37};
    default: {
      const uint16_t base[] = {0, 0x80, 0, 0x90, 0xA0, 0x120};
      const uint16_t b = base[timer];
      // clang-format off
      return {true, b, static_cast<uint16_t>(b + 1), static_cast<uint16_t>(b + 4),
              static_cast<uint16_t>(b + 8), static_cast<uint16_t>(b + 10),
              static_cast<uint16_t>(b + 12), static_cast<uint16_t>(b + 6),
              static_cast<uint16_t>(0x6E + timer), static_cast<uint16_t>(0x35 + timer)};
      // clang-format on
    }
  }
}

Board TimerBoard() {
  Board b;
  b.name = "timer-modes";
  auto pc = [](uint8_t bit) { return PinRef{'C', bit}; };
  b.motors.push_back(BoardMotor{pc(kPinTov), pc(kPinA), pc(kPinB)});
  b.motors.push_back(BoardMotor{pc(kPinC), pc(kPinIcf), std::nullopt});
  return b;
}

// The firmware running under the simavr target, with its command protocol.
class Rig {
 public:
  explicit Rig(const char* elf, SimavrTarget::Options options = {})
      : target_(
            SimavrSpec{elf, elf == std::string(kElf2560) ? "atmega2560" : "atmega328p", 16'000'000},
            options) {
    EXPECT_EQ(target_.WatchPins(TimerBoard()), std::nullopt);
    EXPECT_EQ(target_.Open(), std::nullopt) << elf;
    EXPECT_EQ(Read(1), std::vector<uint8_t>{'>'}) << target_.Name();
  }

  SimavrTarget& target() { return target_; }

  void Write(uint16_t addr, uint8_t v) {
    Send({'W', static_cast<uint8_t>(addr), static_cast<uint8_t>(addr >> 8), v});
    EXPECT_EQ(Read(1), std::vector<uint8_t>{'w'}) << "W " << addr;
  }
  // High byte first: the low byte's write moves both through TEMP.
  void Write16(uint16_t addr, uint16_t v) {
    Write(addr + 1, static_cast<uint8_t>(v >> 8));
    Write(addr, static_cast<uint8_t>(v));
  }
  uint8_t Peek(uint16_t addr) {
    Send({'R', static_cast<uint8_t>(addr), static_cast<uint8_t>(addr >> 8)});
    const auto r = Read(1);
    return r.empty() ? 0 : r[0];
  }
  // Two 16-bit reads of `addr`, 128 cycles apart.
  std::pair<uint16_t, uint16_t> TimedRead(uint16_t addr) {
    Send({'T', static_cast<uint8_t>(addr), static_cast<uint8_t>(addr >> 8)});
    const auto r = Read(4);
    if (r.size() != 4) return {0, 0};
    return {static_cast<uint16_t>(r[0] | (r[1] << 8)), static_cast<uint16_t>(r[2] | (r[3] << 8))};
  }
  // Runs the firmware for `cycles` more CPU cycles.
  void Run(uint64_t cycles) {
    const uint64_t end = target_.cycles() + cycles;
    const TimeNs deadline = static_cast<TimeNs>(end * 1000 / 16) + 1;
    wire::Bytes out;
    while (target_.Now() < deadline && target_.Receive(deadline, out)) {
    }
    EXPECT_TRUE(out.empty());
  }
  // Cycles of the edges of PC`bit` after `after_cycle`.
  std::vector<uint64_t> Edges(int bit, uint64_t after_cycle) const {
    std::vector<uint64_t> out;
    const PinTrace* trace = target_.Pins();
    for (const PinSignal& s : trace->signals) {
      if (s.pin != PinRef{'C', static_cast<uint8_t>(bit)}) continue;
      for (const PinEdge& e : s.edges) {
        if (e.cycle > after_cycle) out.push_back(e.cycle);
      }
    }
    return out;
  }

 private:
  void Send(std::vector<uint8_t> bytes) { EXPECT_TRUE(target_.Send(bytes)); }
  std::vector<uint8_t> Read(size_t n) {
    const TimeNs deadline = target_.Now() + 50'000'000;  // 50 ms
    while (pending_.size() < n && target_.Now() < deadline) {
      if (!target_.Receive(deadline, pending_)) break;
    }
    const size_t take = std::min(n, pending_.size());
    std::vector<uint8_t> r(pending_.begin(), pending_.begin() + static_cast<long>(take));
    pending_.erase(pending_.begin(), pending_.begin() + static_cast<long>(take));
    return r;
  }

  SimavrTarget target_;
  wire::Bytes pending_;
};

// One timer set up one way, and the edge intervals each enabled flag's pin must show.
struct ModeCase {
  const char* name;
  bool mega;  // ATmega2560, else ATmega328P
  int timer;
  int wgm;
  int cs;
  uint16_t ocra, ocrb, ocrc, icr;
  uint8_t timsk;
  // The intervals (in CPU cycles) between successive edges of each enabled
  // pin: a flag set once a period shows {P}; a compare match on both slopes of
  // a dual-slope mode alternates between two values.
  std::vector<std::pair<int, std::vector<uint64_t>>> expect;
};

void PrintTo(const ModeCase& c, std::ostream* os) { *os << c.name; }

// Datasheet formulas (16.9 "Modes of Operation"): N is the prescaler, TOP the mode's.
uint64_t SingleSlope(uint64_t n, uint64_t top) { return n * (top + 1); }  // normal, CTC, fast
uint64_t DualSlope(uint64_t n, uint64_t top) { return 2 * n * top; }      // PC, PFC
// A compare match at `v` on both slopes: 2N(TOP-v) from the way up to the way down, then 2Nv.
std::vector<uint64_t> BothSlopes(uint64_t n, uint64_t top, uint64_t v) {
  return {2 * n * (top - v), 2 * n * v};
}

void Configure(Rig& rig, const ModeCase& c) {
  const TimerRegs r = Regs(c.timer);
  // Compare and TOP registers first, in normal mode (no double buffering), the
  // clock last.
  if (r.wide) {
    rig.Write16(r.ocra, c.ocra);
    rig.Write16(r.ocrb, c.ocrb);
    if (c.mega) rig.Write16(r.ocrc, c.ocrc);
    rig.Write16(r.icr, c.icr);
    rig.Write16(r.tcnt, 0);
    rig.Write(r.timsk, c.timsk);
    rig.Write(r.tccra, static_cast<uint8_t>(c.wgm & 3));
    rig.Write(r.tccrb, static_cast<uint8_t>(((c.wgm >> 2) << 3) | c.cs));
  } else {
    rig.Write(r.ocra, static_cast<uint8_t>(c.ocra));
    rig.Write(r.ocrb, static_cast<uint8_t>(c.ocrb));
    rig.Write(r.tcnt, 0);
    rig.Write(r.timsk, c.timsk);
    rig.Write(r.tccra, static_cast<uint8_t>(c.wgm & 3));
    rig.Write(r.tccrb, static_cast<uint8_t>(((c.wgm >> 2) << 3) | c.cs));
  }
}

class SimavrTimerModes : public ::testing::TestWithParam<ModeCase> {};

TEST_P(SimavrTimerModes, InterruptsComeAtTheDatasheetPeriod) {
  const ModeCase& c = GetParam();
  Rig rig(c.mega ? kElf2560 : kElf328p);
  Configure(rig, c);
  uint64_t longest = 0;
  for (const auto& [pin, intervals] : c.expect) {
    for (uint64_t i : intervals) longest = std::max(longest, i);
  }
  // Two periods to settle (the first interval runs from the start), then eight edges.
  const uint64_t start = rig.target().cycles() + 2 * longest;
  rig.Run(11 * longest);
  for (const auto& [pin, intervals] : c.expect) {
    const std::vector<uint64_t> edges = rig.Edges(pin, start);
    ASSERT_GE(edges.size(), 7u) << c.name << " pin PC" << pin;
    std::vector<uint64_t> seen;
    for (size_t i = 1; i < edges.size(); ++i) seen.push_back(edges[i] - edges[i - 1]);
    // The distinct intervals measured, for the test report (--gtest_output=xml).
    std::string measured;
    for (uint64_t m : std::set<uint64_t>(seen.begin(), seen.end())) {
      measured += (measured.empty() ? "" : " ") + std::to_string(m);
    }
    RecordProperty("PC" + std::to_string(pin) + "_cycles", measured);
    if (intervals.size() == 1) {
      for (uint64_t s : seen) EXPECT_EQ(s, intervals[0]) << c.name << " pin PC" << pin;
    } else {
      // Alternating: each interval is one of the two, and they alternate.
      const std::set<uint64_t> allowed(intervals.begin(), intervals.end());
      for (size_t i = 0; i < seen.size(); ++i) {
        EXPECT_TRUE(allowed.count(seen[i]))
            << c.name << " pin PC" << pin << " interval " << i << " = " << seen[i];
        if (i > 0) {
          EXPECT_EQ(seen[i] + seen[i - 1], intervals[0] + intervals[1]) << c.name;
        }
      }
    }
  }
}

// clang-format off
const ModeCase kModeCases[] = {
    // ---- ATmega328P Timer0 (8-bit; prescalers 1, 8, 64, 256, 1024) ----
    {"m328p_t0_mode0_normal_n8", false, 0, 0, 2, 100, 0, 0, 0, kToie | kOcieA,
     {{kPinTov, {SingleSlope(8, 255)}}, {kPinA, {SingleSlope(8, 255)}}}},
    {"m328p_t0_mode1_pc8_n1", false, 0, 1, 1, 0, 60, 0, 0, kToie | kOcieB,
     {{kPinTov, {DualSlope(1, 255)}}, {kPinB, BothSlopes(1, 255, 60)}}},
    {"m328p_t0_mode2_ctc_ocra_n64", false, 0, 2, 3, 99, 50, 0, 0, kOcieA | kOcieB,
     {{kPinA, {SingleSlope(64, 99)}}, {kPinB, {SingleSlope(64, 99)}}}},
    {"m328p_t0_mode3_fast8_n256", false, 0, 3, 4, 10, 0, 0, 0, kToie | kOcieA,
     {{kPinTov, {SingleSlope(256, 255)}}, {kPinA, {SingleSlope(256, 255)}}}},
    {"m328p_t0_mode5_pc_ocra_n1024", false, 0, 5, 5, 150, 40, 0, 0, kToie | kOcieB,
     {{kPinTov, {DualSlope(1024, 150)}}, {kPinB, BothSlopes(1024, 150, 40)}}},
    {"m328p_t0_mode7_fast_ocra_n1", false, 0, 7, 1, 199, 100, 0, 0, kToie | kOcieB,
     {{kPinTov, {SingleSlope(1, 199)}}, {kPinB, {SingleSlope(1, 199)}}}},
    // ---- ATmega328P Timer2 (8-bit; prescalers 1, 8, 32, 64, 128, 256, 1024) ----
    {"m328p_t2_mode0_normal_n1", false, 2, 0, 1, 0, 0, 0, 0, kToie,
     {{kPinTov, {SingleSlope(1, 255)}}}},
    {"m328p_t2_mode0_normal_n32", false, 2, 0, 3, 0, 0, 0, 0, kToie,
     {{kPinTov, {SingleSlope(32, 255)}}}},
    {"m328p_t2_mode1_pc8_n128", false, 2, 1, 5, 100, 0, 0, 0, kToie | kOcieA,
     {{kPinTov, {DualSlope(128, 255)}}, {kPinA, BothSlopes(128, 255, 100)}}},
    {"m328p_t2_mode2_ctc_ocra_n64", false, 2, 2, 4, 249, 0, 0, 0, kOcieA,
     {{kPinA, {SingleSlope(64, 249)}}}},
    {"m328p_t2_mode3_fast8_n256", false, 2, 3, 6, 0, 200, 0, 0, kToie | kOcieB,
     {{kPinTov, {SingleSlope(256, 255)}}, {kPinB, {SingleSlope(256, 255)}}}},
    {"m328p_t2_mode5_pc_ocra_n1024", false, 2, 5, 7, 77, 0, 0, 0, kToie | kOcieA,
     {{kPinTov, {DualSlope(1024, 77)}}, {kPinA, {DualSlope(1024, 77)}}}},
    {"m328p_t2_mode7_fast_ocra_n8", false, 2, 7, 2, 149, 20, 0, 0, kToie | kOcieB,
     {{kPinTov, {SingleSlope(8, 149)}}, {kPinB, {SingleSlope(8, 149)}}}},
    // ---- ATmega328P Timer1 (16-bit), every mode but the reserved 13 ----
    {"m328p_t1_mode0_normal_n1", false, 1, 0, 1, 1000, 30000, 0, 0, kToie | kOcieA | kOcieB,
     {{kPinTov, {SingleSlope(1, 0xFFFF)}},
      {kPinA, {SingleSlope(1, 0xFFFF)}},
      {kPinB, {SingleSlope(1, 0xFFFF)}}}},
    {"m328p_t1_mode1_pc8_n8", false, 1, 1, 2, 100, 0, 0, 0, kToie | kOcieA,
     {{kPinTov, {DualSlope(8, 0xFF)}}, {kPinA, BothSlopes(8, 0xFF, 100)}}},
    {"m328p_t1_mode2_pc9_n1", false, 1, 2, 1, 0, 300, 0, 0, kToie | kOcieB,
     {{kPinTov, {DualSlope(1, 0x1FF)}}, {kPinB, BothSlopes(1, 0x1FF, 300)}}},
    {"m328p_t1_mode3_pc10_n64", false, 1, 3, 3, 1023, 0, 0, 0, kToie | kOcieA,
     {{kPinTov, {DualSlope(64, 0x3FF)}}, {kPinA, {DualSlope(64, 0x3FF)}}}},
    {"m328p_t1_mode4_ctc_ocra_n8", false, 1, 4, 2, 1999, 500, 0, 0, kOcieA | kOcieB,
     {{kPinA, {SingleSlope(8, 1999)}}, {kPinB, {SingleSlope(8, 1999)}}}},
    {"m328p_t1_mode5_fast8_n1", false, 1, 5, 1, 128, 0, 0, 0, kToie | kOcieA,
     {{kPinTov, {SingleSlope(1, 0xFF)}}, {kPinA, {SingleSlope(1, 0xFF)}}}},
    {"m328p_t1_mode6_fast9_n256", false, 1, 6, 4, 0, 0, 0, 0, kToie,
     {{kPinTov, {SingleSlope(256, 0x1FF)}}}},
    {"m328p_t1_mode7_fast10_n1024", false, 1, 7, 5, 0, 0, 0, 0, kToie,
     {{kPinTov, {SingleSlope(1024, 0x3FF)}}}},
    // DFMoco 2.0.0's step timer: TCCR1B = _BV(WGM13), ICR1 = 200: 40 kHz at 16 MHz.
    {"m328p_t1_mode8_pfc_icr_dfmoco", false, 1, 8, 1, 0, 0, 0, 200, kToie,
     {{kPinTov, {DualSlope(1, 200)}}}},
    {"m328p_t1_mode8_pfc_icr_n1", false, 1, 8, 1, 100, 0, 0, 400, kToie | kOcieA | kIcie,
     {{kPinTov, {DualSlope(1, 400)}},
      {kPinA, BothSlopes(1, 400, 100)},
      {kPinIcf, {DualSlope(1, 400)}}}},
    {"m328p_t1_mode9_pfc_ocra_n8", false, 1, 9, 2, 300, 100, 0, 0, kToie | kOcieA | kOcieB,
     {{kPinTov, {DualSlope(8, 300)}},
      {kPinA, {DualSlope(8, 300)}},
      {kPinB, BothSlopes(8, 300, 100)}}},
    {"m328p_t1_mode10_pc_icr_n1", false, 1, 10, 1, 0, 250, 0, 1000, kToie | kOcieB | kIcie,
     {{kPinTov, {DualSlope(1, 1000)}},
      {kPinB, BothSlopes(1, 1000, 250)},
      {kPinIcf, {DualSlope(1, 1000)}}}},
    {"m328p_t1_mode11_pc_ocra_n64", false, 1, 11, 3, 500, 0, 0, 0, kToie | kOcieA,
     {{kPinTov, {DualSlope(64, 500)}}, {kPinA, {DualSlope(64, 500)}}}},
    {"m328p_t1_mode12_ctc_icr_n1", false, 1, 12, 1, 300, 0, 0, 999, kOcieA | kIcie,
     {{kPinA, {SingleSlope(1, 999)}}, {kPinIcf, {SingleSlope(1, 999)}}}},
    {"m328p_t1_mode14_fast_icr_n8", false, 1, 14, 2, 400, 0, 0, 799, kToie | kOcieA | kIcie,
     {{kPinTov, {SingleSlope(8, 799)}},
      {kPinA, {SingleSlope(8, 799)}},
      {kPinIcf, {SingleSlope(8, 799)}}}},
    {"m328p_t1_mode15_fast_ocra_n1", false, 1, 15, 1, 499, 250, 0, 0, kToie | kOcieB,
     {{kPinTov, {SingleSlope(1, 499)}}, {kPinB, {SingleSlope(1, 499)}}}},
    // ---- ATmega2560: mode 8 on every 16-bit timer, more modes with compare C ----
    {"m2560_t1_mode8_pfc_icr_dfmoco", true, 1, 8, 1, 0, 0, 0, 200, kToie,
     {{kPinTov, {DualSlope(1, 200)}}}},
    {"m2560_t3_mode8_pfc_icr_n8", true, 3, 8, 2, 0, 0, 150, 600, kToie | kOcieC,
     {{kPinTov, {DualSlope(8, 600)}}, {kPinC, BothSlopes(8, 600, 150)}}},
    {"m2560_t4_mode8_pfc_icr_n1", true, 4, 8, 1, 0, 0, 0, 300, kToie | kIcie,
     {{kPinTov, {DualSlope(1, 300)}}, {kPinIcf, {DualSlope(1, 300)}}}},
    {"m2560_t5_mode8_pfc_icr_n64", true, 5, 8, 3, 0, 0, 0, 200, kToie,
     {{kPinTov, {DualSlope(64, 200)}}}},
    {"m2560_t1_mode11_pc_ocra_n1_ocrc", true, 1, 11, 1, 700, 0, 200, 0, kToie | kOcieC,
     {{kPinTov, {DualSlope(1, 700)}}, {kPinC, BothSlopes(1, 700, 200)}}},
    {"m2560_t3_mode9_pfc_ocra_n256", true, 3, 9, 4, 100, 30, 0, 0, kToie | kOcieB,
     {{kPinTov, {DualSlope(256, 100)}}, {kPinB, BothSlopes(256, 100, 30)}}},
    {"m2560_t4_mode10_pc_icr_n1", true, 4, 10, 1, 0, 0, 600, 900, kIcie | kOcieC,
     {{kPinIcf, {DualSlope(1, 900)}}, {kPinC, BothSlopes(1, 900, 600)}}},
    {"m2560_t5_mode14_fast_icr_n1024", true, 5, 14, 5, 0, 0, 20, 99, kToie | kOcieC,
     {{kPinTov, {SingleSlope(1024, 99)}}, {kPinC, {SingleSlope(1024, 99)}}}},
    {"m2560_t3_mode4_ctc_ocra_n1", true, 3, 4, 1, 999, 0, 0, 0, kOcieA,
     {{kPinA, {SingleSlope(1, 999)}}}},
    {"m2560_t4_mode1_pc8_n8", true, 4, 1, 2, 0, 0, 0, 0, kToie,
     {{kPinTov, {DualSlope(8, 0xFF)}}}},
    {"m2560_t5_mode12_ctc_icr_n8", true, 5, 12, 2, 0, 0, 0, 4999, kIcie,
     {{kPinIcf, {SingleSlope(8, 4999)}}}},
    {"m2560_t0_mode5_pc_ocra_n8", true, 0, 5, 2, 200, 0, 0, 0, kToie,
     {{kPinTov, {DualSlope(8, 200)}}}},
    {"m2560_t2_mode1_pc8_n32", true, 2, 1, 3, 0, 0, 0, 0, kToie,
     {{kPinTov, {DualSlope(32, 0xFF)}}}},
};
// clang-format on

INSTANTIATE_TEST_SUITE_P(Modes, SimavrTimerModes, ::testing::ValuesIn(kModeCases),
                         [](const ::testing::TestParamInfo<ModeCase>& param_info) {
                           return std::string(param_info.param.name);
                         });

// simavr 1.6 alone, for the record (FACTS "simavr"): mode 8 runs single slope on
// the 328P (twice the rate) and never overflows on the 2560. The model is what
// makes the cases above pass.
TEST(SimavrTimers, PlainSimavrGetsMode8Wrong) {
  SimavrTarget::Options plain;
  plain.timer_model = false;
  const ModeCase& uno = kModeCases[21];
  ASSERT_STREQ(uno.name, "m328p_t1_mode8_pfc_icr_dfmoco");
  {
    Rig rig(kElf328p, plain);
    Configure(rig, uno);
    const uint64_t start = rig.target().cycles() + 2000;
    rig.Run(10000);
    const std::vector<uint64_t> edges = rig.Edges(kPinTov, start);
    ASSERT_GE(edges.size(), 3u);
    EXPECT_LT(edges[2] - edges[1], DualSlope(1, 200));
    RecordProperty("plain_simavr_mode8_uno_cycles", std::to_string(edges[2] - edges[1]));
  }
  {
    Rig rig(kElf2560, plain);
    ModeCase mega = uno;
    mega.mega = true;
    Configure(rig, mega);
    const uint64_t start = rig.target().cycles();
    rig.Run(10000);
    EXPECT_TRUE(rig.Edges(kPinTov, start).empty());
  }
}

// TCNTn read back: two reads 128 cycles apart differ by 128 / N ticks
// (single slope), or lie 128 ticks apart along the up-down path (dual slope).
TEST(SimavrTimers, TcntReadsFollowTheCounter) {
  Rig rig(kElf328p);
  const TimerRegs t1 = Regs(1);
  // Stopped: what is written is read.
  rig.Write16(t1.tcnt, 0x1234);
  EXPECT_EQ(rig.TimedRead(t1.tcnt), std::make_pair(uint16_t{0x1234}, uint16_t{0x1234}));
  const std::pair<int, uint16_t> single[] = {{1, 128}, {2, 16}, {3, 2}};  // CS1 -> 128/N
  for (const auto& [cs, diff] : single) {
    rig.Write(t1.tccrb, static_cast<uint8_t>(cs));  // normal mode
    for (int i = 0; i < 5; ++i) {
      const auto [a, b] = rig.TimedRead(t1.tcnt);
      EXPECT_EQ(static_cast<uint16_t>(b - a), diff) << "CS1 " << cs << ": " << a << " " << b;
    }
  }
  rig.Write(t1.tccrb, 0);
  // Timer0 and Timer2 at N = 1: the 8-bit counter wraps at 256.
  for (int timer : {0, 2}) {
    const TimerRegs r = Regs(timer);
    rig.Write(r.tccrb, 1);
    for (int i = 0; i < 3; ++i) {
      const auto [a, b] = rig.TimedRead(r.tcnt);
      EXPECT_EQ(static_cast<uint8_t>((b & 0xFF) - (a & 0xFF)), 128) << "Timer" << timer;
    }
    rig.Write(r.tccrb, 0);
  }
  // Dual slope, mode 10 with ICR1 = 300 at N = 1: along 0..300..0 (period 600).
  rig.Write16(t1.icr, 300);
  rig.Write16(t1.tcnt, 0);
  rig.Write(t1.tccra, 2);             // WGM11
  rig.Write(t1.tccrb, (1 << 4) | 1);  // WGM13, CS10
  auto phases = [](uint32_t c) { return std::set<uint32_t>{c, (600 - c) % 600}; };
  for (int i = 0; i < 8; ++i) {
    const auto [a, b] = rig.TimedRead(t1.tcnt);
    ASSERT_LE(a, 300);
    ASSERT_LE(b, 300);
    bool consistent = false;
    for (uint32_t p : phases(a)) consistent = consistent || phases(b).count((p + 128) % 600);
    EXPECT_TRUE(consistent) << a << " then " << b;
  }
}

// OCRnA as TOP is double buffered in fast PWM (16.7.1): a new TOP takes effect
// when the running period ends, so no period is cut short.
TEST(SimavrTimers, ANewTopTakesEffectAtTheEndOfThePeriod) {
  Rig rig(kElf328p);
  ModeCase c = kModeCases[28];  // m328p_t1_mode15_fast_ocra_n1, TOP 499
  ASSERT_STREQ(c.name, "m328p_t1_mode15_fast_ocra_n1");
  c.cs = 2;  // N = 8: a period of 4000 cycles
  c.timsk = kToie;
  Configure(rig, c);
  rig.Run(20000);
  rig.Write16(Regs(1).ocra, 249);                // new TOP: 2000 cycles
  const uint64_t write = rig.target().cycles();  // just after the write's answer
  rig.Run(20000);
  const std::vector<uint64_t> edges = rig.Edges(kPinTov, 0);
  ASSERT_GE(edges.size(), 10u);
  int long_periods_after_write = 0;
  for (size_t i = 2; i < edges.size(); ++i) {
    const uint64_t d = edges[i] - edges[i - 1];
    if (edges[i] <= write) {
      EXPECT_EQ(d, SingleSlope(8, 499));
    } else if (d == SingleSlope(8, 499)) {
      ++long_periods_after_write;  // the period under way when OCR1A was written
    } else {
      EXPECT_EQ(d, SingleSlope(8, 249));
    }
  }
  EXPECT_LE(long_periods_after_write, 1);
}

// An edge on ICP1 (PB0 on the 328P; ICES1: rising) copies TCNT1 into ICR1 and
// raises the input capture interrupt.
TEST(SimavrTimers, AnEdgeOnTheCapturePinLatchesTcnt) {
  Rig rig(kElf328p);
  const TimerRegs t1 = Regs(1);
  constexpr uint16_t kDdrb = 0x24, kPortb = 0x25;
  rig.Write(kDdrb, 1);
  rig.Write(t1.timsk, kIcie);
  rig.Write(t1.tccrb, (1 << 6) | 2);  // ICES1, N = 8
  rig.Run(1000);
  const uint64_t before = rig.target().cycles();
  rig.Write(kPortb, 1);  // rising edge on ICP1
  rig.Run(1000);
  EXPECT_EQ(rig.Edges(kPinIcf, before).size(), 1u);
  const auto [icr_a, icr_b] = rig.TimedRead(t1.icr);
  EXPECT_EQ(icr_a, icr_b);  // latched, not counting
  const auto [tcnt, tcnt_later] = rig.TimedRead(t1.tcnt);
  // Captured a little earlier: the 1000-cycle run, the reads' bytes on the line.
  EXPECT_GT(icr_a, 0);
  EXPECT_LT(static_cast<uint16_t>(tcnt - icr_a), 20000 / 8);
  EXPECT_EQ(tcnt_later - tcnt, 128 / 8);
  rig.Write(kPortb, 0);  // falling edge: not the selected one
  rig.Run(1000);
  EXPECT_EQ(rig.Edges(kPinIcf, before).size(), 1u);
}

// A CPU write to TCNTn blocks the compare match on the next timer tick (16.7.3):
// writing TCNT1 = OCR1A does not raise OCF1A.
TEST(SimavrTimers, WritingTcntBlocksTheNextCompareMatch) {
  Rig rig(kElf328p);
  const TimerRegs t1 = Regs(1);
  rig.Write16(t1.ocra, 5);
  rig.Write16(t1.tcnt, 1000);
  rig.Write(t1.timsk, kOcieA);
  rig.Write(t1.tccrb, 5);  // normal, N = 1024: the next match is 64 Mi cycles away
  rig.Run(100);
  const uint64_t before = rig.target().cycles();
  rig.Write16(t1.tcnt, 5);
  rig.Run(20000);  // well past the next tick
  EXPECT_TRUE(rig.Edges(kPinA, before).empty());
  rig.Write16(t1.tcnt, 4);  // not blocked: the match comes as the counter leaves 5
  rig.Run(5000);
  EXPECT_EQ(rig.Edges(kPinA, before).size(), 1u);
}

// TIFRn: writing 1 clears that flag only; TIMSKn set over a raised flag pends it.
TEST(SimavrTimers, FlagsClearByWritingOneAndPendWhenEnabled) {
  Rig rig(kElf328p);
  const TimerRegs t1 = Regs(1);
  rig.Write16(t1.ocra, 1000);
  rig.Write(t1.tccrb, 1);  // normal, N = 1, no interrupt enabled
  rig.Run(70000);
  EXPECT_EQ(rig.Peek(t1.tifr) & 0x03, 0x03);  // TOV1 and OCF1A
  rig.Write(t1.tifr, 0x01);                   // clear TOV1 only
  EXPECT_EQ(rig.Peek(t1.tifr) & 0x03, 0x02);
  rig.Write(t1.tccrb, 0);  // stopped: no compare match can come from counting
  const uint64_t before = rig.target().cycles();
  rig.Write(t1.timsk, kOcieA);  // OCF1A is set: its interrupt is taken at once
  rig.Run(1000);
  const std::vector<uint64_t> edges = rig.Edges(kPinA, before);
  EXPECT_EQ(edges.size(), 1u);
  EXPECT_EQ(rig.Peek(t1.tifr) & 0x02, 0);  // entering the interrupt cleared OCF1A
}

// What the model does not reproduce is named; a timer that can never interrupt is too.
TEST(SimavrTimers, UnmodelledFeaturesAndSilentInterruptsAreNamed) {
  Rig rig(kElf328p);
  const TimerRegs t1 = Regs(1), t0 = Regs(0), t2 = Regs(2);
  rig.Write16(t1.ocra, 999);
  rig.Write(t1.timsk, kToie);         // overflow enabled ...
  rig.Write(t1.tccra, 1 << 6);        // COM1A0: toggle OC1A
  rig.Write(t1.tccrb, (1 << 3) | 1);  // ... but CTC (mode 4) never reaches MAX
  rig.Write(t0.timsk, kToie);
  rig.Write(t0.tccrb, 7);       // external clock T0, rising edge
  rig.Write(t2.timsk, kOcieA);  // Timer2 compare A enabled, clock stopped
  rig.Run(200000);
  const std::vector<std::string> notes = rig.target().Unmodelled();
  const std::vector<std::string> caveats = rig.target().Caveats();
  auto has = [](const std::vector<std::string>& v, const std::string& text) {
    return std::find(v.begin(), v.end(), text) != v.end();
  };
  EXPECT_TRUE(has(notes, "Timer1 output compare pin OC1A (COM1A bits) is not driven under simavr"))
      << ::testing::PrintToString(notes);
  EXPECT_TRUE(has(notes,
                  "Timer0 external clock on pin T0 (CS0 = 7) is not modelled: the timer "
                  "does not count under simavr"))
      << ::testing::PrintToString(notes);
  EXPECT_TRUE(has(caveats,
                  "Timer1 overflow interrupt is enabled in TIMSK1 but never fired: in "
                  "CTC mode (WGM1 = 4) the counter never reaches MAX, its TOP being 999"))
      << ::testing::PrintToString(caveats);
  EXPECT_TRUE(has(caveats,
                  "Timer0 overflow interrupt is enabled in TIMSK0 but never fired: its "
                  "clock or mode is not modelled (see the notes above)"))
      << ::testing::PrintToString(caveats);
  EXPECT_TRUE(has(caveats,
                  "Timer2 compare match A interrupt is enabled in TIMSK2 but never "
                  "fired: its clock is stopped (CS2 = 0)"))
      << ::testing::PrintToString(caveats);
  // Notes survive a restart (the run's report lists what any case used).
  rig.target().Restart();
  EXPECT_TRUE(has(rig.target().Unmodelled(),
                  "Timer1 output compare pin OC1A (COM1A bits) is not driven under simavr"));
}

// A firmware that uses only modelled features gets no caveats.
TEST(SimavrTimers, AModelledTimerGetsNoCaveat) {
  Rig rig(kElf2560);
  Configure(rig, kModeCases[29]);  // m2560_t1_mode8_pfc_icr_dfmoco
  rig.Run(4000);
  EXPECT_EQ(rig.target().Caveats(), std::vector<std::string>{});
}

// The run report carries the target's caveats to the console, JSON and HTML
// (mococheck run fills RunReport::target_caveats from Target::Caveats()).
TEST(SimavrTimers, TheReportsShowTheTargetsCaveats) {
  Rig rig(kElf328p);
  const TimerRegs t1 = Regs(1);
  rig.Write(t1.tccra, 1 << 6);  // COM1A0
  RunReport report;
  report.target = rig.target().Name();
  report.target_caveats = rig.target().Caveats();
  const std::string note = "Timer1 output compare pin OC1A (COM1A bits) is not driven under simavr";
  ASSERT_EQ(report.target_caveats, std::vector<std::string>{note});
  EXPECT_NE(ConsoleSummary(report, false).find("target caveat: " + note), std::string::npos);
  EXPECT_EQ(JsonReport(report)["target_caveats"], nlohmann::json::array({note}));
  EXPECT_NE(HtmlReport(report).find("<li>" + note + "</li>"), std::string::npos);
}

}  // namespace
}  // namespace moco::conformance
