// What `mococheck run` and `mococheck certify` share (run_setup.h).
#include "conformance/cli/run_setup.h"

#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <set>

#include "base/file_io.h"
#include "base/vcd.h"
#include "cli_numbers.h"
#include "conformance/core/report.h"
#include "conformance/targets/native_target.h"
#include "wire/protocol.h"

namespace moco::conformance::cli {
namespace {

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

// The comma-separated globs of a --rules / --cases value, empty ones left out.
std::vector<std::string> SplitGlobs(const std::string& text) {
  std::vector<std::string> globs;
  size_t start = 0;
  while (start <= text.size()) {
    const size_t comma = text.find(',', start);
    std::string one = text.substr(start, comma == std::string::npos ? comma : comma - start);
    if (!one.empty()) globs.push_back(std::move(one));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return globs;
}

// The watched pins of every case, one after the other on one time line (each
// case starts where the previous ended plus 1 ms, every level low as the
// firmware restarts), as a Value Change Dump.
std::string PinsVcd(const RunReport& report) {
  std::vector<base::VcdWire> wires;
  std::string comment = "mococheck " + report.target + "; cases:";
  int64_t offset = 0;
  for (const CaseResult& c : report.cases) {
    if (!c.pins) continue;
    const PinTrace& t = *c.pins;
    if (wires.empty()) {
      for (const PinSignal& s : t.signals) wires.push_back({s.name, false, {}});
    }
    comment += " " + c.suite + "/" + c.name + " at " + std::to_string(offset) + " ns;";
    int64_t end = c.target_ns;
    for (size_t i = 0; i < t.signals.size() && i < wires.size(); ++i) {
      wires[i].changes.emplace_back(offset, t.signals[i].initial);
      for (const PinEdge& e : t.signals[i].edges) {
        wires[i].changes.emplace_back(offset + e.t_ns, e.level);
        end = std::max<int64_t>(end, e.t_ns);
      }
    }
    offset += end + sim::kNsPerMs;
  }
  return base::VcdText("board", comment, wires);
}

// "auto (default: ...), sketch (...) or stackshot3x (...)": what --dialect
// may name for `runner`'s protocol.
std::string DialectChoices(const ProtocolRunner& runner) {
  std::string s = std::string(kAutoDialect) + " (default" +
                  (runner.auto_picks.empty() ? "" : ": " + std::string(runner.auto_picks)) + ")";
  for (size_t i = 0; i < runner.dialects.size(); ++i) {
    const DialectChoice& d = runner.dialects[i];
    s += (i + 1 == runner.dialects.size() ? " or " : ", ") + std::string(d.name) + " (" +
         std::string(d.description) + ")";
  }
  return s;
}

// The protocols whose devices speak several dialects (from the registry).
std::vector<Protocol> ProtocolsWithDialects() {
  std::vector<Protocol> out;
  for (const ProtocolRunner& r : Runners()) {
    if (!r.dialects.empty()) out.push_back(r.protocol);
  }
  return out;
}

}  // namespace

// The cases the run selects: --shard, --rules and --cases checked against
// the protocol's rules and cases (each glob must select something: a misspelt
// one would otherwise shrink the run without a word) and set in `options`.
// An error message, or nullopt.
std::optional<std::string> SelectCases(const RunArgs& a, const ProtocolRunner& runner,
                                       Protocol proto, RunOptions& options) {
  const std::string title(wire::Info(proto).title);
  if (!ParseShard(a.shard, options.shard_index, options.shard_count)) {
    return "--shard " + a.shard + ": give i/n with 1 <= i <= n, e.g. --shard 1/4";
  }
  for (const std::string& glob : SplitGlobs(a.rules_glob)) {
    bool any = false;
    for (const Rule& r : runner.rules()) any = any || GlobMatch(glob, r.id);
    if (!any) {
      return "--rules " + a.rules_glob + ": '" + glob + "' matches no " + title +
             " rule; see the rule ids with 'mococheck rules'";
    }
  }
  for (const std::string& glob : SplitGlobs(a.cases_glob)) {
    bool any = false;
    for (const CaseInfo& k : runner.cases()) any = any || GlobMatch(glob, k.suite + "/" + k.name);
    if (!any) {
      return "--cases " + a.cases_glob + ": '" + glob + "' selects no " + title +
             " case; see the case names with 'mococheck cases --protocol " +
             std::string(ProtocolName(proto)) + "'";
    }
  }
  if ((!a.rules_glob.empty() && SplitGlobs(a.rules_glob).empty()) ||
      (!a.cases_glob.empty() && SplitGlobs(a.cases_glob).empty())) {
    return std::string(SplitGlobs(a.rules_glob).empty() && !a.rules_glob.empty() ? "--rules"
                                                                                 : "--cases") +
           " holds no glob: give globs separated by commas, e.g. 'motor/*,rt/*'";
  }
  options.rules = a.rules_glob;
  options.cases = a.cases_glob;
  size_t selected = 0;
  const std::vector<CaseInfo>& all = runner.cases();
  for (size_t i = 0; i < all.size(); ++i) {
    selected += CaseSelected(options, i, all[i].suite + "/" + all[i].name);
  }
  if (selected == 0) {
    return "--shard " + a.shard + (a.cases_glob.empty() ? "" : " with --cases " + a.cases_glob) +
           " selects no " + title + " case (" + std::to_string(all.size()) +
           " in all); use fewer shards or a wider --cases";
  }
  return std::nullopt;
}

// --dialect's help: the dialects of every protocol that has some.
std::string DialectHelp() {
  std::string s =
      "Dialect the device is judged in, for a protocol whose devices speak several (the others "
      "take auto only)";
  for (const ProtocolRunner& r : Runners()) {
    if (r.dialects.empty()) continue;
    s += "; --protocol " + std::string(ProtocolName(r.protocol)) + ": " + DialectChoices(r);
  }
  return s;
}

// --dialect checked against the dialects `runner`'s protocol names: an error
// message, or nullopt.
std::optional<std::string> CheckDialect(const std::string& dialect, const ProtocolRunner& runner) {
  if (dialect == kAutoDialect) return std::nullopt;
  for (const DialectChoice& d : runner.dialects) {
    if (d.name == dialect) return std::nullopt;
  }
  const std::string name(ProtocolName(runner.protocol));
  if (!runner.dialects.empty()) {
    return "--dialect " + dialect + ": give " + DialectChoices(runner) + " for --protocol " + name;
  }
  const std::vector<Protocol> with = ProtocolsWithDialects();
  return "--dialect " + dialect + ": this target speaks " + name +
         ", which has no dialects (give auto, the default, or leave --dialect out)" +
         (with.empty() ? std::string()
                       : "; --dialect applies to --protocol " + wire::NameList(with) + " only");
}

// The host's deadlines and timeouts and the random suite's settings, set in
// `options`. An error message (a bad --deadline), or nullopt.
std::optional<std::string> SetHostOptions(const RunArgs& a, RunOptions& options) {
  options.host.deadline_ns = a.deadline_ms * sim::kNsPerMs;
  for (const std::string& d : a.deadlines) {
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
      return "--deadline " + d +
             ": give KIND=MS with KIND one of hi, query, command, upload, rt and MS a whole "
             "number in 1..600000, e.g. --deadline rt=500";
    }
    options.host.deadline_by_kind_ns[kind] = ms * sim::kNsPerMs;
  }
  options.host.dialect = a.dialect;
  options.host.answer_timeout_ns = a.answer_timeout_ms * sim::kNsPerMs;
  if (a.wait_every_answer) options.host.give_up_after_unanswered = 0;
  options.host.position_gap_ns = a.position_gap_ms * sim::kNsPerMs;
  options.random.seed = a.seed;
  options.random.steps = a.steps;
  options.random.session_path = a.session_path;
  return std::nullopt;
}

// --board and --driver loaded into `board` and the pin judge of `options`.
// An error message, or nullopt.
std::optional<std::string> LoadPins(const RunArgs& a, RunOptions& options,
                                    std::optional<Board>& board) {
  if (a.board_path.empty() && (!a.driver.empty() || !a.vcd_path.empty())) {
    return std::string(a.driver.empty() ? "--vcd" : "--driver") +
           " needs --board: give the board profile naming the watched pins, e.g. --board "
           "fixtures/boards/own-dfmoco.json";
  }
  if (a.board_path.empty()) return std::nullopt;
  auto pins = LoadPinJudge(a.board_path, a.driver);
  if (const auto* err = std::get_if<std::string>(&pins)) return *err;
  options.pins = std::get<PinJudgeOptions>(pins);
  board = options.pins->board;
  return std::nullopt;
}

std::variant<PinJudgeOptions, std::string> LoadPinJudge(const std::string& board_path,
                                                        const std::string& driver_name) {
  auto loaded = LoadBoard(board_path);
  if (const auto* err = std::get_if<std::string>(&loaded)) return *err;
  auto driver = LoadDriver(driver_name.empty() ? "a4988" : driver_name);
  if (const auto* err = std::get_if<std::string>(&driver)) return *err;
  PinJudgeOptions pins;
  pins.board = std::get<Board>(loaded);
  pins.driver = std::get<DriverProfile>(driver);
  return pins;
}

void AddPinOptions(CLI::App* sub, std::string& board_path, std::string& driver) {
  sub->add_option("--board", board_path,
                  "Board profile (JSON, fixtures/boards/) naming the pins to watch on a simavr: "
                  "or native: target; enables the pin rules (*-PIN-*)")
      ->check(moco::cli::NonEmptyPath());
  sub->add_option("--driver", driver,
                  "Step driver whose STEP/DIR timing the pin rules judge: a4988 (default), "
                  "drv8825, tmc2209, or a driver profile (JSON, fixtures/drivers/); needs --board");
}

// The files a run reads: the profile, board and driver files, the firmware
// of a simavr: or native: target, and `extra` (the command's own).
std::vector<std::pair<std::string, std::string>> RunInputs(
    const RunArgs& a, const PreparedRun& p,
    const std::vector<std::pair<std::string, std::string>>& extra) {
  std::vector<std::pair<std::string, std::string>> inputs = {{"--profile", a.profile},
                                                             {"--board", a.board_path}};
  std::error_code ec;
  if (!a.driver.empty() && std::filesystem::is_regular_file(a.driver, ec)) {
    inputs.push_back({"--driver", a.driver});
  }
  if (p.resolved.spec.kind == TargetSpec::Kind::kSimavr) {
    auto spec = ParseSimavrAddress(p.resolved.spec.address);
    if (const auto* s = std::get_if<SimavrSpec>(&spec)) {
      inputs.push_back({"--target's firmware", s->elf_path});
    }
  }
  if (p.resolved.spec.kind == TargetSpec::Kind::kNative) {
    auto spec = ParseNativeAddress(p.resolved.spec.address);
    if (const auto* s = std::get_if<NativeSpec>(&spec)) {
      inputs.push_back({"--target's firmware", s->path});
    }
  }
  inputs.insert(inputs.end(), extra.begin(), extra.end());
  return inputs;
}

// Every output checked before the run, not after it (docs/files.md): each
// writable, none a file the run reads (`inputs`), no two the same file. An
// error message, or nullopt.
std::optional<std::string> CheckOutputs(
    const RunArgs& a, const std::vector<std::pair<std::string, std::string>>& extra,
    const std::vector<std::pair<std::string, std::string>>& inputs) {
  std::vector<std::pair<std::string, std::string>> outputs = {{"--junit", a.junit},
                                                              {"--html", a.html_path},
                                                              {"--json", a.json_path},
                                                              {"--save-session", a.session_path},
                                                              {"--vcd", a.vcd_path}};
  outputs.insert(outputs.end(), extra.begin(), extra.end());
  for (size_t i = 0; i < outputs.size(); ++i) {
    const auto& [option, path] = outputs[i];
    if (path.empty()) continue;
    if (auto err = base::CheckOutputPath(path, option)) return *err;
    for (const auto& [input, input_path] : inputs) {
      if (!input_path.empty() && base::SameFile(path, input_path)) {
        const std::string what = input.starts_with("--") ? input.substr(2) : input;
        return option + " " + path + " is the " + input + "; writing it would destroy the " + what +
               ": choose another path for " + option;
      }
    }
    for (size_t j = 0; j < i; ++j) {
      if (!outputs[j].second.empty() && base::SameFile(path, outputs[j].second)) {
        return option + " " + path + " is also " + outputs[j].first +
               "; one report would overwrite the other: give each its own file";
      }
    }
  }
  return std::nullopt;
}

void ConsoleStream::PrintDevice(const RunReport& so_far) {
  if (device_printed) return;
  device_printed = true;
  if (so_far.device.empty() && !target.VirtualClock()) {
    std::cerr << "mococheck: " << target.Name() << " did not introduce itself; is a " << title
              << " device there, at this baud rate?" << std::endl;
  }
  if (!a.quiet) std::cout << ConsoleDevice(so_far) << std::flush;
}

void ConsoleStream::CaseStarts(const RunReport& so_far, const std::string& name, size_t index,
                               size_t total) {
  PrintDevice(so_far);
  if (a.quiet) return;
  std::set<std::string> judged, failing;
  for (const CaseResult& c : so_far.cases) {
    for (const auto& [id, o] : c.outcomes) {
      judged.insert(id);
      if (o.status == Status::kFail) failing.insert(id);
    }
  }
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  char elapsed[32];
  std::snprintf(elapsed, sizeof elapsed, "%.1f s", s);
  std::cerr << "mococheck: [" << index << "/" << total << "] " << name << " (" << elapsed
            << " elapsed; " << judged.size() << " rules judged so far, " << failing.size()
            << " failing)" << std::endl;
}

void ConsoleStream::Attach(RunOptions& options) {
  options.on_progress = [this](const RunReport& so_far) {
    PrintDevice(so_far);
    for (; printed < so_far.cases.size(); ++printed) {
      if (!a.quiet) std::cout << ConsoleCase(so_far.cases[printed], a.verbose) << std::flush;
    }
  };
  options.on_case_start = [this](const RunReport& so_far, const std::string& name, size_t index,
                                 size_t total) { CaseStarts(so_far, name, index, total); };
}

// The end of the run on the console: a target error on stderr, then the
// summary (with -q the result line and the target's caveats).
void PrintSummary(const RunArgs& a, const Target& target, const RunReport& report) {
  if (!report.target_error.empty()) {
    std::cerr << "mococheck: target error: " << target.Name() << ": " << report.target_error
              << "; the outcomes prove nothing about the device" << std::endl;
  }
  if (a.quiet) {
    // The result line, and what the target could not reproduce faithfully:
    // a clock or peripheral run wrong is never silent, even here.
    const std::string text = ConsoleSummary(report, false);
    for (const std::string& caveat : report.target_caveats) {
      std::cout << "target caveat: " << caveat << "\n";
    }
    std::cout << text.substr(text.rfind("result:")) << std::flush;
  } else {
    std::cout << ConsoleSummary(report, a.verbose) << std::flush;
  }
}

// Every report that can be written is written: one that fails (a full disk,
// a folder gone) is named with its option, and the others still land. The
// exit status: the run's, or kExitUsage when a report is missing.
int WriteReports(const RunArgs& a, const RunReport& report) {
  std::vector<std::string> written, failed;
  auto write = [&](const char* option, const std::string& path, const auto& render) {
    if (path.empty()) return;
    if (auto err = WriteAtomically(path, render()); !err.empty()) {
      failed.push_back(std::string(option) + " " + path + ": " + err);
    } else {
      written.push_back(std::string(option) + " " + path);
    }
  };
  write("--junit", a.junit, [&] { return JunitReport(report); });
  write("--html", a.html_path, [&] { return HtmlReport(report); });
  write("--vcd", a.vcd_path, [&] { return PinsVcd(report); });
  write("--json", a.json_path, [&] {
    return JsonReport(report).dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n";
  });
  if (!failed.empty()) {
    for (const std::string& f : failed) std::cerr << "mococheck: could not write " << f << "\n";
    std::string others;
    for (const std::string& w : written) others += (others.empty() ? "" : ", ") + w;
    std::cerr << "mococheck: " << (others.empty() ? "no report was written" : "written: " + others)
              << "; the verdict above stands, but a report is missing: free space or choose "
                 "another path and run again"
              << std::endl;
    return kExitUsage;
  }
  return ExitCode(report);
}

std::optional<PreparedRun> PrepareRun(
    const RunArgs& a, int& exit_code,
    const std::vector<std::pair<std::string, std::string>>& extra_outputs,
    const std::vector<std::pair<std::string, std::string>>& extra_inputs) {
  auto fail = [&](const std::string& message) {
    exit_code = Fail(message);
    return std::nullopt;
  };
  TargetRequest request;
  request.text = a.target_text;
  request.profile = a.profile;
  request.baud = a.baud;
  request.protocol_option = a.protocol;
  auto resolved = ResolveTarget(request);
  if (const auto* err = std::get_if<std::string>(&resolved)) return fail(*err);
  PreparedRun p;
  p.resolved = std::move(std::get<ResolvedTarget>(resolved));
  const Protocol proto = p.resolved.protocol;
  p.runner = FindRunner(proto);
  if (p.runner == nullptr) {
    return fail(std::string(wire::Info(proto).title) +
                " has no conformance suites in this build; use a DMC v2 target");
  }
  if (auto err = CheckDialect(a.dialect, *p.runner)) return fail(*err);
  if (auto err = SelectCases(a, *p.runner, proto, p.options)) return fail(*err);
  if (auto err = SetHostOptions(a, p.options)) return fail(*err);
  if (auto err = LoadPins(a, p.options, p.board)) return fail(*err);
  if (auto err = CheckOutputs(a, extra_outputs, RunInputs(a, p, extra_inputs))) {
    return fail(*err);
  }
  return p;
}

std::optional<RunReport> ExecuteRun(const RunArgs& a, PreparedRun& p, Target& target,
                                    bool console) {
  const Protocol proto = p.resolved.protocol;
  if (p.board) {
    if (auto err = target.WatchPins(*p.board)) {
      Fail(*err);
      return std::nullopt;
    }
  }
  if (auto err = target.Open()) {
    Fail(*err);
    return std::nullopt;
  }
  // The console streams: the title now, the device once it answered, each
  // case's verdict as it ends, the summary last.
  if (console && !a.quiet) {
    std::cout << ConsoleTitle(target.Name(), std::string(ProtocolName(proto))) << std::flush;
  }
  ConsoleStream stream{a, target, std::string(wire::Info(proto).title)};
  if (console) stream.Attach(p.options);
  RunReport report = p.runner->run(target, p.options);
  if (p.options.on_progress) p.options.on_progress(report);  // what the runner did not announce
  p.options.on_progress = nullptr;
  p.options.on_case_start = nullptr;
  report.options.on_progress = nullptr;
  report.options.on_case_start = nullptr;
  if (const auto lost = target.LinkLost()) report.target_error = *lost;
  report.target_caveats = target.Caveats();
  if (console) PrintSummary(a, target, report);
  return report;
}

void AddRunOptions(CLI::App* sub, RunArgs& a, bool subsets) {
  using moco::cli::AddNumber;
  sub->add_option("--target", a.target_text,
                  "in-process:MODEL (e.g. in-process:dmc16, virtual time), pty:PATH or serial:PATH "
                  "(raw 8N1 at --baud), tcp:HOST:PORT, simavr:PATH.elf[@MCU[:HZ]] (AVR "
                  "firmware under simavr on its own clock; default @atmega328p:16000000), or "
                  "native:PATH[@PORT] (a sketch built with mococheck-build-native, in simulated "
                  "time; PORT: serial (default), serial1, serial2 or bluetooth)")
      ->required();
  sub->add_option("--protocol", a.protocol,
                  "Protocol spoken by the target: dmc (DMC v2), dfmoco or stackshot. Default: the "
                  "in-process model's protocol, else dmc");
  sub->add_option("--dialect", a.dialect, DialectHelp())->capture_default_str();
  sub->add_option("--profile", a.profile, "Device profile (JSON) for an in-process target")
      ->check(CLI::ExistingFile);
  AddNumber(sub, "--seed", a.seed, uint64_t{0}, UINT64_MAX, "Seed of the random sequence suite");
  AddNumber(sub, "--steps", a.steps, 1, 100000, "Requests in the random sequence");
  sub->add_option("--junit", a.junit,
                  "Write a JUnit XML report here (one testcase per rule and case)")
      ->check(moco::cli::NonEmptyPath());
  sub->add_option("--json", a.json_path, "Write a JSON report here")
      ->check(moco::cli::NonEmptyPath());
  sub->add_option("--html", a.html_path,
                  "Write a self-contained HTML report here (evidence, transcripts, position plots)")
      ->check(moco::cli::NonEmptyPath());
  AddNumber(sub, "--baud", a.baud, uint32_t{0}, uint32_t{4000000},
            "Baud rate of a pty:/serial: target (default 0: the protocol's: " +
                wire::DefaultBaudList() + ")");
  AddNumber(sub, "--deadline-ms", a.deadline_ms, int64_t{1}, int64_t{600000},
            "DMC-DL-* answer deadline");
  sub->add_option("--deadline", a.deadlines,
                  "Per-kind deadline KIND=MS (kinds: hi, query, command, upload, rt); repeatable, "
                  "overrides --deadline-ms for that kind");
  AddNumber(sub, "--answer-timeout-ms", a.answer_timeout_ms, int64_t{1}, int64_t{600000},
            "DMC-ACK-001: a request unanswered after this has no answer");
  sub->add_flag("--wait-every-answer", a.wait_every_answer,
                "Wait out the answer timeout for every request, even of a kind the device has "
                "left unanswered 3 times in a row (by default such answers are judged missing "
                "at once, which judges a broken device in about the time of a good one with the "
                "same failing rules)");
  AddNumber(sub, "--position-gap-ms", a.position_gap_ms, int64_t{1}, int64_t{600000},
            "DMC-POS-002: the largest gap between position updates while moving");
  AddPinOptions(sub, a.board_path, a.driver);
  sub->add_option("--vcd", a.vcd_path,
                  "Write the watched pins of every case here as a Value Change Dump (GTKWave, "
                  "PulseView, sigrok-cli -I vcd); needs --board")
      ->check(moco::cli::NonEmptyPath());
  sub->add_flag("-v,--verbose", a.verbose, "List passing rules and every case's log");
  sub->add_flag("-q,--quiet", a.quiet, "Print only the result line (and any target caveat)");
  if (subsets) {
    sub->add_option(
        "--rules", a.rules_glob,
        "Only check rules whose id matches: globs separated by commas, e.g. 'DMC-HI-*'");
    sub->add_option("--cases", a.cases_glob,
                    "Only run cases matching suite/name globs, e.g. 'motor/*,rt/*'");
    sub->add_option("--shard", a.shard, "Run only shard i of n (1-based), e.g. 2/4")
        ->capture_default_str();
    sub->add_option("--save-session", a.session_path,
                    "Save a failing random sequence here (JSON Lines, docs/sessions.md)")
        ->check(moco::cli::NonEmptyPath());
  }
}

}  // namespace moco::conformance::cli
