// Benchmarks of the simulation core: scheduler events per second, analytic
// step edges per second with 32 motors moving, memory of a long move.
#include <benchmark/benchmark.h>

#include <cstdint>
#include <vector>

#include "sim/scheduler.h"

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

}  // namespace
}  // namespace moco::sim
