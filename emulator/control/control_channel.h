// The run-time control of every emulated device (docs/control.md): the
// channel that executes the vocabulary's commands (command_codec.h) against
// devices and their links: e-stop, limit switches, GIO inputs, power cycles,
// link cuts and faults, and state queries, shared by the control socket and
// scenario files.
#ifndef MOCO_CONTROL_CONTROL_CHANNEL_H_
#define MOCO_CONTROL_CONTROL_CHANNEL_H_

#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include <nlohmann/json.hpp>

#include "control/command_codec.h"
#include "control/link_control.h"
#include "devices/device.h"
#include "session/session.h"
#include "sim/limits.h"
#include "sim/line_faults.h"
#include "sim/scheduler.h"
#include "sim/stepper_motor.h"

namespace moco::control {

// ---- Events -----------------------------------------------------------------

// One executed command, for logs and session files.
struct ControlEvent {
  sim::TimeNs t_ns = 0;
  std::string source;      // "control" (a socket line), "scenario", or the caller's name
  int index = -1;          // scenario: the event's index in "events"; -1 otherwise
  nlohmann::json request;  // ToJson(command)
  nlohmann::json reply;    // the reply object ("ok", ...)

  // The session-file event line (docs/sessions.md):
  // {"t_ns":..., "event":"<cmd>", <command fields>, "source":..., ["index":...,]
  //  "ok":true|false, ["error":...]}
  nlohmann::json SessionLine() const;
  session::SessionEntry ToSessionEntry() const;
};

// Something a device did by itself (devices::DeviceEventListener), stamped
// with the time and the device's name and numbered per device from 1.
struct DeviceEvent {
  sim::TimeNs t_ns = 0;
  std::string device;
  uint64_t seq = 0;
  nlohmann::json event;  // {"event":"stall", ...} as the device reported it

  // The session-file event line (docs/sessions.md):
  // {"t_ns":..., "event":"stall", <the device's fields>, "source":"device", "seq":...}
  nlohmann::json SessionLine() const;
  session::SessionEntry ToSessionEntry() const;
};

// ---- The channel ------------------------------------------------------------

// Executes commands against named devices. Each device is a devices::Device
// (its rig(), gio(), State(), PowerOff/PowerOn) and, when it is served on an
// endpoint, the LinkControl of its link (link cuts, faults, link stats, power
// cycles through the link).
//
// Typical use:
//   ControlChannel channel(scheduler);
//   channel.AddDevice("dmc16", device, &link);  // link: a LinkControl, or none
//   std::string reply = channel.Handle(line);
//
// Every call comes from the thread that owns the scheduler. Called from
// outside a scheduler callback in real time, the caller syncs the clock first
// and re-arms it after (ControlSocket does both). The scheduler, the devices
// and the links must outlive the channel.
class ControlChannel {
 public:
  // Called after each executed action (not after queries), whatever its source.
  using ActionListener = std::function<void(const ControlEvent&)>;
  // Called for every event a device reports by itself.
  using DeviceEventListener = std::function<void(const DeviceEvent&)>;
  // Device events kept per device for the "events" query (older ones are dropped).
  static constexpr size_t kEventsKept = 256;

  explicit ControlChannel(sim::Scheduler& scheduler);
  // Cancels pending in-process power-ons and detaches from the devices' events.
  ~ControlChannel();
  ControlChannel(const ControlChannel&) = delete;
  ControlChannel& operator=(const ControlChannel&) = delete;

  // Adds a device under `name` (letters, digits, '-', '_', '.'; 1..64 bytes)
  // and becomes the listener of its events (Device::SetEventListener).
  // `link` (may be null: the device runs in-process) must be the link that
  // serves `device`. `device` (and `link`) must outlive the channel: its
  // destructor detaches from the device's events.
  // Throws std::invalid_argument for a bad or duplicate name (a start-up error).
  void AddDevice(std::string name, devices::Device& device, LinkControl* link = nullptr);
  std::vector<std::string> DeviceNames() const;

  void SetActionListener(ActionListener listener) { listener_ = std::move(listener); }
  void SetDeviceEventListener(DeviceEventListener listener) {
    device_event_listener_ = std::move(listener);
  }

  // One request line -> one reply line (a JSON object, no newline):
  // {"ok":true,...} or {"ok":false,"error":"..."}. Never throws, whatever
  // the input (malformed JSON, unknown command or device, bad field).
  std::string Handle(std::string_view line, std::string_view source = "control");

  // Executes a parsed command and returns the reply object.
  nlohmann::json Execute(const Command& command, std::string_view source = "control",
                         int index = -1);

  // What can be checked before a command runs: the device exists (or is the
  // only one), the motor / set numbers exist on its rig, it has GIO, and link
  // commands have a link. nullopt when it would run; else the reason. Whether
  // a motor is bound to a limit set is only known when the command runs.
  std::optional<std::string> Check(const Command& command) const;

  sim::Scheduler& scheduler() { return scheduler_; }

 private:
  struct Target {
    std::string name;
    devices::Device* device = nullptr;
    LinkControl* link = nullptr;
    sim::Scheduler::TimerId power_on_timer = sim::Scheduler::kNoTimer;
    std::deque<DeviceEvent> events;  // the last kEventsKept
    uint64_t events_seen = 0;
  };
  void OnDeviceEvent(Target& target, const nlohmann::json& event);
  nlohmann::json EventsOf(const Target& target, uint64_t after) const;
  // The target named `device_name` (empty: the only one), or null with
  // `error` set.
  Target* Find(const std::string& device_name, std::string* error) const;
  std::optional<std::string> CheckTarget(const Target& target, const CommandBody& body) const;
  nlohmann::json Run(Target& target, const CommandBody& body);
  nlohmann::json StateOf(const Target& target) const;
  nlohmann::json DevicesReply() const;

  sim::Scheduler& scheduler_;
  std::vector<std::unique_ptr<Target>> targets_;  // stable addresses for timers
  ActionListener listener_;
  DeviceEventListener device_event_listener_;
};

}  // namespace moco::control

#endif  // MOCO_CONTROL_CONTROL_CHANNEL_H_
