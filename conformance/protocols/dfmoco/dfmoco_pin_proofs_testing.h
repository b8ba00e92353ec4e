// For the pin rules' proving tests on firmware targets (simavr and native): the
// own DFMoco firmware's whole suite with its pins judged as the CLI's `--board
// fixtures/boards/own-dfmoco.json --driver a4988` judges them, and the check
// that a planted fault fails its rule and no other.
#ifndef MOCO_CONFORMANCE_PROTOCOLS_DFMOCO_DFMOCO_PIN_PROOFS_TESTING_H_
#define MOCO_CONFORMANCE_PROTOCOLS_DFMOCO_DFMOCO_PIN_PROOFS_TESTING_H_

#include <gtest/gtest.h>

#include <set>
#include <string>

#include "conformance/core/own_dfmoco_pins_testing.h"
#include "conformance/core/report.h"
#include "conformance/core/rule_proof_testing.h"
#include "conformance/protocols/dfmoco/dfmoco_protocol.h"
#include "conformance/targets/target.h"

namespace moco::conformance {

// Every DFMoco case on `target` (not yet open), the own firmware's pins judged.
inline RunReport RunOwnDfmocoWithPins(Target& target) {
  const PinJudgeOptions pins = OwnDfmocoPins();
  EXPECT_EQ(target.WatchPins(pins.board), std::nullopt);
  EXPECT_EQ(target.Open(), std::nullopt) << target.Name();
  RunOptions options;
  options.pins = pins;
  return RunDfmoco(target, options);
}

// The fault fails `rule` and no other rule (of any level); a SHOULD rule
// leaves the run's exit code 0.
inline void ExpectOnlyRuleFailed(const RunReport& r, const std::string& rule, bool must) {
  proof::ExpectCaught(r, rule);
  std::set<std::string> failed;
  for (const auto& [id, s] : r.rules) {
    if (s.status == Status::kFail) failed.insert(id);
  }
  EXPECT_EQ(failed, std::set<std::string>{rule}) << ConsoleReport(r, false);
  proof::ExpectMustsFailed(r, must ? std::set<std::string>{rule} : std::set<std::string>{});
  EXPECT_EQ(ExitCode(r), must ? 1 : 0);
}

}  // namespace moco::conformance

#endif  // MOCO_CONFORMANCE_PROTOCOLS_DFMOCO_DFMOCO_PIN_PROOFS_TESTING_H_
