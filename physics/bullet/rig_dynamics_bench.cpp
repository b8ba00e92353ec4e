// Speed of the boom rig dynamics (docs/rig-dynamics.md "Cost"): 1 kHz fixed
// steps of the full rig on one core, as a real-time factor (simulated
// seconds per wall second) and steps per second.
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdlib>
#include <string>

#include "physics/bullet/rig_dynamics.h"

namespace moco::physics {
namespace {

RigProfile Profile() {
  const char* dir = std::getenv("MOCO_SOURCE_DIR");
  const std::string path = std::string(dir != nullptr ? dir : ".") + "/fixtures/rigs/boom-jib.json";
  const RigProfileResult r = ReadRigProfile(path);
  if (!r.ok()) std::abort();
  return r.value();
}

// Every joint moving on a slow sine (no stalls, no contact): the common case.
void BM_BoomRigStepMoving(benchmark::State& state) {
  BoomRigDynamics rig(Profile());
  int64_t i = 0;
  for (auto _ : state) {
    const double t = static_cast<double>(i++) * kStepS;
    const double s = std::sin(0.5 * t);
    const JointVector cmd = {1.0 + 0.5 * s, 0.5 * s, 0.3 * s, 0.8 * s, 0.2 * s, 0.1 * s};
    benchmark::DoNotOptimize(rig.Step(cmd));
  }
  state.counters["real_time_factor"] = benchmark::Counter(
      static_cast<double>(state.iterations()) * kStepS, benchmark::Counter::kIsRate);
  state.counters["steps_per_s"] =
      benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_BoomRigStepMoving);

// The head resting on the floor: the contact test finds a touching pair
// every step.
void BM_BoomRigStepInContact(benchmark::State& state) {
  BoomRigDynamics rig(Profile());
  const JointVector cmd = {0, 0, -58 * 3.14159265358979 / 180, 0, 0, 0};
  rig.Reset(cmd);
  for (auto _ : state) benchmark::DoNotOptimize(rig.Step(cmd));
  state.counters["real_time_factor"] = benchmark::Counter(
      static_cast<double>(state.iterations()) * kStepS, benchmark::Counter::kIsRate);
}
BENCHMARK(BM_BoomRigStepInContact);

}  // namespace
}  // namespace moco::physics
