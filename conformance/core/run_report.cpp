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

// Why `rule` was not exercised: the reason a case gave for it
// (Verdicts::NotExercised), or a case log naming it; else how many cases ran
// without reaching it and which did not run.
std::string WhyNotExercised(const RunReport& report, const Rule& rule) {
  if (!report.target_error.empty()) return "no verdict: " + report.target_error;
  const std::string id(rule.id);
  for (const CaseResult& c : report.cases) {
    if (auto it = c.not_exercised.find(id); it != c.not_exercised.end()) {
      return c.suite + "/" + c.name + ": " + it->second;
    }
  }
  for (const CaseResult& c : report.cases) {
    for (const std::string& line : c.log) {
      if (line.find(id) != std::string::npos && line.size() < 400) {
        return c.suite + "/" + c.name + ": " + line;
      }
    }
  }
  size_t ran = 0, not_run = 0;
  std::string first_not_run;
  for (const CaseResult& c : report.cases) {
    if (c.applicable) {
      ++ran;
    } else if (not_run++ == 0) {
      first_not_run = c.suite + "/" + c.name + ": " + c.not_applicable_because;
    }
  }
  std::string why =
      "the " + std::to_string(ran) + " case(s) that ran never reached the situation it judges";
  if (not_run > 0) {
    why += "; " + std::to_string(not_run) + " did not run (" + first_not_run +
           (not_run > 1 ? ", ..." : "") + ")";
  }
  if (!report.options.cases.empty() || report.options.shard_count > 1) {
    why += "; --cases / --shard selected part of the suite";
  }
  return why;
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
