// What a mococheck run produces, whatever the protocol: the options it ran
// with, how the device introduced itself, each case's rule outcomes and
// traffic, the roll-up per rule, and the exit code (docs/exit-codes.md).
#ifndef MOCO_CONFORMANCE_CORE_RUN_REPORT_H_
#define MOCO_CONFORMANCE_CORE_RUN_REPORT_H_

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "conformance/core/cases.h"
#include "conformance/core/host_link.h"
#include "conformance/core/pin_judge.h"
#include "conformance/core/verdicts.h"
#include "conformance/rules/catalogue.h"

namespace moco::conformance {

struct RunReport;

struct RunOptions {
  std::string rules;         // GlobMatch over rule ids; empty: all
  std::string cases;         // GlobMatch over "suite/name"; empty: all
  uint32_t shard_index = 0;  // 0-based; this run takes cases i, i+n, i+2n, ...
  uint32_t shard_count = 1;
  HostOptions host;
  RandomOptions random;
  // The driver and board the pin rules judge against (--board, --driver);
  // nullopt: no pin rules apply.
  std::optional<PinJudgeOptions> pins;
  // Called once the device has introduced itself (report.device is set, no
  // case has run yet) and again after each case is appended to report.cases:
  // the console streams its verdicts from here. May be empty.
  std::function<void(const RunReport& report)> on_progress;
  // Called as case `index` (1-based) of the `total` the run selected starts,
  // with what ran so far: the console's progress line. May be empty.
  std::function<void(const RunReport& report, const std::string& case_name, size_t index,
                     size_t total)>
      on_case_start;
};

// Whether case `i` of `count` named suite/name is selected by the shard and
// the --cases globs of `options`.
bool CaseSelected(const RunOptions& options, size_t i, const std::string& name);

// Position reports per motor (1-based): (time, position) samples.
using PositionSeries = std::map<int, std::vector<std::pair<TimeNs, int64_t>>>;

struct CaseResult {
  std::string suite;
  std::string name;
  std::string summary;
  bool applicable = true;
  std::string not_applicable_because;
  // The answers the case did not wait for, the device having left the last
  // requests of their kind unanswered (HostOptions::give_up_after_unanswered);
  // "" when it waited for every answer.
  std::string not_waited_for;
  std::map<std::string, RuleOutcome, std::less<>> outcomes;
  // Why rules could not be judged in this case (Verdicts::NotExercised).
  std::map<std::string, std::string, std::less<>> not_exercised;
  TimeNs target_ns = 0;  // the case's length on the target's clock
  double wall_s = 0;
  std::vector<std::string> log;
  // The case's traffic as it crossed the link (for the HTML report's
  // transcripts and plots); at most kMaxTrafficChunks chunks are kept.
  static constexpr size_t kMaxTrafficChunks = 20000;
  std::vector<Chunk> traffic;
  // The positions the device reported in that traffic (the HTML report's plots).
  PositionSeries positions;
  // The pins watched during the case (a simavr: target with --board), else null.
  std::shared_ptr<const PinTrace> pins;
  bool MustFailed() const;
  // Keeps the first kMaxTrafficChunks chunks of a case's traffic.
  void KeepTraffic(const std::vector<Chunk>& all);
};

struct RuleSummary {
  Status status = Status::kNotExercised;
  uint32_t cases_failed = 0;
  uint32_t cases_passed = 0;
  // Why an applicable rule was not exercised (kNotExercised only): what the
  // cases that could judge it said, or why they did not run.
  std::string why_not_exercised;
};

struct RunReport {
  std::string target;
  std::string protocol = "dmc";  // ProtocolName()
  RunOptions options;
  // How the device introduced itself: one line for the console ("" when it
  // did not answer) and the same as fields for the JSON report.
  std::string device;
  nlohmann::json device_info;
  std::vector<CaseResult> cases;
  std::map<std::string, RuleSummary, std::less<>> rules;  // every rule within the filter
  double wall_s = 0;
  // Set by the caller when the link to the device was lost for good (what
  // happened); the outcomes then prove nothing about the device.
  std::string target_error;
  // What the target says it does not reproduce of the device (Target::Caveats():
  // e.g. simavr timer features the firmware used that are not modelled, a timer
  // interrupt enabled but never fired), set by the caller after the run.
  std::vector<std::string> target_caveats;
  // The signal (SIGINT, SIGTERM, SIGHUP) that stopped the run before every
  // case ran; 0 when it ran to the end.
  int interrupted_by = 0;
  // The case (suite/name) the signal cut short: its outcomes are dropped, as
  // a half-run case proves nothing; "" when none was under way.
  std::string interrupted_case;

  bool MustFailed() const;
  // True when at least one rule passed, failed or was noted: a run that
  // judged nothing has no verdict.
  bool JudgedAnyRule() const;
  // Why the run has no verdict ("" when it has one): the target error, the
  // interrupting signal, or no rule judged.
  std::string NoVerdictReason() const;
  // Counts of rules by status.
  std::map<Status, size_t> RuleCounts() const;
};

// Fills report.rules for every rule of `rules` within options.rules: not
// applicable when `applies` says so, else failed / noted / passed / not
// exercised from the case outcomes.
void SummarizeRules(RunReport& report, const std::vector<Rule>& rules,
                    const std::function<bool(const Rule&)>& applies);

// 2 when the run has no verdict (a target error, it was interrupted, or it
// judged no rule), else 0 when every MUST rule passed, 1 when one failed
// (docs/exit-codes.md).
int ExitCode(const RunReport& report);

}  // namespace moco::conformance

#endif  // MOCO_CONFORMANCE_CORE_RUN_REPORT_H_
