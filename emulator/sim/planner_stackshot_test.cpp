// Tests for the StackShot 3X planners (stackshot-protocol.txt
// CC_RAIL_CONFIG_RAMP_TIME, CC_MOTION_CONFIG rules and CC_MOTION_START;
// ERRATA 3.5): ramp time honoured, limits kept, Bezier playback within the
// stated bound of the analytic curve, validation errors. Virtual time.
#include "sim/planner_stackshot.h"

#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <ostream>
#include <string>
#include <vector>

#include "sim/step_trace.h"
#include "sim/stepper_motor.h"

namespace moco::sim {
namespace {

constexpr double kNsPerSecondF = 1e9;

// The step-sequence laws of a trace (as in stepper_motor_test.cpp): edges
// strictly ordered, one step each, velocity <= vmax and acceleration <= amax
// measured from consecutive edge intervals. Empty string or the violation.
std::string CheckTraceLaws(const std::vector<StepEdge>& edges, int64_t start_steps, double vmax,
                           double amax) {
  int64_t p = start_steps;
  for (size_t i = 0; i < edges.size(); ++i) {
    const StepEdge& e = edges[i];
    if (e.step != p + e.direction) return "step skipped or doubled at " + std::to_string(i);
    p = e.step;
    if (i == 0) continue;
    const StepEdge& prev = edges[i - 1];
    if (e.time_ns <= prev.time_ns) return "edges not strictly ordered at " + std::to_string(i);
    if (e.direction != prev.direction) continue;
    const double dt = static_cast<double>(e.time_ns - prev.time_ns) / kNsPerSecondF;
    if (dt < 1 / vmax - 2e-9) return "faster than vmax at " + std::to_string(i);
    if (i < 2 || edges[i - 2].direction != e.direction) continue;
    const double dt0 = static_cast<double>(prev.time_ns - edges[i - 2].time_ns) / kNsPerSecondF;
    const double r0 = 1 / dt0;
    const double r1 = 1 / dt;
    const double slack = (r0 * r0 + r1 * r1) * 2e-9 + 1e-9;
    if (std::abs(r1 - r0) > amax * (dt0 + dt) / 2 * (1 + 1e-9) + slack) {
      return "faster than amax at " + std::to_string(i);
    }
  }
  return "";
}

struct Rail {
  explicit Rail(double vmax, double ramp_s) {
    auto planner = std::make_unique<StackshotPlanner>(ramp_s);
    planner_ = planner.get();
    motor = std::make_unique<StepperMotor>(sched, 1, std::move(planner));
    motor->SetProfile(RampProfile(vmax, ramp_s));
    trace = std::make_unique<StepTrace>(*motor, 1 << 20);
  }
  StackshotPlanner& planner() { return *planner_; }
  Scheduler sched;
  std::unique_ptr<StepperMotor> motor;
  std::unique_ptr<StepTrace> trace;

 private:
  StackshotPlanner* planner_;
};

// ------------------------------------------------------------ ramp time --

TEST(StackshotRampTest, AccelerationIsSpeedOverRampTime) {
  EXPECT_DOUBLE_EQ(RampAccel(8000, 0.4), 20000);
  EXPECT_TRUE(std::isinf(RampAccel(8000, 0)));
  const MotionProfile p = RampProfile(8000, 0.4);
  EXPECT_DOUBLE_EQ(p.max_velocity_steps_per_s, 8000);
  EXPECT_DOUBLE_EQ(p.max_accel_steps_per_s2, 20000);
  StackshotPlanner planner;
  EXPECT_FALSE(planner.SetRampTime(-1));
  EXPECT_FALSE(planner.SetRampTime(std::nan("")));
  EXPECT_TRUE(planner.SetRampTime(1.5));
  EXPECT_DOUBLE_EQ(planner.ramp_time_s(), 1.5);
}

TEST(StackshotRampTest, FromRestFullSpeedComesAfterExactlyTheRampTime) {
  Rail r(8000, 0.4);  // a = 20000 steps/s^2
  ASSERT_EQ(r.motor->MoveTo(100000), MoveStatus::kOk);
  const TimeNs ramp_ns = 400'000'000;
  r.sched.RunUntil(ramp_ns - 1);
  EXPECT_LT(r.motor->Velocity(), 8000);
  r.sched.RunUntil(ramp_ns);
  EXPECT_NEAR(r.motor->Velocity(), 8000, 1e-6);
  // x(t) = a t^2 / 2 while ramping: 1600 steps at the ramp's end, so the
  // edges up to then are those of thresholds 0.5 .. 1599.5.
  r.trace->Sync();
  const auto edges = r.trace->Edges();
  ASSERT_EQ(edges.size(), 1600u);
  for (size_t k = 0; k < edges.size(); k += 97) {
    const double t = std::sqrt(2 * (static_cast<double>(k) + 0.5) / 20000);
    EXPECT_NEAR(static_cast<double>(edges[k].time_ns), std::ceil(t * kNsPerSecondF), 1) << k;
  }
  r.sched.RunUntilIdle();
  EXPECT_EQ(r.motor->Position(), 100000);
}

// Law: whatever the speed and ramp time, a move long enough to reach full
// speed gets there at the ramp time, within one nanosecond (the step
// quantum of this planner).
RC_GTEST_PROP(StackshotRampProp, RampTimeHonoured, ()) {
  const double vmax = *rc::gen::inRange(50, 30001);
  const double ramp_s = *rc::gen::inRange(1, 5000) / 1000.0;
  Rail r(vmax, ramp_s);
  const auto far = static_cast<int64_t>(std::ceil(vmax * ramp_s)) + 100;
  r.sched.RunUntil(*rc::gen::inRange<TimeNs>(0, 1'000'000'000));
  const TimeNs t0 = r.sched.Now();
  RC_ASSERT(r.motor->MoveTo(far) == MoveStatus::kOk);
  const auto ramp_ns = static_cast<TimeNs>(std::llround(ramp_s * kNsPerSecondF));
  r.sched.RunUntil(t0 + ramp_ns - 1);
  RC_ASSERT(r.motor->Velocity() < vmax);
  r.sched.RunUntil(t0 + ramp_ns + 1);
  RC_ASSERT(std::abs(r.motor->Velocity() - vmax) <= vmax * 1e-9);
}

TEST(StackshotRampTest, NewTargetMidMoveDeceleratesAndReverses) {
  Rail r(5000, 0.5);  // a = 10000
  r.motor->MoveTo(20000);
  r.sched.RunUntil(1'500'000'000);  // cruising at 5000, about 5000 steps out
  const int64_t at = r.motor->Position();
  ASSERT_EQ(r.motor->MoveTo(-300), MoveStatus::kOk);
  r.sched.RunUntilIdle();
  EXPECT_EQ(r.motor->Position(), -300);
  const auto edges = r.trace->Edges();
  EXPECT_EQ(CheckTraceLaws(edges, 0, 5000, 10000), "");
  // Braking from 5000 at 10000 steps/s^2 overshoots by v^2 / 2a = 1250.
  int64_t peak = 0;
  for (const StepEdge& e : edges) peak = std::max(peak, e.step);
  EXPECT_NEAR(static_cast<double>(peak - at), 1250, 2);
}

TEST(StackshotRampTest, StopRampsDownInTheRampTime) {
  Rail r(4000, 0.25);
  r.motor->MoveTo(1'000'000);
  r.sched.RunUntil(kNsPerSecond);
  const TimeNs t_stop = r.sched.Now();
  r.motor->Stop();
  r.sched.RunUntilIdle();
  // From full speed the soft ramp lasts the ramp time: v^2/2a = 500 steps.
  EXPECT_NEAR(static_cast<double>(r.sched.Now() - t_stop), 250'000'000, 1);
  EXPECT_EQ(CheckTraceLaws(r.trace->Edges(), 0, 4000, 16000), "");
}

TEST(StackshotRampTest, ZeroRampTimeStepsTheVelocity) {
  Rail r(1000, 0);
  ASSERT_EQ(r.motor->MoveTo(50), MoveStatus::kOk);
  r.sched.RunUntilIdle();
  const auto edges = r.trace->Edges();
  ASSERT_EQ(edges.size(), 50u);
  for (size_t k = 0; k < edges.size(); ++k) {
    // Full speed from the first instant: edge k at (k + 1/2) ms.
    EXPECT_NEAR(static_cast<double>(edges[k].time_ns), static_cast<double>(k) * 1e6 + 5e5, 1) << k;
  }
  r.motor->MoveTo(1000);
  r.sched.RunUntil(r.sched.Now() + 100'000'000);
  const int64_t at = r.motor->Position();
  r.motor->Stop();  // no ramp: stops on the spot
  EXPECT_FALSE(r.motor->IsMoving());
  EXPECT_EQ(r.motor->Position(), at);
}

struct RampCommand {
  int kind;  // 0..2 move, 3 stop, 4 jog
  int64_t target;
  int speed;
  TimeNs delay_ns;
};

void showValue(const RampCommand& c, std::ostream& os) {
  os << "{kind " << c.kind << " target " << c.target << " speed " << c.speed << " after "
     << c.delay_ns << "}";
}

std::vector<StepEdge> RunRampScript(double vmax, double ramp_s,
                                    const std::vector<RampCommand>& script, int64_t* target,
                                    int64_t* pos) {
  Rail r(vmax, ramp_s);
  *target = 0;
  bool last_was_move = true;
  for (const RampCommand& c : script) {
    r.sched.RunUntil(r.sched.Now() + c.delay_ns);
    if (c.kind <= 2) {
      r.motor->MoveTo(c.target);
      *target = c.target;
      last_was_move = true;
    } else if (c.kind == 3) {
      r.motor->Stop();
      last_was_move = !r.motor->IsMoving() && last_was_move;
    } else {
      r.motor->Jog(c.target, c.speed);
      *target = c.target;
      last_was_move = true;
    }
  }
  r.sched.RunUntilIdle();
  *pos = r.motor->Position();
  if (!last_was_move) *target = *pos;
  RC_ASSERT(r.trace->dropped() == 0u);
  return r.trace->Edges();
}

rc::Gen<std::vector<RampCommand>> GenRampScript() {
  return rc::gen::container<std::vector<RampCommand>>(
      *rc::gen::inRange<size_t>(1, 7),
      rc::gen::build<RampCommand>(
          rc::gen::set(&RampCommand::kind, rc::gen::inRange(0, 5)),
          rc::gen::set(&RampCommand::target, rc::gen::inRange<int64_t>(-4000, 4000)),
          rc::gen::set(&RampCommand::speed, rc::gen::inRange(1, 10001)),
          rc::gen::set(&RampCommand::delay_ns, rc::gen::inRange<TimeNs>(0, 2'000'000'000))));
}

// Laws: through moves, re-targets, jogs and stops the trace keeps the step
// laws with velocity <= max speed and acceleration <= max speed / ramp time,
// and the rail ends exactly on its last target.
RC_GTEST_PROP(StackshotRampProp, RetargetsKeepLimitsAndEndOnTarget, ()) {
  const double vmax = *rc::gen::inRange(20, 20001);
  const double ramp_s = *rc::gen::inRange(10, 3000) / 1000.0;
  const auto script = *GenRampScript();
  int64_t target = 0;
  int64_t pos = 0;
  const auto edges = RunRampScript(vmax, ramp_s, script, &target, &pos);
  RC_ASSERT(CheckTraceLaws(edges, 0, vmax, vmax / ramp_s) == "");
  RC_ASSERT(pos == target);
  RC_ASSERT((edges.empty() ? 0 : edges.back().step) == pos);
}

// Law: the same commands give the same edges, bit for bit.
RC_GTEST_PROP(StackshotRampProp, Deterministic, ()) {
  const double vmax = *rc::gen::inRange(20, 20001);
  const double ramp_s = *rc::gen::inRange(0, 3000) / 1000.0;
  const auto script = *GenRampScript();
  int64_t t1 = 0, p1 = 0, t2 = 0, p2 = 0;
  RC_ASSERT(RunRampScript(vmax, ramp_s, script, &t1, &p1) ==
            RunRampScript(vmax, ramp_s, script, &t2, &p2));
}

// ------------------------------------------------------ Bezier: rules --

BezierCurve Curve(double t0, double y0, double t1, double y1, double t2, double y2, double t3,
                  double y3) {
  BezierCurve c;
  c.p = {BezierPoint{t0, y0}, BezierPoint{t1, y1}, BezierPoint{t2, y2}, BezierPoint{t3, y3}};
  return c;
}

// Two keyframed curves: 0 -> 50 mm over 0..4 s, 50 -> 20 mm over 4..10 s;
// curves 2 and 3 unused (P0.x = 0).
MotionCurves TwoCurves() {
  MotionCurves m{};
  m[0] = Curve(0, 0, 1, 0, 3, 50, 4, 50);
  m[1] = Curve(4, 50, 6, 50, 8, 20, 10, 20);
  return m;
}

constexpr double kUnitsLimit = 1000;  // units/s: loose

TEST(StackshotSplineTest, ValidCurvesPass) {
  EXPECT_EQ(ValidateMotionCurves(TwoCurves(), kUnitsLimit), std::nullopt);
  // Only curve 0 used; the unused ones may hold anything after a P0.x of 0.
  MotionCurves one{};
  one[0] = Curve(0, 5, 1, 5, 2, 8, 3, 8);
  one[2] = Curve(7, std::nan(""), -1, 0, 0, 0, 0, 0);
  EXPECT_EQ(ValidateMotionCurves(one, kUnitsLimit), std::nullopt);
}

struct RuleCase {
  const char* name;
  void (*mutate)(MotionCurves&);
  SplineFault expect;
};

TEST(StackshotSplineTest, EachRuleViolationHasItsError) {
  const RuleCase cases[] = {
      {"curve 0 must start at time 0",
       [](MotionCurves& m) { m[0].p[0].t_s = 0.5; },
       {SplineError::kFirstStartNotZero, 0}},
      {"NaN in a used curve",
       [](MotionCurves& m) { m[1].p[2].position = std::nan(""); },
       {SplineError::kNonFinite, 1}},
      {"infinite time",
       [](MotionCurves& m) { m[0].p[3].t_s = INFINITY; },
       {SplineError::kNonFinite, 0}},
      {"P0.x must match the previous P3.x",
       [](MotionCurves& m) { m[1].p[0].t_s = 4.5; },
       {SplineError::kTimeDiscontinuity, 1}},
      {"P0.y must match the previous P3.y",
       [](MotionCurves& m) { m[1].p[0].position = 49; },
       {SplineError::kPositionDiscontinuity, 1}},
      {"a curve must last",
       [](MotionCurves& m) { m[0] = Curve(0, 0, 0, 0, 0, 0, 0, 0); },
       {SplineError::kEmptyCurve, 0}},
      {"P3.x before P0.x",
       [](MotionCurves& m) { m[1].p[3].t_s = 3; },
       {SplineError::kEmptyCurve, 1}},
      {"P1.x < P0.x",
       [](MotionCurves& m) { m[0].p[1].t_s = -0.1; },
       {SplineError::kControlTimeOutOfBounds, 0}},
      {"P2.x > P3.x",
       [](MotionCurves& m) { m[1].p[2].t_s = 10.5; },
       {SplineError::kControlTimeOutOfBounds, 1}},
      {"P1.x > P3.x (time folds back)",
       [](MotionCurves& m) { m[0].p[1].t_s = 5; },
       {SplineError::kControlTimeOutOfBounds, 0}},
      {"P2.x < P0.x (curve 1 back into curve 0's time)",
       [](MotionCurves& m) { m[1].p[2].t_s = 3.9; },
       {SplineError::kControlTimeOutOfBounds, 1}},
      {"vertical tangent: infinite speed",
       [](MotionCurves& m) {
         m[0].p[1] = {0, 10};
       },
       {SplineError::kTooFast, 0}},
      {"faster than the limit",
       [](MotionCurves& m) { m[1] = Curve(4, 50, 5, 50 + 1000, 6, 50 + 2000, 7, 50 + 3000.1); },
       {SplineError::kTooFast, 1}},
  };
  for (const RuleCase& c : cases) {
    MotionCurves m = TwoCurves();
    c.mutate(m);
    const auto fault = ValidateMotionCurves(m, kUnitsLimit);
    ASSERT_TRUE(fault.has_value()) << c.name;
    EXPECT_EQ(fault->error, c.expect.error) << c.name << ": got " << SplineErrorName(fault->error);
    EXPECT_EQ(fault->curve, c.expect.curve) << c.name;
    EXPECT_FALSE(MakeSpline(m, 1, kUnitsLimit).ok()) << c.name;
  }
}

TEST(StackshotSplineTest, SpeedLimitIsInclusiveAndInSteps) {
  MotionCurves m{};
  m[0] = Curve(0, 0, 1, 100, 2, 200, 3, 300);  // 100 mm/s throughout
  EXPECT_EQ(ValidateMotionCurves(m, 100), std::nullopt);
  EXPECT_EQ(ValidateMotionCurves(m, 99.99), (SplineFault{SplineError::kTooFast, 0}));
  // 80 steps/mm: 8000 steps/s.
  EXPECT_TRUE(MakeSpline(m, 80, 8000).ok());
  EXPECT_EQ(MakeSpline(m, 80, 7999).fault, (SplineFault{SplineError::kTooFast, 0}));
  EXPECT_EQ(MakeSpline(m, 0, 8000).fault.error, SplineError::kBadScale);
  EXPECT_EQ(MakeSpline(m, std::nan(""), 8000).fault.error, SplineError::kBadScale);
  // An ease handle on the time axis alone (P1 = P0) is not a vertical
  // tangent: the curve leaves at the slope of P0 -> P2.
  m[0] = Curve(0, 0, 0, 0, 2, 200, 3, 300);
  EXPECT_EQ(ValidateMotionCurves(m, 100), std::nullopt);
}

TEST(StackshotSplineTest, SplineIsAnchoredOnAWholeStepAndRoundsItsEnd) {
  MotionCurves m{};
  m[0] = Curve(0, 10.01, 1, 10.01, 2, 12.5, 3, 12.5);
  const SplineOrFault r = MakeSpline(m, 80, 10000);  // 800.8 -> 1000 steps
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r.spline->StartStep(), 801);
  // Shifted by +0.2 like the start: 1000.2 -> 1000.
  EXPECT_EQ(r.spline->FinalStep(), 1000);
  EXPECT_DOUBLE_EQ(r.spline->PositionAt(0), 801);
  EXPECT_NEAR(r.spline->PositionAt(3), 1000.2, 1e-9);
  EXPECT_DOUBLE_EQ(r.spline->DurationS(), 3);
}

// ---------------------------------------------------- Bezier: playback --

TEST(StackshotSplineTest, LinearCurvePlaysAtConstantSpeedWithExactEdges) {
  MotionCurves m{};
  m[0] = Curve(0, 0, 10.0 / 3, 100.0 / 3, 20.0 / 3, 200.0 / 3, 10, 100);  // 10 mm/s
  const SplineOrFault r = MakeSpline(m, 80, 1000);
  ASSERT_TRUE(r.ok());
  Rail rail(2000, 0.5);
  ASSERT_EQ(PlaySpline(*rail.motor, rail.planner(), *r.spline), MoveStatus::kOk);
  rail.sched.RunUntilIdle();
  EXPECT_EQ(rail.motor->Position(), 8000);
  EXPECT_EQ(rail.sched.Now(), 10 * kNsPerSecond);
  const auto edges = rail.trace->Edges();
  ASSERT_EQ(edges.size(), 8000u);
  for (size_t k = 0; k < edges.size(); k += 123) {
    // 800 steps/s: edge k when x = k + 1/2.
    const double t = (static_cast<double>(k) + 0.5) / 800;
    EXPECT_NEAR(static_cast<double>(edges[k].time_ns), t * kNsPerSecondF, 2) << k;
  }
}

TEST(StackshotSplineTest, EaseInOutStartsAndEndsAtRestPeakingAtOneAndAHalfTimesAverage) {
  // Time handles at thirds and position handles flat: y = D (3u^2 - 2u^3)
  // with t = T u, so v peaks at 1.5 D / T in the middle.
  MotionCurves m{};
  m[0] = Curve(0, 0, 2, 0, 4, 60, 6, 60);
  const SplineOrFault r = MakeSpline(m, 100, 10000);  // 6000 steps in 6 s
  ASSERT_TRUE(r.ok());
  const auto segs = SplineSegments(*r.spline);
  ASSERT_FALSE(segs.empty());
  EXPECT_NEAR(segs.front().v0_steps_per_s, 0, 1e-9);
  EXPECT_NEAR(segs.back().EndVelocity(), 0, 1e-9);
  double peak = 0;
  for (const Segment& s : segs)
    peak = std::max({peak, std::abs(s.v0_steps_per_s), std::abs(s.EndVelocity())});
  EXPECT_NEAR(peak, 1.5 * 6000 / 6, 0.01 * 1500);
}

// A random curve set that keeps the rules by construction: keyframe times
// increasing, control times inside each curve's span (sometimes on its
// ends: ease handles), positions anywhere within +-range.
MotionCurves GenValidCurves(double range) {
  MotionCurves m{};
  const int used = *rc::gen::inRange(1, 5);
  double t = 0;
  double y = *rc::gen::inRange(-1000, 1001) / 10.0;
  for (int c = 0; c < used; ++c) {
    const double dur = *rc::gen::inRange(50, 400) / 100.0;
    const double t3 = t + dur;
    auto inside = [&](int mode) {
      if (mode == 0) return t;
      if (mode == 1) return t3;
      return t + dur * *rc::gen::inRange(1, 1000) / 1000.0;
    };
    const int m1 = *rc::gen::inRange(0, 4);  // 0: on P0.x (ease), else inside
    const int m2 = *rc::gen::inRange(1, 5);  // 1: on P3.x (ease), else inside
    const double y3 = *rc::gen::inRange(-1000, 1001) / 1000.0 * range;
    const double y1 = m1 == 0 ? y : *rc::gen::inRange(-1000, 1001) / 1000.0 * range;
    const double y2 = m2 == 1 ? y3 : *rc::gen::inRange(-1000, 1001) / 1000.0 * range;
    m[static_cast<size_t>(c)] =
        Curve(t, y, inside(m1 == 0 ? 0 : 2), y1, inside(m2 == 1 ? 1 : 2), y2, t3, y3);
    t = t3;
    y = y3;
  }
  return m;
}

// Law (the playback bound): for any valid spline, played on a motor from
// its start step, the continuous plan position stays within
// kSplineToleranceSteps of the analytic curve at any instant, every step
// edge happens while the curve is within that of the edge's half-way
// threshold (so well within 1/2 step), the step position stays within
// 1/2 + kSplineToleranceSteps, and the motor rests on FinalStep() at the
// spline's end time.
RC_GTEST_PROP(StackshotSplineProp, PlaybackStaysWithinTheBoundOfTheCurve, ()) {
  const double steps_per_unit = *rc::gen::element(80.0, -80.0, 12.5, 1.0, 33.3);
  const MotionCurves m = GenValidCurves(50);
  const double vmax = 2e6;
  const SplineOrFault r = MakeSpline(m, steps_per_unit, vmax);
  RC_PRE(r.ok());  // the rare random curve with a vertical tangent
  const BezierSpline& spline = *r.spline;

  Rail rail(1000, 0.5);
  rail.motor->ResetPosition(spline.StartStep());
  const TimeNs t0 = *rc::gen::inRange<TimeNs>(0, 1000);
  rail.sched.RunUntil(t0);
  RC_ASSERT(PlaySpline(*rail.motor, rail.planner(), spline) == MoveStatus::kOk);
  const Plan plan = rail.motor->CurrentPlan();
  auto curve_at = [&](TimeNs t) {
    return spline.PositionAt(static_cast<double>(t - t0) / kNsPerSecondF);
  };
  // Random instants: continuous position and step position.
  for (int q = 0; q < 200; ++q) {
    const TimeNs t = t0 + *rc::gen::inRange<TimeNs>(0, plan.EndNs() - t0 + 1);
    const double y = curve_at(t);
    const double x = static_cast<double>(plan.origin_steps()) + plan.StateAt(t).x_steps;
    RC_ASSERT(std::abs(x - y) <= kSplineToleranceSteps + 1e-6);
    RC_ASSERT(std::abs(static_cast<double>(plan.StepsAt(t)) - y) <=
              0.5 + kSplineToleranceSteps + 1e-6);
  }
  rail.sched.RunUntilIdle();
  RC_ASSERT(rail.motor->Position() == spline.FinalStep());
  const double end_ns = static_cast<double>(t0) + spline.DurationS() * kNsPerSecondF;
  // The end is rounded up to the ns from the laid-out durations' sum.
  RC_ASSERT(std::abs(static_cast<double>(rail.sched.Now()) - end_ns) < 2.0);
  const auto edges = rail.trace->Edges();
  RC_ASSERT(rail.trace->dropped() == 0u);
  int64_t p = spline.StartStep();
  for (size_t i = 0; i < edges.size(); ++i) {
    const StepEdge& e = edges[i];
    RC_ASSERT(e.step == p + e.direction);
    // Strictly ordered, except that a curve touching a half-way threshold
    // exactly and turning back gives its two edges at the same instant.
    if (i > 0 && e.direction == edges[i - 1].direction) {
      RC_ASSERT(e.time_ns > edges[i - 1].time_ns);
    }
    if (i > 0) RC_ASSERT(e.time_ns >= edges[i - 1].time_ns);
    const double threshold = static_cast<double>(p) + 0.5 * e.direction;
    // Edge times are rounded up by < 1 ns, during which the curve moves
    // at most vmax * 1e-9 steps.
    RC_ASSERT(std::abs(curve_at(e.time_ns) - threshold) <= kSplineToleranceSteps + vmax * 1e-9);
    p = e.step;
  }
}

// Law: the same spline gives the same segments and edges, bit for bit.
RC_GTEST_PROP(StackshotSplineProp, Deterministic, ()) {
  const MotionCurves m = GenValidCurves(50);
  const SplineOrFault r = MakeSpline(m, 80, 2e6);
  RC_PRE(r.ok());
  const auto a = SplineSegments(*r.spline);
  const auto b = SplineSegments(*r.spline);
  RC_ASSERT(a.size() == b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    RC_ASSERT(a[i].duration_s == b[i].duration_s);
    RC_ASSERT(a[i].v0_steps_per_s == b[i].v0_steps_per_s);
    RC_ASSERT(a[i].a_steps_per_s2 == b[i].a_steps_per_s2);
  }
  std::vector<StepEdge> traces[2];
  for (auto& out : traces) {
    Rail rail(1000, 0.5);
    rail.motor->ResetPosition(r.spline->StartStep());
    RC_ASSERT(PlaySpline(*rail.motor, rail.planner(), *r.spline) == MoveStatus::kOk);
    rail.sched.RunUntilIdle();
    out = rail.trace->Edges();
  }
  RC_ASSERT(traces[0] == traces[1]);
}

TEST(StackshotSplineTest, PlaySplineRefusesUnlessAtRestOnTheStart) {
  MotionCurves m{};
  m[0] = Curve(0, 1, 1, 1, 2, 3, 3, 3);
  const SplineOrFault r = MakeSpline(m, 100, 10000);  // 100 -> 300 steps
  ASSERT_TRUE(r.ok());
  Rail rail(2000, 0.2);
  EXPECT_EQ(PlaySpline(*rail.motor, rail.planner(), *r.spline), MoveStatus::kBadArgument);
  rail.motor->MoveTo(100);
  EXPECT_EQ(PlaySpline(*rail.motor, rail.planner(), *r.spline), MoveStatus::kMoving);
  rail.sched.RunUntilIdle();
  // A soft limit below the final step refuses, and leaves nothing armed:
  // the next move is a plain ramp move.
  SoftLimits limits;
  limits.upper_enabled = true;
  limits.upper_steps = 250;
  rail.motor->SetSoftLimits(limits);
  EXPECT_EQ(PlaySpline(*rail.motor, rail.planner(), *r.spline), MoveStatus::kSoftLimitUpper);
  EXPECT_FALSE(rail.planner().armed());
  rail.motor->SetSoftLimits({});
  ASSERT_EQ(PlaySpline(*rail.motor, rail.planner(), *r.spline), MoveStatus::kOk);
  rail.sched.RunUntilIdle();
  EXPECT_EQ(rail.motor->Position(), 300);
  // Afterwards the rail moves by ramp time again.
  ASSERT_EQ(rail.motor->MoveTo(0), MoveStatus::kOk);
  rail.sched.RunUntilIdle();
  EXPECT_EQ(rail.motor->Position(), 0);
}

TEST(StackshotSplineTest, StopDuringPlaybackRampsDown) {
  MotionCurves m{};
  m[0] = Curve(0, 0, 10.0 / 3, 100.0 / 3, 20.0 / 3, 200.0 / 3, 10, 100);
  const SplineOrFault r = MakeSpline(m, 80, 1000);  // 800 steps/s
  ASSERT_TRUE(r.ok());
  Rail rail(2000, 0.5);  // stop decel 4000 steps/s^2
  ASSERT_EQ(PlaySpline(*rail.motor, rail.planner(), *r.spline), MoveStatus::kOk);
  rail.sched.RunUntil(5 * kNsPerSecond);
  rail.motor->Stop();
  rail.sched.RunUntilIdle();
  // 4000 steps at the stop, then 800^2 / (2 * 4000) = 80 steps of ramp.
  EXPECT_NEAR(static_cast<double>(rail.motor->Position()), 4080, 1);
  EXPECT_NEAR(static_cast<double>(rail.sched.Now()), 5.2e9, 1);
}

}  // namespace
}  // namespace moco::sim
