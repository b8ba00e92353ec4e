// The DMC v2 scenario suites of mococheck (dmc-v2-protocol.txt, every section
// a suite exercises is named in its case): fixed, deterministic cases and a
// seeded random sequence of valid requests.
#ifndef MOCO_CONFORMANCE_PROTOCOLS_DMC_DMC_SUITES_H_
#define MOCO_CONFORMANCE_PROTOCOLS_DMC_DMC_SUITES_H_

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "conformance/core/cases.h"
#include "conformance/protocols/dmc/dmc_host.h"
#include "conformance/rules/catalogue.h"
#include "conformance/targets/target.h"

namespace moco::conformance {

// What a DMC v2 case works with: the host has read the device's HI already
// (`device`).
using DmcCaseContext = CaseContextOf<DmcHost, dmc::HiResponse>;
// suite: "connect", "motor", "errors", "limits", "rt", "gomotion", "random".
using DmcCase = CaseOf<DmcCaseContext>;

// Every DMC v2 case in run order.
const std::vector<DmcCase>& DmcCases();

// --- used by the cases and the random suite --------------------------------------------

// Positions from MOTOR_GET_POSITION, or nullopt when the answer is missing.
std::optional<std::vector<int32_t>> GetPositions(DmcHost& host);
// Polls MOTOR_STATUS every 50 ms until nothing moves or `timeout_ns` passes.
// A status of rest is believed when the unsolicited position updates agree:
// when they changed just before it, the host waits one more update period,
// and an update that still moves makes the status stale (recorded, and the
// host goes on waiting until the updates stop changing too).
struct RestWait {
  bool rested = false;
  const DmcRecord* stale_status = nullptr;  // the first status of rest while moving
  const DmcRecord* moved_after = nullptr;   // the update that showed it
};
RestWait WaitRestSeen(DmcHost& host, TimeNs timeout_ns);
bool WaitRest(DmcHost& host, TimeNs timeout_ns);
// As above, and a stale status fails DMC-STAT-004 in the case.
bool WaitRest(DmcCaseContext& c, TimeNs timeout_ns);
// The random suite's case: a sequence of valid motor requests drawn from
// `random.seed`, checked against a model of where each motor must end; a
// failing sequence is shrunk (on a restartable target), printed and saved.
void RandomSequence(DmcCaseContext& c);

}  // namespace moco::conformance

#endif  // MOCO_CONFORMANCE_PROTOCOLS_DMC_DMC_SUITES_H_
