// Throughput of mococheck in-process (virtual time): random property
// sequences of 50 requests per second for each protocol (each sequence on a
// freshly powered device, with every stream rule checked), and fuzz
// executions per second over the golden sessions.
#include <benchmark/benchmark.h>

#include <cstdlib>
#include <string>

#include "conformance/fuzz/campaign.h"
#include "conformance/protocols/registry.h"

namespace moco::conformance {
namespace {

constexpr const char* kModels[] = {"dmc16", "dfmoco", "stackshot3x"};
constexpr const char* kSessions[] = {"dmc16-workflow.jsonl", "dfmoco-uno-workflow.jsonl",
                                     "stackshot3x-workflow.jsonl"};

std::string SessionPath(const char* name) {
  const char* root = std::getenv("MOCO_SOURCE_DIR");
  return std::string(root ? root : ".") + "/fixtures/sessions/" + name;
}

// One iteration: the random case (one sequence of 50 requests, seed = iteration).
void BM_RandomSequence50(benchmark::State& state) {
  const auto which = static_cast<size_t>(state.range(0));
  const Protocol protocol = kAllProtocols[which];
  auto target = InProcessTarget::ForModel(kModels[which], "");
  if (target->Open()) {
    state.SkipWithError("cannot open the in-process device");
    return;
  }
  RunOptions options;
  options.cases = "random/*";
  options.random.steps = 50;
  uint64_t seed = 1;
  int64_t failed = 0;
  for (auto _ : state) {
    options.random.seed = seed++;
    const RunReport r = FindRunner(protocol)->run(*target, options);
    failed += r.MustFailed();
    benchmark::DoNotOptimize(r.cases.size());
  }
  state.counters["sequences/s"] =
      benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
  state.counters["failed"] = static_cast<double>(failed);
  state.SetLabel(std::string(ProtocolName(protocol)));
}
BENCHMARK(BM_RandomSequence50)->DenseRange(0, 2)->Unit(benchmark::kMillisecond);

// One iteration: one mutant of the protocol's golden session run on a fresh device.
void BM_FuzzExec(benchmark::State& state) {
  const auto which = static_cast<size_t>(state.range(0));
  const Protocol protocol = kAllProtocols[which];
  auto seed = LoadSeed(SessionPath(kSessions[which]));
  if (!std::holds_alternative<Seed>(seed)) {
    state.SkipWithError(std::get<std::string>(seed).c_str());
    return;
  }
  const Messages original = std::get<Seed>(seed).messages;
  FuzzExecutor executor(protocol, InProcessTarget::ForModel(kModels[which], ""));
  if (executor.Open()) {
    state.SkipWithError("cannot open the in-process device");
    return;
  }
  SessionMutator mutator(protocol, 1);
  int64_t violations = 0;
  for (auto _ : state) {
    Messages m = original;
    mutator.Mutate(m, {});
    violations += !executor.Run(m).ok;
  }
  state.counters["execs/s"] =
      benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
  state.counters["violations"] = static_cast<double>(violations);
  state.SetLabel(std::string(ProtocolName(protocol)));
}
BENCHMARK(BM_FuzzExec)->DenseRange(0, 2)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace moco::conformance
