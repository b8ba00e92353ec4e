// Timing facts of the DMC v2 protocol: the line's speed, the idle gap that
// ends a partial frame, and the periods the spec (dmc-v2-protocol.txt) and the
// reference firmware (FACTS "DMC v2", dmc-lite) give. Durations are int64_t
// nanoseconds (this layer has no clock type); the suite's own waits are in
// conformance/protocols/dmc/dmc_timing.h. dmc_constants.h includes this file.
#ifndef MOCO_WIRE_DMC_TIMING_H_
#define MOCO_WIRE_DMC_TIMING_H_

#include <cstdint>

namespace moco::dmc {

// --- The line ------------------------------------------------------------------
// dmc-v2-protocol.txt names no line speed. 115200 baud 8N1 is the setting a
// DMC v2 device is opened at (FACTS "DMC v2": dmc-lite's "port is USB CDC (the
// 115200 baud setting does not pace it)"; docs/device-facts.md, DMC v2;
// docs/profiles.md `baud`). The DMC-16 profile's default and the protocol table's
// DMC line read it.
inline constexpr uint32_t kBaudRate = 115200;
// The spec has no inter-byte timeout; mocosim's reading (docs/protocol-notes.md
// "Idle line"): a line idle this long ends any partial frame, which is given
// up and its bytes rescanned. The DMC-16 does so, and the transcripts
// (`mocosim decode`) and the Wireshark dissector follow it.
inline constexpr int64_t kLineIdleGapNs = 50'000'000;  // 50 ms

// --- Periods ---------------------------------------------------------------------
// MSG_MOTOR_GET_POSITION: "The device should send these out, about every 0.10
// seconds, if any of the motors are moving" (DMC-POS-002).
inline constexpr int64_t kPositionUpdatePeriodNs = 100'000'000;  // 100 ms
// FACTS "DMC v2": dmc-lite runs its motion on a 20 ms velocity tick (a new
// speed every 20 ms); nothing it is told moves before its next tick.
inline constexpr int64_t kReferenceMotionTickNs = 20'000'000;  // 20 ms
// FACTS "DMC v2": STOP_ALL while moving puts dmc-lite into a hard-stop state
// that refuses commands with ERR_HARD_LOW until ~100 velocity updates (~2 s)
// after the motors are still.
inline constexpr int64_t kReferenceStopAllLockoutNs = 2'000'000'000;  // ~2 s

}  // namespace moco::dmc

#endif  // MOCO_WIRE_DMC_TIMING_H_
