// The DMC v2 suite's own waits, polls and tolerance windows: how long a case
// lets motion start, waits for rest, listens for a report and judges one late,
// and the waits of the random sequence, the fuzz hooks and the greeting before
// each case (dmc_protocol.cpp). Each says why it has its value: the rule whose
// text gives it, or a plan choice and what it waits for. The protocol's own
// timing facts are in wire/dmc_timing.h; a wait that follows from one is
// written from it.
#ifndef MOCO_CONFORMANCE_PROTOCOLS_DMC_DMC_TIMING_H_
#define MOCO_CONFORMANCE_PROTOCOLS_DMC_DMC_TIMING_H_

#include <cstdint>

#include "sim/scheduler.h"
#include "wire/dmc_timing.h"

namespace moco::conformance {

using sim::TimeNs;

namespace dmc_cases {

inline constexpr TimeNs kMs = sim::kNsPerMs;

// --- Rest (WaitRest, dmc_cases.cpp) ------------------------------------------------
// Plan choice: how long a case waits for every motor to rest after a move, a
// jog or a run before it goes on regardless.
inline constexpr TimeNs kRestWaitNs = 60'000 * kMs;
// Plan choice: how long a case waits for rest after it stopped the motion
// (MOTOR_STOP, STOP_ALL, VIRT_STOP, VIRT_JOG_ON_LINE speed 0) before judging
// it still moving (DMC-STOP-001, DMC-STOP-002; "within 10 s" in DMC-VIRT-007's
// and DMC-VIRT-008's evidence).
inline constexpr TimeNs kStopRestWaitNs = 10'000 * kMs;
// Plan choice: WaitRestSeen and the greeting poll MOTOR_STATUS this often while
// they wait for rest.
inline constexpr TimeNs kRestPollNs = 50 * kMs;
// A device "should send [position updates] about every 0.10 seconds, if any of
// the motors are moving": a rest the updates have not contradicted for an
// update period and half of one again (from the last update or the last
// command) is believed.
inline constexpr TimeNs kRestQuietNs = dmc::kPositionUpdatePeriodNs * 3 / 2;  // 150 ms
// How long after a command a device may take to start its motion (two of
// dmc-lite's 20 ms motion ticks, and a margin): a MOTOR_STATUS of 0 asked
// before then is not stale.
inline constexpr TimeNs kStartLatencyNs = 2 * dmc::kReferenceMotionTickNs + 10 * kMs;  // 50 ms

// --- Connect and I/O -----------------------------------------------------------
// DMC-HI-011: how long the boot HI is waited for once the case looks; plan
// choice (the spec says only "whenever it starts up", so a HI that comes while
// the case waits counts, whatever the device's start-up took).
inline constexpr TimeNs kBootHiWithinNs = 1000 * kMs;
// DMC-GIO-005 evidence: an unsolicited GIO_IN "within 1 s of the change";
// plan choice (the spec says "any time the inputs change").
inline constexpr TimeNs kGioInChangeWithinNs = 1000 * kMs;
// DMC-DMX-003: "DMX STATUS 0 again within 30 s of a full-range ramp".
inline constexpr TimeNs kDmxRampEndWithinNs = 30'000 * kMs;
// Plan choice: MOTOR_STATUS is polled this often while the ramp runs, as a
// host waiting for the rig to settle would.
inline constexpr TimeNs kDmxRampPollNs = 100 * kMs;

// --- Motors ----------------------------------------------------------------------
// Plan choice: Move lets the 2000-step move get under way before MOTOR_STATUS
// must show motor 1 moving (DMC-STAT-004).
inline constexpr TimeNs kMoveUnderWayNs = 250 * kMs;
// Plan choice: after the move rests, Move listens this long for the update
// that reports the final position (DMC-POS-004) before it reads the updates.
inline constexpr TimeNs kMoveLastUpdateNs = 300 * kMs;
// DMC-POS-003 (NOTE, updates "much more often than every 100 ms"): noted when
// the mean gap is below three quarters of the spec's update period; plan
// choice of the fraction.
inline constexpr TimeNs kUpdateMeanFloorNs = dmc::kPositionUpdatePeriodNs * 3 / 4;  // 75 ms
// Plan choice: Stop lets motor 1 run towards its far target this long before
// MOTOR_STOP (DMC-STOP-001).
inline constexpr TimeNs kRunBeforeStopNs = 500 * kMs;
// Plan choice: StopAll lets the motors run this long before STOP_ALL; motor 1
// is then at about 1600 steps/s (DMC-STOP-005).
inline constexpr TimeNs kRunBeforeStopAllNs = 400 * kMs;
// Plan choice: each StopDistance run lasts this long before its STOP_ALL, one
// or two (DMC-STOP-004).
inline constexpr TimeNs kRunBeforeHardStopNs = 600 * kMs;
// Plan choice: a wait past any "soon after" window of MSG_MOTOR_STOP_ALL, so
// that the next STOP_ALL is a first one again (DMC-STOP-004; the spec gives
// none, the DMC-16 model's default is 1 s).
inline constexpr TimeNs kPastHardStopWindowNs = 1500 * kMs;
// DMC-RST-002 evidence: the confirming MOTOR_GET_POSITION "after the ACK,
// within 500 ms"; plan choice (the spec gives no time).
inline constexpr TimeNs kResetUpdateWithinNs = 500 * kMs;
// Plan choice: each JogSpeeds leg jogs this long before its position is read;
// at 3000 steps/s and 6000 steps/s^2 a full-speed jog covers about 1000 steps
// in it and 1% of it under 20 (DMC-CFG-006).
inline constexpr TimeNs kJogLegNs = 600 * kMs;
// Plan choice: NoHostAck asks MOTOR_STATUS four times this far apart, 600 ms
// of motion with no update ACKed (DMC-UNS-002).
inline constexpr TimeNs kNoAckPollNs = 150 * kMs;
// Plan choice: the move under way before the runner presses the e-stop or
// closes a limit switch (DMC-UNS-003, DMC-LIM-007).
inline constexpr TimeNs kRunBeforeSwitchNs = 300 * kMs;
// DMC-UNS-003 and DMC-LIM-007 evidence: MOTOR_HARD_STOP "within 500 ms" of the
// e-stop or of the switch closing; plan choice (the spec gives no time).
inline constexpr TimeNs kHardStopReportWithinNs = 500 * kMs;
// DMC-LIM-007 evidence: motor 1 "at rest within 200 ms" of its limit switch
// closing; plan choice (the spec gives no time).
inline constexpr TimeNs kLimitHaltWithinNs = 200 * kMs;
// Plan choice: after a refused (ERR_SOFT_LOW) or corrupted MOTOR_MOVE, any
// motion it wrongly started has this long to show before the positions are
// read (DMC-LIM-003, DMC-CSUM-005).
inline constexpr TimeNs kRefusedMoveShowNs = 200 * kMs;

// --- Real-time runs and go-motion ----------------------------------------------------
// The frame rate of the cases' runs (ShortRun, RT_RUN_MOVE FPS) and its frame
// interval (DMC-RT-007, DMC-RT-023).
inline constexpr uint16_t kRunFps = 24;
inline constexpr TimeNs kRunFrameNs = sim::kNsPerSecond / kRunFps;
// Plan choice: ShortRun's PRE-ROLL and POST-ROLL TIME (ms on the wire).
inline constexpr uint32_t kShortRunRollMs = 500;
// Plan choice: Go() retries RT_GO this often while the device answers
// ERR_NOT_IN_POSITION, for up to kArmingLimitNs (dmc-lite arms for 40-60 ms,
// FACTS "DMC v2"); DMC-RT-015 judges the delay.
inline constexpr TimeNs kArmingRetryNs = 10 * kMs;
inline constexpr TimeNs kArmingLimitNs = 1000 * kMs;
// Plan choice: how long a run's RT_END is waited for after GO ("none within
// 20 s" in DMC-RT-005's and DMC-RT-021's evidence).
inline constexpr TimeNs kRunEndWaitNs = 20'000 * kMs;
// Plan choice: after RT_END, LiveRun listens this long for a second one
// (DMC-RT-006).
inline constexpr TimeNs kSecondRtEndWatchNs = 500 * kMs;
// Plan choice: the frame reports' slack on a real clock, either side of half
// to one and a half frame intervals (DMC-RT-007); none on a virtual clock.
inline constexpr TimeNs kFrameReportSlackNs = 30 * kMs;
// Plan choice: StopRun waits this long for the run to report frame 3 before
// its STOP_ALL.
inline constexpr TimeNs kRunFrameWaitNs = 10'000 * kMs;
// DMC-RT-012 evidence: RT_END "within 5 s" of a STOP_ALL that ends a live run;
// plan choice (the spec gives no time).
inline constexpr TimeNs kStopRunEndWithinNs = 5000 * kMs;
// Plan choice: after a JOG_ALL rests, JogAll listens this long for late frame
// reports (DMC-RT-013).
inline constexpr TimeNs kJogAllLateReportsNs = 200 * kMs;
// Plan choice: Shoot's EXPOSURE TIME (ms on the wire); RT_END sooner than the
// exposure after GO ended no exposure (DMC-GM-001, DMC-GM-002).
inline constexpr uint32_t kShootExposureMs = 200;
inline constexpr TimeNs kShootExposureNs = TimeNs{kShootExposureMs} * kMs;
// Plan choice: how long Shoot waits for RT_END after GO ("none within 10 s";
// DMC-GM-001, DMC-GM-002).
inline constexpr TimeNs kShootEndWaitNs = 10'000 * kMs;
// Plan choice: StopLoop waits this long for the ping-pong run to report its end
// frame, and again for a frame on the way back (DMC-LOOP-001).
inline constexpr TimeNs kLoopPassWaitNs = 10'000 * kMs;
// Plan choice: RT_END is waited for this long after STOP_LOOP ("no RT_END
// within 10 s of STOP_LOOP", DMC-LOOP-001).
inline constexpr TimeNs kStopLoopEndWaitNs = 10'000 * kMs;

// --- Real-time outputs (dmc_cases_rt_io.cpp) ----------------------------------------
// Plan choice: where the outputs are observable, GoAndWatch samples them this
// often.
inline constexpr TimeNs kOutputSampleNs = 2 * kMs;
// Plan choice: the BLOOP TIME the runs send (ms on the wire); a bloop lasts
// half to one and a half times it (DMC-DMX-011, DMC-RT-020) ...
inline constexpr uint16_t kBloopMs = 200;
// ... with two samples of slack either way.
inline constexpr TimeNs kBloopSlackNs = 2 * kOutputSampleNs;  // 4 ms
// Plan choice: after a stills run, the end frame's exposure closes after its
// report: listened for this long (DMC-RT-022).
inline constexpr TimeNs kLastExposureCloseNs = 200 * kMs;
// DMC-RT-023: a stills exposure opens and closes "within a tenth of a frame"
// of its angles; and a millisecond.
inline constexpr TimeNs kExposureEdgeTolNs = kRunFrameNs / 10 + kMs;
// Plan choice: after a video run, its presses have this long to come in
// (DMC-RT-025).
inline constexpr TimeNs kVideoPressesSettleNs = 500 * kMs;
// DMC-RT-025: a press lasts a moment; one may wait for the previous to be
// released: a press up to this long after its frame counts (plan choice).
inline constexpr TimeNs kVideoPressLateNs = 300 * kMs;
// Plan choice: a PRE-ROLL or POST-ROLL TIME (ms on the wire) that takes motor 1
// past its soft limits (240 steps at 960 steps/s, DMC-RT-026, DMC-RT-027), and
// one that stays within them (48 steps, DMC-RT-029).
inline constexpr uint32_t kRollPastLimitMs = 500;
inline constexpr uint32_t kRollWithinLimitMs = 100;
// Plan choice: after a refused RT_RUN_MOVE, any pre-roll it wrongly started has
// this long to show before the positions are read (DMC-RT-028).
inline constexpr TimeNs kRefusedRunShowNs = 300 * kMs;

// --- Virtual axes ----------------------------------------------------------------
// Plan choice: after a refused VIRT_MOVE, any motion it wrongly started has
// this long to show before the positions are read (DMC-VIRT-004).
inline constexpr TimeNs kRefusedVirtMoveShowNs = 100 * kMs;
// Plan choice: VirtStopShort's move under way before VIRT_STOP (DMC-VIRT-007).
inline constexpr TimeNs kVirtRunBeforeStopNs = 200 * kMs;
// Plan choice: each VIRT_JOG_ON_LINE under way before its speed 0 or
// VIRT_STOP (DMC-VIRT-008).
inline constexpr TimeNs kVirtJogBeforeStopNs = 300 * kMs;

// --- The random sequence (dmc_random.cpp) --------------------------------------------
// Plan choice: the longest wait step the generator draws (ms).
inline constexpr int32_t kRandomWaitMaxMs = 800;
// Plan choice: the final wait for rest after the sequence; the generator's
// speeds keep every move within seconds.
inline constexpr TimeNs kRandomRestWaitNs = 600'000 * kMs;

// --- The greeting before each case (dmc_protocol.cpp) -----------------------------------
// Plan choice: how long the first HI of the greeting is waited for before the
// line is flushed of an unfinished frame.
inline constexpr TimeNs kSettleHiAnswerNs = 500 * kMs;
// Plan choice: the wait after the flush, before HI is asked again.
inline constexpr TimeNs kSettleFlushNs = 100 * kMs;
// Plan choice: how long motion an earlier case left is waited out (polled every
// kRestPollNs).
inline constexpr TimeNs kSettleMotionWaitNs = 3000 * kMs;
// Plan choice: how long MOTOR_CONFIGURE is retried while the device refuses
// commands after a stop (ERR_HARD_LOW, ERR_MOVING); it outlasts dmc-lite's
// STOP_ALL lockout (dmc::kReferenceStopAllLockoutNs).
inline constexpr TimeNs kSettleBusyWaitNs = 3000 * kMs;
static_assert(kSettleBusyWaitNs > dmc::kReferenceStopAllLockoutNs);
// Plan choice: MOTOR_CONFIGURE is retried this often meanwhile.
inline constexpr TimeNs kSettleBusyRetryNs = 100 * kMs;

// --- The fuzz hooks (dmc_fuzz_hooks.cpp) ---------------------------------------------------
// Between two host messages: one millisecond, about ten bytes at 115200 baud
// (dmc::kBaudRate).
inline constexpr TimeNs kFuzzGapNs = 1 * kMs;
// How long the host listens for stray answers after the last one it awaited.
inline constexpr TimeNs kFuzzQuietNs = 20 * kMs;
// Plan choice: a pause the mutator puts between two messages (an empty
// message, core/fuzz_protocol.h): two of the 40-60 ms apart position updates
// a moving device sends (FACTS "DMC"), so a move runs on with nothing asked.
inline constexpr TimeNs kFuzzPauseNs = 100 * kMs;

}  // namespace dmc_cases
}  // namespace moco::conformance

#endif  // MOCO_CONFORMANCE_PROTOCOLS_DMC_DMC_TIMING_H_
