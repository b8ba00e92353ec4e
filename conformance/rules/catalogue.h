// The catalogue of conformance rules for the three device protocols (DMC v2:
// dmc-v2-protocol.txt, ERRATA dmc 1-11, FACTS "DMC v2"; DFMoco; StackShot 3X):
// each rule names the spec clause it enforces, its level and what the device
// must advertise for it to apply. Rule ids carry the protocol's prefix
// ("DMC-", "DFM-", "SS-").
#ifndef MOCO_CONFORMANCE_RULES_CATALOGUE_H_
#define MOCO_CONFORMANCE_RULES_CATALOGUE_H_

#include <array>
#include <iterator>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "conformance/rules/dfmoco_needs.h"
#include "conformance/rules/dmc_needs.h"
#include "conformance/rules/needs.h"
#include "conformance/rules/stackshot_needs.h"
#include "wire/dmc.h"
#include "wire/protocol.h"

namespace moco::conformance {

// A protocol is the wire table's (names, titles, rule prefixes: wire/protocol.h).
using wire::Protocol;
using wire::ProtocolName;
// MUST failures fail the run (exit 1); SHOULD failures are reported only;
// NOTE marks a reading the spec leaves open (ERRATA) and never fails.
enum class Level { kMust, kShould, kNote };
std::string_view LevelName(Level level);  // "MUST", "SHOULD", "NOTE"

struct Rule {
  std::string_view id;  // "DMC-ACK-003"
  Level level = Level::kMust;
  Need needs = SharedNeeds::kNothing;  // the protocol's own (rules/<p>_needs.h) or shared
  std::string_view title;              // one line: what the device must do
  std::string_view clause;  // the spec text enforced, quoted (or the ERRATA/FACTS reading)
  std::string_view source;  // where the clause is: "MSG_FLAG_ACK", "ERRATA 1.4", ...
};

// Every DMC v2 rule, ordered by id family as the catalogue lists them
// (conformance/rules/dmc_rules.cpp).
const std::vector<Rule>& DmcRules();
// Every DFMoco rule (conformance/rules/dfmoco_rules.cpp).
const std::vector<Rule>& DfmocoRules();
// The DFMoco pin rules (conformance/rules/pin_rules.cpp), part of DfmocoRules().
const std::vector<Rule>& DfmocoPinRules();
// Every StackShot 3X rule (conformance/rules/stackshot_rules.cpp).
const std::vector<Rule>& StackshotRules();

// The rules layer's registry: each protocol with rules, in the catalogue's
// order, its rule table and its own needs (a rule needs one of those or one
// of SharedNeeds). A new protocol is one line here.
struct RuleSet {
  Protocol protocol;
  const std::vector<Rule>& (*rules)();
  std::span<const Need> needs;
};
inline constexpr RuleSet kRuleSets[] = {
    {Protocol::kDmc, &DmcRules, DmcNeeds::kOwn},
    {Protocol::kDfmoco, &DfmocoRules, DfmocoNeeds::kOwn},
    {Protocol::kStackshot, &StackshotRules, StackshotNeeds::kOwn},
};
// The protocols with rules, in the catalogue's order (from kRuleSets).
inline constexpr auto kAllProtocols = [] {
  std::array<Protocol, std::size(kRuleSets)> protocols{};
  for (size_t i = 0; i < protocols.size(); ++i) protocols[i] = kRuleSets[i].protocol;
  return protocols;
}();

// The rules of one protocol; empty for a protocol without rules of its own.
const std::vector<Rule>& RulesFor(Protocol p);
// Total number of rules over every protocol.
size_t RuleCount();
// Searches every protocol's rules; nullptr for an unknown id.
const Rule* FindRule(std::string_view id);

// The tests that plant a fault and show this rule failing
// (conformance/rules/proofs/*.tsv, checked by CTest conformance_rule_proofs);
// empty when none is recorded.
std::vector<std::string_view> ProofsOf(std::string_view id);
// Why the rule has its level, read with its clause
// (conformance/rules/reasons/*.tsv); empty when none is recorded.
std::string_view LevelReasonOf(std::string_view id);
// What is wrong with those tables: a malformed line, an id no rule has, a rule
// listed twice in the reasons; empty when they are sound.
std::vector<std::string> RuleTableProblems();

namespace detail {
// The text of one protocol's proofs and reasons tables, compiled in
// (rule_tables.cpp.in, one entry per rules/proofs/<protocol>.tsv).
struct RuleTableText {
  std::string_view protocol;  // the files' name: "dmc"
  std::string_view proofs;
  std::string_view reasons;
};
std::span<const RuleTableText> RuleTableTexts();
}  // namespace detail

// Shell-style match: '*' any run, '?' one character; a comma separates
// alternatives ("DMC-HI-*,DMC-ACK-00?").
bool GlobMatch(std::string_view patterns, std::string_view text);

// The catalogue as Markdown (docs/rules.md) and as plain text (`mococheck rules`).
std::string RulesMarkdown();
std::string RulesText();
// The catalogue as JSON (`mococheck rules --json`): one object per rule with
// its id, level, needs, title, clause, source, reason and proofs.
std::string RulesJson();

}  // namespace moco::conformance

#endif  // MOCO_CONFORMANCE_RULES_CATALOGUE_H_
