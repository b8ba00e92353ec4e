// How long the DFMoco suites wait and what time windows their checks allow: the
// cases (dfmoco_cases*.cpp), the wait for rest they share, the greeting
// (dfmoco_protocol.cpp), the random sequence (dfmoco_random.cpp) and the fuzz hooks
// (dfmoco_fuzz_hooks.cpp). Each is the runner's own choice unless its comment names
// the rule, spec clause or fact it serves; the protocol's own timing (the baud rate,
// the `mp` report period, the go-motion ramps) is in wire/dfmoco_timing.h and the
// sketch's chunk in sim/planner_dfmoco.h.
#ifndef MOCO_CONFORMANCE_PROTOCOLS_DFMOCO_DFMOCO_TIMING_H_
#define MOCO_CONFORMANCE_PROTOCOLS_DFMOCO_DFMOCO_TIMING_H_

#include "sim/scheduler.h"
#include "wire/dfmoco_timing.h"

namespace moco::conformance::dfmoco_cases {

// A millisecond, to write durations in and to print them.
inline constexpr sim::TimeNs kMs = sim::kNsPerMs;

// --- waiting for rest (DfmWaitRest, the cases' Rest) -----------------------------------
// Plan choice: how long a case waits for every motor to rest (DFM-MS-004).
inline constexpr sim::TimeNs kRestTimeout = 120'000 * kMs;
// Plan choice: DfmWaitRest's `ms` polling period.
inline constexpr sim::TimeNs kPollNs = 50 * kMs;
// Plan choice: with `ms` unanswered, positions unchanged this long count as rest.
inline constexpr sim::TimeNs kStillForRest = 150 * kMs;

// --- what the checks allow -------------------------------------------------------------
// FACTS: `mp` once a second (DFM-MP-003, DFM-MP-004).
inline constexpr sim::TimeNs kReportPeriodNs = dfmoco::kReportPeriodNs;
// DFM-SM-002 / SA-002 / SS-007 "fairly quickly": at rest within 5 s of the stop.
inline constexpr sim::TimeNs kStopWithinNs = 5000 * kMs;
// DFM-MP-002 / SS-003: a motor that moves for more than 1.5 s is reported while it moves.
inline constexpr sim::TimeNs kLongMoveNs = 1500 * kMs;
// DFM-PR-003: the pulse-rate case's 1500 steps at pr 1000 take at least 1.5 s.
inline constexpr sim::TimeNs kPulseRateMoveMinNs = 1500 * kMs;
// DFM-GO-006's tolerance on the go-motion move's length and on each sample along it.
inline constexpr sim::TimeNs kGoWithinNs = 150 * kMs;
// Plan choice (DFM-HI-001): the boot `hi` is looked for within 1 s of power-on, and
// the greeting waits that long for it before sending its own `hi`.
inline constexpr sim::TimeNs kBootHiWithinNs = 1000 * kMs;

// --- how long the cases let the device act ---------------------------------------------
// Plan choice (DFM-MP-007): after any report still owed, how long the queries case
// listens for a line at rest.
inline constexpr sim::TimeNs kQuietAtRestNs = 2500 * kMs;
// Plan choice: how long a case listens for the answer to a line that may get none (a
// command ended by a bare "\n", DFM-LINE-007; unknown words, DFM-REPLY-003).
inline constexpr sim::TimeNs kListenForReplyNs = 300 * kMs;
// Plan choice: lets a motor just commanded get under way before the case goes on (`np`
// while it moves, DFM-SS-006; the wait for the end of a jog at a velocity, DFM-JM-003).
inline constexpr sim::TimeNs kMotorStartNs = 300 * kMs;
// Plan choice: how long the stop case's motors move before `sm 1` (DFM-SM-002).
inline constexpr sim::TimeNs kMoveBeforeStopNs = 1200 * kMs;
// Plan choice: after `sm 1`, when `ms` checks that motor 2 still moves (DFM-SM-003).
inline constexpr sim::TimeNs kAfterStopCheckNs = 200 * kMs;
// Plan choice: how long the stop-all case's motors move before `sa` (DFM-SA-002).
inline constexpr sim::TimeNs kMoveBeforeStopAllNs = 1500 * kMs;
// The fast reversal's motor at pr 20000 reaches 20000 steps/s after 2 s at 10000
// steps/s^2 (FACTS: acceleration pr / 2); plan choice: 300 ms more at that speed.
inline constexpr sim::TimeNs kReachTopRateNs = 2300 * kMs;
// Plan choice: `jm` repeated this often, as a host does while the jog button is held.
inline constexpr sim::TimeNs kJogRepeatNs = 200 * kMs;
// Plan choice: after `bf -1`, how long before the case checks that nothing moves
// (DFM-GO-008).
inline constexpr sim::TimeNs kAfterBlurRefusedNs = 200 * kMs;

// --- the StackShot 3X dialect's cases --------------------------------------------------
// Plan choice: after the first answer to `mp *`, how long the case reads the other
// motors' lines (DFM-SS-004).
inline constexpr sim::TimeNs kMpAllLinesNs = 300 * kMs;
// Plan choice: how long the motors move before `sa 1` (DFM-SS-007).
inline constexpr sim::TimeNs kSsMoveBeforeStopAllNs = 500 * kMs;
// Plan choice: how long after `bf`, and again after `go`, the case listens for a
// go-motion answer or motion (DFM-SS-009).
inline constexpr sim::TimeNs kSsGoMotionListenNs = 1500 * kMs;

// --- the random sequence (dfmoco_random.cpp) -------------------------------------------
// Plan choice: how long the sequence's settle steps and its end wait for rest.
inline constexpr sim::TimeNs kRandomRestTimeoutNs = 600'000 * kMs;

// --- the fuzz hooks (dfmoco_fuzz_hooks.cpp) --------------------------------------------
// Plan choice: the spacing a saved finding's messages are written with.
inline constexpr sim::TimeNs kFuzzGapNs = 1 * kMs;
// Plan choice: a pause the mutator puts between two messages (an empty
// message, core/fuzz_protocol.h): Dragonframe's polling period while a motor
// moves, as the golden session shows (fixtures/sessions/dfmoco-uno-workflow.jsonl:
// `ms` and `mp` 250 ms apart). A run otherwise follows each answer at once and
// never lets a move run its course.
inline constexpr sim::TimeNs kFuzzPauseNs = 250 * kMs;
// A host waits for the answer before the next command, as Dragonframe does (the
// sketch's 57600 baud line and 16-message queue cannot keep up with more). A
// message with commands every sketch answers is followed as soon as their reply
// lines have come, and the line has then been quiet for kFuzzReplyQuietNs: two
// byte frames at the baud rate, so that a line queued behind a reply (`zm`'s
// second `mp`) comes within it. A message with none is followed once the line
// has been quiet for kFuzzSettleQuietNs. Either waits at most kFuzzSettleMaxNs,
// and a reply not come by then counts as lost (plan choices).
inline constexpr sim::TimeNs kFuzzReplyQuietNs =
    2 * 10 * sim::kNsPerSecond / moco::dfmoco::kBaudRate;
inline constexpr sim::TimeNs kFuzzSettleQuietNs = 5 * kMs;
inline constexpr sim::TimeNs kFuzzSettleMaxNs = 100 * kMs;
// Plan choice: the sketch's boot greeting comes within this of power-on.
inline constexpr sim::TimeNs kFuzzBootGreetingNs = 3000 * kMs;
// Plan choice: each of the two `hi` after the session is answered within this;
// no answer to either, while the firmware runs, is a hang.
inline constexpr sim::TimeNs kFuzzHiAnswerNs = 1000 * kMs;
// Plan choice: what is read after that answer, for lines still on their way, until
// the line has been quiet this long: a transmitter's backlog goes out byte after
// byte at the line rate, so a quiet of some byte frames means nothing is left.
inline constexpr sim::TimeNs kFuzzTailNs = 2 * kMs;
// Plan choice: the longest the end of a run waits for output still on its way
// (quiet for kFuzzTailNs ends it sooner); a backlog of about 11 kB at 57600 baud.
inline constexpr sim::TimeNs kFuzzDrainMaxNs = 2000 * kMs;
// Plan choice: a write the every-request-answered law judges holds at most this
// many bytes (less than the Arduino core's 64-byte receive buffer).
inline constexpr size_t kFuzzJudgedWriteBytes = 60;

}  // namespace moco::conformance::dfmoco_cases

#endif  // MOCO_CONFORMANCE_PROTOCOLS_DFMOCO_DFMOCO_TIMING_H_
