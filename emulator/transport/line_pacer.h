// Serial line pacing (wire/line.h LineSettings): a UART sends one byte
// after another, each taking 1/BytesPerSecond() s; a byte reaches the other
// end when its stop bit ends. Pure arithmetic on the scheduler clock.
#ifndef MOCO_TRANSPORT_LINE_PACER_H_
#define MOCO_TRANSPORT_LINE_PACER_H_

#include <cstdint>

#include "sim/scheduler.h"

namespace moco::transport {

// The earliest time each byte of a stream may be handed over: byte k of a
// burst that starts at time a (the line being idle at a) completes at
//   a + ceil((k + 1) * 1e9 / bytes_per_second)   ns,
// computed from the burst's start so no rounding error accumulates. A byte
// that becomes ready after the line went idle starts a new burst.
class LinePacer {
 public:
  // bytes_per_second == 0 means unpaced: every byte is due when it is ready.
  explicit LinePacer(uint32_t bytes_per_second = 0) : bytes_per_second_(bytes_per_second) {}

  bool paced() const { return bytes_per_second_ != 0; }
  uint32_t bytes_per_second() const { return bytes_per_second_; }

  // Time the next byte would complete if it became ready at ready_ns. Pure.
  sim::TimeNs DueTime(sim::TimeNs ready_ns) const;

  // Sends the next byte (ready at ready_ns) and returns its completion time.
  // REQUIRES: ready_ns is non-decreasing across calls.
  sim::TimeNs Take(sim::TimeNs ready_ns);

  // Forgets the current burst: the next byte starts a new one.
  void Reset() { in_burst_ = false; }

 private:
  // End of byte k (0-based) of the current burst.
  sim::TimeNs SlotEnd(uint64_t k) const;
  // Whether a byte ready at ready_ns finds the line idle (starts a new burst).
  bool Idle(sim::TimeNs ready_ns) const;

  uint32_t bytes_per_second_;
  bool in_burst_ = false;
  sim::TimeNs anchor_ns_ = 0;  // start of the current burst
  uint64_t sent_ = 0;          // bytes of the current burst already sent
};

}  // namespace moco::transport

#endif  // MOCO_TRANSPORT_LINE_PACER_H_
