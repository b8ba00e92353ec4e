// The pin rules (issue "firmware truth at the pins"): what a step driver and a
// camera see of a firmware run under simavr, judged against the position the
// protocol reports, the driver's datasheet timing (FACTS "Step drivers") and
// the sketch's motion (FACTS "DFMoco"). One table per protocol whose firmware
// can run under simavr; each rule needs a watched board (SharedNeeds::kPins) and is
// "not applicable" on every other target. The judge is conformance/core/pin_judge.
#include "conformance/rules/catalogue.h"
#include "conformance/rules/dfmoco_needs.h"

namespace moco::conformance {
namespace {

using L = Level;
using N = DfmocoNeeds;

const std::vector<Rule> kDfmocoPinRules = {
    {"DFM-PIN-001", L::kMust, N::kPins,
     "At rest (and at a stop or turn), the reported position (`mp`) equals the signed count of "
     "STEP pulses (DIR sampled at each rising STEP edge) since the firmware started or the last "
     "`np`/`zm`, as it was at most 50 ms before the report",
     "OUT: mp <motor> <position> ... Motor position is in steps.",
     "Motor Position (mp); docs/device-facts.md, Step drivers (a STEP rising edge is one step)"},
    {"DFM-PIN-002", L::kMust, N::kPins,
     "While a motor moves, each reported position is off the signed STEP count by at most the "
     "steps taken one reporting period either side of the report",
     "While moving, `mp m pos` goes out once per second per moving motor ... The reported "
     "position is the planned end of the current 50 ms chunk.",
     "docs/device-facts.md, DFMoco"},
    {"DFM-PIN-003", L::kMust, N::kPins,
     "No STEP pulse is narrower than the driver's minimum high time, and no gap between pulses "
     "shorter than its minimum low time (--driver)",
     "A4988: STEP high >= 1 us and low >= 1 us ... DRV8825: STEP high >= 1.9 us, low >= 1.9 us "
     "... TMC2209 (STEP/DIR mode): about 100 ns high, low",
     "docs/device-facts.md, Step drivers (datasheet timing)"},
    {"DFM-PIN-004", L::kMust, N::kPins,
     "DIR is stable for the driver's setup time before, and its hold time after, every rising "
     "STEP edge (--driver)",
     "DIR setup >= 200 ns before the STEP rising edge and hold >= 200 ns after ... DRV8825: ... "
     "setup and hold >= 650 ns",
     "docs/device-facts.md, Step drivers (datasheet timing)"},
    {"DFM-PIN-005", L::kMust, N::kPins,
     "No 8 consecutive STEP intervals of a motor are shorter than the board's maximum step rate "
     "allows (DFMoco on an Uno: 20 kHz), less 8 us of interrupt latency",
     "one tick raises step pins (phase accumulator carry), the next lowers them: at most 20 kHz "
     "per motor",
     "docs/device-facts.md, DFMoco (step generation); board profile max_step_rate_hz"},
    {"DFM-PIN-006", L::kShould, N::kPins,
     "The step rate, counted over 50 ms windows, changes no faster than the planner's "
     "acceleration (pulse rate / 2 per second) plus 50 % and 3 pulses per window",
     "`pr m v` -> `pr m v`, v clamped to 100..20000 steps/s; acceleration becomes v/2 steps/s^2.",
     "docs/device-facts.md, DFMoco"},
    {"DFM-PIN-007", L::kShould, N::kPins,
     "DIR changes only when the motor has slowed down: the last STEP interval before a "
     "direction change is no faster than the board's reversal rate",
     "Every 50 ms the next velocity chunk is loaded and direction pins set; a direction change "
     "waits one chunk.",
     "docs/device-facts.md, DFMoco (step generation); board profile reversal_max_rate_hz"},
};

}  // namespace

const std::vector<Rule>& DfmocoPinRules() { return kDfmocoPinRules; }

}  // namespace moco::conformance
