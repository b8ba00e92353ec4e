// The StackShot 3X scenario suites of mococheck (stackshot-protocol.txt
// sections 1.1 and 2; ERRATA stackshot; FACTS "StackShot"): fixed cases named
// by what they exercise and a seeded random sequence of valid requests.
#ifndef MOCO_CONFORMANCE_PROTOCOLS_STACKSHOT_STACKSHOT_SUITES_H_
#define MOCO_CONFORMANCE_PROTOCOLS_STACKSHOT_STACKSHOT_SUITES_H_

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "conformance/core/cases.h"
#include "conformance/protocols/stackshot/stackshot_host.h"
#include "conformance/rules/catalogue.h"
#include "conformance/rules/needs.h"
#include "conformance/rules/stackshot_needs.h"
#include "conformance/targets/target.h"

namespace moco::conformance {

// How the device introduced itself (identity reads and an axis probe).
struct SsDeviceInfo {
  bool answered = false;    // PING was answered
  bool three_axes = false;  // CC_RAIL_STATUS answered RSP_OK for axes Y and Z
  std::optional<std::string> software_string;
  std::optional<uint32_t> software_id;
  std::optional<uint32_t> hardware_id;
  std::optional<uint32_t> bootloader_id;
  std::optional<uint32_t> serial_number;
};

// Reads the identity with `host` (its checks land in the host's verdicts).
SsDeviceInfo DiscoverStackshot(SsHost& host);
// Whether a StackShot rule or case with `needs` (StackshotNeeds,
// rules/stackshot_needs.h) applies to `device`.
bool SsApplies(const Need& needs, const SsDeviceInfo& device);

// What a StackShot case works with: the host has had a PING answered, and
// `device` is what discovery read of the device.
using SsCaseContext = CaseContextOf<SsHost, SsDeviceInfo>;
// suite: "connect", "errors", "rail", "config", "nvm", "stack", "curve", "random".
using SsCase = CaseOf<SsCaseContext>;

// Every StackShot 3X case in run order.
const std::vector<SsCase>& StackshotCases();

// --- used by the cases, the random suite and the tests --------------------------------

// The current (or target) rail position of `axis` in steps; nullopt without
// an RSP_OK reply.
std::optional<int64_t> SsPositionSteps(SsHost& host, uint8_t axis, bool target = false);
// CC_RAIL_STATUS of `axis`; nullopt without an RSP_OK reply.
std::optional<uint32_t> SsRailStatus(SsHost& host, uint8_t axis);
// Polls CC_RAIL_STATUS of each axis in `axes` every 100 ms (as host tools
// do) until none moves or `timeout_ns` passes. True at rest.
bool SsWaitRest(SsHost& host, const std::vector<uint8_t>& axes, TimeNs timeout_ns);
// The random suite's case: a seeded sequence of valid rail requests checked
// against a model of the status each may get and where each axis must rest;
// a failing sequence is shrunk on a restartable target, printed and saved.
void SsRandomSequence(SsCaseContext& c);

}  // namespace moco::conformance

#endif  // MOCO_CONFORMANCE_PROTOCOLS_STACKSHOT_STACKSHOT_SUITES_H_
