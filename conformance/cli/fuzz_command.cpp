// `mococheck fuzz`: recorded host traffic mutated and run against fresh
// in-process devices, each mutant checked against the device invariants.
#include <unistd.h>

#include <cstdio>
#include <iostream>
#include <memory>

#include "cli_numbers.h"
#include "conformance/cli/commands.h"
#include "conformance/fuzz/campaign.h"

namespace moco::conformance::cli {
namespace {

struct FuzzArgs {
  std::vector<std::string> sessions;
  std::string target, profile, crashes = "mococheck-fuzz";
  uint64_t seed = 1, runs = 0;
  double seconds = 10;
  size_t max_failures = 5;
};

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
  request.in_process_only_message =
      "fuzz runs in-process devices only (each mutant needs a fresh device in virtual "
      "time); give --target in-process:MODEL, and use replay for a real device";
  auto resolved = ResolveTarget(request);
  if (const auto* err = std::get_if<std::string>(&resolved)) return Fail(*err);
  const std::string model = std::get<ResolvedTarget>(resolved).spec.address;
  FuzzExecutor executor(proto, InProcessTarget::ForModel(
                                   model, a.profile, std::get<ResolvedTarget>(resolved).speaking));
  if (auto err = executor.Open()) return Fail(*err);
  FuzzOptions options;
  options.seed = a.seed;
  options.runs = a.runs;
  options.seconds = a.seconds;
  options.crash_dir = a.crashes;
  options.device = model;
  options.max_failures = a.max_failures;
  const bool tty = isatty(STDERR_FILENO) != 0;
  const FuzzReport r = RunFuzz(executor, proto, seeds, options, [&](const FuzzReport& so_far) {
    char line[160];
    std::snprintf(line, sizeof line, "fuzz: %llu execs, %.0f/s, %zu failure(s)",
                  static_cast<unsigned long long>(so_far.execs), so_far.ExecsPerSecond(),
                  so_far.failures.size());
    std::cerr << line << (tty ? "\r" : "\n") << std::flush;
  });
  if (tty) std::cerr << "\n";
  char summary[200];
  std::snprintf(summary, sizeof summary,
                "mococheck fuzz: %s, %zu seed session(s), seed %llu: %llu execs in %.1f s (%.0f "
                "execs/s, %llu host messages)\n",
                model.c_str(), seeds.size(), static_cast<unsigned long long>(a.seed),
                static_cast<unsigned long long>(r.execs), r.wall_s, r.ExecsPerSecond(),
                static_cast<unsigned long long>(r.messages));
  std::cout << summary;
  for (const FuzzFailure& f : r.failures) {
    std::cout << "FAIL " << f.violation << "\n  mutations:";
    for (const std::string& m : f.mutations) std::cout << " " << m;
    std::cout << "\n  shrunk to " << f.messages.size() << " host message(s)";
    if (!f.saved_path.empty()) std::cout << "; saved: " << f.saved_path;
    std::cout << "\n";
  }
  std::cout << (r.failures.empty()
                    ? "result: no invariant broken\n"
                    : "result: " + std::to_string(r.failures.size()) + " invariant failure(s)\n");
  return r.failures.empty() ? 0 : 1;
}

}  // namespace

Runner AddFuzzCommand(CLI::App& app, CLI::App*& sub) {
  using moco::cli::AddNumber;
  auto a = std::make_shared<FuzzArgs>();
  CLI::App* fuzz = app.add_subcommand(
      "fuzz", "Mutate recorded host traffic and check device invariants (in-process targets)");
  sub = fuzz;
  fuzz->add_option("sessions", a->sessions, "Session files to mutate (same protocol)")->required();
  fuzz->add_option("--target", a->target, "in-process:MODEL (default: the first session's device)");
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
  return [a] { return Fuzz(*a); };
}

}  // namespace moco::conformance::cli
