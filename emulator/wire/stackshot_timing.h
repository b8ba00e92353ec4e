// Timing facts of the Cognisys StackShot / StackShot 3X protocol: the line
// rates, the inter-frame gap and the host timeouts and periods the spec,
// ERRATA.md part 3 and FACTS.md "StackShot" state (stackshot-protocol.txt
// sections 1.3, 2 and 3). Durations are int64_t nanoseconds (the wire
// layer has no clock of its own), with the human value beside each.
#ifndef MOCO_WIRE_STACKSHOT_TIMING_H_
#define MOCO_WIRE_STACKSHOT_TIMING_H_

#include <cstdint>

namespace moco::stackshot {

// --- Line rates (8N1) --------------------------------------------------------
inline constexpr uint32_t kBaudRate = 38400;        // STACKSHOT_BAUD_RATE (1.3; ERRATA 3.7)
inline constexpr uint32_t kDfMocoBaudRate = 57600;  // section 3 "57600 8N1" (ERRATA 3.7)

// --- Framing -----------------------------------------------------------------
// Mandatory inter-frame gap that lets a receiver drop a partial packet
// ("Mandatory 2ms inter-frame delay", section 2; ERRATA 3.6).
inline constexpr int64_t kInterFrameGapNs = 2'000'000;  // 2 ms

// --- Hosts -------------------------------------------------------------------
// Host tools give up on a reply after 1 s (FACTS.md "StackShot": "with 1 s timeouts").
inline constexpr int64_t kHostReplyTimeoutNs = 1'000'000'000;  // 1 s
// Host tools poll CC_RAIL_STATUS this often (FACTS.md "StackShot": "poll status every 100 ms").
inline constexpr int64_t kHostStatusPollNs = 100'000'000;  // 100 ms

}  // namespace moco::stackshot

#endif  // MOCO_WIRE_STACKSHOT_TIMING_H_
