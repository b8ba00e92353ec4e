// The waits of the StackShot 3X suites: how long the host polls, lets a
// motion start, watches for motion that must not happen, gives up waiting
// for rest or for the shutter, and the waits of the random sequence and of
// the fuzz hooks. A wait that follows from a protocol fact is written from
// wire/stackshot_timing.h; the others are the suite's own choices, each with
// what it waits for.
#ifndef MOCO_CONFORMANCE_PROTOCOLS_STACKSHOT_STACKSHOT_TIMING_H_
#define MOCO_CONFORMANCE_PROTOCOLS_STACKSHOT_STACKSHOT_TIMING_H_

#include "sim/scheduler.h"
#include "wire/stackshot_timing.h"

namespace moco::conformance {

// --- The host (stackshot_host.cpp) -------------------------------------------
// CC_SOFTWARE_CHECKSUM's reply deadline (SS-DL-003): host tools time out after 1 s.
inline constexpr sim::TimeNs kSsChecksumDeadlineNs = stackshot::kHostReplyTimeoutNs;

// --- Waiting for rest (SsWaitRest) -------------------------------------------
// CC_RAIL_STATUS is polled as often as host tools poll it (FACTS "StackShot");
// also the period of the position polls without a status, and of the stack
// case's polls (its 0.3 s pulses are long enough for these polls to see).
inline constexpr sim::TimeNs kSsStatusPollNs = stackshot::kHostStatusPollNs;
// Plan choice: without a status to go by, positions unchanged this long count as rest.
inline constexpr sim::TimeNs kSsStillForRestNs = 200 * sim::kNsPerMs;

// --- The random sequence (stackshot_random.cpp) ------------------------------
// Plan choice: how long the sequence waits for every axis to rest: before it
// starts, at each settle step and at its end.
inline constexpr sim::TimeNs kSsRandomRestWaitNs = 60'000 * sim::kNsPerMs;
// Plan choice: the longest wait step; a step waits 0 ms up to this.
inline constexpr sim::TimeNs kSsRandomWaitMaxNs = 800 * sim::kNsPerMs;

// --- The fuzz hooks (stackshot_fuzz_hooks.cpp) -------------------------------
// Plan choice: the pause between two host messages, more than the 2 ms
// inter-frame gap (stackshot-protocol.txt section 2), so a partial packet is
// dropped before the next one.
inline constexpr sim::TimeNs kSsFuzzGapNs = 3 * sim::kNsPerMs;
static_assert(kSsFuzzGapNs > stackshot::kInterFrameGapNs);
// Plan choice: a pause the mutator puts between two messages (an empty
// message, core/fuzz_protocol.h): the host tools' status poll period (FACTS
// "StackShot": every 100 ms), so a rail move runs on with nothing asked.
inline constexpr sim::TimeNs kSsFuzzPauseNs = 100 * sim::kNsPerMs;
// Plan choice: the PING after the session is answered within this.
inline constexpr sim::TimeNs kSsFuzzPingAnswerNs = 500 * sim::kNsPerMs;
// Plan choice: replies still on their way are read until the device is quiet this long.
inline constexpr sim::TimeNs kSsFuzzDrainQuietNs = 50 * sim::kNsPerMs;

namespace ss_cases {

inline constexpr sim::TimeNs kMs = sim::kNsPerMs;  // the unit the waits below are written in

// --- Every case --------------------------------------------------------------
// Plan choice: how long a case waits for its axes to rest (SsWaitRest)
// before it reads where they are.
inline constexpr sim::TimeNs kRestWaitNs = 120'000 * kMs;

// --- connect/resync ----------------------------------------------------------
// Plan choice: the pause after noise and after a partial packet before the
// next request, well over the 2 ms inter-frame gap (SS-PKT-006).
inline constexpr sim::TimeNs kResyncPauseNs = 10 * kMs;
static_assert(kResyncPauseNs > stackshot::kInterFrameGapNs);

// --- Motion that must not happen ---------------------------------------------
// Plan choice: errors/bad-length watches this long after the refused short
// CC_RAIL_MOVE before checking the rail did not move (SS-ERR-003).
inline constexpr sim::TimeNs kBadLengthStillNs = 100 * kMs;
// Plan choice: rail/bad-move after its refused moves (SS-MOVE-005) and
// rail/stop after a CC_RAIL_STOP at rest (SS-STOP-002) watch this long before
// checking the rail did not move.
inline constexpr sim::TimeNs kNoMotionWatchNs = 200 * kMs;

// --- Moves -------------------------------------------------------------------
// Plan choice: how long a long move runs before the case acts during it
// (rail/move-at-speed's MOVE_AT_SPEED, SS-MOVE-004; rail/user-abort's button
// abort, SS-STATUS-005).
inline constexpr sim::TimeNs kMotorStartNs = 200 * kMs;
// Plan choice: how long rail/stop's 200000-step move runs before CC_RAIL_STOP,
// so that it stops under way, short of its target (SS-STOP-001).
inline constexpr sim::TimeNs kRunBeforeStopNs = 300 * kMs;
// Plan choice: a stopped rail rests within this (SS-STOP-001).
inline constexpr sim::TimeNs kStopRestWaitNs = 10'000 * kMs;
// Plan choice: how long rail/user-abort waits after the button abort before
// reading USER_ABORTED (SS-STATUS-005).
inline constexpr sim::TimeNs kAfterAbortNs = 50 * kMs;

// --- rail/shutter ------------------------------------------------------------
// Plan choice: CC_RAIL_STATUS is polled this often while SHUTTER is set.
inline constexpr sim::TimeNs kShutterPollNs = 20 * kMs;
// Plan choice: SHUTTER clears within this (SS-STATUS-004).
inline constexpr sim::TimeNs kShutterClearWaitNs = 10'000 * kMs;
// How long the case's fire of 2 pulses of 0.2 s on and 0.2 s off lasts.
inline constexpr sim::TimeNs kTwoPulsesNs = 800 * kMs;
// Plan choice: how long the out-of-range fire (0 pulses, -1 s on, 0 s off,
// bounded by the device, SS-SHUT-001) is waited out without a status.
inline constexpr sim::TimeNs kBoundedPulsesNs = 1000 * kMs;

// --- config/power-on, nvm/persist --------------------------------------------
// Plan choice: after CC_RESET, PING is sent again after each such pause, 20
// times, so the controller has 2 s to answer (SS-RESET-001).
inline constexpr sim::TimeNs kResetPingPauseNs = 100 * kMs;

// --- stack/run ---------------------------------------------------------------
// Plan choice: a three-frame stack ends within this (SS-STACK-001).
inline constexpr sim::TimeNs kStackRunWaitNs = 60'000 * kMs;

// --- curve/play --------------------------------------------------------------
// Plan choice: after CC_MOTION_START, the curve gets this long to start
// before the case waits for rest (SS-CURVE-001).
inline constexpr sim::TimeNs kCurveStartNs = 100 * kMs;
// Plan choice: the position is read this often while a curve plays (SS-CURVE-005).
inline constexpr sim::TimeNs kCurveSampleNs = 200 * kMs;
// Plan choice: MOVING is checked on a reading at least this far (in seconds)
// from the curve's start and end (SS-CURVE-005).
inline constexpr double kCurveMovingMarginS = 0.5;

}  // namespace ss_cases
}  // namespace moco::conformance

#endif  // MOCO_CONFORMANCE_PROTOCOLS_STACKSHOT_STACKSHOT_TIMING_H_
