// The native target's speed (docs/benchmarks.md "Native target": the goal is
// at least 10 simulated seconds a wall second): the DFMoco test firmware built
// for the host Arduino core stepping four motors at 20000 steps/s from its
// 40 kHz timer interrupt (four_motors_bench.h), per wall second.
#include <benchmark/benchmark.h>

#include "conformance/targets/four_motors_bench.h"
#include "conformance/targets/native_target.h"

namespace moco::conformance {
namespace {

void BM_NativeFourMotorsAt20kHz(benchmark::State& state) {
  NativeTarget target(NativeSpec{MOCO_DFMOCO_NATIVE});
  bench::FourMotorsAt20kHz(state, target);
}
BENCHMARK(BM_NativeFourMotorsAt20kHz)
    ->Arg(0)
    ->Arg(1)
    ->Unit(benchmark::kMillisecond)
    ->Iterations(8)
    ->UseRealTime();

}  // namespace
}  // namespace moco::conformance

BENCHMARK_MAIN();
