// Tests for DFMoco's chunked step generation (FACTS.md, DFMoco "Step
// generation": 40 kHz ticks, 20 kHz cap, 50 ms velocity chunks, a direction
// change waits one chunk; "pr": accel = pulse rate / 2).
#include "sim/planner_dfmoco.h"

#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>

#include <memory>
#include <vector>

#include "sim/planner_trapezoid.h"
#include "sim/step_trace.h"
#include "sim/stepper_motor.h"

namespace moco::sim {
namespace {

MotionProfile PulseRate(double pr) {
  MotionProfile p;
  p.max_velocity_steps_per_s = pr;
  p.max_accel_steps_per_s2 = pr / 2;
  return p;
}

struct Bench {
  Scheduler s;
  StepperMotor m{s, 1, std::make_unique<DfmocoPlanner>()};
  StepTrace trace{m, 1 << 18};
};

TEST(DfmocoPlannerTest, MoveStartsOnTheNextChunkEdgesOnTicksEndsOnTarget) {
  Bench b;
  b.m.SetProfile(PulseRate(5000));  // the sketch's default pulse rate
  b.s.RunUntil(10 * kNsPerMs);
  ASSERT_EQ(b.m.MoveTo(12345), MoveStatus::kOk);
  EXPECT_TRUE(b.m.IsMoving());
  b.s.RunUntilIdle();
  EXPECT_EQ(b.m.Position(), 12345);
  EXPECT_EQ(b.s.Now() % kDfmocoChunkNs, 0);  // ends on a chunk boundary
  const auto edges = b.trace.Edges();
  ASSERT_EQ(edges.size(), 12345u);
  EXPECT_GT(edges.front().time_ns, 50 * kNsPerMs);  // nothing before the boundary
  for (size_t i = 0; i < edges.size(); ++i) {
    EXPECT_EQ(edges[i].time_ns % kDfmocoTickNs, 0) << i;
    EXPECT_EQ(edges[i].step, static_cast<int64_t>(i) + 1);
    if (i > 0) {
      ASSERT_GE(edges[i].time_ns - edges[i - 1].time_ns, 2 * kDfmocoTickNs) << i;
    }
  }
}

TEST(DfmocoPlannerTest, ChunkEndsFollowTheTrapezoidProfile) {
  Bench b;
  b.m.SetProfile(PulseRate(4000));  // a = 2000
  b.m.MoveTo(20000);
  // From rest at t = 0 (a chunk boundary): x(t) = 1000 t^2 while accelerating
  // (2 s to 4000 steps/s); the position at each chunk end follows it.
  for (int j = 1; j <= 40; ++j) {
    const double t = j * 0.05;
    b.s.RunUntil(j * kDfmocoChunkNs);
    EXPECT_NEAR(static_cast<double>(b.m.Position()), 1000 * t * t, 1.0) << j;
  }
  b.s.RunUntilIdle();
  EXPECT_EQ(b.m.Position(), 20000);
}

TEST(DfmocoPlannerTest, VelocityIsCappedAt20kHz) {
  Bench b;
  b.m.SetProfile(PulseRate(30000));
  b.m.MoveTo(100000);
  b.s.RunUntilIdle();
  const auto edges = b.trace.Edges();
  for (size_t i = 1; i < edges.size(); ++i) {
    ASSERT_GE(edges[i].time_ns - edges[i - 1].time_ns, 50'000) << i;
  }
  EXPECT_EQ(b.m.Position(), 100000);
}

TEST(DfmocoPlannerTest, DirectionChangeWaitsOneChunk) {
  Bench b;
  b.m.SetProfile(PulseRate(20000));  // a = 10000: 500 steps/s per chunk
  b.m.MoveTo(3000);
  b.s.RunUntil(510 * kNsPerMs);  // decelerating
  ASSERT_EQ(b.m.MoveTo(-100), MoveStatus::kOk);
  // In the plan, two stepping chunks of opposite directions are never
  // adjacent: an idle chunk (direction pins only) sits between them.
  const auto& segs = b.m.CurrentPlan().segments();
  bool reversed = false;
  for (size_t i = 1; i < segs.size(); ++i) {
    const double v0 = segs[i - 1].v0_steps_per_s;
    const double v1 = segs[i].v0_steps_per_s;
    EXPECT_FALSE(v0 != 0 && v1 != 0 && (v0 > 0) != (v1 > 0)) << "chunk " << i;
    if (v0 == 0 && i >= 2 && segs[i - 2].v0_steps_per_s > 0 && v1 < 0) reversed = true;
  }
  EXPECT_TRUE(reversed);
  b.s.RunUntilIdle();
  EXPECT_EQ(b.m.Position(), -100);
  const auto edges = b.trace.Edges();
  size_t flip = 0;
  for (size_t i = 1; i < edges.size(); ++i) {
    if (edges[i].direction != edges[i - 1].direction) {
      EXPECT_EQ(flip, 0u) << "one reversal only";
      flip = i;
    }
  }
  ASSERT_GT(flip, 0u);
  EXPECT_GE(edges[flip].time_ns - edges[flip - 1].time_ns, kDfmocoChunkNs);
}

TEST(DfmocoPlannerTest, StopDeceleratesAndRestsOnAWholeStep) {
  Bench b;
  b.m.SetProfile(PulseRate(5000));
  b.m.MoveTo(1'000'000);
  b.s.RunUntil(3 * kNsPerSecond);  // cruising at 5000
  const int64_t at = b.m.Position();
  b.m.Stop();
  b.s.RunUntilIdle();
  // v^2 / 2a = 5000 steps, plus up to one chunk at full speed before it bites.
  EXPECT_NEAR(static_cast<double>(b.m.Position() - at), 5000, 260);
  EXPECT_EQ(b.trace.Edges().back().step, b.m.Position());
}

// Laws: through random re-targets, edges stay on ticks, at most 20 kHz,
// strictly ordered and one step apart; the motor ends on the last target and
// its reported position always matches the trace.
RC_GTEST_PROP(DfmocoPlannerProp, ChunkedMotionKeepsTheStepLaws, ()) {
  Bench b;
  b.m.SetProfile(PulseRate(*rc::gen::inRange(100, 20001)));
  int64_t target = 0;
  std::vector<std::pair<TimeNs, int64_t>> seen;
  const int n = *rc::gen::inRange(1, 6);
  for (int i = 0; i < n; ++i) {
    target = *rc::gen::inRange<int64_t>(-5000, 5000);
    b.m.MoveTo(target);
    b.s.RunUntil(b.s.Now() + *rc::gen::inRange<TimeNs>(0, 1'500'000'000));
    seen.push_back({b.s.Now(), b.m.Position()});
  }
  b.s.RunUntilIdle();
  RC_ASSERT(b.m.Position() == target);
  const auto edges = b.trace.Edges();
  int64_t p = 0;
  for (size_t i = 0; i < edges.size(); ++i) {
    RC_ASSERT(edges[i].time_ns % kDfmocoTickNs == 0);
    RC_ASSERT(edges[i].step == p + edges[i].direction);
    p = edges[i].step;
    if (i > 0) RC_ASSERT(edges[i].time_ns - edges[i - 1].time_ns >= 2 * kDfmocoTickNs);
  }
  for (const auto& [t, pos] : seen) {
    int64_t expect = 0;
    for (const auto& e : edges) {
      if (e.time_ns <= t) expect = e.step;
    }
    RC_ASSERT(pos == expect);
  }
}

}  // namespace
}  // namespace moco::sim
