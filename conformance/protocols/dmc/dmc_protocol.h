// DMC v2 as the runner sees it (core/run.h): discovery and the description of
// the device from MSG_HI (dmc-v2-protocol.txt "Capabilities"), which rules and
// cases apply to what HI advertises, and the greeting every case starts with.
#ifndef MOCO_CONFORMANCE_PROTOCOLS_DMC_DMC_PROTOCOL_H_
#define MOCO_CONFORMANCE_PROTOCOLS_DMC_DMC_PROTOCOL_H_

#include <optional>
#include <vector>

#include "conformance/core/run.h"
#include "conformance/protocols/dmc/dmc_host.h"
#include "conformance/protocols/dmc/dmc_suites.h"
#include "conformance/rules/dmc_needs.h"
#include "wire/dmc.h"

namespace moco::conformance {

// Whether a DMC rule or case with `needs` (DmcNeeds, rules/dmc_needs.h)
// applies to a device that answered HI with `hi`. Needs of the other
// protocols never apply.
bool Applies(const Need& needs, const dmc::HiResponse& hi);
inline bool Applies(const Rule& rule, const dmc::HiResponse& hi) { return Applies(rule.needs, hi); }

struct DmcProtocol {
  static constexpr Protocol kProtocol = Protocol::kDmc;
  static constexpr std::string_view kLacking = "the device does not advertise ";
  static constexpr std::string_view kIntroductionRule = "DMC-HI-016";
  using Host = DmcHost;
  using Device = dmc::HiResponse;
  using Case = DmcCase;
  static const std::vector<DmcCase>& Cases() { return DmcCases(); }
  static const std::vector<Rule>& Rules() { return DmcRules(); }
  static std::optional<dmc::HiResponse> Discover(DmcHost& probe);
  static void Describe(const dmc::HiResponse& hi, RunReport& report);
  static bool Applies(const Need& needs, const dmc::HiResponse& hi) {
    return conformance::Applies(needs, hi);
  }
  static std::optional<dmc::HiResponse> Greet(DmcHost& host, Target& target,
                                              const dmc::HiResponse& discovered);
  // Every MOTOR_GET_POSITION message the device sent.
  static PositionSeries Positions(const std::vector<Chunk>& traffic);
  // The fuzzer's hooks (core/fuzz_protocol.h), in dmc_fuzz_hooks.cpp.
  static std::span<const FuzzHooks> Fuzz();
};

// The runner over DmcProtocol (registry.cpp runs it the same way).
inline RunReport RunDmc(Target& target, const RunOptions& options) {
  return Run<DmcProtocol>(target, options);
}

}  // namespace moco::conformance

#endif  // MOCO_CONFORMANCE_PROTOCOLS_DMC_DMC_PROTOCOL_H_
