// USB serial bridge packets (see usb_bridge_pacer.h).
#include "transport/usb_bridge_pacer.h"

#include <algorithm>

namespace moco::transport {

sim::TimeNs UsbBridgePacer::NextTick(sim::TimeNs t) const {
  const sim::TimeNs period = bridge_.period_ns;
  if (period <= 0 || t <= anchor_ns_) return std::max(t, anchor_ns_);
  const sim::TimeNs periods = (t - anchor_ns_ + period - 1) / period;
  return anchor_ns_ + periods * period;
}

UsbBridgePacer::Packet UsbBridgePacer::Next(size_t count,
                                            const std::function<sim::TimeNs(size_t)>& arrival,
                                            sim::TimeNs floor_ns) const {
  Packet p;
  if (count == 0) return p;
  const sim::TimeNs tick = NextTick(std::max(arrival(0), floor_ns));
  const size_t limit =
      bridge_.flush_at_bytes == 0 ? count : std::min<size_t>(count, bridge_.flush_at_bytes);
  size_t n = 0;
  while (n < limit && arrival(n) <= tick) ++n;
  if (bridge_.flush_at_bytes != 0 && n == bridge_.flush_at_bytes) {
    // Full before the timer: it leaves as its last byte arrives.
    p.at_ns = std::max(arrival(n - 1), floor_ns);
    p.full = true;
  } else {
    p.at_ns = tick;
  }
  p.bytes = n;
  return p;
}

void UsbBridgePacer::Sent(const Packet& packet) {
  if (packet.full && bridge_.full_packet_restarts_timer) anchor_ns_ = packet.at_ns;
}

}  // namespace moco::transport
