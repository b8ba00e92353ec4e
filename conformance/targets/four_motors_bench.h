// The benchmark both firmware targets share (simavr_bench, native_bench): the own
// DFMoco firmware cruising four motors at 20000 steps/s (its step interrupt every
// 25 us, 160k pin edges per firmware second), one second of firmware time per
// iteration, its eight STEP/DIR pins watched (range(0) == 1) or not.
#ifndef MOCO_CONFORMANCE_TARGETS_FOUR_MOTORS_BENCH_H_
#define MOCO_CONFORMANCE_TARGETS_FOUR_MOTORS_BENCH_H_

#include <benchmark/benchmark.h>

#include <string>

#include "conformance/targets/target.h"

namespace moco::conformance::bench {

inline constexpr TimeNs kSecond = 1'000'000'000;

inline void SendLine(Target& t, const std::string& line) {
  const std::string bytes = line + "\r\n";
  t.Send(wire::ByteView(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size()));
}

inline void RunTo(Target& t, TimeNs until) {
  wire::Bytes out;
  while (t.Now() < until) {
    out.clear();
    if (!t.Receive(until, out)) break;
  }
}

// fixtures/boards/own-dfmoco.json: motors on PD4/PD5, PD6/PD7, PB0/PB1, PB2/PB3.
inline Board OwnDfmocoBoard() {
  Board board;
  board.name = "own-dfmoco";
  for (int i = 0; i < 4; ++i) {
    const char port = i < 2 ? 'D' : 'B';
    const auto step = static_cast<uint8_t>(i < 2 ? 4 + 2 * i : 2 * (i - 2));
    board.motors.push_back(
        {PinRef{port, step}, PinRef{port, static_cast<uint8_t>(step + 1)}, std::nullopt});
  }
  return board;
}

// Opens `target` (watching the pins when range(0) is 1), brings the four
// motors to cruise and times one firmware second per iteration: the counter
// firmware_s_per_s (per wall second with UseRealTime()), and the edges kept.
inline void FourMotorsAt20kHz(benchmark::State& state, Target& target) {
  if (state.range(0) != 0) target.WatchPins(OwnDfmocoBoard());
  if (auto err = target.Open()) {
    state.SkipWithError(err->c_str());
    return;
  }
  RunTo(target, kSecond / 20);
  for (int m = 1; m <= 4; ++m) SendLine(target, "pr " + std::to_string(m) + " 20000");
  // 2 s to reach 20000 steps/s (10000 steps/s^2), then a long cruise.
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

}  // namespace moco::conformance::bench

#endif  // MOCO_CONFORMANCE_TARGETS_FOUR_MOTORS_BENCH_H_
