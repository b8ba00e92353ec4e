// mococheck: the conformance runner for DMC v2, DFMoco and StackShot 3X
// devices (the three vendor specs; ERRATA; docs/rules.md). Drives
// Dragonframe-style traffic at a device and checks every byte against the
// rule catalogue. Exit: 0 every MUST rule passed,
// 1 a MUST rule failed, 2 usage or target error, or a run cut short by a
// signal (docs/exit-codes.md).
#include <algorithm>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <map>
#include <set>

#include <unistd.h>
#include <string>

#include <CLI/CLI.hpp>

#include "base/file_io.h"
#include "cli_numbers.h"
#include "conformance/fuzz/campaign.h"
#include "conformance/fuzz/replay.h"
#include "conformance/rules/catalogue.h"
#include "conformance/runner/report.h"
#include "conformance/runner/runner.h"
#include "conformance/suites/suites.h"
#include "conformance/targets/target.h"
#include "session/session.h"
#include "devices/registry.h"

namespace {

using namespace moco::conformance;

constexpr int kExitUsage = 2;

int Fail(const std::string& message) {
  std::cerr << "mococheck: " << message << "\n";
  return kExitUsage;
}

// "i/n" with 1 <= i <= n <= 1000, both whole decimal numbers.
bool ParseShard(const std::string& text, uint32_t& index, uint32_t& count) {
  const size_t slash = text.find('/');
  if (slash == std::string::npos) return false;
  const auto i = moco::cli::ParseNumber<uint32_t>(std::string_view(text).substr(0, slash));
  const auto n = moco::cli::ParseNumber<uint32_t>(std::string_view(text).substr(slash + 1));
  if (!i || !n || *n == 0 || *i == 0 || *i > *n || *n > 1000) return false;
  index = *i - 1;
  count = *n;
  return true;
}

// SIGINT, SIGTERM and SIGHUP during `mococheck run`: the run stops after the
// current case and the reports of what ran are written; a second signal ends
// the program at once.
extern "C" void OnStopSignal(int sig) {
  if (moco::conformance::StopRequested() != 0) {
    std::signal(sig, SIG_DFL);
    std::raise(sig);
    return;
  }
  moco::conformance::RequestStop(sig);
}

void InstallStopHandlers() {
  struct sigaction sa {};
  sa.sa_handler = OnStopSignal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = 0;  // no SA_RESTART: a waiting poll() returns EINTR and sees the request
  for (const int sig : {SIGINT, SIGTERM, SIGHUP}) sigaction(sig, &sa, nullptr);
}

// The device model a session names ("dfmoco-uno" -> "dfmoco"), if registered.
std::string ModelOfSessionDevice(const std::string& device) {
  for (const auto& m : moco::devices::DeviceModels()) {
    if (device == m.name || device.rfind(std::string(m.name) + "-", 0) == 0) {
      return std::string(m.name);
    }
  }
  return "";
}

uint32_t DefaultBaud(Protocol p) {
  switch (p) {
    case Protocol::kDfmoco:
      return 57600;
    case Protocol::kStackshot:
      return 38400;
    case Protocol::kDmc:
      break;
  }
  return 115200;
}

int RunReplay(const std::string& path, std::string target_text, const std::string& profile,
              uint32_t baud, int64_t steps, int64_t ms) {
  auto loaded = moco::control::LoadSession(path);
  if (const auto* err = std::get_if<moco::control::SessionError>(&loaded)) {
    return Fail(path + (err->line ? ":" + std::to_string(err->line) : std::string()) + ": " +
                err->message);
  }
  const moco::control::Session& session = std::get<moco::control::Session>(loaded);
  if (const std::string w = moco::control::SessionWarning(session); !w.empty()) {
    std::fprintf(stderr, "mococheck: %s: %s\n", path.c_str(), w.c_str());
  }
  const auto proto = ParseProtocol(moco::wire::ProtocolName(session.header.protocol));
  if (!proto) {
    return Fail(path + ": protocol " +
                std::string(moco::wire::ProtocolName(session.header.protocol)) +
                " cannot be replayed; sessions in dmc, dfmoco or stackshot can");
  }
  if (target_text.empty()) {
    const std::string model = ModelOfSessionDevice(session.header.device);
    if (model.empty()) {
      return Fail(path + ": the session names no emulated device (\"" + session.header.device +
                  "\"); give --target");
    }
    target_text = "in-process:" + model;
  }
  const auto spec = ParseTargetSpec(target_text);
  if (const auto* err = std::get_if<std::string>(&spec)) return Fail(*err);
  const TargetSpec& ts = std::get<TargetSpec>(spec);
  if (ts.kind == TargetSpec::Kind::kInProcess) {
    const auto* m = moco::devices::FindDeviceModel(ts.address);
    if (m != nullptr && ParseProtocol(moco::wire::ProtocolName(m->protocol)) != proto) {
      return Fail("in-process:" + ts.address + " does not speak the session's protocol " +
                  std::string(ProtocolName(*proto)));
    }
  }
  auto made = MakeTarget(ts, profile, baud ? baud : DefaultBaud(*proto));
  if (const auto* err = std::get_if<std::string>(&made)) return Fail(*err);
  std::unique_ptr<Target> target = std::move(std::get<std::unique_ptr<Target>>(made));
  if (auto err = target->Open()) return Fail(*err);
  ReplayOptions options;
  if (steps >= 0) options.position_steps = steps;
  if (ms >= 0) options.time_ms = ms;
  const ReplayResult r = Replay(session, *proto, *target, options);
  std::cout << "mococheck replay: " << path << " -> " << target->Name() << "\n"
            << ReplayText(r) << std::flush;
  if (const auto lost = target->LinkLost()) {
    return Fail("target error: " + target->Name() + ": " + *lost +
                "; the comparison proves nothing about the device");
  }
  return r.ok() ? 0 : 1;
}

int RunFuzzCommand(const std::vector<std::string>& paths, std::string target_text,
                   const std::string& profile, uint64_t seed, uint64_t runs, double seconds,
                   const std::string& crashes, size_t max_failures) {
  std::vector<Seed> seeds;
  for (const std::string& p : paths) {
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
  if (target_text.empty()) {
    const std::string model = ModelOfSessionDevice(seeds.front().device);
    if (model.empty()) return Fail("the sessions name no emulated device; give --target");
    target_text = "in-process:" + model;
  }
  const auto spec = ParseTargetSpec(target_text);
  if (const auto* err = std::get_if<std::string>(&spec)) return Fail(*err);
  const TargetSpec& ts = std::get<TargetSpec>(spec);
  if (ts.kind != TargetSpec::Kind::kInProcess) {
    return Fail(
        "fuzz runs in-process devices only (each mutant needs a fresh device in virtual "
        "time); give --target in-process:MODEL, and use replay for a real device");
  }
  const auto* model = moco::devices::FindDeviceModel(ts.address);
  if (model == nullptr) {
    std::string known;
    for (const auto& m : moco::devices::DeviceModels())
      known += (known.empty() ? "" : ", ") + std::string(m.name);
    return Fail("unknown in-process model \"" + ts.address + "\"; the models are: " + known);
  }
  if (ParseProtocol(moco::wire::ProtocolName(model->protocol)) != proto) {
    return Fail("in-process:" + ts.address + " does not speak the sessions' protocol " +
                std::string(ProtocolName(proto)));
  }
  FuzzExecutor executor(proto, InProcessTarget::ForModel(ts.address, profile));
  if (auto err = executor.Open()) return Fail(*err);
  FuzzOptions options;
  options.seed = seed;
  options.runs = runs;
  options.seconds = seconds;
  options.crash_dir = crashes;
  options.device = ts.address;
  options.max_failures = max_failures;
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
                ts.address.c_str(), seeds.size(), static_cast<unsigned long long>(seed),
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

int main(int argc, char** argv) {
  // A closed pipe or socket is a failed write (EPIPE), handled where it
  // happens, never a silent death: a TCP target that hangs up is a target
  // error with the reports written, and `| head` only loses console text.
  std::signal(SIGPIPE, SIG_IGN);
  using moco::cli::AddNumber;
  CLI::App app{
      "mococheck: conformance runner for motion-control devices.\n"
      "Plays Dragonframe-style traffic (DMC v2, DFMoco or StackShot 3X) at a device and checks\n"
      "every byte against the rules in docs/rules.md. Exit status: 0 when every MUST rule passed, "
      "1 when one failed,\n"
      "2 on a usage or target error or when a signal cut the run short (docs/exit-codes.md).\n\n"
      "Examples:\n"
      "  mococheck run --target in-process:dmc16\n"
      "  mococheck run --target pty:/tmp/dmc16 --baud 115200 --junit report.xml\n"
      "  mococheck run --target tcp:127.0.0.1:5000 --rules 'DMC-ACK-*,DMC-CSUM-*'\n"
      "  mococheck replay fixtures/sessions/dmc16-workflow.jsonl --target in-process:dmc16\n"
      "  mococheck fuzz fixtures/sessions/*.jsonl --target in-process:dmc16 --seconds 30\n"
      "  mococheck rules --markdown > docs/rules.md\n"
      "  mococheck cases"};
  app.require_subcommand(1);

  // --- run ---
  CLI::App* run = app.add_subcommand("run", "Run the conformance suites against a device");
  std::string target_text, protocol, profile, rules_glob, cases_glob, junit, json_path,
      shard = "1/1", session_path;
  uint64_t seed = 1;
  int steps = 40;
  uint32_t baud = 0;
  int64_t deadline_ms = 250, answer_timeout_ms = 2000, position_gap_ms = 200;
  bool verbose = false, quiet = false;
  run->add_option("--target", target_text,
                  "in-process:MODEL (e.g. in-process:dmc16, virtual time), pty:PATH or serial:PATH "
                  "(raw 8N1 at --baud), tcp:HOST:PORT, or simavr:PATH.elf[@MCU[:HZ]] (AVR "
                  "firmware under simavr on its own clock; default @atmega328p:16000000)")
      ->required();
  run->add_option("--protocol", protocol,
                  "Protocol spoken by the target: dmc (DMC v2), dfmoco or stackshot. Default: the "
                  "in-process model's protocol, else dmc");
  run->add_option("--profile", profile, "Device profile (JSON) for an in-process target")
      ->check(CLI::ExistingFile);
  run->add_option("--rules", rules_glob,
                  "Only check rules whose id matches: globs separated by commas, e.g. 'DMC-HI-*'");
  run->add_option("--cases", cases_glob,
                  "Only run cases matching suite/name globs, e.g. 'motor/*,rt/*'");
  AddNumber(run, "--seed", seed, uint64_t{0}, UINT64_MAX, "Seed of the random sequence suite");
  AddNumber(run, "--steps", steps, 1, 100000, "Requests in the random sequence");
  run->add_option("--junit", junit,
                  "Write a JUnit XML report here (one testcase per rule and case)")
      ->check(moco::cli::NonEmptyPath());
  run->add_option("--json", json_path, "Write a JSON report here")
      ->check(moco::cli::NonEmptyPath());
  std::string html_path;
  run->add_option("--html", html_path,
                  "Write a self-contained HTML report here (evidence, transcripts, position plots)")
      ->check(moco::cli::NonEmptyPath());
  run->add_option("--shard", shard, "Run only shard i of n (1-based), e.g. 2/4")
      ->capture_default_str();
  AddNumber(run, "--baud", baud, uint32_t{0}, uint32_t{4000000},
            "Baud rate of a pty:/serial: target (default 0: the protocol's: DMC v2 115200, "
            "DFMoco 57600, StackShot 38400)");
  AddNumber(run, "--deadline-ms", deadline_ms, int64_t{1}, int64_t{600000},
            "DMC-DL-* answer deadline");
  std::vector<std::string> deadlines;
  run->add_option("--deadline", deadlines,
                  "Per-kind deadline KIND=MS (kinds: hi, query, command, upload, rt); repeatable, "
                  "overrides --deadline-ms for that kind");
  AddNumber(run, "--answer-timeout-ms", answer_timeout_ms, int64_t{1}, int64_t{600000},
            "DMC-ACK-001: a request unanswered after this has no answer");
  AddNumber(run, "--position-gap-ms", position_gap_ms, int64_t{1}, int64_t{600000},
            "DMC-POS-002: the largest gap between position updates while moving");
  run->add_option("--save-session", session_path,
                  "Save a failing random sequence here (JSON Lines, docs/sessions.md)")
      ->check(moco::cli::NonEmptyPath());
  run->add_flag("-v,--verbose", verbose, "List passing rules and every case's log");
  run->add_flag("-q,--quiet", quiet, "Print only the summary line");

  // --- rules ---
  CLI::App* rules = app.add_subcommand("rules", "List the rule catalogue");
  bool markdown = false;
  rules->add_flag("--markdown", markdown, "Print docs/rules.md (the catalogue as Markdown)");

  // --- cases ---
  CLI::App* cases =
      app.add_subcommand("cases", "List the scenario cases (suite/name) and what they need");
  std::string cases_protocol = "dmc";
  cases->add_option("--protocol", cases_protocol, "dmc, dfmoco or stackshot")
      ->capture_default_str();

  // --- replay ---
  CLI::App* replay = app.add_subcommand(
      "replay",
      "Resend a recorded session's host side and compare the device side (docs/sessions.md)");
  std::string replay_session, replay_target, replay_profile;
  int64_t replay_steps = -1, replay_ms = -1;
  uint32_t replay_baud = 0;
  replay->add_option("session", replay_session, "Session file (JSON Lines)")->required();
  replay->add_option("--target", replay_target,
                     "in-process:MODEL (default: the session's device), pty:PATH, serial:PATH or "
                     "tcp:HOST:PORT");
  replay->add_option("--profile", replay_profile, "Device profile for an in-process target")
      ->check(CLI::ExistingFile);
  AddNumber(replay, "--baud", replay_baud, uint32_t{0}, uint32_t{4000000},
            "Baud rate of a pty:/serial: target (default 0: the protocol's)");
  AddNumber(replay, "--position-tolerance", replay_steps, int64_t{0}, int64_t{1} << 31,
            "Steps a reported position may differ (default: the session's, else 0)")
      ->default_str("the session's");
  AddNumber(replay, "--time-tolerance-ms", replay_ms, int64_t{0}, int64_t{3600000},
            "How far a device message may arrive from its recorded time (default: the "
            "session's, else 0 in-process and 50 on a real link)")
      ->default_str("the session's");

  // --- fuzz ---
  CLI::App* fuzz = app.add_subcommand(
      "fuzz", "Mutate recorded host traffic and check device invariants (in-process targets)");
  std::vector<std::string> fuzz_sessions;
  std::string fuzz_target, fuzz_profile, fuzz_crashes = "mococheck-fuzz";
  uint64_t fuzz_seed = 1, fuzz_runs = 0;
  double fuzz_seconds = 10;
  size_t fuzz_max_failures = 5;
  fuzz->add_option("sessions", fuzz_sessions, "Session files to mutate (same protocol)")
      ->required();
  fuzz->add_option("--target", fuzz_target,
                   "in-process:MODEL (default: the first session's device)");
  fuzz->add_option("--profile", fuzz_profile, "Device profile for the in-process device")
      ->check(CLI::ExistingFile);
  AddNumber(fuzz, "--seed", fuzz_seed, uint64_t{0}, UINT64_MAX, "Seed of the mutator");
  AddNumber(fuzz, "--runs", fuzz_runs, uint64_t{0}, uint64_t{1000000000000},
            "Mutants to run (0: run for --seconds)");
  AddNumber(fuzz, "--seconds", fuzz_seconds, 0.0, 86400.0, "Time budget when --runs is 0");
  fuzz->add_option("--crashes", fuzz_crashes,
                   "Directory for failing mutants (session files that replay reruns)")
      ->capture_default_str();
  AddNumber(fuzz, "--max-failures", fuzz_max_failures, size_t{1}, size_t{1000},
            "Stop after this many distinct failures");

  if (const auto exit_code = moco::cli::ParseCommandLine(app, argc, argv, kExitUsage)) {
    return *exit_code;
  }

  if (*cases) {
    const auto p = ParseProtocol(cases_protocol);
    if (!p) return Fail("--protocol " + cases_protocol + ": give dmc, dfmoco or stackshot");
    const ProtocolRunner* runner = FindRunner(*p);
    if (runner == nullptr) {
      return Fail("no suites for " + std::string(ProtocolTitle(*p)) + " yet");
    }
    for (const CaseInfo& k : runner->cases()) {
      std::string name = k.suite + "/" + k.name;
      name.resize(std::max<size_t>(name.size() + 2, 26), ' ');
      std::cout << name << k.summary;
      if (!k.needs.empty()) std::cout << " [needs " << k.needs << "]";
      std::cout << "\n";
    }
    return 0;
  }
  if (*rules) {
    std::cout << (markdown ? RulesMarkdown() : RulesText());
    return 0;
  }
  if (*replay)
    return RunReplay(replay_session, replay_target, replay_profile, replay_baud, replay_steps,
                     replay_ms);
  if (*fuzz) {
    return RunFuzzCommand(fuzz_sessions, fuzz_target, fuzz_profile, fuzz_seed, fuzz_runs,
                          fuzz_seconds, fuzz_crashes, fuzz_max_failures);
  }

  const auto spec = ParseTargetSpec(target_text);
  if (const auto* err = std::get_if<std::string>(&spec)) return Fail(*err);
  const TargetSpec& ts = std::get<TargetSpec>(spec);
  // The protocol: as given, else the in-process model's, else DMC v2.
  Protocol proto = Protocol::kDmc;
  std::optional<Protocol> model_proto;
  if (ts.kind == TargetSpec::Kind::kInProcess) {
    if (const auto* m = moco::devices::FindDeviceModel(ts.address)) {
      model_proto = ParseProtocol(moco::wire::ProtocolName(m->protocol));
    }
  }
  if (!protocol.empty()) {
    const auto p = ParseProtocol(protocol);
    if (!p) return Fail("--protocol " + protocol + ": give dmc, dfmoco or stackshot");
    if (model_proto && *model_proto != *p) {
      return Fail("--protocol " + protocol + " does not match in-process:" + ts.address +
                  ", which speaks " + std::string(ProtocolName(*model_proto)) +
                  "; drop --protocol or pick the matching model");
    }
    proto = *p;
  } else if (model_proto) {
    proto = *model_proto;
  }
  const ProtocolRunner* runner = FindRunner(proto);
  if (runner == nullptr) {
    return Fail(std::string(ProtocolTitle(proto)) +
                " has no conformance suites in this build; use a DMC v2 target");
  }
  RunOptions options;
  if (!ParseShard(shard, options.shard_index, options.shard_count)) {
    return Fail("--shard " + shard + ": give i/n with 1 <= i <= n, e.g. --shard 1/4");
  }
  if (!rules_glob.empty()) {
    bool any = false;
    for (const Rule& r : RulesFor(proto)) any = any || GlobMatch(rules_glob, r.id);
    if (!any) {
      return Fail("--rules " + rules_glob + " matches no " + std::string(ProtocolTitle(proto)) +
                  " rule; see 'mococheck rules'");
    }
  }
  if (!cases_glob.empty()) {
    bool any = false;
    for (const CaseInfo& k : runner->cases())
      any = any || GlobMatch(cases_glob, k.suite + "/" + k.name);
    if (!any) {
      return Fail("--cases " + cases_glob + " selects no " + std::string(ProtocolTitle(proto)) +
                  " case; see the case names with 'mococheck cases --protocol " +
                  std::string(ProtocolName(proto)) + "'");
    }
  }
  options.rules = rules_glob;
  options.cases = cases_glob;
  options.host.deadline_ns = deadline_ms * moco::sim::kNsPerMs;
  for (const std::string& d : deadlines) {
    const size_t eq = d.find('=');
    const std::string kind = d.substr(0, eq);
    bool known = false;
    for (const char* k : kDeadlineKinds) known = known || kind == k;
    int64_t ms = 0;
    const std::string problem = eq == std::string::npos
                                    ? "no '='"
                                    : moco::cli::CheckNumber(std::string_view(d).substr(eq + 1),
                                                             int64_t{1}, int64_t{600000}, ms);
    if (!known || !problem.empty()) {
      return Fail("--deadline " + d +
                  ": give KIND=MS with KIND one of hi, query, command, upload, rt and MS a whole "
                  "number in 1..600000, e.g. --deadline rt=500");
    }
    options.host.deadline_by_kind_ns[kind] = ms * moco::sim::kNsPerMs;
  }
  options.host.answer_timeout_ns = answer_timeout_ms * moco::sim::kNsPerMs;
  options.host.position_gap_ns = position_gap_ms * moco::sim::kNsPerMs;
  options.random.seed = seed;
  options.random.steps = steps;
  options.random.session_path = session_path;

  if (!profile.empty() && ts.kind != TargetSpec::Kind::kInProcess) {
    return Fail("--profile applies to in-process targets only; an external device has its own");
  }
  // Every output is checked before the run, not after it (docs/files.md).
  {
    const std::vector<std::pair<std::string, std::string>> outputs = {
        {"--junit", junit},
        {"--html", html_path},
        {"--json", json_path},
        {"--save-session", session_path}};
    for (size_t i = 0; i < outputs.size(); ++i) {
      const auto& [option, path] = outputs[i];
      if (path.empty()) continue;
      if (auto err = moco::base::CheckOutputPath(path, option)) return Fail(*err);
      if (!profile.empty() && moco::base::SameFile(path, profile)) {
        return Fail(option + " " + path + " is the --profile; writing it would destroy the " +
                    "profile: choose another path for " + option);
      }
      for (size_t j = 0; j < i; ++j) {
        if (!outputs[j].second.empty() && moco::base::SameFile(path, outputs[j].second)) {
          return Fail(option + " " + path + " is also " + outputs[j].first +
                      "; one report would overwrite the other: give each its own file");
        }
      }
    }
  }
  // From here a signal stops the run and the reports of what ran are written.
  InstallStopHandlers();
  auto made = MakeTarget(ts, profile, baud ? baud : DefaultBaud(proto));
  if (const auto* err = std::get_if<std::string>(&made)) return Fail(*err);
  std::unique_ptr<Target> target = std::move(std::get<std::unique_ptr<Target>>(made));
  if (auto err = target->Open()) return Fail(*err);

  // The console streams: the title now, the device once it answered, each
  // case's verdict as it ends (flushed, whatever stdout is), the summary last.
  if (!quiet) {
    std::cout << ConsoleTitle(target->Name(), std::string(ProtocolName(proto))) << std::flush;
  }
  bool device_printed = false;
  size_t printed = 0;
  auto print_device = [&](const RunReport& so_far) {
    if (device_printed) return;
    device_printed = true;
    if (so_far.device.empty() && !target->VirtualClock()) {
      std::cerr << "mococheck: " << target->Name() << " did not introduce itself; is a "
                << ProtocolTitle(proto) << " device there, at this baud rate?" << std::endl;
    }
    if (!quiet) std::cout << ConsoleDevice(so_far) << std::flush;
  };
  options.on_progress = [&](const RunReport& so_far) {
    print_device(so_far);
    for (; printed < so_far.cases.size(); ++printed) {
      if (!quiet) std::cout << ConsoleCase(so_far.cases[printed], verbose) << std::flush;
    }
  };
  RunReport report = runner->run(*target, options);
  options.on_progress(report);  // whatever the runner did not announce
  if (const auto lost = target->LinkLost()) report.target_error = *lost;
  if (!report.target_error.empty()) {
    std::cerr << "mococheck: target error: " << target->Name() << ": " << report.target_error
              << "; the outcomes prove nothing about the device" << std::endl;
  }
  if (quiet) {
    const std::string text = ConsoleSummary(report, false);
    std::cout << text.substr(text.rfind("result:")) << std::flush;
  } else {
    std::cout << ConsoleSummary(report, verbose) << std::flush;
  }
  if (!junit.empty()) {
    if (auto err = WriteAtomically(junit, JunitReport(report)); !err.empty()) return Fail(err);
  }
  if (!html_path.empty()) {
    if (auto err = WriteAtomically(html_path, HtmlReport(report)); !err.empty()) return Fail(err);
  }
  if (!json_path.empty()) {
    if (auto err = WriteAtomically(json_path, JsonReport(report).dump(2) + "\n"); !err.empty()) {
      return Fail(err);
    }
  }
  return ExitCode(report);
}
