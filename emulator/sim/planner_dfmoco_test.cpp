// Tests for DFMoco's chunked step generation (FACTS.md, DFMoco "Step
// generation": 40 kHz ticks, 20 kHz cap, 50 ms velocity chunks, a direction
// change waits one chunk; "pr": accel = pulse rate / 2).
#include "sim/planner_dfmoco.h"

#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
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

// The chunk-per-segment planner as it was before chunk runs: one Segment per
// 50 ms chunk. Kept verbatim as the reference the run form must reproduce.
class ChunkPerSegmentPlanner final : public Planner {
 public:
  std::vector<Segment> Plan(const PlanRequest& req) override {
    constexpr double kChunkS = static_cast<double>(kDfmocoChunkNs) / 1e9;
    auto position_at = [](const std::vector<Segment>& segs, double x_start, double t) {
      double x = x_start;
      double t0 = 0;
      for (const Segment& s : segs) {
        if (t <= t0 + s.duration_s) {
          return x + (t - t0) * (s.v0_steps_per_s + 0.5 * s.a_steps_per_s2 * (t - t0));
        }
        x += s.duration_s * (s.v0_steps_per_s + 0.5 * s.a_steps_per_s2 * s.duration_s);
        t0 += s.duration_s;
      }
      return x;
    };
    std::vector<Segment> out;
    if (req.kind == PlanRequest::Kind::kMoveTo && req.start.v_steps_per_s == 0 &&
        static_cast<double>(req.target_steps) == req.start.x_steps) {
      return out;
    }
    const TimeNs next_boundary =
        (req.now_ns + kDfmocoChunkNs - 1) / kDfmocoChunkNs * kDfmocoChunkNs;
    const double wait_s = static_cast<double>(next_boundary - req.now_ns) / 1e9;
    const double v_now = req.start.v_steps_per_s;
    if (wait_s > 0) {
      Segment s;
      s.v0_steps_per_s = v_now;
      s.duration_s = wait_s;
      out.push_back(s);
    }
    const KinematicState at_boundary{req.start.x_steps + v_now * wait_s, v_now};
    const double vmax = std::min(req.max_velocity_steps_per_s, kDfmocoMaxStepsPerS);
    const double accel = req.max_accel_steps_per_s2;
    std::vector<Segment> profile;
    double target = at_boundary.x_steps;
    if (req.kind == PlanRequest::Kind::kStop) {
      profile = PlanDecelerateToRest(at_boundary, req.decel_steps_per_s2);
      target = position_at(profile, at_boundary.x_steps, 1e300);
      target = std::round(target);
    } else {
      target = static_cast<double>(req.target_steps);
      profile = PlanTrapezoid(at_boundary, target, vmax, accel,
                              req.decel_steps_per_s2 > 0 ? req.decel_steps_per_s2 : accel);
    }
    double total_s = 0;
    for (const Segment& s : profile) total_s += s.duration_s;
    const auto chunks = static_cast<int64_t>(std::ceil(total_s / kChunkS));
    double x = at_boundary.x_steps;
    double prev_v = v_now;
    for (int64_t j = 0; j < chunks; ++j) {
      const double t_end = static_cast<double>(j + 1) * kChunkS;
      const double x_end =
          j + 1 == chunks ? target : position_at(profile, at_boundary.x_steps, t_end);
      double v = (x_end - x) / kChunkS;
      v = std::clamp(v, -kDfmocoMaxStepsPerS, kDfmocoMaxStepsPerS);
      if (v != 0 && prev_v != 0 && (v > 0) != (prev_v > 0)) {
        Segment idle;
        idle.duration_s = kChunkS;
        out.push_back(idle);
      }
      Segment s;
      s.v0_steps_per_s = v;
      s.duration_s = kChunkS;
      out.push_back(s);
      x += v * kChunkS;
      prev_v = v;
    }
    return out;
  }
  TimeNs StepQuantumNs() const override { return kDfmocoTickNs; }
};

bool SameBits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// One command of a random DFMoco script.
struct DfCommand {
  int kind;  // 0..3 move, 4 stop, 5 hard stop, 6 jog
  int64_t target;
  int speed;
  TimeNs delay_ns;
};

void Apply(StepperMotor& m, const DfCommand& c) {
  if (c.kind <= 3) {
    m.MoveTo(c.target);
  } else if (c.kind == 4) {
    m.Stop();
  } else if (c.kind == 5) {
    m.HardStop();
  } else {
    m.Jog(c.target, c.speed);
  }
}

// Law: the chunk-run plans move the motor exactly as one Segment per chunk
// did: the same edges (time, step, direction) bit for bit, and the same
// position and velocity (bit for bit) at every query, through random moves,
// re-targets mid-chunk, reversals, stops and jogs.
RC_GTEST_PROP(DfmocoPlannerProp, ChunkRunsReproduceOneSegmentPerChunkBitForBit, ()) {
  const double pr = *rc::gen::inRange(100, 20001);
  const int n = *rc::gen::inRange(1, 7);
  std::vector<DfCommand> script;
  for (int i = 0; i < n; ++i) {
    DfCommand c;
    c.kind = *rc::gen::inRange(0, 7);
    c.target = *rc::gen::inRange<int64_t>(-30000, 30000);
    c.speed = *rc::gen::inRange(1, 10001);
    c.delay_ns = *rc::gen::inRange<TimeNs>(0, 3'000'000'000);
    script.push_back(c);
  }
  Scheduler s;
  StepperMotor runs(s, 1, std::make_unique<DfmocoPlanner>());
  StepperMotor chunks(s, 2, std::make_unique<ChunkPerSegmentPlanner>());
  StepTrace runs_trace(runs, 1 << 20);
  StepTrace chunks_trace(chunks, 1 << 20);
  runs.SetProfile(PulseRate(pr));
  chunks.SetProfile(PulseRate(pr));
  for (const DfCommand& c : script) {
    // Queries at random instants inside the delay, then the command.
    const TimeNs until = s.Now() + c.delay_ns;
    for (int q = 0; q < 4; ++q) {
      s.RunUntil(std::min(until, s.Now() + *rc::gen::inRange<TimeNs>(1, 800'000'000)));
      RC_ASSERT(runs.Position() == chunks.Position());
      RC_ASSERT(SameBits(runs.Velocity(), chunks.Velocity()));
    }
    s.RunUntil(until);
    Apply(runs, c);
    Apply(chunks, c);
    RC_ASSERT(runs.CurrentPlan().EndNs() == chunks.CurrentPlan().EndNs());
    RC_ASSERT(runs.CurrentPlan().EdgeCount() == chunks.CurrentPlan().EdgeCount());
    RC_ASSERT(runs.CurrentPlan().EndSteps() == chunks.CurrentPlan().EndSteps());
    // Random-access queries on the plans themselves.
    const Plan& a = runs.CurrentPlan();
    const Plan& b = chunks.CurrentPlan();
    for (int q = 0; q < 8; ++q) {
      const TimeNs t = a.origin_ns() +
                       *rc::gen::inRange<TimeNs>(0, std::max<TimeNs>(1, a.EndNs() - a.origin_ns()));
      RC_ASSERT(a.StepsAt(t) == b.StepsAt(t));
      const KinematicState sa = a.StateAt(t);
      const KinematicState sb = b.StateAt(t);
      RC_ASSERT(SameBits(sa.x_steps, sb.x_steps));
      RC_ASSERT(SameBits(sa.v_steps_per_s, sb.v_steps_per_s));
      const int64_t step = a.origin_steps() + *rc::gen::inRange<int64_t>(-40000, 40000);
      for (int dir : {-1, 1}) RC_ASSERT(a.TimeOfStep(step, dir, t) == b.TimeOfStep(step, dir, t));
    }
  }
  s.RunUntilIdle();
  RC_ASSERT(runs_trace.dropped() == 0u);
  RC_ASSERT(runs_trace.total() == chunks_trace.total());
  RC_ASSERT(runs_trace.Edges() == chunks_trace.Edges());
  RC_ASSERT(runs.Position() == chunks.Position());
}

// A ten-minute move holds a few runs, not one Segment per chunk: the plan's
// heap stays under 16 KiB where the chunk-per-segment plan needs ~12000 of
// them, and both give the same edge count and end.
TEST(DfmocoPlannerTest, TenMinuteMovePlanIsSmall) {
  Scheduler s;
  StepperMotor m(s, 1, std::make_unique<DfmocoPlanner>());
  StepperMotor ref(s, 2, std::make_unique<ChunkPerSegmentPlanner>());
  m.SetProfile(PulseRate(20000));
  ref.SetProfile(PulseRate(20000));
  ASSERT_EQ(m.MoveTo(20000LL * 600), MoveStatus::kOk);
  ASSERT_EQ(ref.MoveTo(20000LL * 600), MoveStatus::kOk);
  EXPECT_GT(m.CurrentPlan().EndNs(), 600 * kNsPerSecond);
  EXPECT_LT(m.CurrentPlan().HeapBytes(), 16u * 1024);
  EXPECT_GT(ref.CurrentPlan().segments().size(), 12000u);
  EXPECT_LE(m.CurrentPlan().segments().size(), 4u);
  EXPECT_EQ(m.CurrentPlan().EdgeCount(), ref.CurrentPlan().EdgeCount());
  EXPECT_EQ(m.CurrentPlan().EndNs(), ref.CurrentPlan().EndNs());
  s.RunUntil(300 * kNsPerSecond);
  EXPECT_EQ(m.Position(), ref.Position());
  s.RunUntilIdle();
  EXPECT_EQ(m.Position(), 20000LL * 600);
}

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
