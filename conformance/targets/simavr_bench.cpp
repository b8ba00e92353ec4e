// simavr speed with and without pin watching (issue "firmware truth at the
// pins": watching may cost at most 20 %): the own DFMoco firmware with four
// motors at 20000 steps/s, one second of firmware time per iteration.
#include <benchmark/benchmark.h>

#include <string>

#include "conformance/targets/simavr_target.h"

namespace moco::conformance {
namespace {

constexpr TimeNs kSecond = 1'000'000'000;

void Send(Target& t, const std::string& line) {
  const std::string bytes = line + "\r\n";
  t.Send(wire::ByteView(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size()));
}

void RunUntil(Target& t, TimeNs until) {
  wire::Bytes out;
  while (t.Now() < until) {
    out.clear();
    if (!t.Receive(until, out)) break;
  }
}

// range(0): 1 watches the own firmware's eight STEP/DIR pins, 0 does not.
void BM_FourMotorsAt20kHz(benchmark::State& state) {
  SimavrTarget target(SimavrSpec{MOCO_DFMOCO_ELF, "", 0});
  if (state.range(0) != 0) {
    Board board;
    board.name = "own-dfmoco";
    for (int i = 0; i < 4; ++i) {
      const char port = i < 2 ? 'D' : 'B';
      const auto step = static_cast<uint8_t>(i < 2 ? 4 + 2 * i : 2 * (i - 2));
      board.motors.push_back(
          {PinRef{port, step}, PinRef{port, static_cast<uint8_t>(step + 1)}, std::nullopt});
    }
    target.WatchPins(board);
  }
  if (auto err = target.Open()) {
    state.SkipWithError(err->c_str());
    return;
  }
  RunUntil(target, kSecond / 20);
  for (int m = 1; m <= 4; ++m) Send(target, "pr " + std::to_string(m) + " 20000");
  // 2 s to reach 20000 steps/s (10000 steps/s^2), then a long cruise.
  for (int m = 1; m <= 4; ++m) Send(target, "mm " + std::to_string(m) + " 2000000");
  RunUntil(target, 2500 * kSecond / 1000);
  TimeNs simulated = 0;
  for (auto _ : state) {
    const TimeNs t0 = target.Now();
    RunUntil(target, t0 + kSecond);
    simulated += target.Now() - t0;
  }
  state.counters["firmware_s_per_s"] =
      benchmark::Counter(static_cast<double>(simulated) / kSecond, benchmark::Counter::kIsRate);
  if (const PinTrace* pins = target.Pins()) {
    state.counters["edges"] = static_cast<double>(pins->EdgeCount());
  }
}
BENCHMARK(BM_FourMotorsAt20kHz)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->Iterations(4);

}  // namespace
}  // namespace moco::conformance

BENCHMARK_MAIN();
