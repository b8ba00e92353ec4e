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

// What the device's MSG_HI must advertise for a rule to apply.
enum class Needs {
  kNothing,
  kMotors,          // MOTOR COUNT >= 1
  kTwoMotors,       // MOTOR COUNT >= 2
  kDmx,             // DMX COUNT >= 1
  kGioOut,          // GIO OUT COUNT >= 1
  kGioIn,           // GIO INPUT COUNT >= 1
  kHwLimits,        // HW LIMIT COUNT >= 1 and MOTOR COUNT >= 1
  kRealTime,        // capability 0x0001
  kGoMotion,        // capability 0x0002
  kGoMotion2,       // capability 0x0080
  kLooping,         // capability 0x0200
  kVirtual,         // any of 0x0004, 0x0008, 0x0010, 0x0020
  kNoVirtual,       // none of the virtual capabilities
  kVirtualBoomRig,  // capability 0x0004 (boom-swing-track) and MOTOR COUNT >= 6
  kAimPoint,        // capability 0x0040
  kCoupleMotors,    // capability 0x0100 and MOTOR COUNT >= 2
  kRtDmx,           // capability 0x0001, MOTOR COUNT >= 1 and DMX COUNT >= 1
  kRtTriggers,      // capability 0x0001, MOTOR COUNT >= 1 and GIO OUT COUNT >= 1
  kRtCamera,        // capabilities 0x0001 and 0x0400 (camera trigger), MOTOR COUNT >= 1
  // DFMoco: what the `hi` reply advertises (dfmoco_rules.cpp).
  kDfmMotors,       // `hi` number of axes >= 1
  kDfmTwoMotors,    // `hi` number of axes >= 2
  kDfmJogVelocity,  // `hi` major version >= 2 (the jm velocity argument)
  kDfmGoMotion,     // `hi` version 1.2.7 or later (bf / go)
  kDfmBlurRefusal,  // `hi` version 1.3.1 or later (`bf -1`)
  // StackShot 3X: what the device reports (stackshot_rules.cpp).
  kSsThreeAxes,  // answers CC_RAIL_STATUS for axes X, Y and Z (a StackShot 3X)
  // Any protocol: the target watches the firmware's pins (simavr with --board).
  kPins,
};
std::string_view NeedsText(Needs needs);

struct Rule {
  std::string_view id;  // "DMC-ACK-003"
  Level level = Level::kMust;
  Needs needs = Needs::kNothing;
  std::string_view title;   // one line: what the device must do
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
// order, and its rule table. A new protocol is one line here.
struct RuleSet {
  Protocol protocol;
  const std::vector<Rule>& (*rules)();
};
inline constexpr RuleSet kRuleSets[] = {
    {Protocol::kDmc, &DmcRules},
    {Protocol::kDfmoco, &DfmocoRules},
    {Protocol::kStackshot, &StackshotRules},
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
