// DFMoco as the runner sees it (core/run.h): discovery from the `hi` reply
// (dfmoco-protocol.txt "Hello (hi)"; FACTS "DFMoco": dialects 1.2.7, 1.3.x,
// 2.0.0), which DFM-* rules and cases apply to what it advertises, and the
// greeting every case starts with.
#ifndef MOCO_CONFORMANCE_PROTOCOLS_DFMOCO_DFMOCO_PROTOCOL_H_
#define MOCO_CONFORMANCE_PROTOCOLS_DFMOCO_DFMOCO_PROTOCOL_H_

#include <array>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "conformance/core/run.h"
#include "conformance/protocols/dfmoco/dfmoco_host.h"
#include "conformance/protocols/dfmoco/dfmoco_suites.h"
#include "conformance/rules/catalogue.h"
#include "conformance/rules/dfmoco_needs.h"
#include "wire/dfmoco.h"

namespace moco::conformance {

// A dotted version "1.3.1" as {1, 3, 1} (missing parts are 0); nullopt when
// the text does not start with a number.
std::optional<std::array<int, 3>> ParseDfmocoVersion(std::string_view text);

// Whether DFMoco `rule` (or a case gated like one) applies to a device that
// answered `hi` with `hello`: it decides DfmocoNeeds (rules/dfmoco_needs.h);
// of the other needs only kNothing applies.
bool DfmocoApplies(const Rule& rule, const dfmoco::HelloReply& hello);
bool DfmocoApplies(const Need& needs, const dfmoco::HelloReply& hello);

// Why DFMoco `rule` (or case `k`) does not apply to `device`'s dialect, ""
// when it does: the sketch's own behaviour (FACTS DFMoco) is not judged on a
// StackShot 3X in DfMoco mode, and the DFM-SS-* rules and the "stackshot"
// suite judge only that dialect (stackshot-protocol.txt section 3; ERRATA 3.9).
std::string DfmocoDialectExcludes(std::string_view rule_or_case, const DfmDevice& device);

struct DfmocoProtocol {
  static constexpr Protocol kProtocol = Protocol::kDfmoco;
  static constexpr std::string_view kLacking = "the device does not advertise ";
  static constexpr std::string_view kIntroductionRule = "DFM-HI-008";
  using Host = DfmHost;
  using Device = DfmDevice;
  using Case = DfmCase;
  static const std::vector<DfmCase>& Cases() { return DfmocoCases(); }
  static const std::vector<Rule>& Rules() { return DfmocoRules(); }
  static std::optional<DfmDevice> Discover(DfmHost& probe);
  static void Describe(const DfmDevice& device, RunReport& report);
  static bool Applies(const Need& needs, const dfmoco::HelloReply& hello) {
    return DfmocoApplies(needs, hello);
  }
  static std::optional<DfmDevice> Greet(DfmHost& host, Target& target, const DfmDevice& discovered);
  static std::string RuleNotApplicable(const Rule& rule, const DfmDevice& device) {
    return DfmocoDialectExcludes(rule.id, device);
  }
  static std::string CaseNotApplicable(const DfmCase& k, const DfmDevice& device) {
    return DfmocoDialectExcludes(k.suite + "/" + k.name, device);
  }
  // Every `mp` line the device sent (dfmoco_traffic.cpp).
  static PositionSeries Positions(const std::vector<Chunk>& traffic);
  // The pin rules' family (DFM-PIN-*, conformance/rules/pin_rules.cpp) and
  // what the traffic said of the motors' positions and pulse rates
  // (dfmoco_traffic.cpp).
  static constexpr std::string_view kPinRulePrefix = "DFM-";
  static std::vector<PinPositionEvent> PinEvents(const std::vector<Chunk>& traffic);
  // The fuzzer's hooks (core/fuzz_protocol.h), in dfmoco_fuzz_hooks.cpp.
  static std::span<const FuzzHooks> Fuzz();
  // The longest line a fuzz mutant carries (its line end aside).
  static constexpr size_t kMaxFuzzLine = 96;
  // The dialects a device is judged in (HostOptions::dialect), and which one
  // kAutoDialect picks (DfmHost::stackshot()).
  static constexpr DialectChoice kDialects[] = {
      {kSketchDialect, "Dragonframe's Arduino sketch"},
      {kStackshotDialect,
       "a StackShot 3X in DfMoco mode, stackshot-protocol.txt section 3, as "
       "in-process:stackshot3x runs with --protocol dfmoco"},
  };
  static constexpr std::string_view kAutoPicks =
      "stackshot3x when `hi` is exactly `hi 1 3 1.2.6`, else sketch";
};

// The runner over DfmocoProtocol (registry.cpp runs it the same way).
inline RunReport RunDfmoco(Target& target, const RunOptions& options) {
  return Run<DfmocoProtocol>(target, options);
}

}  // namespace moco::conformance

#endif  // MOCO_CONFORMANCE_PROTOCOLS_DFMOCO_DFMOCO_PROTOCOL_H_
