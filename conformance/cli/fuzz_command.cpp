// `mococheck fuzz`: recorded host traffic mutated and run against fresh
// in-process devices or firmware under simavr, each mutant checked against the
// device invariants; firmware is booted once, each mutant runs in a process
// forked from the booted state, and its code coverage guides the corpus.
#include <unistd.h>

#include <cstdio>
#include <cstring>
#include <iostream>
#include <memory>

#include "cli_numbers.h"
#include "conformance/cli/commands.h"
#include "conformance/cli/run_setup.h"
#include "conformance/fuzz/campaign.h"

namespace moco::conformance::cli {
namespace {

// The coverage map of a firmware run: 64 KiB, as AFL's (few collisions below
// some ten thousand edges; an AVR firmware of 32 KiB of flash has fewer).
constexpr size_t kCoverageBytes = size_t{64} << 10;
// Snapshots of the firmware after a session's first messages kept at once
// (FuzzExecutor::Options::snapshots): a campaign mutates one prefix at a time
// in batches, so a few suffice; each is a process.
constexpr size_t kSnapshots = 8;

struct FuzzArgs {
  std::vector<std::string> sessions;
  std::string target, profile, crashes = "mococheck-fuzz", board_path, driver;
  uint64_t seed = 1, runs = 0;
  double seconds = 10;
  size_t max_failures = 5;
  uint32_t pause_percent = SessionMutator::kDefaultPausePercent;
};

// --board and --driver into the executor's options; an error message or nullopt.
std::optional<std::string> LoadFuzzPins(const FuzzArgs& a, bool firmware,
                                        FuzzExecutor::Options& options) {
  if (a.board_path.empty() && !a.driver.empty()) {
    return "--driver needs --board: give the board profile naming the watched pins, e.g. "
           "--board fixtures/boards/own-dfmoco.json";
  }
  if (a.board_path.empty()) return std::nullopt;
  if (!firmware) {
    return "--board watches the pins of firmware; give --target simavr:FIRMWARE.elf or "
           "native:FIRMWARE";
  }
  auto pins = LoadPinJudge(a.board_path, a.driver);
  if (const auto* err = std::get_if<std::string>(&pins)) return *err;
  options.pins = std::get<PinJudgeOptions>(pins);
  return std::nullopt;
}

int Fuzz(const FuzzArgs& a) {
  std::vector<Seed> seeds;
  for (const std::string& p : a.sessions) {
    auto s = LoadSeed(p);
    if (const auto* err = std::get_if<std::string>(&s)) return Fail(*err);
    seeds.push_back(std::move(std::get<Seed>(s)));
    if (!seeds.back().warning.empty()) {
      std::fprintf(stderr, "mococheck: %s: %s\n", p.c_str(), seeds.back().warning.c_str());
    }
    if (seeds.back().protocol != seeds.front().protocol) {
      return Fail(p + " speaks " + std::string(ProtocolName(seeds.back().protocol)) + " but " +
                  seeds.front().path + " speaks " +
                  std::string(ProtocolName(seeds.front().protocol)) +
                  "; fuzz the sessions of one protocol at a time");
    }
  }
  const Protocol proto = seeds.front().protocol;
  TargetRequest request;
  request.text = a.target;
  request.session_device = seeds.front().device;
  request.profile = a.profile;
  request.protocol = proto;
  request.traffic_name = "the sessions'";
  request.no_device_message = "the sessions name no emulated device; give --target";
  request.virtual_clock_only_message =
      "fuzz runs devices in virtual time only (each mutant needs a fresh device): give "
      "--target in-process:MODEL, simavr:FIRMWARE.elf or native:FIRMWARE, and use replay for "
      "a real device";
  auto resolved = ResolveTarget(request);
  if (const auto* err = std::get_if<std::string>(&resolved)) return Fail(*err);
  ResolvedTarget& target = std::get<ResolvedTarget>(resolved);
  // simavr firmware runs forked from snapshots with its code's coverage; a
  // native firmware is a process of its own, started afresh for each run
  // (its code is not observed: the search is blind).
  const bool simavr = target.spec.kind == TargetSpec::Kind::kSimavr;
  const bool firmware = simavr || target.spec.kind == TargetSpec::Kind::kNative;
  FuzzExecutor::Options run_options;
  run_options.fork = simavr;
  run_options.coverage_bytes = simavr ? kCoverageBytes : 0;
  run_options.snapshots = simavr ? kSnapshots : 0;
  if (auto err = LoadFuzzPins(a, firmware, run_options)) return Fail(*err);
  FuzzExecutor executor(proto, std::move(target.target), run_options);
  if (auto err = executor.Open()) return Fail(*err);
  // From here a signal ends the campaign; its summary and findings are still
  // printed (each finding's file is already complete).
  InstallStopHandlers();
  // Saved mutants name the device the sessions were recorded with; for
  // firmware, replay them with the same --target.
  const std::string model = firmware ? seeds.front().device : target.spec.address;
  FuzzOptions options;
  options.seed = a.seed;
  options.runs = a.runs;
  options.seconds = a.seconds;
  options.crash_dir = a.crashes;
  options.device = model;
  options.max_failures = a.max_failures;
  options.pause_percent = a.pause_percent;
  const bool tty = isatty(STDERR_FILENO) != 0;
  const FuzzReport r = RunFuzz(executor, proto, seeds, options, [&](const FuzzReport& so_far) {
    char line[200];
    std::snprintf(line, sizeof line, "fuzz: %llu execs, %.0f/s, %zu failure(s)",
                  static_cast<unsigned long long>(so_far.execs), so_far.ExecsPerSecond(),
                  so_far.failures.size());
    std::string text = line;
    if (so_far.coverage) {
      text +=
          ", " + std::to_string(so_far.edges) + " edges, corpus " + std::to_string(so_far.corpus);
    }
    std::cerr << text << (tty ? "\r" : "\n") << std::flush;
  });
  if (tty) std::cerr << "\n";
  char counts[160];
  std::snprintf(counts, sizeof counts,
                "%zu seed session(s), seed %llu: %llu execs in %.1f s (%.0f execs/s, %llu host "
                "messages)\n",
                seeds.size(), static_cast<unsigned long long>(a.seed),
                static_cast<unsigned long long>(r.execs), r.wall_s, r.ExecsPerSecond(),
                static_cast<unsigned long long>(r.messages));
  // The target's name may be long (a firmware's path): not in the fixed buffer.
  std::cout << "mococheck fuzz: " << (firmware ? executor.target_name() : model) << ", " << counts;
  if (firmware && r.execs > 0 && r.wall_s > 0) {
    const double simulated_s = static_cast<double>(r.simulated_ns) / 1e9;
    char line[160];
    std::snprintf(line, sizeof line,
                  "firmware time: %.1f s simulated, %.1f ms per run, %.1f times real time\n",
                  simulated_s, 1000.0 * simulated_s / static_cast<double>(r.execs),
                  simulated_s / r.wall_s);
    std::cout << line;
  }
  if (r.shrink_runs > 0) {
    std::cout << "shrinking: " << r.shrink_runs << " more runs to shrink the findings\n";
  }
  if (r.coverage) {
    std::cout << "coverage: " << r.edges << " edges of the firmware's code reached; corpus "
              << r.corpus << " session(s), " << r.corpus - seeds.size()
              << " of them mutants that reached new edges\n";
  }
  if (r.snapshot_runs > 0) {
    std::cout << "snapshots: " << r.snapshot_runs << " of the mutants ran from a snapshot "
              << "of the firmware after the messages they keep\n";
  }
  if (r.code) {
    const CodeCoverage& c = *r.code;
    auto pct = [](size_t n, size_t of) {
      char t[16];
      std::snprintf(t, sizeof t, "%.1f%%",
                    of == 0 ? 0.0 : 100.0 * static_cast<double>(n) / static_cast<double>(of));
      return std::string(t);
    };
    std::cout << "code: " << c.instructions_reached << " of " << c.instructions
              << " instructions ran (" << pct(c.instructions_reached, c.instructions) << "), "
              << c.edges_reached << " of " << c.edges << " static edges taken ("
              << pct(c.edges_reached, c.edges) << "), " << c.functions - c.never_entered.size()
              << " of " << c.functions << " functions entered\n";
    if (!c.never_entered.empty()) {
      std::cout << "never entered:";
      for (const std::string& name : c.never_entered) std::cout << " " << name;
      std::cout << "\n";
    }
  }
  for (const FuzzFailure& f : r.failures) {
    std::cout << "FAIL [" << FindingKindName(f.kind) << "] " << f.violation << "\n  mutations:";
    for (const std::string& m : f.mutations) std::cout << " " << m;
    std::cout << "\n";
    for (size_t i = 0; i < f.backtrace.size(); ++i) {
      std::cout << (i == 0 ? "  at " : "  called from ") << f.backtrace[i] << "\n";
    }
    std::cout << "  shrunk to " << f.messages.size() << " host message(s)";
    if (!f.saved_path.empty()) std::cout << "; saved: " << f.saved_path;
    std::cout << "\n";
    if (firmware && f.saved_path.rfind("not saved", 0) != 0 && !f.saved_path.empty()) {
      std::cout << "  rerun: mococheck replay " << f.saved_path << " --target " << a.target;
      if (!a.board_path.empty()) std::cout << " --board " << a.board_path;
      if (!a.driver.empty()) std::cout << " --driver " << a.driver;
      std::cout << "\n";
    }
  }
  if (r.interrupted_by != 0) {
    std::cout << "result: INTERRUPTED by signal " << r.interrupted_by << " ("
              << strsignal(r.interrupted_by) << ") after " << r.execs << " execs, "
              << r.failures.size() << " finding(s)\n";
    return r.failures.empty() ? kExitUsage : 1;
  }
  std::cout << (r.failures.empty()
                    ? "result: no invariant broken\n"
                    : "result: " + std::to_string(r.failures.size()) + " finding(s)\n");
  return r.failures.empty() ? 0 : 1;
}

}  // namespace

Runner AddFuzzCommand(CLI::App& app, CLI::App*& sub) {
  using moco::cli::AddNumber;
  auto a = std::make_shared<FuzzArgs>();
  CLI::App* fuzz = app.add_subcommand(
      "fuzz",
      "Mutate recorded host traffic and check device invariants (in-process devices, AVR "
      "firmware under simavr with coverage, or native firmware)");
  sub = fuzz;
  fuzz->add_option("sessions", a->sessions, "Session files to mutate (same protocol)")->required();
  fuzz->add_option("--target", a->target,
                   "in-process:MODEL (default: the first session's device), "
                   "simavr:FIRMWARE.elf[@MCU[:HZ]] (booted once, each mutant forked from there, "
                   "coverage-guided) or native:FIRMWARE[@PORT] (a sketch built with "
                   "mococheck-build-native, started afresh for each mutant; no coverage)");
  fuzz->add_option("--profile", a->profile, "Device profile for the in-process device")
      ->check(CLI::ExistingFile);
  AddNumber(fuzz, "--seed", a->seed, uint64_t{0}, UINT64_MAX, "Seed of the mutator");
  AddNumber(fuzz, "--runs", a->runs, uint64_t{0}, uint64_t{1000000000000},
            "Mutants to run (0: run for --seconds)");
  AddNumber(fuzz, "--seconds", a->seconds, 0.0, 86400.0, "Time budget when --runs is 0");
  fuzz->add_option("--crashes", a->crashes,
                   "Directory for failing mutants (session files that replay reruns)")
      ->capture_default_str();
  AddNumber(fuzz, "--max-failures", a->max_failures, size_t{1}, size_t{1000},
            "Stop after this many distinct failures");
  AddNumber(fuzz, "--pause-percent", a->pause_percent, uint32_t{0},
            SessionMutator::kMaxPausePercent,
            "Of every 100 mutations, how many put in a pause of the protocol's polling "
            "period between two messages (DFMoco 250 ms, 1-4 in a row), so a move runs "
            "its course; 0: none (a firmware whose idle time is slow to simulate runs "
            "more mutants without)");
  AddPinOptions(fuzz, a->board_path, a->driver);
  return [a] { return Fuzz(*a); };
}

}  // namespace moco::conformance::cli
