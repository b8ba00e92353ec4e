// The pin rules judged on hand-made traces (conformance/rules/pin_rules.cpp; FACTS
// "Step drivers", "DFMoco"), the board and driver profiles (fixtures/boards,
// fixtures/drivers), and the rules' applicability: only a target watching pins.
#include "conformance/core/pin_judge.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <sstream>

#include "conformance/protocols/registry.h"

namespace moco::conformance {
namespace {

constexpr sim::TimeNs kUs = 1000;

std::string Root() {
  const char* root = std::getenv("MOCO_SOURCE_DIR");
  return root != nullptr ? root : ".";
}

Board OneMotorBoard() {
  Board b;
  b.name = "test";
  b.motors.push_back({PinRef{'D', 4}, PinRef{'D', 5}, std::nullopt});
  return b;
}

// Motor 1 steps `n` times forward, one pulse every `period`, high for `high`,
// starting at `t0`; DIR goes high `setup` before the first rising edge.
PinTrace Pulses(int n, sim::TimeNs t0, sim::TimeNs period, sim::TimeNs high,
                sim::TimeNs setup = 10 * kUs) {
  PinTrace t = PinTrace::For(OneMotorBoard());
  t.frequency_hz = 16'000'000;
  t.signals[1].edges.push_back({t0 - setup, 0, true});
  for (int i = 0; i < n; ++i) {
    const sim::TimeNs r = t0 + i * period;
    t.signals[0].edges.push_back({r, 0, true});
    t.signals[0].edges.push_back({r + high, 0, false});
  }
  return t;
}

PinJudgeOptions A4988() {
  PinJudgeOptions o;
  o.driver = std::get<DriverProfile>(LoadDriver("a4988"));
  o.board = OneMotorBoard();
  return o;
}

Status StatusOf(const Verdicts& v, const std::string& id) {
  auto it = v.outcomes().find(id);
  return it == v.outcomes().end() ? Status::kNotExercised : it->second.status;
}

TEST(PinJudge, APulseShorterThanTheDriversHighTimeFailsPin003ButNotForAFasterDriver) {
  const PinTrace t = Pulses(10, 1000 * kUs, 200 * kUs, 187);  // 3 cycles at 16 MHz
  Verdicts a4988, tmc;
  JudgePins("DFM-", t, {}, A4988(), 10 * sim::kNsPerSecond, a4988);
  EXPECT_EQ(StatusOf(a4988, "DFM-PIN-003"), Status::kFail);
  PinJudgeOptions o = A4988();
  o.driver = std::get<DriverProfile>(LoadDriver("tmc2209"));
  JudgePins("DFM-", t, {}, o, 10 * sim::kNsPerSecond, tmc);
  EXPECT_EQ(StatusOf(tmc, "DFM-PIN-003"), Status::kPass);
  EXPECT_EQ(StatusOf(a4988, "DFM-PIN-004"), Status::kPass);
}

TEST(PinJudge, DirChangedAtTheStepEdgeFailsSetupAndOneJustOverTheSetupTimePasses) {
  Verdicts late, ok;
  JudgePins("DFM-", Pulses(3, 1000 * kUs, 200 * kUs, 25 * kUs, 0), {}, A4988(), sim::kNsPerSecond,
            late);
  EXPECT_EQ(StatusOf(late, "DFM-PIN-004"), Status::kFail);
  JudgePins("DFM-", Pulses(3, 1000 * kUs, 200 * kUs, 25 * kUs, 200), {}, A4988(), sim::kNsPerSecond,
            ok);
  EXPECT_EQ(StatusOf(ok, "DFM-PIN-004"), Status::kPass);
}

TEST(PinJudge, AReportAtRestMustEqualTheSignedStepCountSinceTheLastReset) {
  const PinTrace t = Pulses(100, 1000 * kUs, 200 * kUs, 25 * kUs);  // 100 steps by 21 ms
  using K = PinPositionEvent::Kind;
  const sim::TimeNs later = 500 * sim::kNsPerMs;
  Verdicts right, lost;
  JudgePins("DFM-", t, {{K::kReport, later, 1, 100}}, A4988(), sim::kNsPerSecond, right);
  EXPECT_EQ(StatusOf(right, "DFM-PIN-001"), Status::kPass);
  JudgePins("DFM-", t, {{K::kReport, later, 1, 101}}, A4988(), sim::kNsPerSecond, lost);
  EXPECT_EQ(StatusOf(lost, "DFM-PIN-001"), Status::kFail);
  // np 1 1000 before the pulses: 1100 afterwards.
  Verdicts reset;
  JudgePins("DFM-", t, {{K::kReset, 0, 1, 1000}, {K::kReport, later, 1, 1100}}, A4988(),
            sim::kNsPerSecond, reset);
  EXPECT_EQ(StatusOf(reset, "DFM-PIN-001"), Status::kPass);
}

TEST(PinJudge, StepsFasterThanTheBoardsTopRateFailPin005) {
  Verdicts at_top, over;
  JudgePins("DFM-", Pulses(40, 1000 * kUs, 50 * kUs, 25 * kUs), {}, A4988(), sim::kNsPerSecond,
            at_top);
  EXPECT_EQ(StatusOf(at_top, "DFM-PIN-005"), Status::kPass);
  JudgePins("DFM-", Pulses(40, 1000 * kUs, 40 * kUs, 20 * kUs), {}, A4988(), sim::kNsPerSecond,
            over);
  EXPECT_EQ(StatusOf(over, "DFM-PIN-005"), Status::kFail);
}

// Motor 1 steps forward at `rate_hz` from `t0` for `n` pulses, each pulse
// `late` later than its tick when `late_every` > 0 says it is one (a step
// entered late after a long interrupt).
PinTrace Steady(int n, sim::TimeNs t0, double rate_hz, int late_every = 0, sim::TimeNs late = 0) {
  PinTrace t = PinTrace::For(OneMotorBoard());
  t.frequency_hz = 16'000'000;
  t.signals[1].edges.push_back({t0 - 10 * kUs, 0, true});
  for (int i = 0; i < n; ++i) {
    sim::TimeNs r = t0 + static_cast<sim::TimeNs>(i * 1e9 / rate_hz);
    if (late_every > 0 && i % late_every == 0 && i > 0) r += late;
    t.signals[0].edges.push_back({r, 0, true});
    t.signals[0].edges.push_back({r + 2 * kUs, 0, false});
  }
  return t;
}

// Measured on Dragonframe's DFMoco 2.0.0 with a correct clock: at 20 kHz, the
// step after each 50 ms chunk load is entered ~12.4 us late (the long
// interrupt), so 8 intervals take 387.6 us against 400. That is latency, not
// a rate: no window holds more pulses than 20 kHz allows.
TEST(PinJudge, AStepEnteredLateAfterALongInterruptIsNotARate) {
  Verdicts v;
  JudgePins("DFM-", Steady(4000, 1000 * kUs, 20000, 1000, 12400), {}, A4988(), sim::kNsPerSecond,
            v);
  EXPECT_EQ(StatusOf(v, "DFM-PIN-005"), Status::kPass);
}

// A rate just 1 % over the board's 20 kHz, sustained, is caught over 10 ms.
TEST(PinJudge, ASustainedRateJustOverTheTopFailsPin005) {
  Verdicts v;
  JudgePins("DFM-", Steady(4000, 1000 * kUs, 20200), {}, A4988(), sim::kNsPerSecond, v);
  ASSERT_EQ(StatusOf(v, "DFM-PIN-005"), Status::kFail);
  EXPECT_NE(v.outcomes().at("DFM-PIN-005").evidence.at(0).observed.find("within 10 ms"),
            std::string::npos)
      << v.outcomes().at("DFM-PIN-005").evidence.at(0).observed;
}

// The evidence is the worst window of the case, not the first over the rate:
// 21 kHz for a while, then 41 kHz.
TEST(PinJudge, Pin005ShowsTheWorstWindowNotTheFirst) {
  PinTrace t = Steady(2000, 1000 * kUs, 21000);
  const PinTrace fast = Steady(400, 200 * sim::kNsPerMs, 41000);
  for (size_t i = 0; i < fast.signals[0].edges.size(); ++i) {
    t.signals[0].edges.push_back(fast.signals[0].edges[i]);
  }
  Verdicts v;
  JudgePins("DFM-", t, {}, A4988(), sim::kNsPerSecond, v);
  ASSERT_EQ(StatusOf(v, "DFM-PIN-005"), Status::kFail);
  const Evidence& e = v.outcomes().at("DFM-PIN-005").evidence.at(0);
  EXPECT_GE(e.t_ns, 200 * sim::kNsPerMs) << e.observed;
  EXPECT_NE(e.observed.find("(41"), std::string::npos) << e.observed;
}

// The sketch reports the planned end of the chunk its timer is about to step
// out (FACTS DFMoco): an `mp` at the start of a move, with every pulse of the
// chunk still to come, is a report while moving (PIN-002), not at rest.
TEST(PinJudge, AReportOfTheChunkStillBeingSteppedOutIsJudgedAsMoving) {
  using K = PinPositionEvent::Kind;
  // 250 steps at 5 kHz from 1 ms: the first 50 ms chunk ends at 250.
  const PinTrace t = Steady(250, 1000 * kUs, 5000);
  Verdicts v;
  JudgePins("DFM-", t, {{K::kReport, 900 * kUs, 1, 250}, {K::kReport, 600 * sim::kNsPerMs, 1, 250}},
            A4988(), sim::kNsPerSecond, v);
  EXPECT_EQ(StatusOf(v, "DFM-PIN-001"), Status::kPass);
  EXPECT_EQ(StatusOf(v, "DFM-PIN-002"), Status::kPass);
}

// A trace that ends soon after a report (a run or a case cut short) cannot
// tell whether the motor was at rest: the report is left unjudged, and judged
// once the trace holds the rest window after it. A report while moving whose
// reporting period runs past the end is judged only when it passes within the
// steps the trace holds (more steps could only widen the allowance).
TEST(PinJudge, AReportIsJudgedOnlyWhereTheTraceHoldsWhatItsRuleNeedsAfterIt) {
  using K = PinPositionEvent::Kind;
  // 100 steps by 21 ms, the report (one step off) at 30 ms.
  const PinTrace t = Pulses(100, 1000 * kUs, 200 * kUs, 25 * kUs);
  const sim::TimeNs at = 30 * sim::kNsPerMs;
  Verdicts cut, whole;
  JudgePins("DFM-", t, {{K::kReport, at, 1, 101}}, A4988(), at + kPinRestWindowNs - 1, cut);
  EXPECT_EQ(StatusOf(cut, "DFM-PIN-001"), Status::kNotExercised);
  JudgePins("DFM-", t, {{K::kReport, at, 1, 101}}, A4988(), at + kPinRestWindowNs, whole);
  EXPECT_EQ(StatusOf(whole, "DFM-PIN-001"), Status::kFail);

  // 2000 steps at 1 kHz from 1 ms; a report at 500 ms (500 pulses by then)
  // with the trace judged up to 600 ms holds 600 of the steps a period (1 s)
  // either side allows; up to 3 s, 1500.
  const PinTrace moving = Steady(2000, 1000 * kUs, 1000);
  const sim::TimeNs mid = 500 * sim::kNsPerMs, end = 600 * sim::kNsPerMs;
  const sim::TimeNs after = 3 * sim::kNsPerSecond;
  Verdicts near, far, far_after, farther_after;
  JudgePins("DFM-", moving, {{K::kReport, mid, 1, 1060}}, A4988(), end, near);
  EXPECT_EQ(StatusOf(near, "DFM-PIN-002"), Status::kPass) << "within the steps held";
  JudgePins("DFM-", moving, {{K::kReport, mid, 1, 1200}}, A4988(), end, far);
  EXPECT_EQ(StatusOf(far, "DFM-PIN-002"), Status::kNotExercised) << "steps may yet come";
  JudgePins("DFM-", moving, {{K::kReport, mid, 1, 1200}}, A4988(), after, far_after);
  EXPECT_EQ(StatusOf(far_after, "DFM-PIN-002"), Status::kPass) << "and they came";
  JudgePins("DFM-", moving, {{K::kReport, mid, 1, 2100}}, A4988(), after, farther_after);
  EXPECT_EQ(StatusOf(farther_after, "DFM-PIN-002"), Status::kFail);
}

TEST(PinProfiles, TheDriverFilesHoldTheBuiltInDatasheetFigures) {
  for (const DriverProfile& d : BuiltInDrivers()) {
    const auto read = LoadDriver(Root() + "/fixtures/drivers/" + d.name + ".json");
    ASSERT_TRUE(std::holds_alternative<DriverProfile>(read)) << std::get<std::string>(read);
    const DriverProfile& f = std::get<DriverProfile>(read);
    EXPECT_EQ(f.step_high_min_ns, d.step_high_min_ns) << d.name;
    EXPECT_EQ(f.step_low_min_ns, d.step_low_min_ns) << d.name;
    EXPECT_EQ(f.dir_setup_min_ns, d.dir_setup_min_ns) << d.name;
    EXPECT_EQ(f.dir_hold_min_ns, d.dir_hold_min_ns) << d.name;
  }
  const auto unknown = LoadDriver("l298");
  ASSERT_TRUE(std::holds_alternative<std::string>(unknown));
  EXPECT_NE(std::get<std::string>(unknown).find("a4988"), std::string::npos);
}

TEST(PinProfiles, TheBoardFilesReadAndTheOwnFirmwareDrivesTheUnoPins) {
  for (const char* name : {"own-dfmoco", "dfmoco-uno", "dfmoco-mega"}) {
    const auto b = LoadBoard(Root() + "/fixtures/boards/" + name + ".json");
    ASSERT_TRUE(std::holds_alternative<Board>(b)) << std::get<std::string>(b);
    EXPECT_EQ(std::get<Board>(b).motors.size(), 4u);
  }
  const Board own = std::get<Board>(LoadBoard(Root() + "/fixtures/boards/own-dfmoco.json"));
  EXPECT_EQ(own.motors[2].step, (PinRef{'B', 0}));  // Arduino pin 8
  EXPECT_EQ(own.motors[3].dir, (PinRef{'B', 3}));   // Arduino pin 11
}

TEST(PinProfiles, PinsAreNamedByPortAndBitOrByNumber) {
  EXPECT_EQ(ParsePinRef("pd4"), (PinRef{'D', 4}));
  EXPECT_EQ(ParsePinRef("GPIO26"), (PinRef{'B', 0, 26}));
  EXPECT_EQ(ParsePinRef("d13"), (PinRef{'B', 0, 13}));
  EXPECT_EQ(ParsePinRef("D13")->Name(), "D13");
  EXPECT_FALSE(ParsePinRef("GPIO"));
  EXPECT_FALSE(ParsePinRef("D1x"));
  EXPECT_FALSE(ParsePinRef("D1000"));
  EXPECT_FALSE(ParsePinRef("PD8"));
}

TEST(PinProfiles, BadBoardsAreRefusedNamingTheProblem) {
  auto error = [](std::string_view text) {
    const auto b = ParseBoard(text, "b.json");
    return std::holds_alternative<std::string>(b) ? std::get<std::string>(b) : std::string();
  };
  EXPECT_NE(error("").find("empty"), std::string::npos);
  EXPECT_NE(error("{").find("not valid JSON"), std::string::npos);
  EXPECT_NE(error(R"({"board":"x","motors":[{"step":"Q4","dir":"PD5"}]})").find("PD4"),
            std::string::npos);
  EXPECT_NE(error(R"({"board":"x","motors":[{"step":"GPIO256","dir":"PD5"}]})").find("GPIO26"),
            std::string::npos);
  EXPECT_NE(error(R"({"board":"x","motors":[{"step":"PD4","dir":"PD4"}]})").find("named twice"),
            std::string::npos);
  EXPECT_NE(error(R"({"board":"x","motors":[]})").find("1..16"), std::string::npos);
  EXPECT_NE(error(R"({"board":"x","motors":[{"step":"PD4","dir":"PD5"}],"spead":1})").find("spead"),
            std::string::npos);
  EXPECT_NE(error(R"({"board":"x","motors":[{"step":"PD4","step":"PD6","dir":"PD5"}]})")
                .find("field \"motors[].step\" is given twice"),
            std::string::npos);
}

TEST(PinRules, AreNotApplicableOnATargetThatWatchesNoPins) {
  auto target = InProcessTarget::ForModel("dfmoco", "");
  ASSERT_TRUE(target);
  ASSERT_FALSE(target->Open());
  RunOptions options;
  options.cases = "connect/hi";
  options.pins = A4988();  // even with a board given
  const RunReport report = FindRunner(Protocol::kDfmoco)->run(*target, options);
  size_t pin_rules = 0;
  for (const auto& [id, s] : report.rules) {
    if (id.find("-PIN-") == std::string::npos) continue;
    ++pin_rules;
    EXPECT_EQ(s.status, Status::kNotApplicable) << id;
  }
  EXPECT_EQ(pin_rules, DfmocoPinRules().size());
  EXPECT_TRUE(target->WatchPins(OneMotorBoard()).has_value());  // in-process: refused
}

}  // namespace
}  // namespace moco::conformance
