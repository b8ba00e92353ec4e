// Judges the pin rules (conformance/rules/pin_rules.cpp) of one case: the
// watched pins of a firmware under simavr (targets/simavr_pins.h) against the
// positions its protocol reported in the case's traffic, the step driver's
// timing and the board's limits.
#ifndef MOCO_CONFORMANCE_CORE_PIN_JUDGE_H_
#define MOCO_CONFORMANCE_CORE_PIN_JUDGE_H_

#include <string>
#include <vector>

#include "conformance/core/host_link.h"
#include "conformance/core/verdicts.h"
#include "conformance/rules/catalogue.h"
#include "conformance/targets/simavr_pins.h"

namespace moco::conformance {

// What the protocol said about a motor's position, in any protocol's terms
// (a protocol's traits read them from its traffic: PinEvents, core/run.h).
struct PinPositionEvent {
  enum class Kind {
    kReport,     // the device reported `position` (a report or an answer)
    kReset,      // the device's position became `position` without motion (np, zm)
    kPulseRate,  // the motor's pulse rate became `position` steps/s (DFMoco pr)
  };
  Kind kind = Kind::kReport;
  sim::TimeNs t_ns = 0;  // when the device's line was complete
  int motor = 1;         // 1-based
  int64_t position = 0;
};

// A motor with no rising STEP edge for this long after a report was at rest
// when it reported (PIN-001); a trace that ends sooner after a report cannot
// tell, and leaves the report unjudged.
inline constexpr sim::TimeNs kPinRestWindowNs = 50 * sim::kNsPerMs;

struct PinJudgeOptions {
  DriverProfile driver;
  Board board;
  // The planner's acceleration for a pulse rate (DFMoco: rate / 2) and the
  // rate a motor starts with.
  double accel_per_rate = 0.5;
  double default_pulse_rate = 5000;
};

// Rule ids of a protocol's pin family: "<prefix>PIN-001" ... "<prefix>PIN-007".
// Records every check of the case in `v`; `end_ns` is the case's end on the
// target's clock. A report is judged only where the trace holds what its
// rule needs after it: the rest window (PIN-001), a reporting period while
// the motor moves (PIN-002).
void JudgePins(std::string_view prefix, const PinTrace& trace,
               const std::vector<PinPositionEvent>& events, const PinJudgeOptions& options,
               sim::TimeNs end_ns, Verdicts& v);

}  // namespace moco::conformance

#endif  // MOCO_CONFORMANCE_CORE_PIN_JUDGE_H_
