// Test support: a proving test plants a fault and shows the rule that names it
// failing. `ExpectCaught` asserts that, and that the failing case explains
// itself (expected and observed); when MOCO_PROOF_LOG names a file it also
// appends "<test name>\t<rule>" to it, so the catalogue's table of proving
// tests (conformance/rules/proofs/*.tsv, shown by `mococheck rules`) is
// checked against what the tests really catch (CTest conformance_rule_proofs,
// tools/rule-proofs update).
#ifndef MOCO_CONFORMANCE_CORE_RULE_PROOF_TESTING_H_
#define MOCO_CONFORMANCE_CORE_RULE_PROOF_TESTING_H_

#include <fcntl.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <set>
#include <string>

#include "conformance/core/report.h"
#include "conformance/core/run_report.h"
#include "conformance/rules/catalogue.h"

namespace moco::conformance::proof {

// Appends one proof line to MOCO_PROOF_LOG (one O_APPEND write, so test
// processes running in parallel never interleave a line).
inline void LogProof(const std::string& rule) {
  const char* path = std::getenv("MOCO_PROOF_LOG");
  if (path == nullptr || *path == '\0') return;
  const ::testing::TestInfo* t = ::testing::UnitTest::GetInstance()->current_test_info();
  if (t == nullptr) return;
  const std::string line = std::string(t->test_suite_name()) + "." + t->name() + "\t" + rule + "\n";
  const int fd = ::open(path, O_WRONLY | O_APPEND | O_CREAT | O_CLOEXEC | O_NOFOLLOW, 0644);
  if (fd < 0) return;
  const ssize_t n = ::write(fd, line.data(), line.size());
  (void)n;
  ::close(fd);
}

// The run judged `rule` `want` (a failure by default), with evidence that
// explains it; a planted fault caught this way is logged as the rule's proof.
inline void ExpectCaught(const RunReport& r, const std::string& rule, Status want = Status::kFail) {
  // MOCOCHECK_PRINT=1 shows what a user of mococheck would see.
  if (std::getenv("MOCOCHECK_PRINT") != nullptr) {
    std::printf("%s\n", ConsoleReport(r, false).c_str());
  }
  ASSERT_TRUE(r.rules.count(rule)) << rule;
  const bool judged = r.rules.at(rule).status == want;
  EXPECT_TRUE(judged) << rule << " is " << StatusName(r.rules.at(rule).status) << ", not "
                      << StatusName(want) << "\n"
                      << ConsoleReport(r, false);
  bool explained = false;
  for (const CaseResult& c : r.cases) {
    auto it = c.outcomes.find(rule);
    if (it == c.outcomes.end() || it->second.evidence.empty()) continue;
    const Evidence& e = it->second.evidence.front();
    explained = explained || (!e.expected.empty() && !e.observed.empty());
  }
  EXPECT_TRUE(explained) << rule << " explains no failure";
  if (judged && explained && want == Status::kFail) LogProof(rule);
}

// The MUST rules a run failed (a planted fault should fail its rule and few others).
inline std::set<std::string> FailedMusts(const RunReport& r) {
  std::set<std::string> out;
  for (const auto& [id, s] : r.rules) {
    const Rule* rule = FindRule(id);
    if (s.status == Status::kFail && rule != nullptr && rule->level == Level::kMust) {
      out.insert(id);
    }
  }
  return out;
}

// The planted fault failed these MUST rules and no other.
inline void ExpectMustsFailed(const RunReport& r, const std::set<std::string>& musts) {
  EXPECT_EQ(FailedMusts(r), musts) << ConsoleReport(r, false);
}

}  // namespace moco::conformance::proof

#endif  // MOCO_CONFORMANCE_CORE_RULE_PROOF_TESTING_H_
