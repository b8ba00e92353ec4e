// The native target's speed (docs/benchmarks.md "Native target": the goal is
// at least 10 simulated seconds a wall second): the DFMoco test firmware built
// for the host Arduino core stepping four motors at 20000 steps/s from its
// 40 kHz timer interrupt, one second of firmware time per iteration, its eight
// STEP/DIR pins watched (range 1) or not (range 0).
#include <benchmark/benchmark.h>

#include <string>

#include "conformance/targets/native_target.h"

namespace moco::conformance {
namespace {

constexpr TimeNs kSecond = 1'000'000'000;

void SendLine(Target& t, const std::string& line) {
  const std::string bytes = line + "\r\n";
  t.Send(wire::ByteView(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size()));
}

void RunTo(Target& t, TimeNs until) {
  wire::Bytes out;
  while (t.Now() < until) {
    out.clear();
    if (!t.Receive(until, out)) break;
  }
}

void BM_NativeFourMotorsAt20kHz(benchmark::State& state) {
  NativeTarget target(NativeSpec{MOCO_DFMOCO_NATIVE});
  if (state.range(0) != 0) {
    Board board;
    board.name = "own-dfmoco";
    for (const char* pins : {"D4D5", "D6D7", "B0B1", "B2B3"}) {
      board.motors.push_back({PinRef{pins[0], static_cast<uint8_t>(pins[1] - '0')},
                              PinRef{pins[2], static_cast<uint8_t>(pins[3] - '0')}, std::nullopt});
    }
    target.WatchPins(board);
  }
  if (auto err = target.Open()) {
    state.SkipWithError(err->c_str());
    return;
  }
  RunTo(target, kSecond / 20);
  for (int m = 1; m <= 4; ++m) SendLine(target, "pr " + std::to_string(m) + " 20000");
  // 2 s to reach 20000 steps/s, then a long cruise.
  for (int m = 1; m <= 4; ++m) SendLine(target, "mm " + std::to_string(m) + " 2000000");
  RunTo(target, 2500 * kSecond / 1000);
  TimeNs simulated = 0;
  for (auto _ : state) {
    const TimeNs t0 = target.Now();
    RunTo(target, t0 + kSecond);
    simulated += target.Now() - t0;
  }
  state.counters["firmware_s_per_s"] =
      benchmark::Counter(static_cast<double>(simulated) / kSecond, benchmark::Counter::kIsRate);
  if (const PinTrace* pins = target.Pins()) {
    state.counters["edges"] = static_cast<double>(pins->EdgeCount());
  }
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
