// What a run produces (see run_report.h): the roll-up of rule outcomes and
// the exit code.
#include "conformance/core/run_report.h"

#include <algorithm>
#include <string>

namespace moco::conformance {

bool CaseResult::MustFailed() const {
  for (const auto& [id, o] : outcomes) {
    const Rule* r = FindRule(id);
    if (o.status == Status::kFail && r != nullptr && r->level == Level::kMust) return true;
  }
  return false;
}

bool RunReport::MustFailed() const {
  for (const auto& [id, s] : rules) {
    const Rule* r = FindRule(id);
    if (s.status == Status::kFail && r != nullptr && r->level == Level::kMust) return true;
  }
  return false;
}

std::map<Status, size_t> RunReport::RuleCounts() const {
  std::map<Status, size_t> n;
  for (const auto& [id, s] : rules) ++n[s.status];
  return n;
}

void CaseResult::KeepTraffic(const std::vector<Chunk>& all) {
  traffic.assign(all.begin(),
                 all.begin() + static_cast<ptrdiff_t>(std::min(all.size(), kMaxTrafficChunks)));
}

bool RunReport::JudgedAnyRule() const {
  return std::any_of(rules.begin(), rules.end(), [](const auto& r) {
    const Status s = r.second.status;
    return s == Status::kPass || s == Status::kFail || s == Status::kNoted;
  });
}

std::string RunReport::NoVerdictReason() const {
  if (!target_error.empty()) return "target error: " + target_error;
  if (interrupted_by != 0) {
    return "interrupted by signal " + std::to_string(interrupted_by) +
           (interrupted_case.empty() ? std::string() : " during " + interrupted_case);
  }
  if (!JudgedAnyRule()) {
    return "no rule was judged: the selected cases and rules (" +
           (options.cases.empty() ? std::string("every case") : "--cases " + options.cases) +
           (options.rules.empty() ? std::string() : ", --rules " + options.rules) +
           ") have nothing in common on this device; widen --cases or --rules";
  }
  return "";
}

int ExitCode(const RunReport& report) {
  if (!report.NoVerdictReason().empty()) return 2;
  return report.MustFailed() ? 1 : 0;
}

namespace {

// Why `rule` was not exercised, from what the run's cases said: a case log
// naming the rule, or one saying what the target could not exercise; else
// the cases that did not run; else the selection.
std::string WhyNotExercised(const RunReport& report, const Rule& rule) {
  const std::string id(rule.id);
  for (const CaseResult& c : report.cases) {
    for (const std::string& line : c.log) {
      if (line.find(id) != std::string::npos && line.size() < 400) {
        return c.suite + "/" + c.name + ": " + line;
      }
    }
  }
  std::string not_exercised, not_run;
  size_t not_run_count = 0;
  for (const CaseResult& c : report.cases) {
    if (!c.applicable) {
      if (not_run_count++ == 0) {
        not_run = c.suite + "/" + c.name + ": " + c.not_applicable_because;
      }
      continue;
    }
    for (const std::string& line : c.log) {
      if (not_exercised.empty() && line.find("not exercised") != std::string::npos &&
          line.size() < 400) {
        not_exercised = c.suite + "/" + c.name + ": " + line;
      }
    }
  }
  std::string why;
  if (!not_exercised.empty()) why = "possibly " + not_exercised;
  if (not_run_count > 0) {
    why += std::string(why.empty() ? "" : "; ") + std::to_string(not_run_count) +
           " case(s) did not run (" + not_run + (not_run_count > 1 ? ", ..." : "") + ")";
  }
  if (!why.empty()) return why;
  if (!report.options.cases.empty() || report.options.shard_count > 1) {
    return "no selected case reached it (--cases / --shard select part of the suite)";
  }
  return "no case reached the situation it judges on this device";
}

}  // namespace

void SummarizeRules(RunReport& report, const std::vector<Rule>& rules,
                    const std::function<bool(const Rule&)>& applies) {
  const RunOptions& options = report.options;
  for (const Rule& rule : rules) {
    if (!options.rules.empty() && !GlobMatch(options.rules, rule.id)) continue;
    RuleSummary s;
    if (!applies(rule)) {
      s.status = Status::kNotApplicable;
    } else {
      bool noted = false;
      for (const CaseResult& c : report.cases) {
        auto it = c.outcomes.find(rule.id);
        if (it == c.outcomes.end()) continue;
        if (it->second.status == Status::kFail)
          ++s.cases_failed;
        else if (it->second.status == Status::kNoted)
          noted = true;
        else
          ++s.cases_passed;
      }
      s.status = s.cases_failed > 0   ? Status::kFail
                 : noted              ? Status::kNoted
                 : s.cases_passed > 0 ? Status::kPass
                                      : Status::kNotExercised;
      if (s.status == Status::kNotExercised) s.why_not_exercised = WhyNotExercised(report, rule);
    }
    report.rules.emplace(std::string(rule.id), s);
  }
}

bool CaseSelected(const RunOptions& options, size_t i, const std::string& name) {
  if (options.shard_count == 0 || i % options.shard_count != options.shard_index) return false;
  return options.cases.empty() || GlobMatch(options.cases, name);
}

}  // namespace moco::conformance
