// Go-motion maths and its chunked execution (dfmoco-protocol.txt "Go-Motion
// (Blur)": exposure from p1 - (p1 - p0) * b to p1 + (p2 - p1) * b, half the
// exposure on each half, a 1 s ramp before and after).
#include "devices/dfmoco_arduino/go_motion.h"

#include <cmath>
#include <memory>

#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>

#include "sim/stepper_motor.h"

namespace moco::devices {
namespace {

TEST(PlanBlur, HalfBlurOfEvenFrames) {
  // p0 = 1000, p1 = 2000, p2 = 3000, blur 500 (180 deg), exposure 1 s:
  // exposure 1500 -> 2000 -> 2500, 500 steps in 0.5 s each half = 1000 steps/s;
  // the 1 s ramp covers 1000 / 2 = 500 steps on each side: 1000 -> 3000.
  const BlurMove m = PlanBlur(1000, 500, 1000, 2000, 3000);
  EXPECT_DOUBLE_EQ(m.exposure_start_steps, 1500);
  EXPECT_DOUBLE_EQ(m.exposure_end_steps, 2500);
  EXPECT_DOUBLE_EQ(m.v1_steps_per_s, 1000);
  EXPECT_DOUBLE_EQ(m.v2_steps_per_s, 1000);
  EXPECT_DOUBLE_EQ(m.start_steps, 1000);
  EXPECT_DOUBLE_EQ(m.end_steps, 3000);
  EXPECT_DOUBLE_EQ(m.DurationS(), 3.0);
  EXPECT_DOUBLE_EQ(m.PositionAt(0), 1000);
  EXPECT_DOUBLE_EQ(m.PositionAt(0.5), 1000 + 0.5 * 1000 * 0.25);
  EXPECT_DOUBLE_EQ(m.PositionAt(1.0), 1500);
  EXPECT_DOUBLE_EQ(m.PositionAt(1.5), 2000);
  EXPECT_DOUBLE_EQ(m.PositionAt(2.0), 2500);
  EXPECT_DOUBLE_EQ(m.PositionAt(3.0), 3000);
  EXPECT_DOUBLE_EQ(m.PositionAt(10.0), 3000);
}

TEST(PlanBlur, UnevenHalvesAndFullBlur) {
  // blur 1000: the exposure spans all of p0 -> p1 -> p2; 0.2 s exposure.
  const BlurMove m = PlanBlur(200, 1000, 0, 100, 400);
  EXPECT_DOUBLE_EQ(m.exposure_start_steps, 0);
  EXPECT_DOUBLE_EQ(m.exposure_end_steps, 400);
  EXPECT_DOUBLE_EQ(m.v1_steps_per_s, 1000);  // 100 steps in 0.1 s
  EXPECT_DOUBLE_EQ(m.v2_steps_per_s, 3000);  // 300 steps in 0.1 s
  EXPECT_DOUBLE_EQ(m.MaxSpeed(), 3000);
  EXPECT_DOUBLE_EQ(m.start_steps, -500);
  EXPECT_DOUBLE_EQ(m.end_steps, 1900);
}

TEST(PlanBlur, ZeroBlurHoldsStill) {
  const BlurMove m = PlanBlur(500, 0, 0, 700, 900);
  EXPECT_DOUBLE_EQ(m.start_steps, 700);
  EXPECT_DOUBLE_EQ(m.end_steps, 700);
  EXPECT_DOUBLE_EQ(m.MaxSpeed(), 0);
}

// The position is continuous across the four pieces of the move.
RC_GTEST_PROP(PlanBlur, PositionIsContinuous, ()) {
  const auto exposure = *rc::gen::inRange(1, 5000);
  const auto blur = *rc::gen::inRange(0, 1001);
  const auto p0 = *rc::gen::inRange(-100000, 100000);
  const auto p1 = *rc::gen::inRange(-100000, 100000);
  const auto p2 = *rc::gen::inRange(-100000, 100000);
  const BlurMove m = PlanBlur(exposure, blur, p0, p1, p2);
  const double e = m.exposure_s;
  for (const double t :
       {kGoMotionRampS, kGoMotionRampS + e / 2, kGoMotionRampS + e, 2 * kGoMotionRampS + e}) {
    const double tol = 1e-6 * (1 + m.MaxSpeed());
    RC_ASSERT(std::fabs(m.PositionAt(t - 1e-9) - m.PositionAt(t + 1e-9)) < tol);
  }
  RC_ASSERT(std::fabs(m.PositionAt(kGoMotionRampS + e / 2) - p1) < 1e-6);
}

// Run by a motor, the chunked move lands on the end and passes the exposure
// points within a step at chunk boundaries.
TEST(GoMotionPlanner, MotorFollowsTheMoveAtChunkBoundaries) {
  sim::Scheduler sched;
  sched.RunUntil(2 * sim::kNsPerSecond + 12'500'000);  // between chunk boundaries
  sim::StepperMotor motor(sched, 1);
  ASSERT_EQ(motor.ResetPosition(1000), sim::MoveStatus::kOk);
  const BlurMove m = PlanBlur(1000, 500, 1000, 2000, 3000);
  const sim::TimeNs start = sched.Now() + 25'000;
  motor.SetPlanner(std::make_unique<GoMotionPlanner>(m, start, 3000));
  ASSERT_EQ(motor.MoveTo(3000), sim::MoveStatus::kOk);
  for (int k = 0; k <= 60; ++k) {
    const sim::TimeNs t = start + k * sim::kDfmocoChunkNs;
    const double want = m.PositionAt(static_cast<double>(k) * 0.05);
    EXPECT_NEAR(static_cast<double>(motor.PositionAt(t)), want, 1.0) << "chunk " << k;
  }
  EXPECT_EQ(motor.CurrentPlan().EndNs(), start + 3 * sim::kNsPerSecond);
  sched.RunUntilIdle();
  EXPECT_EQ(motor.Position(), 3000);
}

TEST(GoMotionPlanner, ReversalWaitsOneChunk) {
  // 0 -> 1000 -> 0 with full blur: v1 = +2000, v2 = -2000; the direction
  // change costs one idle chunk, so the move ends 50 ms late.
  sim::Scheduler sched;
  sim::StepperMotor motor(sched, 1);
  const BlurMove m = PlanBlur(1000, 1000, 0, 1000, 0);
  ASSERT_EQ(motor.ResetPosition(std::llround(m.start_steps)), sim::MoveStatus::kOk);
  motor.SetPlanner(std::make_unique<GoMotionPlanner>(m, 0, std::llround(m.end_steps)));
  ASSERT_EQ(motor.MoveTo(std::llround(m.end_steps)), sim::MoveStatus::kOk);
  EXPECT_EQ(motor.CurrentPlan().EndNs(), 3 * sim::kNsPerSecond + sim::kDfmocoChunkNs);
  EXPECT_NEAR(static_cast<double>(motor.PositionAt(1500 * sim::kNsPerMs)), 1000, 1.0);
  sched.RunUntilIdle();
  EXPECT_EQ(motor.Position(), std::llround(m.end_steps));
}

TEST(GoMotionPlanner, SpeedCapCatchesUpAfterTheMove) {
  // 40000 steps/s asked for 0.1 s: the 20 kHz cap holds the motor back, and it
  // still ends on the target.
  sim::Scheduler sched;
  sim::StepperMotor motor(sched, 1);
  const BlurMove m = PlanBlur(100, 1000, 0, 2000, 4000);
  ASSERT_GT(m.MaxSpeed(), sim::kDfmocoMaxStepsPerS);
  ASSERT_EQ(motor.ResetPosition(std::llround(m.start_steps)), sim::MoveStatus::kOk);
  const int64_t end = std::llround(m.end_steps);
  motor.SetPlanner(std::make_unique<GoMotionPlanner>(m, 0, end));
  ASSERT_EQ(motor.MoveTo(end), sim::MoveStatus::kOk);
  for (const sim::Segment& s : motor.CurrentPlan().segments()) {
    EXPECT_LE(std::fabs(s.v0_steps_per_s), sim::kDfmocoMaxStepsPerS);
  }
  sched.RunUntilIdle();
  EXPECT_EQ(motor.Position(), end);
}

}  // namespace
}  // namespace moco::devices
