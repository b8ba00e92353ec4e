// The timing of the DFMoco line and of the sketch behind it (dfmoco-protocol.txt
// "Protocol", "Go-Motion (Blur)", "Notes"; ERRATA part 2; FACTS "DFMoco"): the baud
// rate, the period of the unprompted `mp` reports and the go-motion ramps. What the
// protocol states or the real sketch does, not what a host or the conformance runner
// chooses to wait. Durations are int64_t nanoseconds.
//
// The sketch's step tick (25 us, sim::kDfmocoTickNs) and velocity chunk (50 ms,
// sim::kDfmocoChunkNs) are defined with its planner in emulator/sim/planner_dfmoco.h.
#ifndef MOCO_WIRE_DFMOCO_TIMING_H_
#define MOCO_WIRE_DFMOCO_TIMING_H_

#include <cstdint>

namespace moco::dfmoco {

// "Speed: 57600 Baud", 8 data bits, 1 stop bit (ERRATA 2.1: 57600 8N1).
inline constexpr uint32_t kBaudRate = 57600;

// While a motor moves, `mp m pos` goes out once per second per moving motor (FACTS DFMoco).
inline constexpr int64_t kReportPeriodNs = 1'000'000'000;  // 1 s
// The first report tick, after the first chunk boundary of the running sketch
// (docs/devices/dfmoco.md "Periodic position reports").
inline constexpr int64_t kFirstReportNs = 500'000'000;  // 500 ms
// Go-motion: the ramp up to speed before the exposure "should take exactly 1 second"
// (Go-Motion (Blur); ERRATA 2.5), and the slow-down after it as long (FACTS DFMoco).
inline constexpr int64_t kGoMotionRampNs = 1'000'000'000;  // 1 s

}  // namespace moco::dfmoco

#endif  // MOCO_WIRE_DFMOCO_TIMING_H_
