// Outcomes of conformance rules within one scenario case, with the evidence
// a failure explains itself with (h2spec style: expected, observed, bytes, time).
#ifndef MOCO_CONFORMANCE_CORE_VERDICTS_H_
#define MOCO_CONFORMANCE_CORE_VERDICTS_H_

#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "conformance/rules/catalogue.h"
#include "sim/scheduler.h"

namespace moco::conformance {

// kNoted: a NOTE rule whose reading the device takes (never a failure).
// kNotExercised: applicable, but no case in the run reached the check.
enum class Status { kPass, kFail, kNoted, kNotApplicable, kNotExercised };
std::string_view StatusName(Status s);  // "pass", "fail", "note", "n/a", "not exercised"

struct Evidence {
  std::string expected;
  std::string observed;
  std::string hex;       // the bytes concerned, lower-case hex; may be empty
  sim::TimeNs t_ns = 0;  // on the target's clock
};

struct RuleOutcome {
  Status status = Status::kPass;
  uint32_t checks = 0;
  uint32_t failures = 0;
  std::vector<Evidence> evidence;  // the first few failures (or notes)
};

// The rule outcomes of one case. Checks of rules outside `filter` (a GlobMatch
// pattern; empty: all) are not recorded.
class Verdicts {
 public:
  static constexpr size_t kMaxEvidence = 3;

  explicit Verdicts(std::string filter = {}) : filter_(std::move(filter)) {}

  // Records one evaluation of rule `id`. `make_evidence` (returns Evidence) is
  // called only when !ok. REQUIRES: FindRule(id) != nullptr. Returns ok.
  template <typename F>
  bool Check(std::string_view id, bool ok, F&& make_evidence) {
    RuleOutcome* o = Slot(id);
    if (o == nullptr) return ok;
    ++o->checks;
    if (!ok) Record(*o, id, make_evidence());
    return ok;
  }
  bool Pass(std::string_view id) {
    return Check(id, true, [] { return Evidence{}; });
  }
  bool Fail(std::string_view id, Evidence e) {
    return Check(id, false, [&] { return std::move(e); });
  }

  // Records why rule `id` could not be judged in this case (the target cannot
  // press an e-stop, the device never gave occasion), kept with the rule when
  // no case judged it; the first reason given is kept. Muted, filtered and
  // excluded rules are ignored as for Check. REQUIRES: FindRule(id) != nullptr.
  void NotExercised(std::string_view id, std::string why);
  const std::map<std::string, std::string, std::less<>>& not_exercised() const {
    return not_exercised_;
  }

  // While muted, checks are not recorded: the runner's preparation of the
  // device before a case (settling it, enabling motors) is not a verdict.
  void set_muted(bool muted) { muted_ = muted; }
  bool muted() const { return muted_; }

  // Rules `excluded` names are not judged at all (a DFMoco device's dialect
  // the rule does not apply to); empty: none.
  void set_excluded(std::function<bool(std::string_view id)> excluded) {
    excluded_ = std::move(excluded);
  }

  const std::map<std::string, RuleOutcome, std::less<>>& outcomes() const { return outcomes_; }
  // True when a MUST rule failed in this case.
  bool MustFailed() const;

 private:
  RuleOutcome* Slot(std::string_view id);
  void Record(RuleOutcome& o, std::string_view id, Evidence e);

  std::string filter_;
  std::map<std::string, RuleOutcome, std::less<>> outcomes_;
  std::map<std::string, std::string, std::less<>> not_exercised_;
  bool muted_ = false;
  std::function<bool(std::string_view)> excluded_;
};

// Mutes `v` for its lifetime (restoring what it was).
class MutedVerdicts {
 public:
  explicit MutedVerdicts(Verdicts& v) : v_(v), was_(v.muted()) { v_.set_muted(true); }
  ~MutedVerdicts() { v_.set_muted(was_); }
  MutedVerdicts(const MutedVerdicts&) = delete;
  MutedVerdicts& operator=(const MutedVerdicts&) = delete;

 private:
  Verdicts& v_;
  bool was_;
};

}  // namespace moco::conformance

#endif  // MOCO_CONFORMANCE_CORE_VERDICTS_H_
