// When the bytes a USB serial bridge holds reach the host
// (devices/usb_bridge.h): the bridge sends a packet at once when it holds a
// full one, and otherwise whatever it holds at its timer's next tick. Pure
// arithmetic on the scheduler clock, as LinePacer is for the UART before it.
#ifndef MOCO_TRANSPORT_USB_BRIDGE_PACER_H_
#define MOCO_TRANSPORT_USB_BRIDGE_PACER_H_

#include <cstddef>
#include <functional>

#include "devices/usb_bridge.h"
#include "sim/scheduler.h"

namespace moco::transport {

class UsbBridgePacer {
 public:
  explicit UsbBridgePacer(devices::UsbBridge bridge = {}) : bridge_(bridge) {}

  bool active() const { return bridge_.active(); }
  const devices::UsbBridge& bridge() const { return bridge_; }

  struct Packet {
    sim::TimeNs at_ns = 0;  // when it reaches the host
    size_t bytes = 0;       // how many of the bytes held, from the oldest
    bool full = false;      // sent for its size, not for the timer
  };

  // The next packet, given the `count` bytes the bridge holds (count > 0) and
  // arrival(i), the time byte i reached it (non-decreasing). A byte is not
  // sent before floor_ns (the host opened the port then). Bytes still on
  // their way through the UART are not counted: call again once they arrive
  // (a packet due at t is final once every byte arriving by t is held).
  Packet Next(size_t count, const std::function<sim::TimeNs(size_t)>& arrival,
              sim::TimeNs floor_ns) const;

  // The packet left: a full one restarts an FTDI chip's latency timer.
  void Sent(const Packet& packet);

  // The first tick of the bridge's timer at or after t.
  sim::TimeNs NextTick(sim::TimeNs t) const;

 private:
  devices::UsbBridge bridge_;
  sim::TimeNs anchor_ns_ = 0;  // a tick of the timer
};

}  // namespace moco::transport

#endif  // MOCO_TRANSPORT_USB_BRIDGE_PACER_H_
