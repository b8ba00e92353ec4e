// What `mococheck run` and `mococheck certify` share: their options, the
// checks that turn them into RunOptions before anything runs, the console as
// the run goes, and the reports written after it (docs/files.md,
// docs/exit-codes.md).
#ifndef MOCO_CONFORMANCE_CLI_RUN_SETUP_H_
#define MOCO_CONFORMANCE_CLI_RUN_SETUP_H_

#include <chrono>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <CLI/CLI.hpp>

#include "conformance/cli/commands.h"
#include "conformance/core/run_report.h"
#include "conformance/protocols/registry.h"

namespace moco::conformance::cli {

struct RunArgs {
  std::string target_text, protocol, profile, rules_glob, cases_glob, junit, json_path, html_path,
      shard = "1/1", session_path, board_path, driver, vcd_path, dialect = "auto";
  uint64_t seed = 1;
  int steps = 40;
  uint32_t baud = 0;
  int64_t deadline_ms = 250, answer_timeout_ms = 2000, position_gap_ms = 200;
  std::vector<std::string> deadlines;
  bool verbose = false, quiet = false, wait_every_answer = false;
};

// Adds run's options to `sub`, bound to `a`. `subsets`: also --rules,
// --cases, --shard and --save-session (a certificate always runs the whole
// suite).
void AddRunOptions(CLI::App* sub, RunArgs& a, bool subsets);

// A board profile and a step driver (a name or a profile file; empty: a4988)
// loaded as the pin judge's options, or an error message naming the file.
std::variant<PinJudgeOptions, std::string> LoadPinJudge(const std::string& board_path,
                                                        const std::string& driver_name);
// The --board and --driver options of a command that runs firmware.
void AddPinOptions(CLI::App* sub, std::string& board_path, std::string& driver);

// --dialect's help: the dialects of every protocol that has some.
std::string DialectHelp();
// --dialect checked against the dialects `runner`'s protocol names: an error
// message, or nullopt.
std::optional<std::string> CheckDialect(const std::string& dialect, const ProtocolRunner& runner);
// The cases the run selects: --shard, --rules and --cases checked against the
// protocol's rules and cases and set in `options`. An error message, or nullopt.
std::optional<std::string> SelectCases(const RunArgs& a, const ProtocolRunner& runner,
                                       Protocol proto, RunOptions& options);
// The host's deadlines and timeouts and the random suite's settings, set in
// `options`. An error message (a bad --deadline), or nullopt.
std::optional<std::string> SetHostOptions(const RunArgs& a, RunOptions& options);
// --board and --driver loaded into `board` and the pin judge of `options`.
// An error message, or nullopt.
std::optional<std::string> LoadPins(const RunArgs& a, RunOptions& options,
                                    std::optional<Board>& board);
// Every output checked before the run: each writable, none the --profile, no
// two the same file. `extra`: more (option, path) pairs the command writes.
std::optional<std::string> CheckOutputs(
    const RunArgs& a, const std::vector<std::pair<std::string, std::string>>& extra = {});

// The console as the run goes: the device once it answered, each case's
// verdict as it ends on stdout, and progress on stderr as each case starts.
// Attached to `options`; it must outlive the run.
struct ConsoleStream {
  const RunArgs& a;
  const Target& target;
  std::string title;
  bool device_printed = false;
  size_t printed = 0;
  std::chrono::steady_clock::time_point wall0 = std::chrono::steady_clock::now();

  void PrintDevice(const RunReport& so_far);
  void CaseStarts(const RunReport& so_far, const std::string& name, size_t index, size_t total);
  void Attach(RunOptions& options);
};

// The end of the run on the console: a target error on stderr, then the
// summary (with -q the result line and the target's caveats).
void PrintSummary(const RunArgs& a, const Target& target, const RunReport& report);

// Writes every report asked for (--junit, --html, --vcd, --json); one that
// cannot be written is named and the others still land. The exit status: the
// run's, or kExitUsage when a report is missing.
int WriteReports(const RunArgs& a, const RunReport& report);

// Everything a run needs before its target opens, checked: the target (not
// opened), its protocol's runner and the options. On a usage error the
// message is printed and `exit_code` holds kExitUsage.
struct PreparedRun {
  ResolvedTarget resolved;
  const ProtocolRunner* runner = nullptr;
  RunOptions options;
  std::optional<Board> board;
};
// `extra_outputs`: the command's own files to write (certify's --out), checked
// with the reports; `extra_inputs`: its own files to read (certify's --key),
// which no output may be, as the run's profile, board, driver and firmware
// may not.
std::optional<PreparedRun> PrepareRun(
    const RunArgs& a, int& exit_code,
    const std::vector<std::pair<std::string, std::string>>& extra_outputs = {},
    const std::vector<std::pair<std::string, std::string>>& extra_inputs = {});

// Opens `target` (watching the board's pins when there is one), runs the
// suite with the console streaming (`console` false: nothing printed but an
// error), and returns the report (the caveats and a lost link filled in).
// nullopt, with the message printed, when the target would not open. The
// calls it makes to `target` are the same either way.
std::optional<RunReport> ExecuteRun(const RunArgs& a, PreparedRun& p, Target& target,
                                    bool console = true);

}  // namespace moco::conformance::cli

#endif  // MOCO_CONFORMANCE_CLI_RUN_SETUP_H_
