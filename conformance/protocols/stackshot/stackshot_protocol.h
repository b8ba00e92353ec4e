// StackShot 3X as the runner sees it (core/run.h): identity and axis
// discovery (stackshot-protocol.txt 1.1.10-1.1.15, CC_RAIL_STATUS per axis),
// which SS-* rules and cases apply, and the PING every case starts with.
#ifndef MOCO_CONFORMANCE_PROTOCOLS_STACKSHOT_STACKSHOT_PROTOCOL_H_
#define MOCO_CONFORMANCE_PROTOCOLS_STACKSHOT_STACKSHOT_PROTOCOL_H_

#include <optional>
#include <string_view>
#include <vector>

#include "conformance/core/run.h"
#include "conformance/protocols/stackshot/stackshot_host.h"
#include "conformance/protocols/stackshot/stackshot_suites.h"

namespace moco::conformance {

struct StackshotProtocol {
  static constexpr Protocol kProtocol = Protocol::kStackshot;
  static constexpr std::string_view kLacking = "the device does not have ";
  using Host = SsHost;
  using Device = SsDeviceInfo;
  using Case = SsCase;
  static const std::vector<SsCase>& Cases() { return StackshotCases(); }
  static const std::vector<Rule>& Rules() { return StackshotRules(); }
  // nullopt when PING went unanswered.
  static std::optional<SsDeviceInfo> Discover(SsHost& probe);
  static void Describe(const SsDeviceInfo& device, RunReport& report);
  static bool Applies(const Need& needs, const SsDeviceInfo& device) {
    return SsApplies(needs, device);
  }
  // The discovered device when the case's PING is answered RSP_OK.
  static std::optional<SsDeviceInfo> Greet(SsHost& host, Target& target,
                                           const SsDeviceInfo& discovered);
  // Rail positions are read, not reported: nothing to plot.
  static PositionSeries Positions(const std::vector<Chunk>& /*traffic*/) { return {}; }
  // The fuzzer's hooks (core/fuzz_protocol.h), in stackshot_fuzz_hooks.cpp.
  static std::span<const FuzzHooks> Fuzz();
};

// The runner over StackshotProtocol (registry.cpp runs it the same way).
inline RunReport RunStackshot(Target& target, const RunOptions& options) {
  return Run<StackshotProtocol>(target, options);
}

}  // namespace moco::conformance

#endif  // MOCO_CONFORMANCE_PROTOCOLS_STACKSHOT_STACKSHOT_PROTOCOL_H_
