// Tests for the step model and the stepper motor (ARCHITECTURE "Motion";
// dmc-v2-protocol.txt MSG_MOTOR_MOVE / STOP / JOG / CONFIGURE / SET_LIMITS).
// All in virtual time.
#include "sim/stepper_motor.h"

#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>

#include <cmath>
#include <cstdint>
#include <ostream>
#include <string>
#include <vector>

#include "sim/planner_trapezoid.h"
#include "sim/step_trace.h"

namespace moco::sim {
namespace {

constexpr double kNsPerSecondF = 1e9;

struct Recorder : MotorObserver {
  struct Finished {
    int motor;
    TimeNs time;
    int64_t steps;
  };
  struct Tripped {
    int motor;
    LimitEnd end;
    TimeNs time;
    int64_t steps;
  };
  std::vector<Finished> finished;
  std::vector<Tripped> tripped;
  std::vector<TimeNs> started;
  void OnMotionStarted(int, TimeNs time_ns) override { started.push_back(time_ns); }
  void OnMotionFinished(int motor_id, TimeNs time_ns, int64_t steps) override {
    finished.push_back({motor_id, time_ns, steps});
  }
  void OnLimitTripped(int motor_id, LimitEnd end, TimeNs time_ns, int64_t steps) override {
    tripped.push_back({motor_id, end, time_ns, steps});
  }
};

MotionProfile Profile(double v, double a, double hard = 4) {
  MotionProfile p;
  p.max_velocity_steps_per_s = v;
  p.max_accel_steps_per_s2 = a;
  p.hard_stop_multiple = hard;
  return p;
}

// The step-sequence laws every trace obeys, whatever the commands. Returns
// an empty string or the first violation.
std::string CheckTraceLaws(const std::vector<StepEdge>& edges, int64_t start_steps, double vmax,
                           double amax) {
  int64_t p = start_steps;
  for (size_t i = 0; i < edges.size(); ++i) {
    const StepEdge& e = edges[i];
    if (e.direction != 1 && e.direction != -1) return "bad direction at " + std::to_string(i);
    if (e.step != p + e.direction) return "step skipped or doubled at " + std::to_string(i);
    p = e.step;
    if (i == 0) continue;
    const StepEdge& prev = edges[i - 1];
    if (e.time_ns <= prev.time_ns) return "edges not strictly ordered at " + std::to_string(i);
    if (e.direction != prev.direction) continue;
    // Velocity: at most vmax between two same-direction edges (each edge time
    // is rounded up by < 1 ns).
    const double dt = static_cast<double>(e.time_ns - prev.time_ns) / kNsPerSecondF;
    if (dt < 1 / vmax - 2e-9) return "faster than vmax at " + std::to_string(i);
    if (i < 2 || edges[i - 2].direction != e.direction) continue;
    // Acceleration: 1/dt is the mean velocity over an interval, i.e. the
    // velocity at its midpoint for constant acceleration; between two
    // midpoints it changes by at most amax times their distance, plus the
    // rounding of the edge times.
    const double dt0 = static_cast<double>(prev.time_ns - edges[i - 2].time_ns) / kNsPerSecondF;
    const double r0 = 1 / dt0;
    const double r1 = 1 / dt;
    const double slack = (r0 * r0 + r1 * r1) * 2e-9 + 1e-9;
    if (std::abs(r1 - r0) > amax * (dt0 + dt) / 2 * (1 + 1e-9) + slack) {
      return "faster than amax at " + std::to_string(i) + ": dr=" + std::to_string(r1 - r0) +
             " over " + std::to_string((dt0 + dt) / 2);
    }
  }
  return "";
}

class MotorTest : public ::testing::Test {
 protected:
  Scheduler sched_;
  Recorder rec_;
  StepperMotor motor_{sched_, 1, nullptr, &rec_};
  StepTrace trace_{motor_, 1 << 20};
};

TEST_F(MotorTest, TrapezoidMoveEndsExactlyOnTargetAtTheAnalyticTime) {
  ASSERT_EQ(motor_.SetProfile(Profile(1000, 500)), MoveStatus::kOk);
  ASSERT_EQ(motor_.MoveTo(5000), MoveStatus::kOk);
  EXPECT_TRUE(motor_.IsMoving());
  sched_.RunUntilIdle();
  // 2 s up to 1000 steps/s (1000 steps), 3000 steps cruise (3 s), 2 s down.
  ASSERT_EQ(rec_.finished.size(), 1u);
  EXPECT_NEAR(static_cast<double>(rec_.finished[0].time), 7e9, 1.0);
  EXPECT_EQ(rec_.finished[0].steps, 5000);
  EXPECT_EQ(motor_.Position(), 5000);
  EXPECT_FALSE(motor_.IsMoving());
  const auto edges = trace_.Edges();
  ASSERT_EQ(edges.size(), 5000u);
  EXPECT_EQ(CheckTraceLaws(edges, 0, 1000, 500), "");
  EXPECT_EQ(edges.back().step, 5000);
}

TEST_F(MotorTest, EveryNewPlanIsAnnouncedWhoeverCommandsIt) {
  ASSERT_EQ(motor_.SetProfile(Profile(1000, 500)), MoveStatus::kOk);
  EXPECT_EQ(motor_.MoveTo(0), MoveStatus::kOk);  // already there: no plan
  EXPECT_TRUE(rec_.started.empty());
  // A move commanded from a timer (as a device's own clock does).
  sched_.At(2 * kNsPerSecond, [this] { motor_.MoveTo(3000); });
  sched_.RunUntil(3 * kNsPerSecond);
  ASSERT_EQ(rec_.started.size(), 1u);
  EXPECT_EQ(rec_.started[0], 2 * kNsPerSecond);
  // A re-plan while moving (a stop ramp) is a new plan too.
  motor_.Stop();
  ASSERT_EQ(rec_.started.size(), 2u);
  EXPECT_EQ(rec_.started[1], 3 * kNsPerSecond);
  sched_.RunUntilIdle();
  EXPECT_EQ(rec_.started.size(), 2u);
  EXPECT_EQ(rec_.finished.size(), 1u);
}

TEST_F(MotorTest, TriangularMoveTakesTwiceSqrtDistanceOverAccel) {
  motor_.SetProfile(Profile(1000, 500));
  motor_.MoveTo(-1000);  // needs 2000 steps to reach 1000 steps/s: triangle
  sched_.RunUntilIdle();
  ASSERT_EQ(rec_.finished.size(), 1u);
  EXPECT_NEAR(static_cast<double>(rec_.finished[0].time), 2 * std::sqrt(1000.0 / 500) * 1e9, 2.0);
  EXPECT_EQ(motor_.Position(), -1000);
  const auto edges = trace_.Edges();
  ASSERT_EQ(edges.size(), 1000u);
  EXPECT_EQ(edges.front().direction, -1);
  EXPECT_EQ(CheckTraceLaws(edges, 0, 1000, 500), "");
}

TEST_F(MotorTest, EdgeTimesAreTheRootsOfTheSegmentEquation) {
  // From rest at a = 400: x(t) = 200 t^2; edge k (to step k+1) at x = k + 1/2,
  // t_k = sqrt((k + 1/2) / 200), rounded up to the nanosecond.
  motor_.SetProfile(Profile(100000, 400));
  motor_.MoveTo(100);
  sched_.RunUntilIdle();
  const auto edges = trace_.Edges();
  ASSERT_EQ(edges.size(), 100u);
  for (int k = 0; k < 10; ++k) {
    const double t = std::sqrt((k + 0.5) / 200.0) * 1e9;
    EXPECT_NEAR(static_cast<double>(edges[k].time_ns), std::ceil(t), 1.0) << k;
    EXPECT_EQ(edges[k].step, k + 1);
  }
}

TEST_F(MotorTest, PositionAtAnyTimeCountsTheEdgesUpToThatTime) {
  motor_.SetProfile(Profile(3000, 7000));
  motor_.MoveTo(777);
  const Plan plan = motor_.CurrentPlan();
  std::vector<StepEdge> edges;
  plan.ForEachEdge(0, kTimeNever, [&](const StepEdge& e) { edges.push_back(e); });
  ASSERT_EQ(edges.size(), 777u);
  for (const StepEdge& e : edges) {
    EXPECT_EQ(plan.StepsAt(e.time_ns), e.step);
    EXPECT_EQ(plan.StepsAt(e.time_ns - 1), e.step - 1);
  }
}

TEST_F(MotorTest, OnlyPlanEndsAreScheduledNotSteps) {
  motor_.SetProfile(Profile(20000, 20000));
  motor_.MoveTo(10'000'000);  // ~500 s move
  EXPECT_LE(sched_.PendingCount(), 1u);
  const size_t ran = sched_.RunUntilIdle();
  EXPECT_EQ(ran, 1u);
  EXPECT_EQ(motor_.Position(), 10'000'000);
  EXPECT_EQ(trace_.total(), 10'000'000u);
}

TEST_F(MotorTest, RetargetReversesWithoutSkippingOrDoubleCounting) {
  motor_.SetProfile(Profile(2000, 1000));
  motor_.MoveTo(3000);
  sched_.RunUntil(2'500'000'000);
  const int64_t mid = motor_.Position();
  EXPECT_GT(mid, 1000);
  EXPECT_GT(motor_.Velocity(), 0);
  ASSERT_EQ(motor_.MoveTo(-500), MoveStatus::kOk);
  sched_.RunUntilIdle();
  EXPECT_EQ(motor_.Position(), -500);
  const auto edges = trace_.Edges();
  EXPECT_EQ(CheckTraceLaws(edges, 0, 2000, 1000), "");
  int64_t ups = 0;
  int64_t downs = 0;
  for (const auto& e : edges) (e.direction > 0 ? ups : downs) += 1;
  EXPECT_EQ(ups - downs, -500);
  EXPECT_GT(ups, mid);  // it kept going up while decelerating
  ASSERT_EQ(rec_.finished.size(), 1u);
}

TEST_F(MotorTest, StopDeceleratesAtMaxAccelAndHardStopFaster) {
  auto stop_distance = [](bool hard) {
    Scheduler s;
    StepperMotor m(s, 1);
    m.SetProfile(Profile(4000, 2000, 4));
    m.MoveTo(1'000'000);
    s.RunUntil(3'000'000'000);  // cruising at 4000 steps/s
    EXPECT_DOUBLE_EQ(m.Velocity(), 4000);
    const int64_t at = m.Position();
    const TimeNs t0 = s.Now();
    hard ? m.HardStop() : m.Stop();
    s.RunUntilIdle();
    return std::make_pair(m.Position() - at, s.Now() - t0);
  };
  const auto [soft_d, soft_t] = stop_distance(false);
  const auto [hard_d, hard_t] = stop_distance(true);
  // v^2 / 2a = 4000 steps in 2 s; hard: a x 4 -> 1000 steps in 0.5 s.
  EXPECT_NEAR(static_cast<double>(soft_d), 4000, 1);
  EXPECT_NEAR(static_cast<double>(soft_t), 2e9, 2);
  EXPECT_NEAR(static_cast<double>(hard_d), 1000, 1);
  EXPECT_NEAR(static_cast<double>(hard_t), 0.5e9, 2);
}

TEST_F(MotorTest, HardStopTraceRespectsTheHardDeceleration) {
  motor_.SetProfile(Profile(4000, 2000, 4));
  motor_.MoveTo(100000);
  sched_.RunUntil(2'500'000'000);
  motor_.HardStop();
  sched_.RunUntilIdle();
  EXPECT_EQ(CheckTraceLaws(trace_.Edges(), 0, 4000, 8000), "");
  EXPECT_NE(CheckTraceLaws(trace_.Edges(), 0, 4000, 2000), "");  // it did exceed the soft rate
}

TEST_F(MotorTest, EmergencyHaltStopsOnTheCurrentStep) {
  motor_.SetProfile(Profile(4000, 2000));
  motor_.MoveTo(100000);
  sched_.RunUntil(1'000'000'000);
  const int64_t at = motor_.Position();
  motor_.EmergencyHalt();
  EXPECT_FALSE(motor_.IsMoving());
  EXPECT_EQ(motor_.Position(), at);
  sched_.RunUntil(5'000'000'000);
  EXPECT_EQ(motor_.Position(), at);
  trace_.Sync();
  EXPECT_EQ(trace_.Edges().back().step, at);
  ASSERT_EQ(rec_.finished.size(), 1u);
  EXPECT_EQ(rec_.finished[0].steps, at);
  EXPECT_EQ(rec_.finished[0].time, 1'000'000'000);
}

TEST_F(MotorTest, DisabledMotorRefusesAndDisablingHalts) {
  motor_.SetEnabled(false);
  EXPECT_EQ(motor_.MoveTo(10), MoveStatus::kDisabled);
  EXPECT_EQ(motor_.Jog(10, 100), MoveStatus::kDisabled);
  EXPECT_FALSE(motor_.IsMoving());
  motor_.SetEnabled(true);
  ASSERT_EQ(motor_.MoveTo(100000), MoveStatus::kOk);
  sched_.RunUntil(500'000'000);
  motor_.SetEnabled(false);
  EXPECT_FALSE(motor_.IsMoving());
}

TEST_F(MotorTest, BlurFlagIsStored) {
  EXPECT_FALSE(motor_.blur());
  motor_.SetBlur(true);
  EXPECT_TRUE(motor_.blur());
}

TEST_F(MotorTest, ResetPositionOnlyAtRest) {
  motor_.MoveTo(1000);
  EXPECT_EQ(motor_.ResetPosition(5), MoveStatus::kMoving);
  sched_.RunUntilIdle();
  EXPECT_EQ(motor_.ResetPosition(-42), MoveStatus::kOk);
  EXPECT_EQ(motor_.Position(), -42);
  motor_.MoveTo(-40);
  sched_.RunUntilIdle();
  EXPECT_EQ(motor_.Position(), -40);
  const auto edges = trace_.Edges();
  ASSERT_EQ(edges.size(), 1002u);
  EXPECT_EQ(edges[1000].step, -41);  // counting resumed from the new position
}

TEST_F(MotorTest, MoveToCurrentPositionDoesNotMove) {
  EXPECT_EQ(motor_.MoveTo(0), MoveStatus::kOk);
  EXPECT_FALSE(motor_.IsMoving());
  EXPECT_EQ(sched_.PendingCount(), 0u);
  EXPECT_TRUE(rec_.finished.empty());
}

TEST(JogSpeed, OneToTenThousandIsOnePercentToAllOfTheJogSpeed) {
  // dmc-v2-protocol.txt MSG_MOTOR_JOG: "A value in between 1 and 10,000
  // should provide an appropriate speed between 1% and 100% of the jog speed."
  EXPECT_DOUBLE_EQ(JogSpeedFraction(1), 0.01);
  EXPECT_DOUBLE_EQ(JogSpeedFraction(10000), 1.0);
  EXPECT_NEAR(JogSpeedFraction(5000), 0.01 + 0.99 * 4999.0 / 9999.0, 1e-15);
  for (int s = kJogSpeedMin; s < kJogSpeedMax; ++s) {
    ASSERT_LT(JogSpeedFraction(s), JogSpeedFraction(s + 1)) << s;
  }
}

TEST_F(MotorTest, JogRunsAtItsShareOfTheMaximaAndBrakesAtTheFullDeceleration) {
  motor_.SetProfile(Profile(1000, 500));
  EXPECT_EQ(motor_.Jog(10, 0), MoveStatus::kBadArgument);
  EXPECT_EQ(motor_.Jog(10, 10001), MoveStatus::kBadArgument);
  ASSERT_EQ(motor_.Jog(5000, 10000), MoveStatus::kOk);
  sched_.RunUntilIdle();
  EXPECT_NEAR(static_cast<double>(sched_.Now()), 7e9, 1);  // same as MoveTo
  // Speed 5000: f = 0.01 + 0.99 * 4999 / 9999 of v = 1000 and a = 500. Up to
  // v f at a f takes 2 s (v f steps); braking at the full 500 takes v f / 500 s
  // ((v f)^2 / 1000 steps); the rest of the 5000 steps is cruise.
  const double vf = 1000 * JogSpeedFraction(5000);
  const double up_steps = vf;  // (v f)^2 / (2 a f) with a f = v f / 2
  const double brake_steps = vf * vf / 1000;
  const double want_s = 2 + (5000 - up_steps - brake_steps) / vf + vf / 500;
  const TimeNs t0 = sched_.Now();
  ASSERT_EQ(motor_.Jog(0, 5000), MoveStatus::kOk);
  sched_.RunUntilIdle();
  EXPECT_NEAR(static_cast<double>(sched_.Now() - t0), want_s * 1e9, 1e3);
  EXPECT_EQ(motor_.Position(), 0);
  // Speed 1 (inching): 1% of the maxima, 10 step/s and 5 step/s^2. One step
  // never reaches 10 step/s: the step's edge comes at half a step, after
  // sqrt(2 * 0.5 / 5) = 0.447 s of the ramp.
  ASSERT_EQ(motor_.Jog(1, 1), MoveStatus::kOk);
  const TimeNs t1 = sched_.Now();
  sched_.RunUntil(t1 + 440'000'000);
  EXPECT_EQ(motor_.Position(), 0);
  sched_.RunUntil(t1 + 455'000'000);
  EXPECT_EQ(motor_.Position(), 1);
  sched_.RunUntilIdle();
  EXPECT_EQ(motor_.Position(), 1);
}

TEST_F(MotorTest, SoftLimitsRefuseMovesBeyondAndStopJogsAtTheLimit) {
  motor_.SetSoftLimits({true, -100, true, 200});
  EXPECT_EQ(motor_.MoveTo(201), MoveStatus::kSoftLimitUpper);
  EXPECT_EQ(motor_.MoveTo(-101), MoveStatus::kSoftLimitLower);
  EXPECT_FALSE(motor_.IsMoving());
  EXPECT_EQ(motor_.MoveTo(200), MoveStatus::kOk);
  sched_.RunUntilIdle();
  EXPECT_EQ(motor_.Position(), 200);
  EXPECT_EQ(motor_.Jog(100000, 10000), MoveStatus::kSoftLimitUpper);  // already there
  EXPECT_EQ(motor_.Jog(-100000, 10000), MoveStatus::kOk);
  sched_.RunUntilIdle();
  EXPECT_EQ(motor_.Position(), -100);
  motor_.SetSoftLimits({false, -100, false, 200});
  EXPECT_EQ(motor_.MoveTo(-101), MoveStatus::kOk);
}

// dmc-v2-protocol.txt ERR_SOFT_UP / ERR_SOFT_LOW; FACTS "DMC v2": dmc-lite's
// soft limits act only on RUN_MOVE pre/post-roll and the stop deceleration.
TEST_F(MotorTest, SoftLimitsThatDoNotBoundMovesLetMovesAndJogsPassThem) {
  motor_.SetSoftLimits({true, -100, true, 200});
  motor_.SetSoftLimitsBoundMoves(false);
  EXPECT_EQ(motor_.MoveTo(250), MoveStatus::kOk);
  sched_.RunUntilIdle();
  EXPECT_EQ(motor_.Position(), 250);
  EXPECT_EQ(motor_.Jog(-300, 10000), MoveStatus::kOk);
  sched_.RunUntilIdle();
  EXPECT_EQ(motor_.Position(), -300) << "the jog is not clamped at the lower limit";
  motor_.SetSoftLimitsBoundMoves(true);
  EXPECT_EQ(motor_.MoveTo(250), MoveStatus::kSoftLimitUpper);
}

// A stop never coasts past a soft limit the motor is still inside of: it
// brakes harder, to rest on the limit (either setting of SetSoftLimitsBoundMoves).
TEST_F(MotorTest, StopIsBoundedByTheSoftLimitItWouldPass) {
  for (const bool bound : {true, false}) {
    Scheduler s;
    StepperMotor m(s, 1);
    m.SetProfile(Profile(4000, 2000));
    m.SetSoftLimitsBoundMoves(bound);
    m.MoveTo(100000);
    s.RunUntil(3'000'000'000);  // cruising at 4000 steps/s at 8000 steps
    ASSERT_EQ(m.Position(), 8000);
    // The ramp at 2000 steps/s^2 needs 4000 steps; the limit is 1000 ahead.
    m.SetSoftLimits({false, 0, true, 9000});
    m.Stop();
    s.RunUntilIdle();
    EXPECT_EQ(m.Position(), 9000) << "bound=" << bound;
    // Outside the limit's reach the ordinary ramp runs.
    m.SetSoftLimits({false, 0, true, 1'000'000});
    m.MoveTo(100000);
    s.RunUntil(s.Now() + 3'000'000'000);
    const int64_t at = m.Position();
    m.Stop();
    s.RunUntilIdle();
    EXPECT_NEAR(static_cast<double>(m.Position() - at), 4000, 1);
  }
}

// Capability 0x0100 "Couple motors": a follower makes its leader's step
// edges at the very same times, mirrored when reversed.
// A controller that samples its plans on a tick (dmc-lite's 20 ms) starts a
// move at its next tick: the motor counts as moving from the command, stands
// until the tick, then moves exactly as MoveTo() would have from there.
TEST_F(MotorTest, MoveToAtStartsTheMoveAtItsTickAndCountsAsMovingBefore) {
  ASSERT_EQ(motor_.SetProfile(Profile(1000, 500)), MoveStatus::kOk);
  sched_.RunUntil(7'000'000);
  ASSERT_EQ(motor_.MoveToAt(20'000'000, 5000), MoveStatus::kOk);
  EXPECT_TRUE(motor_.IsMoving());
  EXPECT_TRUE(motor_.CommandPending());
  EXPECT_TRUE(rec_.started.empty());
  sched_.RunUntil(19'999'999);
  EXPECT_EQ(motor_.Position(), 0);
  EXPECT_EQ(motor_.Velocity(), 0);
  sched_.RunUntilIdle();
  ASSERT_EQ(rec_.started.size(), 1u);
  EXPECT_EQ(rec_.started[0], 20'000'000);
  ASSERT_EQ(rec_.finished.size(), 1u);
  // The 7 s trapezoid of TrapezoidMoveEndsExactlyOnTargetAtTheAnalyticTime, from 20 ms.
  EXPECT_NEAR(static_cast<double>(rec_.finished[0].time), 7.02e9, 1.0);
  EXPECT_EQ(motor_.Position(), 5000);
  EXPECT_FALSE(motor_.CommandPending());
  EXPECT_EQ(CheckTraceLaws(trace_.Edges(), 0, 1000, 500), "");
}

// The move is checked on arrival, as MoveTo() checks it.
TEST_F(MotorTest, MoveToAtIsRefusedOnArrivalAsMoveToIs) {
  motor_.SetInhibited(true);
  EXPECT_EQ(motor_.MoveToAt(20'000'000, 100), MoveStatus::kEStop);
  EXPECT_FALSE(motor_.IsMoving());
  EXPECT_FALSE(motor_.CommandPending());
}

// A stop on the tick brakes from the motion at the tick; a moving motor runs
// its plan until then.
TEST_F(MotorTest, StopAtBrakesFromTheMotionAtItsTick) {
  ASSERT_EQ(motor_.SetProfile(Profile(2000, 4000)), MoveStatus::kOk);
  ASSERT_EQ(motor_.MoveTo(100'000), MoveStatus::kOk);
  sched_.RunUntil(605'000'000);  // at 2000 steps/s since 0.5 s: 500 + 210 steps
  motor_.StopAt(620'000'000);
  sched_.RunUntil(619'000'000);
  EXPECT_NEAR(motor_.Velocity(), 2000, 1e-6);  // still cruising
  sched_.RunUntilIdle();
  // From 740 steps at 620 ms: 2000^2 / (2 * 4000) = 500 steps more.
  EXPECT_EQ(motor_.Position(), 1240);
  ASSERT_EQ(rec_.finished.size(), 1u);
  EXPECT_NEAR(static_cast<double>(rec_.finished[0].time), 1.12e9, 1e3);
}

// stop_within_s: the deceleration rises to |v| / stop_within_s where that is
// harder than the max acceleration (dmc-lite's STOP_ALL stops within 1 s).
TEST_F(MotorTest, AStopWithinABoundBrakesAtSpeedPerThatBound) {
  ASSERT_EQ(motor_.SetProfile(Profile(2000, 1000)), MoveStatus::kOk);
  ASSERT_EQ(motor_.MoveTo(100'000), MoveStatus::kOk);
  sched_.RunUntil(3'000'000'000);  // 2000 steps up to speed in 2 s, then 2000 cruising
  ASSERT_EQ(motor_.Position(), 4000);
  motor_.Stop(1.0);
  sched_.RunUntilIdle();
  // At 2000 steps/s^2 (not 1000): 1000 steps in 1 s, not 2000 in 2 s.
  EXPECT_EQ(motor_.Position(), 5000);
  EXPECT_NEAR(static_cast<double>(sched_.Now()), 4e9, 1e3);
  // A bound looser than the max acceleration changes nothing: 2000 steps in 2 s.
  ASSERT_EQ(motor_.MoveTo(20'000), MoveStatus::kOk);
  sched_.RunUntil(sched_.Now() + 4'000'000'000);
  ASSERT_EQ(motor_.Position(), 5000 + 2000 + 4000);
  motor_.Stop(10.0);
  sched_.RunUntilIdle();
  EXPECT_EQ(motor_.Position(), 13'000);
  EXPECT_NEAR(static_cast<double>(sched_.Now()), 10e9, 1e3);
}

// A stop on the tick for a move that has not started yet leaves the motor
// where it stood; a later command replaces a waiting one; an immediate
// command drops it.
TEST_F(MotorTest, TickCommandsReplaceEachOtherAndImmediateOnesDropThem) {
  ASSERT_EQ(motor_.SetProfile(Profile(1000, 500)), MoveStatus::kOk);
  ASSERT_EQ(motor_.MoveToAt(20'000'000, 5000), MoveStatus::kOk);
  motor_.StopAt(20'000'000);
  sched_.RunUntilIdle();
  EXPECT_EQ(motor_.Position(), 0);
  EXPECT_FALSE(motor_.IsMoving());
  ASSERT_EQ(rec_.finished.size(), 1u);
  EXPECT_EQ(rec_.finished[0].time, 20'000'000);
  EXPECT_TRUE(rec_.started.empty());

  ASSERT_EQ(motor_.MoveToAt(40'000'000, 5000), MoveStatus::kOk);
  ASSERT_EQ(motor_.MoveToAt(40'000'000, 300), MoveStatus::kOk);
  sched_.RunUntilIdle();
  EXPECT_EQ(motor_.Position(), 300);

  ASSERT_EQ(motor_.MoveToAt(sched_.Now() + 20'000'000, 5000), MoveStatus::kOk);
  motor_.EmergencyHalt();
  EXPECT_FALSE(motor_.IsMoving());
  EXPECT_FALSE(motor_.CommandPending());
  sched_.RunUntilIdle();
  EXPECT_EQ(motor_.Position(), 300);
}

// A plan that ends before the tick of a waiting command leaves the motor
// moving (for its owner) until the command starts.
TEST_F(MotorTest, APlanEndingBeforeAWaitingCommandsTickKeepsTheMotorMoving) {
  ASSERT_EQ(motor_.SetProfile(Profile(1000, 500)), MoveStatus::kOk);
  ASSERT_EQ(motor_.MoveTo(1), MoveStatus::kOk);
  const TimeNs end = motor_.CurrentPlan().EndNs();
  ASSERT_EQ(motor_.MoveToAt(end + 10'000'000, 0), MoveStatus::kOk);
  sched_.RunUntil(end + 5'000'000);
  EXPECT_EQ(motor_.Position(), 1);
  EXPECT_TRUE(motor_.IsMoving());
  EXPECT_TRUE(rec_.finished.empty());
  sched_.RunUntilIdle();
  EXPECT_EQ(motor_.Position(), 0);
  ASSERT_EQ(rec_.finished.size(), 1u);
}

TEST(MotorFollow, AFollowerMakesTheLeadersEdgesAtTheSameTimesMirroredWhenReversed) {
  for (const int sign : {1, -1}) {
    Scheduler s;
    StepperMotor leader(s, 1);
    StepperMotor follower(s, 2);
    StepTrace lt(leader, 1 << 16);
    StepTrace ft(follower, 1 << 16);
    ASSERT_EQ(follower.ResetPosition(500), MoveStatus::kOk);
    follower.SetFollowing(true);
    EXPECT_EQ(follower.MoveTo(10), MoveStatus::kCoupled);
    EXPECT_EQ(follower.Jog(10, 100), MoveStatus::kCoupled);
    leader.SetProfile(Profile(3000, 7000));
    ASSERT_EQ(leader.MoveTo(4321), MoveStatus::kOk);
    follower.Follow(leader.CurrentPlan(), sign);
    s.RunUntil(700'000'000);
    // Retarget mid-move (reversing), then stop: each new plan is followed.
    ASSERT_EQ(leader.MoveTo(-250), MoveStatus::kOk);
    follower.Follow(leader.CurrentPlan(), sign);
    s.RunUntil(1'500'000'000);
    follower.Stop();  // a follower's own stop does nothing
    leader.Stop();
    follower.Follow(leader.CurrentPlan(), sign);
    s.RunUntilIdle();
    lt.Sync();
    ft.Sync();
    const auto le = lt.Edges();
    const auto fe = ft.Edges();
    ASSERT_EQ(le.size(), fe.size());
    ASSERT_FALSE(le.empty());
    for (size_t i = 0; i < le.size(); ++i) {
      ASSERT_EQ(fe[i].time_ns, le[i].time_ns) << i;
      ASSERT_EQ(fe[i].direction, sign * le[i].direction) << i;
      ASSERT_EQ(fe[i].step, 500 + sign * le[i].step) << i;
    }
    EXPECT_FALSE(follower.IsMoving());
  }
}

TEST(MotorFollow, AnEmptyLeaderPlanHaltsTheFollowerAndADisabledOneStays) {
  Scheduler s;
  StepperMotor leader(s, 1);
  StepperMotor follower(s, 2);
  follower.SetFollowing(true);
  leader.MoveTo(100000);
  follower.Follow(leader.CurrentPlan(), 1);
  s.RunUntil(1'000'000'000);
  EXPECT_TRUE(follower.IsMoving());
  leader.EmergencyHalt();
  follower.Follow(leader.CurrentPlan(), 1);
  EXPECT_FALSE(follower.IsMoving());
  EXPECT_EQ(follower.Position(), leader.Position());
  follower.SetEnabled(false);
  leader.MoveTo(0);
  follower.Follow(leader.CurrentPlan(), 1);
  EXPECT_FALSE(follower.IsMoving());
}

TEST_F(MotorTest, LimitSwitchTripsOnTheSwitchStepAndGuardsThatEnd) {
  motor_.SetProfile(Profile(2000, 4000));
  motor_.SetSwitchPositions({-50, 300});
  ASSERT_EQ(motor_.MoveTo(1000), MoveStatus::kOk);
  sched_.RunUntilIdle();
  ASSERT_EQ(rec_.tripped.size(), 1u);
  EXPECT_EQ(rec_.tripped[0].motor, 1);
  EXPECT_EQ(rec_.tripped[0].end, LimitEnd::kUpper);
  EXPECT_EQ(rec_.tripped[0].steps, 300);
  EXPECT_EQ(motor_.Position(), 300);
  trace_.Sync();
  EXPECT_EQ(trace_.Edges().back().time_ns, rec_.tripped[0].time);  // at the crossing edge
  EXPECT_TRUE(motor_.SwitchTripped(LimitEnd::kUpper));
  EXPECT_EQ(motor_.MoveTo(301), MoveStatus::kHardLimitUpper);
  EXPECT_EQ(motor_.Jog(5000, 10), MoveStatus::kHardLimitUpper);
  ASSERT_EQ(motor_.MoveTo(0), MoveStatus::kOk);  // away is fine
  sched_.RunUntilIdle();
  EXPECT_EQ(motor_.Position(), 0);
  EXPECT_FALSE(motor_.SwitchTripped(LimitEnd::kUpper));
  ASSERT_EQ(motor_.MoveTo(-1000), MoveStatus::kOk);
  sched_.RunUntilIdle();
  ASSERT_EQ(rec_.tripped.size(), 2u);
  EXPECT_EQ(rec_.tripped[1].end, LimitEnd::kLower);
  EXPECT_EQ(motor_.Position(), -50);
  EXPECT_EQ(motor_.MoveTo(-51), MoveStatus::kHardLimitLower);
}

TEST_F(MotorTest, ForcedSwitchHaltsMotionTowardsIt) {
  motor_.MoveTo(100000);
  sched_.RunUntil(1'000'000'000);
  motor_.SetSwitchForced(LimitEnd::kLower, true);  // the other end: no effect
  EXPECT_TRUE(motor_.IsMoving());
  const int64_t at = motor_.Position();
  motor_.SetSwitchForced(LimitEnd::kUpper, true);
  EXPECT_FALSE(motor_.IsMoving());
  ASSERT_EQ(rec_.tripped.size(), 1u);
  EXPECT_EQ(rec_.tripped[0].steps, at);
  EXPECT_EQ(motor_.MoveTo(at + 1), MoveStatus::kHardLimitUpper);
  motor_.SetSwitchForced(LimitEnd::kUpper, false);
  EXPECT_EQ(motor_.MoveTo(at + 1), MoveStatus::kOk);
}

TEST_F(MotorTest, InhibitedMotorRefusesWithEStop) {
  motor_.SetInhibited(true);
  EXPECT_EQ(motor_.MoveTo(5), MoveStatus::kEStop);
  EXPECT_EQ(motor_.Jog(5, 10), MoveStatus::kEStop);
  motor_.SetInhibited(false);
  EXPECT_EQ(motor_.MoveTo(5), MoveStatus::kOk);
}

TEST(MotorMemoryTest, TenMinuteMoveHoldsOnlyItsSegments) {
  Scheduler s;
  StepperMotor m(s, 1);
  m.SetProfile(Profile(20000, 10000));
  m.MoveTo(20000LL * 600);  // ten minutes at 20 kHz
  EXPECT_GT(m.CurrentPlan().EndNs(), 600LL * kNsPerSecond);
  EXPECT_LE(m.CurrentPlan().segments().size(), 4u);
  EXPECT_LT(m.HeapBytes(), 512u);
}

// A random command script for the property tests.
struct Command {
  int kind;  // 0 move, 1 jog, 2 stop
  int64_t target;
  int speed;
  TimeNs delay_ns;
};

void showValue(const Command& c, std::ostream& os) {
  os << "{kind " << c.kind << " target " << c.target << " speed " << c.speed << " after "
     << c.delay_ns << " ns}";
}

rc::Gen<Command> GenCommand() {
  return rc::gen::build<Command>(
      rc::gen::set(&Command::kind, rc::gen::inRange(0, 3)),
      rc::gen::set(&Command::target, rc::gen::inRange<int64_t>(-3000, 3000)),
      rc::gen::set(&Command::speed, rc::gen::inRange(1, 10001)),
      rc::gen::set(&Command::delay_ns, rc::gen::inRange<TimeNs>(0, 2'000'000'000)));
}

std::vector<StepEdge> RunScript(double vmax, double amax, const std::vector<Command>& script,
                                int64_t* final_target, int64_t* final_pos) {
  Scheduler s;
  StepperMotor m(s, 1);
  StepTrace trace(m, 1 << 17);
  m.SetProfile(Profile(vmax, amax));
  *final_target = 0;
  bool last_was_move = true;
  for (const Command& c : script) {
    s.RunUntil(s.Now() + c.delay_ns);
    if (c.kind == 0) {
      m.MoveTo(c.target);
      *final_target = c.target;
      last_was_move = true;
    } else if (c.kind == 1) {
      m.Jog(c.target, c.speed);
      *final_target = c.target;
      last_was_move = true;
    } else {
      m.Stop();
      last_was_move = !m.IsMoving() && last_was_move;
    }
  }
  s.RunUntilIdle();
  *final_pos = m.Position();
  if (!last_was_move) *final_target = *final_pos;
  RC_ASSERT(trace.dropped() == 0u);
  return trace.Edges();
}

// Laws: whatever the targets, speeds and interruptions, edges are strictly
// ordered, every edge moves exactly one step from the previous position,
// velocity and acceleration stay within the limits, and the motor ends
// exactly on the last target.
RC_GTEST_PROP(MotorProp, RetargetingKeepsTheStepLaws, ()) {
  const double vmax = *rc::gen::inRange(20, 20001);
  const double amax = *rc::gen::inRange(20, 50001);
  const auto script =
      *rc::gen::container<std::vector<Command>>(*rc::gen::inRange<size_t>(1, 8), GenCommand());
  int64_t target = 0;
  int64_t pos = 0;
  const auto edges = RunScript(vmax, amax, script, &target, &pos);
  const std::string violation = CheckTraceLaws(edges, 0, vmax, amax);
  RC_ASSERT(violation == "");
  RC_ASSERT(pos == target);
  const int64_t net = edges.empty() ? 0 : edges.back().step;
  RC_ASSERT(net == pos);
}

// Law: the same inputs give the same trace, bit for bit.
RC_GTEST_PROP(MotorProp, SameInputsSameTrace, ()) {
  const double vmax = *rc::gen::inRange(20, 20001);
  const double amax = *rc::gen::inRange(20, 50001);
  const auto script =
      *rc::gen::container<std::vector<Command>>(*rc::gen::inRange<size_t>(1, 6), GenCommand());
  int64_t t1 = 0, p1 = 0, t2 = 0, p2 = 0;
  RC_ASSERT(RunScript(vmax, amax, script, &t1, &p1) == RunScript(vmax, amax, script, &t2, &p2));
}

// Law: the position the motor reports at any instant equals the count of
// trace edges up to that instant, across re-plans.
RC_GTEST_PROP(MotorProp, PositionMatchesTraceAtEveryQuery, ()) {
  const double vmax = *rc::gen::inRange(20, 20001);
  const double amax = *rc::gen::inRange(20, 50001);
  Scheduler s;
  StepperMotor m(s, 1);
  StepTrace trace(m, 1 << 17);
  m.SetProfile(Profile(vmax, amax));
  std::vector<std::pair<TimeNs, int64_t>> seen;
  for (int i = 0; i < 6; ++i) {
    m.MoveTo(*rc::gen::inRange<int64_t>(-2000, 2000));
    for (int q = 0; q < 5; ++q) {
      s.RunUntil(s.Now() + *rc::gen::inRange<TimeNs>(1, 300'000'000));
      seen.push_back({s.Now(), m.Position()});
    }
  }
  s.RunUntilIdle();
  const auto edges = trace.Edges();
  for (const auto& [t, p] : seen) {
    int64_t expect = 0;
    for (const auto& e : edges) {
      if (e.time_ns <= t) expect = e.step;
    }
    RC_ASSERT(p == expect);
  }
}

}  // namespace
}  // namespace moco::sim
