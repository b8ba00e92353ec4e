// Serial line pacing (wire/line.h LineSettings): byte completion times.
#include "transport/line_pacer.h"

namespace moco::transport {

sim::TimeNs LinePacer::SlotEnd(uint64_t k) const {
  // sent_ < bytes_per_second_ (see Take), so (k + 1) * 1e9 stays below 2^63.
  const uint64_t num = (k + 1) * static_cast<uint64_t>(sim::kNsPerSecond);
  const uint64_t ns = (num + bytes_per_second_ - 1) / bytes_per_second_;
  return anchor_ns_ + static_cast<sim::TimeNs>(ns);
}

bool LinePacer::Idle(sim::TimeNs ready_ns) const {
  if (!in_burst_) return true;
  // The line is free once the previous byte has ended.
  const sim::TimeNs free_ns = sent_ == 0 ? anchor_ns_ : SlotEnd(sent_ - 1);
  return ready_ns >= free_ns;
}

sim::TimeNs LinePacer::DueTime(sim::TimeNs ready_ns) const {
  if (!paced()) return ready_ns;
  if (Idle(ready_ns)) {
    LinePacer fresh(bytes_per_second_);
    fresh.in_burst_ = true;
    fresh.anchor_ns_ = ready_ns;
    return fresh.SlotEnd(0);
  }
  return SlotEnd(sent_);
}

sim::TimeNs LinePacer::Take(sim::TimeNs ready_ns) {
  if (!paced()) return ready_ns;
  if (Idle(ready_ns)) {
    in_burst_ = true;
    anchor_ns_ = ready_ns;
    sent_ = 0;
  }
  const sim::TimeNs due = SlotEnd(sent_);
  ++sent_;
  // After exactly bytes_per_second_ bytes the burst has lasted exactly 1 s:
  // move the anchor there, keeping the arithmetic exact and small.
  if (sent_ == bytes_per_second_) {
    anchor_ns_ += sim::kNsPerSecond;
    sent_ = 0;
  }
  return due;
}

}  // namespace moco::transport
