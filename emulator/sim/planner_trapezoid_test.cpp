// Laws of the DMC-16 trapezoid planner (dmc-v2-protocol.txt MSG_MOTOR_MOVE,
// MSG_MOTOR_SET_SPEED): from any state it arrives at rest on the target,
// with continuous velocity, within the speed and acceleration limits.
#include "sim/planner_trapezoid.h"

#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>

#include <algorithm>
#include <cmath>

namespace moco::sim {
namespace {

TEST(TrapezoidPlannerTest, ShapesFromRest) {
  // Long move: accel, cruise, decel. Short: triangle (no cruise).
  const auto trap = PlanTrapezoid({0, 0}, 5000, 1000, 500, 500);
  ASSERT_EQ(trap.size(), 3u);
  EXPECT_DOUBLE_EQ(trap[0].duration_s, 2);
  EXPECT_DOUBLE_EQ(trap[1].duration_s, 3);
  EXPECT_DOUBLE_EQ(trap[2].duration_s, 2);
  const auto tri = PlanTrapezoid({0, 0}, 1000, 1000, 500, 500);
  ASSERT_EQ(tri.size(), 2u);
  EXPECT_NEAR(tri[0].EndVelocity(), std::sqrt(500.0 * 1000), 1e-9);
}

TEST(TrapezoidPlannerTest, MovingAwayStopsFirstThenReverses) {
  const auto segs = PlanTrapezoid({0, 800}, -100, 1000, 400, 400);
  ASSERT_GE(segs.size(), 2u);
  EXPECT_DOUBLE_EQ(segs[0].v0_steps_per_s, 800);
  EXPECT_DOUBLE_EQ(segs[0].a_steps_per_s2, -400);
  EXPECT_DOUBLE_EQ(segs[0].duration_s, 2);  // to rest at 800 steps past the start
  EXPECT_DOUBLE_EQ(segs[0].EndPosition(), 800);
}

TEST(TrapezoidPlannerTest, AlreadyThereAtRestIsEmpty) {
  EXPECT_TRUE(PlanTrapezoid({3, 0}, 3, 1000, 500, 500).empty());
}

RC_GTEST_PROP(TrapezoidPlannerProp, ArrivesAtRestOnTargetWithinLimits, ()) {
  const double vmax = *rc::gen::inRange(1, 30000);
  const double acc = *rc::gen::inRange(1, 100000);
  const double dec = acc * (*rc::gen::inRange(1, 5));
  const double x0 = *rc::gen::inRange(-50, 51) / 100.0;
  const double v0 = *rc::gen::inRange(-40000, 40001) / 1.0;
  const auto target = static_cast<double>(*rc::gen::inRange<int64_t>(-100000, 100001));
  const auto segs = PlanTrapezoid({x0, v0}, target, vmax, acc, dec);
  double x = x0;
  double v = v0;
  const double a_limit = std::max(acc, dec) * (1 + 1e-12);
  const double v_limit = std::max(vmax, std::abs(v0)) * (1 + 1e-12);
  for (const Segment& s : segs) {
    RC_ASSERT(s.duration_s > 0);
    RC_ASSERT(std::abs(s.v0_steps_per_s - v) <= 1e-9 * std::max(1.0, std::abs(v)));
    RC_ASSERT(std::abs(s.x0_steps - x) <= 1e-6 * std::max(1.0, std::abs(x)));
    RC_ASSERT(std::abs(s.a_steps_per_s2) <= a_limit);
    RC_ASSERT(std::abs(s.EndVelocity()) <= v_limit);
    x = s.EndPosition();
    v = s.EndVelocity();
  }
  RC_ASSERT(std::abs(v) <= 1e-6 * std::max(1.0, std::abs(v0) + vmax));
  RC_ASSERT(std::abs(x - target) < 1e-3);
}

}  // namespace
}  // namespace moco::sim
