// What a run produces (see run_report.h): the roll-up of rule outcomes and
// the exit code.
#include "conformance/core/run_report.h"

#include <algorithm>

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

int ExitCode(const RunReport& report) {
  if (!report.target_error.empty() || report.interrupted_by != 0) return 2;
  return report.MustFailed() ? 1 : 0;
}

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
    }
    report.rules.emplace(std::string(rule.id), s);
  }
}

bool CaseSelected(const RunOptions& options, size_t i, const std::string& name) {
  if (options.shard_count == 0 || i % options.shard_count != options.shard_index) return false;
  return options.cases.empty() || GlobMatch(options.cases, name);
}

}  // namespace moco::conformance
