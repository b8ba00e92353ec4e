// Rule outcomes of one conformance case (see verdicts.h).
#include "conformance/core/verdicts.h"

#include <cassert>

namespace moco::conformance {

std::string_view StatusName(Status s) {
  switch (s) {
    case Status::kPass:
      return "pass";
    case Status::kFail:
      return "fail";
    case Status::kNoted:
      return "note";
    case Status::kNotApplicable:
      return "n/a";
    case Status::kNotExercised:
      return "not exercised";
  }
  return "?";
}

RuleOutcome* Verdicts::Slot(std::string_view id) {
  assert(FindRule(id) != nullptr && "rule id missing from the catalogue");
  if (muted_) return nullptr;
  if (!filter_.empty() && !GlobMatch(filter_, id)) return nullptr;
  if (excluded_ && excluded_(id)) return nullptr;
  auto it = outcomes_.find(id);
  if (it == outcomes_.end()) it = outcomes_.emplace(std::string(id), RuleOutcome{}).first;
  return &it->second;
}

void Verdicts::NotExercised(std::string_view id, std::string why) {
  assert(FindRule(id) != nullptr && "rule id missing from the catalogue");
  if (muted_) return;
  if (!filter_.empty() && !GlobMatch(filter_, id)) return;
  if (excluded_ && excluded_(id)) return;
  not_exercised_.emplace(std::string(id), std::move(why));
}

void Verdicts::Record(RuleOutcome& o, std::string_view id, Evidence e) {
  const Rule* rule = FindRule(id);
  ++o.failures;
  o.status = rule != nullptr && rule->level == Level::kNote ? Status::kNoted : Status::kFail;
  if (o.evidence.size() < kMaxEvidence) o.evidence.push_back(std::move(e));
}

bool Verdicts::MustFailed() const {
  for (const auto& [id, o] : outcomes_) {
    const Rule* rule = FindRule(id);
    if (o.status == Status::kFail && rule != nullptr && rule->level == Level::kMust) return true;
  }
  return false;
}

}  // namespace moco::conformance
