// The recording tap of a link (docs/sessions.md): every chunk that crosses the
// device end of a link, with its scheduler timestamp, and the link's events.
#ifndef MOCO_TRANSPORT_TRAFFIC_H_
#define MOCO_TRANSPORT_TRAFFIC_H_

#include <string_view>

#include "sim/scheduler.h"
#include "wire/bytes.h"
#include "wire/line.h"
#include "wire/protocol.h"

namespace moco::transport {

enum class Direction {
  kToDevice,  // host -> device
  kToHost,    // device -> host
};

std::string_view DirectionName(Direction d);  // "to-device" / "to-host"

// Receives a link's traffic and events; called on the io thread. The observer
// sees the device's view, which a replay reproduces exactly:
//  - kToDevice: the bytes handed to Device::OnHostBytes (after link faults and
//    line pacing), stamped with the scheduler time of that call;
//  - kToHost: the bytes the device wrote to its ByteSink (before link faults
//    and pacing), stamped with the scheduler time of the write.
// Timestamps are non-decreasing across both directions and events.
class TrafficObserver {
 public:
  virtual ~TrafficObserver() = default;
  virtual void OnTraffic(sim::TimeNs t_ns, Direction dir, wire::ByteView bytes) = 0;
  // A link event: "host_link" (detail "open"/"closed"), "link_fault" (detail
  // "cut <ns>"), "power_cycle" (detail "off <ns>"). Default: ignored.
  virtual void OnLinkEvent(sim::TimeNs /*t_ns*/, std::string_view /*kind*/,
                           std::string_view /*detail*/) {}
  // kToHost bytes handed to the host's stream (a PTY's or a socket's kernel
  // buffer), in order, each byte once, stamped with the time the write
  // completed: what reached the host, where OnTraffic is what the device
  // said. A byte taken back from a PTY the host closed unread and written
  // again is not reported again. Default: ignored.
  virtual void OnDelivered(sim::TimeNs /*t_ns*/, Direction /*dir*/, wire::ByteView /*bytes*/) {}
  // The device's line speaks `protocol` at `line` from the next byte on
  // (devices::LineSwitch), in order with the traffic: after the bytes the
  // device wrote before the switch, before any host byte it reads after.
  // Default: ignored.
  virtual void OnLineSwitch(sim::TimeNs /*t_ns*/, wire::Protocol /*protocol*/,
                            const wire::LineSettings& /*line*/) {}
};

}  // namespace moco::transport

#endif  // MOCO_TRANSPORT_TRAFFIC_H_
