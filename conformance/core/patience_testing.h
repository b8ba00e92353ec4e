// Test support: a broken device is judged in about the time of a good one,
// with the same rules failing as when every answer is waited out
// (HostOptions::give_up_after_unanswered). Times are the target's, which is
// virtual in-process and real over a serial port or a PTY.
#ifndef MOCO_CONFORMANCE_CORE_PATIENCE_TESTING_H_
#define MOCO_CONFORMANCE_CORE_PATIENCE_TESTING_H_

#include <gtest/gtest.h>

#include <functional>
#include <set>
#include <string>

#include "conformance/core/report.h"
#include "conformance/core/run_report.h"

namespace moco::conformance::patience_testing {

// The run's length on the target's clock: the sum of its cases'.
inline TimeNs TargetTime(const RunReport& r) {
  TimeNs t = 0;
  for (const CaseResult& c : r.cases) t += c.target_ns;
  return t;
}

inline std::set<std::string> FailingRules(const RunReport& r) {
  std::set<std::string> ids;
  for (const auto& [id, s] : r.rules) {
    if (s.status == Status::kFail) ids.insert(id);
  }
  return ids;
}

inline size_t CasesThatDidNotWait(const RunReport& r) {
  size_t n = 0;
  for (const CaseResult& c : r.cases) n += !c.not_waited_for.empty();
  return n;
}

// Runs the full suite with `run(options)` on a good device and, broken, with
// and without waiting out every answer; expects the broken device judged in
// at most twice the good one's time, failing at least one rule and the same
// rules either way, with answers it stopped giving not waited for.
inline void ExpectJudgedFast(const std::function<RunReport(const RunOptions&)>& good,
                             const std::function<RunReport(const RunOptions&)>& broken) {
  const RunReport g = good(RunOptions{});
  const RunReport fast = broken(RunOptions{});
  RunOptions waiting;
  waiting.host.give_up_after_unanswered = 0;
  const RunReport slow = broken(waiting);
  EXPECT_EQ(ExitCode(g), 0) << ConsoleReport(g, false);
  EXPECT_FALSE(FailingRules(fast).empty());
  EXPECT_EQ(FailingRules(fast), FailingRules(slow)) << ConsoleReport(fast, false);
  EXPECT_LE(TargetTime(fast), 2 * TargetTime(g))
      << "good " << TargetTime(g) << " ns, broken " << TargetTime(fast)
      << " ns (waiting every answer: " << TargetTime(slow) << " ns)";
  EXPECT_GT(TargetTime(slow), TargetTime(fast));
  EXPECT_GT(CasesThatDidNotWait(fast), 0u) << ConsoleReport(fast, false);
  EXPECT_EQ(CasesThatDidNotWait(slow), 0u);
}

}  // namespace moco::conformance::patience_testing

#endif  // MOCO_CONFORMANCE_CORE_PATIENCE_TESTING_H_
