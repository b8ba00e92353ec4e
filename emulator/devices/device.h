// The boundary between an emulated device and whatever carries its bytes
// (ARCHITECTURE "three layers"): a device reads host bytes, writes its own
// bytes to a ByteSink and keeps time only through the Scheduler. It never
// opens a socket, a file or a thread.
#ifndef MOCO_DEVICES_DEVICE_H_
#define MOCO_DEVICES_DEVICE_H_

#include <cstdint>
#include <functional>
#include <string_view>
#include <utility>

#include <nlohmann/json.hpp>

#include "devices/usb_bridge.h"
#include "wire/bytes.h"
#include "wire/line.h"
#include "wire/protocol.h"

namespace moco::sim {
class Rig;
class GioPort;
class DmxUniverse;
class CameraPort;
}  // namespace moco::sim

namespace moco::devices {

// Where a device's output goes (a transport session, a test buffer, a recorder).
class ByteSink {
 public:
  virtual ~ByteSink() = default;
  // Takes a copy of `bytes`; never blocks and never fails from the device's
  // point of view (a transport queues, paces or drops as the link would).
  virtual void Write(wire::ByteView bytes) = 0;
  // Whether host bytes wait on the line that the device has not been handed
  // yet (in a transport's kernel buffer or paced queue): the line is not
  // silent then, however long ago the last bytes were handed over. A device
  // that times the line's silence (the DMC-16's idle gap) asks before giving
  // a partial message up. Default: none (in-process, bytes are handed over as
  // they are written).
  virtual bool HostBytesWaiting() { return false; }
};

// The line a device is reached over: its serial settings (the one
// wire::LineSettings; a transport paces at serial.BytesPerSecond()) and the
// USB serial bridge between the device's UART and the host. The bridge stays
// here rather than in wire: it is not part of a protocol (the same protocol
// runs behind an FTDI chip, a 16U2 or the board's own CDC port, as a
// profile's "usb_bridge" says), it is a timing model of hardware (packet
// sizes, latency timers) rather than a codec, and a profile reads it.
struct DeviceLine {
  wire::LineSettings serial;
  UsbBridge bridge;  // none: the host reads bytes as the UART completes them
};

// What carries the host's bytes to a device: its serial line (a USB serial
// port), or a network connection that stands for it (a StackShot 3X's Wi-Fi,
// stackshot-protocol.txt section 4).
enum class HostLink : uint8_t { kSerial, kWifi };

// A device's line now speaks another protocol (and so, often, at another
// rate): a StackShot 3X entering or leaving its DfMoco mode
// (stackshot-protocol.txt section 3). `line` is the device's Line() after
// the switch.
struct LineSwitch {
  wire::Protocol protocol = wire::Protocol::kDmc;
  DeviceLine line;
};
using LineSwitchListener = std::function<void(const LineSwitch& change)>;

// Something the simulated hardware did by itself, not in answer to the host: a
// JSON object whose "event" names it ("stall", "collision", ...) with its own
// fields. The listener stamps it with the scheduler's time.
using DeviceEventListener = std::function<void(const nlohmann::json& event)>;

// An emulated device. Lifecycle: constructed powered off; PowerOn() boots it
// (a device may announce itself then, e.g. DMC HI or DFMoco `hi`); PowerOff()
// drops all volatile state and cancels its timers. All calls come from the
// thread that owns the Scheduler.
class Device {
 public:
  virtual ~Device() = default;

  // Model name for logs, e.g. "dmc16".
  virtual std::string_view Model() const = 0;
  // The line the real device uses; transports pace at this rate unless told not to.
  virtual DeviceLine Line() const = 0;

  virtual void PowerOn() = 0;
  virtual void PowerOff() = 0;
  virtual bool Powered() const = 0;

  // Bytes from the host, in any chunking. Ignored while powered off.
  virtual void OnHostBytes(wire::ByteView bytes) = 0;
  // The host opened (true) or closed (false) the link. Most devices do not care.
  virtual void OnHostLink(bool /*open*/) {}
  // What carries the host's bytes (default kSerial); the serving layer says
  // so before PowerOn(). A device whose protocol or framing depends on it
  // follows; most do not care.
  virtual void SetHostLink(HostLink /*link*/) {}

  // The simulated hardware behind the device, for the run-time control
  // channel (e-stop, limit switches, inputs). Null when the device has none.
  virtual sim::Rig* rig() { return nullptr; }
  virtual sim::GioPort* gio() { return nullptr; }
  // The DMX universe and the camera lines the device drives, for an observer
  // in the same process (the conformance runner's in-process target). Null
  // when the device has none.
  virtual const sim::DmxUniverse* dmx_out() const { return nullptr; }
  virtual const sim::CameraPort* camera_out() const { return nullptr; }
  // The device's front-panel buttons, by the names its model gives them
  // (docs/devices/<model>.md): whether it has `button`, and pressing it once
  // (pressed and released). A device without that button ignores the press.
  virtual bool HasButton(std::string_view /*button*/) const { return false; }
  virtual void PressButton(std::string_view /*button*/) {}
  // A snapshot of the device's state (positions, motion, I/O, mode) for the
  // control channel's "state" query and for logs. An object; {} when none.
  virtual nlohmann::json State() const { return nlohmann::json::object(); }

  // Where the device reports its events (docs/control.md "Device events");
  // replaces the previous listener, null for none. Called back from the
  // scheduler's thread, never re-entrantly from inside this call.
  void SetEventListener(DeviceEventListener listener) { event_listener_ = std::move(listener); }
  // Who hears of each switch of the device's line to another protocol: what
  // carries its bytes (the transport paces at the new rate, a recording
  // notes the switch, docs/sessions.md "line_switch"). Called synchronously,
  // after the bytes the device wrote in the old protocol (a switch's
  // acknowledgement) and before any it writes in the new one; replaces the
  // previous listener, null for none. A device is created speaking its
  // model's protocol (devices/registry.h) and announces every change, the
  // first at PowerOn() when it powers on speaking another (a mode its NVM
  // keeps, or the one it was created to start in: DeviceStart).
  void SetLineSwitchListener(LineSwitchListener listener) {
    line_switch_listener_ = std::move(listener);
  }

 protected:
  void EmitEvent(const nlohmann::json& event) const {
    if (event_listener_) event_listener_(event);
  }
  // The device's line speaks `protocol` from its next byte on (Line() is
  // already the new line).
  void AnnounceLineSwitch(wire::Protocol protocol) const {
    if (line_switch_listener_) line_switch_listener_({protocol, Line()});
  }
  // For a device that wraps `inner` (its Line() is the inner one's): the
  // inner device's switches are announced as this device's. `inner` must not
  // outlive this device's use of it.
  void RelayLineSwitchesOf(Device& inner) {
    inner.SetLineSwitchListener(
        [this](const LineSwitch& change) { AnnounceLineSwitch(change.protocol); });
  }

 private:
  DeviceEventListener event_listener_;
  LineSwitchListener line_switch_listener_;
};

}  // namespace moco::devices

#endif  // MOCO_DEVICES_DEVICE_H_
