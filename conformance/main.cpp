// mococheck: the DMC v2 conformance runner (dmc-v2-protocol.txt; ERRATA dmc;
// docs/rules.md). Drives Dragonframe-style traffic at a device and checks
// every byte against the rule catalogue. Exit: 0 every MUST rule passed,
// 1 a MUST rule failed, 2 usage or target error.
#include <algorithm>
#include <cstdio>
#include <iostream>
#include <string>

#include <CLI/CLI.hpp>

#include "conformance/rules/catalogue.h"
#include "conformance/runner/report.h"
#include "conformance/runner/runner.h"
#include "conformance/suites/suites.h"
#include "conformance/targets/target.h"

namespace {

using namespace moco::conformance;

constexpr int kExitUsage = 2;

int Fail(const std::string& message) {
  std::cerr << "mococheck: " << message << "\n";
  return kExitUsage;
}

// "i/n" with 1 <= i <= n.
bool ParseShard(const std::string& text, uint32_t& index, uint32_t& count) {
  const size_t slash = text.find('/');
  if (slash == std::string::npos) return false;
  try {
    const unsigned long i = std::stoul(text.substr(0, slash));
    const unsigned long n = std::stoul(text.substr(slash + 1));
    if (n == 0 || i == 0 || i > n || n > 1000) return false;
    index = static_cast<uint32_t>(i - 1);
    count = static_cast<uint32_t>(n);
    return true;
  } catch (const std::exception&) {
    return false;
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "mococheck: conformance runner for motion-control devices.\n"
      "Plays Dragonframe-style DMC v2 traffic at a device and checks every byte against the\n"
      "rules in docs/rules.md. Exit status: 0 when every MUST rule passed, 1 when one failed,\n"
      "2 on a usage or target error.\n\n"
      "Examples:\n"
      "  mococheck run --target in-process:dmc16\n"
      "  mococheck run --target pty:/tmp/dmc16 --baud 115200 --junit report.xml\n"
      "  mococheck run --target tcp:127.0.0.1:5000 --rules 'DMC-ACK-*,DMC-CSUM-*'\n"
      "  mococheck rules --markdown > docs/rules.md\n"
      "  mococheck cases"};
  app.require_subcommand(1);

  // --- run ---
  CLI::App* run = app.add_subcommand("run", "Run the conformance suites against a device");
  std::string target_text, protocol = "dmc", profile, rules_glob, cases_glob, junit, json_path,
                           shard = "1/1", session_path;
  uint64_t seed = 1;
  int steps = 40;
  uint32_t baud = 115200;
  int64_t deadline_ms = 250, answer_timeout_ms = 2000, position_gap_ms = 200;
  bool verbose = false, quiet = false;
  run->add_option("--target", target_text,
                  "in-process:MODEL (e.g. in-process:dmc16, virtual time), pty:PATH or serial:PATH "
                  "(raw 8N1 at --baud), tcp:HOST:PORT, or simavr:PATH.elf[@MCU[:HZ]] (AVR "
                  "firmware under simavr on its own clock; default @atmega328p:16000000)")
      ->required();
  run->add_option("--protocol", protocol,
                  "Protocol spoken by the target; only 'dmc' (DMC v2) so far")
      ->capture_default_str();
  run->add_option("--profile", profile, "Device profile (JSON) for an in-process target");
  run->add_option("--rules", rules_glob,
                  "Only check rules whose id matches: globs separated by commas, e.g. 'DMC-HI-*'");
  run->add_option("--cases", cases_glob,
                  "Only run cases matching suite/name globs, e.g. 'motor/*,rt/*'");
  run->add_option("--seed", seed, "Seed of the random sequence suite")->capture_default_str();
  run->add_option("--steps", steps, "Requests in the random sequence")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  run->add_option("--junit", junit,
                  "Write a JUnit XML report here (one testcase per rule and case)");
  run->add_option("--json", json_path, "Write a JSON report here");
  run->add_option("--shard", shard, "Run only shard i of n (1-based), e.g. 2/4")
      ->capture_default_str();
  run->add_option("--baud", baud, "Baud rate of a pty:/serial: target")->capture_default_str();
  run->add_option("--deadline-ms", deadline_ms, "DMC-DL-* answer deadline")
      ->check(CLI::Range(int64_t{1}, int64_t{600000}))
      ->capture_default_str();
  std::vector<std::string> deadlines;
  run->add_option("--deadline", deadlines,
                  "Per-kind deadline KIND=MS (kinds: hi, query, command, upload, rt); repeatable, "
                  "overrides --deadline-ms for that kind");
  run->add_option("--answer-timeout-ms", answer_timeout_ms,
                  "DMC-ACK-001: a request unanswered after this has no answer")
      ->check(CLI::Range(int64_t{1}, int64_t{600000}))
      ->capture_default_str();
  run->add_option("--position-gap-ms", position_gap_ms,
                  "DMC-POS-002: the largest gap between position updates while moving")
      ->check(CLI::Range(int64_t{1}, int64_t{600000}))
      ->capture_default_str();
  run->add_option("--save-session", session_path,
                  "Save a failing random sequence here (JSON Lines, docs/sessions.md)");
  run->add_flag("-v,--verbose", verbose, "List passing rules and every case's log");
  run->add_flag("-q,--quiet", quiet, "Print only the summary line");

  // --- rules ---
  CLI::App* rules = app.add_subcommand("rules", "List the rule catalogue");
  bool markdown = false;
  rules->add_flag("--markdown", markdown, "Print docs/rules.md (the catalogue as Markdown)");

  // --- cases ---
  CLI::App* cases =
      app.add_subcommand("cases", "List the scenario cases (suite/name) and what they need");

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    app.exit(e);
    return kExitUsage;
  }

  if (*cases) {
    for (const Case& k : DmcCases()) {
      std::string name = k.suite + "/" + k.name;
      name.resize(std::max<size_t>(name.size() + 2, 26), ' ');
      std::cout << name << k.summary;
      if (k.needs != Needs::kNothing) std::cout << " [needs " << NeedsText(k.needs) << "]";
      std::cout << "\n";
    }
    return 0;
  }
  if (*rules) {
    std::cout << (markdown ? RulesMarkdown() : RulesText());
    return 0;
  }

  if (protocol != "dmc") {
    return Fail("--protocol " + protocol +
                ": only 'dmc' (DMC v2) has rules so far; DFMoco and StackShot are not covered yet");
  }
  RunOptions options;
  if (!ParseShard(shard, options.shard_index, options.shard_count)) {
    return Fail("--shard " + shard + ": give i/n with 1 <= i <= n, e.g. --shard 1/4");
  }
  if (!rules_glob.empty()) {
    bool any = false;
    for (const Rule& r : DmcRules()) any = any || GlobMatch(rules_glob, r.id);
    if (!any) return Fail("--rules " + rules_glob + " matches no rule; see 'mococheck rules'");
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
    try {
      ms = eq == std::string::npos ? 0 : std::stoll(d.substr(eq + 1));
    } catch (const std::exception&) {
      ms = 0;
    }
    if (!known || ms <= 0) {
      return Fail("--deadline " + d +
                  ": give KIND=MS with KIND one of hi, query, command, upload, rt and MS > 0, "
                  "e.g. --deadline rt=500");
    }
    options.host.deadline_by_kind_ns[kind] = ms * moco::sim::kNsPerMs;
  }
  options.host.answer_timeout_ns = answer_timeout_ms * moco::sim::kNsPerMs;
  options.host.position_gap_ns = position_gap_ms * moco::sim::kNsPerMs;
  options.random.seed = seed;
  options.random.steps = steps;
  options.random.session_path = session_path;

  const auto spec = ParseTargetSpec(target_text);
  if (const auto* err = std::get_if<std::string>(&spec)) return Fail(*err);
  const TargetSpec& ts = std::get<TargetSpec>(spec);
  if (!profile.empty() && ts.kind != TargetSpec::Kind::kInProcess) {
    return Fail("--profile applies to in-process targets only; an external device has its own");
  }
  auto made = MakeTarget(ts, profile, baud);
  if (const auto* err = std::get_if<std::string>(&made)) return Fail(*err);
  std::unique_ptr<Target> target = std::move(std::get<std::unique_ptr<Target>>(made));
  if (auto err = target->Open()) return Fail(*err);

  const RunReport report = RunDmc(*target, options);
  if (!report.hi && !target->VirtualClock()) {
    std::cerr << "mococheck: " << target->Name()
              << " gave no HI answer; is a DMC v2 device there, at this baud rate?\n";
  }
  if (quiet) {
    const std::string text = ConsoleReport(report, false);
    std::cout << text.substr(text.rfind("result:"));
  } else {
    std::cout << ConsoleReport(report, verbose);
  }
  if (!junit.empty()) {
    if (auto err = WriteAtomically(junit, JunitReport(report)); !err.empty()) return Fail(err);
  }
  if (!json_path.empty()) {
    if (auto err = WriteAtomically(json_path, JsonReport(report).dump(2) + "\n"); !err.empty()) {
      return Fail(err);
    }
  }
  return ExitCode(report);
}
