// Benchmarks of the simulation core: scheduler events per second, analytic
// step edges per second with 32 motors moving, memory of a long move, DFMoco
// chunked-run queries, StackShot Bezier fitting.
#include <benchmark/benchmark.h>

#include <cstdint>
#include <memory>
#include <vector>

#include "sim/planner_dfmoco.h"
#include "sim/planner_stackshot.h"
#include "sim/rig.h"
#include "sim/scheduler.h"
#include "sim/step_trace.h"
#include "sim/stepper_motor.h"

namespace moco::sim {
namespace {

// Events per second with `state.range(0)` timers pending at any time: each
// event reschedules itself a pseudo-random delay ahead (a steady-state heap).
void BM_SchedulerSteadyState(benchmark::State& state) {
  Scheduler s;
  const auto pending = static_cast<size_t>(state.range(0));
  uint64_t rng = 0x9e3779b97f4a7c15ull;
  uint64_t fired = 0;
  struct Tick {
    Scheduler* s;
    uint64_t* rng;
    uint64_t* fired;
    void operator()() const {
      ++*fired;
      *rng ^= *rng << 13;
      *rng ^= *rng >> 7;
      *rng ^= *rng << 17;
      s->After(static_cast<TimeNs>(1 + (*rng % 100000)), *this);
    }
  };
  for (size_t i = 0; i < pending; ++i) s.After(static_cast<TimeNs>(i), Tick{&s, &rng, &fired});
  constexpr size_t kBatch = 10000;
  for (auto _ : state) s.RunUntilIdle(kBatch);
  state.SetItemsProcessed(static_cast<int64_t>(fired));
  state.counters["events_per_s"] =
      benchmark::Counter(static_cast<double>(fired), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_SchedulerSteadyState)->Arg(1)->Arg(64)->Arg(4096);

// Schedule-then-cancel churn (timeouts that never fire), plus one firing.
void BM_SchedulerCancelChurn(benchmark::State& state) {
  Scheduler s;
  uint64_t ops = 0;
  for (auto _ : state) {
    const auto id = s.After(1000, [] {});
    benchmark::DoNotOptimize(s.Cancel(id));
    s.After(1, [&ops] { ++ops; });
    s.RunNext();
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations()));
}
BENCHMARK(BM_SchedulerCancelChurn);

// Step edges per core-second: 32 motors each make a trapezoid move (with a
// re-target half way), every edge enumerated analytically into a bounded
// StepTrace ring per motor.
void BM_StepEdges32Motors(benchmark::State& state) {
  constexpr int kMotors = 32;
  uint64_t edges = 0;
  for (auto _ : state) {
    Scheduler s;
    Rig rig(s, kMotors, 0);
    std::vector<std::unique_ptr<StepTrace>> traces;
    for (int id = 1; id <= kMotors; ++id) {
      MotionProfile p;
      p.max_velocity_steps_per_s = 20000;
      p.max_accel_steps_per_s2 = 10000 + 500 * id;
      rig.motor(id).SetProfile(p);
      traces.push_back(std::make_unique<StepTrace>(rig.motor(id), 4096));
      rig.motor(id).MoveTo(200000 + 1000 * id);
    }
    s.RunUntil(5 * kNsPerSecond);
    for (int id = 1; id <= kMotors; ++id) rig.motor(id).MoveTo(-100000 - 1000 * id);
    s.RunUntilIdle();
    for (const auto& t : traces) edges += t->total();
  }
  state.counters["steps_per_s"] =
      benchmark::Counter(static_cast<double>(edges), benchmark::Counter::kIsRate);
  state.SetItemsProcessed(static_cast<int64_t>(edges));
}
BENCHMARK(BM_StepEdges32Motors)->Unit(benchmark::kMillisecond);

// Raw analytic enumeration of a 1,000,000-step plan's edges (no sink
// overhead) made by `planner` (null: the trapezoid).
void EnumeratePlanEdges(benchmark::State& state, std::unique_ptr<Planner> planner) {
  Scheduler s;
  StepperMotor m(s, 1, std::move(planner));
  MotionProfile p;
  p.max_velocity_steps_per_s = 20000;
  p.max_accel_steps_per_s2 = 10000;
  m.SetProfile(p);
  m.MoveTo(1'000'000);
  const Plan plan = m.CurrentPlan();
  uint64_t edges = 0;
  for (auto _ : state) {
    int64_t sum = 0;
    edges += static_cast<uint64_t>(
        plan.ForEachEdge(0, kTimeNever, [&sum](const StepEdge& e) { sum += e.time_ns; }));
    benchmark::DoNotOptimize(sum);
  }
  state.counters["steps_per_s"] =
      benchmark::Counter(static_cast<double>(edges), benchmark::Counter::kIsRate);
}

void BM_PlanForEachEdge(benchmark::State& state) { EnumeratePlanEdges(state, nullptr); }
BENCHMARK(BM_PlanForEachEdge)->Unit(benchmark::kMillisecond);

// Memory of a motor with a ten-minute move in flight: the motor object plus
// its heap (the plan's segments), reported in bytes.
void BM_MotorMemoryTenMinuteMove(benchmark::State& state) {
  size_t bytes = 0;
  size_t segments = 0;
  for (auto _ : state) {
    Scheduler s;
    StepperMotor m(s, 1);
    MotionProfile p;
    p.max_velocity_steps_per_s = 20000;
    p.max_accel_steps_per_s2 = 10000;
    m.SetProfile(p);
    m.MoveTo(20000LL * 600);  // 600 s at 20 kHz
    s.RunUntil(300 * kNsPerSecond);
    bytes = sizeof(StepperMotor) + m.HeapBytes();
    segments = m.CurrentPlan().segments().size();
    benchmark::DoNotOptimize(m.Position());
  }
  state.counters["bytes"] = static_cast<double>(bytes);
  state.counters["segments"] = static_cast<double>(segments);
}
BENCHMARK(BM_MotorMemoryTenMinuteMove);

// The same with DFMoco's 50 ms chunks: 12000 chunks held as a few chunked
// runs (Segment::chunks), so the plan's heap stays a few KiB (target: under
// 16 KiB; one Segment per chunk held ~945 KB). plan_bytes is the plan alone.
void BM_MotorMemoryTenMinuteMoveDfmoco(benchmark::State& state) {
  size_t bytes = 0;
  size_t plan_bytes = 0;
  size_t segments = 0;
  for (auto _ : state) {
    Scheduler s;
    StepperMotor m(s, 1, std::make_unique<DfmocoPlanner>());
    MotionProfile p;
    p.max_velocity_steps_per_s = 20000;
    p.max_accel_steps_per_s2 = 10000;
    m.SetProfile(p);
    m.MoveTo(20000LL * 600);
    s.RunUntil(300 * kNsPerSecond);
    bytes = sizeof(StepperMotor) + m.HeapBytes();
    plan_bytes = m.CurrentPlan().HeapBytes();
    segments = m.CurrentPlan().segments().size();
    benchmark::DoNotOptimize(m.Position());
  }
  state.counters["bytes"] = static_cast<double>(bytes);
  state.counters["plan_bytes"] = static_cast<double>(plan_bytes);
  state.counters["segments"] = static_cast<double>(segments);
}
BENCHMARK(BM_MotorMemoryTenMinuteMoveDfmoco)->Unit(benchmark::kMillisecond);

// Random-access queries on a ten-minute DFMoco plan (a run walks at most
// one mark stride of chunks): StepsAt per second.
void BM_DfmocoStepsAtTenMinuteMove(benchmark::State& state) {
  Scheduler s;
  StepperMotor m(s, 1, std::make_unique<DfmocoPlanner>());
  MotionProfile p;
  p.max_velocity_steps_per_s = 20000;
  p.max_accel_steps_per_s2 = 10000;
  m.SetProfile(p);
  m.MoveTo(20000LL * 600);
  const Plan plan = m.CurrentPlan();
  uint64_t rng = 0x9e3779b97f4a7c15ull;
  const auto span = static_cast<uint64_t>(plan.EndNs() - plan.origin_ns());
  for (auto _ : state) {
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    benchmark::DoNotOptimize(plan.StepsAt(plan.origin_ns() + static_cast<TimeNs>(rng % span)));
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations()));
}
BENCHMARK(BM_DfmocoStepsAtTenMinuteMove);

// Edge enumeration of a DFMoco plan (chunked runs walked piece by piece).
void BM_DfmocoForEachEdge(benchmark::State& state) {
  EnumeratePlanEdges(state, std::make_unique<DfmocoPlanner>());
}
BENCHMARK(BM_DfmocoForEachEdge)->Unit(benchmark::kMillisecond);

// Fitting a four-curve CC_MOTION_CONFIG spline (a 60 s keyframed move over
// 400 mm at 80 steps/mm) into constant-acceleration segments within
// kSplineToleranceSteps; reports the segment count and plan bytes.
void BM_StackshotSplineFit(benchmark::State& state) {
  MotionCurves m{};
  auto curve = [](double t0, double y0, double t3, double y3) {
    BezierCurve c;
    const double d = (t3 - t0) / 3;
    c.p = {BezierPoint{t0, y0}, BezierPoint{t0 + d, y0}, BezierPoint{t3 - d, y3},
           BezierPoint{t3, y3}};
    return c;
  };
  m[0] = curve(0, 0, 15, 120);
  m[1] = curve(15, 120, 30, 400);
  m[2] = curve(30, 400, 45, 250);
  m[3] = curve(45, 250, 60, 0);
  const SplineOrFault r = MakeSpline(m, 80, 20000);
  size_t segments = 0;
  size_t plan_bytes = 0;
  for (auto _ : state) {
    const std::vector<Segment> segs = SplineSegments(*r.spline);
    segments = segs.size();
    const Plan plan = Plan::Build(0, 0, 0, segs);
    plan_bytes = plan.HeapBytes();
    benchmark::DoNotOptimize(plan.EndSteps());
  }
  state.counters["segments"] = static_cast<double>(segments);
  state.counters["plan_bytes"] = static_cast<double>(plan_bytes);
}
BENCHMARK(BM_StackshotSplineFit)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace moco::sim
