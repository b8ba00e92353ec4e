// simavr speed with and without pin watching (issue "firmware truth at the
// pins": watching may cost at most 20 %): the own DFMoco firmware with four
// motors at 20000 steps/s, one second of firmware time per iteration.
#include <benchmark/benchmark.h>

#include "conformance/targets/four_motors_bench.h"
#include "conformance/targets/simavr_target.h"

namespace moco::conformance {
namespace {

// range(0): 1 watches the own firmware's eight STEP/DIR pins, 0 does not.
void BM_FourMotorsAt20kHz(benchmark::State& state) {
  SimavrTarget target(SimavrSpec{MOCO_DFMOCO_ELF, "", 0});
  bench::FourMotorsAt20kHz(state, target);
}
BENCHMARK(BM_FourMotorsAt20kHz)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->Iterations(4);

}  // namespace
}  // namespace moco::conformance

BENCHMARK_MAIN();
