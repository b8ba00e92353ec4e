// The protocols mococheck can certify, one entry each: its rules, its runner
// (core/run.h over the protocol's traits) and its cases. A new protocol is a
// folder beside dmc/, dfmoco/ and stackshot/ and one line in registry.cpp.
#ifndef MOCO_CONFORMANCE_PROTOCOLS_REGISTRY_H_
#define MOCO_CONFORMANCE_PROTOCOLS_REGISTRY_H_

#include <span>
#include <string_view>
#include <vector>

#include "conformance/core/cases.h"
#include "conformance/core/fuzz_protocol.h"
#include "conformance/core/run_report.h"
#include "conformance/rules/catalogue.h"
#include "conformance/targets/target.h"

namespace moco::conformance {

// What mococheck can run for one protocol.
struct ProtocolRunner {
  Protocol protocol;
  const std::vector<Rule>& (*rules)();
  RunReport (*run)(Target& target, const RunOptions& options);
  std::vector<CaseInfo> (*cases)();
  // How the fuzzer and replay treat each protocol this folder speaks (its
  // own, and a dialect another device switches to).
  std::span<const FuzzHooks> (*fuzz)();
  // The dialects mococheck run --dialect may name besides kAutoDialect
  // (empty: the protocol has none and takes kAutoDialect only), and which of
  // them kAutoDialect picks.
  std::span<const DialectChoice> dialects;
  std::string_view auto_picks;
};

// Every protocol with suites, in the catalogue's order.
std::span<const ProtocolRunner> Runners();
// nullptr when the protocol has no runner.
const ProtocolRunner* FindRunner(Protocol p);
// The fuzz hooks of `p`, from whichever runner speaks it; nullptr when none does.
const FuzzHooks* FindFuzzHooks(Protocol p);

}  // namespace moco::conformance

#endif  // MOCO_CONFORMANCE_PROTOCOLS_REGISTRY_H_
