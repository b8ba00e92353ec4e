// The DFMoco scenario suites of mococheck (dfmoco-protocol.txt, every section
// a case exercises is named in it; FACTS "DFMoco"): fixed, deterministic cases
// and a seeded random sequence of valid commands with a model of where every
// motor must come to rest.
#ifndef MOCO_CONFORMANCE_PROTOCOLS_DFMOCO_DFMOCO_SUITES_H_
#define MOCO_CONFORMANCE_PROTOCOLS_DFMOCO_DFMOCO_SUITES_H_

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "conformance/core/cases.h"
#include "conformance/protocols/dfmoco/dfmoco_host.h"
#include "conformance/rules/catalogue.h"
#include "conformance/targets/target.h"

namespace moco::conformance {

// What a DFMoco case works with: the host has read the device's `hi`
// already (`device`).
using DfmCaseContext = CaseContextOf<DfmHost, DfmDevice>;
// suite: "connect", "motor", "errors", "gomotion", "shoot", "stackshot", "random".
using DfmCase = CaseOf<DfmCaseContext>;

// Every DFMoco case in run order.
const std::vector<DfmCase>& DfmocoCases();

// --- used by the cases, the random suite and the tests ---------------------------------

// The position `mp m` reports, or nullopt when the answer is missing.
std::optional<int32_t> DfmPosition(DfmHost& host, int32_t motor);

// The outcome of polling `ms` until every motor rests.
struct DfmRest {
  bool rested = false;
  TimeNs rest_ns = 0;  // the `ms` answer that showed every motor at rest
  // Per motor (index motor - 1): the last `ms` answer that showed it moving,
  // or -1 when none did.
  std::vector<TimeNs> last_moving_ns;
};
// Polls `ms` every 50 ms until every digit is 0 or `timeout_ns` passes;
// `while_moving`, when set, runs after each `ms` answer that shows a motor
// moving (to sample positions along the move).
DfmRest DfmWaitRest(DfmHost& host, TimeNs timeout_ns,
                    const std::function<void()>& while_moving = {});

// The random suite's case: a sequence of valid commands drawn from
// `random.seed`, checked against a model of where each motor must rest; a
// failing sequence is shrunk (on a restartable target), printed and saved as
// a session file (docs/sessions.md).
void DfmRandomSequence(DfmCaseContext& c);

}  // namespace moco::conformance

#endif  // MOCO_CONFORMANCE_PROTOCOLS_DFMOCO_DFMOCO_SUITES_H_
