// DFMoco as the runner sees it (core/run.h): discovery from the `hi` reply
// (dfmoco-protocol.txt "Hello (hi)"; FACTS "DFMoco": dialects 1.2.7, 1.3.x,
// 2.0.0), which DFM-* rules and cases apply to what it advertises, and the
// greeting every case starts with.
#ifndef MOCO_CONFORMANCE_PROTOCOLS_DFMOCO_DFMOCO_PROTOCOL_H_
#define MOCO_CONFORMANCE_PROTOCOLS_DFMOCO_DFMOCO_PROTOCOL_H_

#include <array>
#include <optional>
#include <string_view>
#include <vector>

#include "conformance/core/run.h"
#include "conformance/protocols/dfmoco/dfmoco_host.h"
#include "conformance/protocols/dfmoco/dfmoco_suites.h"
#include "conformance/rules/catalogue.h"
#include "wire/dfmoco.h"

namespace moco::conformance {

// A dotted version "1.3.1" as {1, 3, 1} (missing parts are 0); nullopt when
// the text does not start with a number.
std::optional<std::array<int, 3>> ParseDfmocoVersion(std::string_view text);

// Whether DFMoco `rule` (or a case gated like one) applies to a device that
// answered `hi` with `hello`. Needs outside the DFMoco ones apply only when
// kNothing.
bool DfmocoApplies(const Rule& rule, const dfmoco::HelloReply& hello);
bool DfmocoApplies(Needs needs, const dfmoco::HelloReply& hello);

struct DfmocoProtocol {
  static constexpr Protocol kProtocol = Protocol::kDfmoco;
  static constexpr std::string_view kLacking = "the device does not advertise ";
  using Host = DfmHost;
  using Device = dfmoco::HelloReply;
  using Case = DfmCase;
  static const std::vector<DfmCase>& Cases() { return DfmocoCases(); }
  static const std::vector<Rule>& Rules() { return DfmocoRules(); }
  static std::optional<dfmoco::HelloReply> Discover(DfmHost& probe);
  static void Describe(const dfmoco::HelloReply& hello, RunReport& report);
  static bool Applies(Needs needs, const dfmoco::HelloReply& hello) {
    return DfmocoApplies(needs, hello);
  }
  static std::optional<dfmoco::HelloReply> Greet(DfmHost& host, Target& target,
                                                 const dfmoco::HelloReply& discovered);
  // Every `mp` line the device sent.
  static PositionSeries Positions(const std::vector<Chunk>& traffic);
};

// The runner over DfmocoProtocol (registry.cpp runs it the same way).
inline RunReport RunDfmoco(Target& target, const RunOptions& options) {
  return Run<DfmocoProtocol>(target, options);
}

}  // namespace moco::conformance

#endif  // MOCO_CONFORMANCE_PROTOCOLS_DFMOCO_DFMOCO_PROTOCOL_H_
