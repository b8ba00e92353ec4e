// The run-time control vocabulary of every emulated device (docs/control.md):
// e-stop, limit switches, GIO inputs, power cycles, link cuts and faults, and
// state queries, one JSON object per request, shared by the control socket
// and scenario files.
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

#include "control/session.h"
#include "devices/device.h"
#include "sim/limits.h"
#include "sim/scheduler.h"
#include "sim/stepper_motor.h"
#include "transport/link_faults.h"

namespace moco::transport {
class DeviceServer;
}  // namespace moco::transport

namespace moco::control {

// ---- Commands ---------------------------------------------------------------

// {"cmd":"estop","engaged":true}
struct EStopCommand {
  bool engaged = false;
};
// {"cmd":"limit","set":1,"input":"low","active":true} or
// {"cmd":"limit","motor":3,"end":"upper","active":true}: exactly one of the
// two forms (set + input, or motor + end).
struct LimitCommand {
  std::optional<int> set;
  sim::SwitchInput input = sim::SwitchInput::kLow;
  std::optional<int> motor;
  sim::LimitEnd end = sim::LimitEnd::kLower;
  bool active = false;
};
// {"cmd":"gio_in","bit":4,"level":true} or {"cmd":"gio_in","bits":"0x0000ff00"}:
// raw input levels as wired (the device debounces them).
struct GioInCommand {
  std::optional<int> bit;  // 0..31; when absent, `bits` sets all 32 inputs
  bool level = false;
  uint32_t bits = 0;
};
// {"cmd":"power_cycle","off_ms":500}
struct PowerCycleCommand {
  int64_t off_ms = 0;
};
// {"cmd":"cut_link","ms":2000}
struct CutLinkCommand {
  int64_t ms = 0;
};
// {"cmd":"faults","config":"seed=42,dir=to-host,drop=0.01"} or {"config":"off"}
struct FaultsCommand {
  std::string spec;  // as given ("off" for none)
  transport::FaultConfig config;
};
struct StateCommand {};
// {"cmd":"events","after":12}: the device's own events (stalls, collisions)
// with a sequence number above `after` (default 0: every one still kept).
struct EventsCommand {
  uint64_t after = 0;
};
struct DevicesCommand {};
struct HelpCommand {};

using CommandBody =
    std::variant<EStopCommand, LimitCommand, GioInCommand, PowerCycleCommand, CutLinkCommand,
                 FaultsCommand, StateCommand, EventsCommand, DevicesCommand, HelpCommand>;

struct Command {
  std::string device;  // empty: the only device served
  CommandBody body;
  nlohmann::json id;  // echoed in the reply when not null
};

// The command's name ("estop", "limit", ...).
std::string_view CommandName(const CommandBody& body);
// Whether the command changes the device or its link (queries do not).
bool IsAction(const CommandBody& body);
// The canonical JSON form of a command: "cmd", its fields, and "device" when
// given. ParseCommand(ToJson(c)) yields c again.
nlohmann::json ToJson(const Command& command);

// Parses JSON text like nlohmann::json::parse (throws its exceptions) and
// reports in `duplicate` the first key given twice in one object ("" when
// none): the control vocabulary refuses {"engaged":true,"engaged":false}
// rather than letting the last one win.
nlohmann::json ParseJsonNotingDuplicateKeys(std::string_view text, std::string& duplicate);

// Parses one request object. Fields `extra_fields` are allowed besides the
// command's own (a scenario's "at_ms") and ignored. Never throws. On failure
// returns a message naming the field, what was found and what to write.
std::variant<Command, std::string> ParseCommand(const nlohmann::json& request,
                                                const std::vector<std::string>& extra_fields = {});

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
  SessionEntry ToSessionEntry() const;
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
  SessionEntry ToSessionEntry() const;
};

// ---- The channel ------------------------------------------------------------

// Executes commands against named devices. Each device is a devices::Device
// (its rig(), gio(), State(), PowerOff/PowerOn) and, when it is served on an
// endpoint, its transport::DeviceServer (link cuts, faults, link stats, power
// cycles through the link).
//
// Typical use:
//   ControlChannel channel(scheduler);
//   channel.AddDevice("dmc16", device, &server);
//   std::string reply = channel.Handle(line);
//
// Every call comes from the thread that owns the scheduler. Called from
// outside a scheduler callback in real time, the caller syncs the clock first
// and re-arms it after (ControlSocket does both). The scheduler, the devices
// and the servers must outlive the channel.
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
  // `server` (may be null: the device runs in-process) must serve `device`.
  // `device` (and `server`) must outlive the channel: its destructor detaches
  // from the device's events.
  // Throws std::invalid_argument for a bad or duplicate name (a start-up error).
  void AddDevice(std::string name, devices::Device& device,
                 transport::DeviceServer* server = nullptr);
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
    transport::DeviceServer* server = nullptr;
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

// The vocabulary as data: one entry per command with its fields and an
// example, for "help" and docs/control.md.
nlohmann::json Vocabulary();

}  // namespace moco::control

#endif  // MOCO_CONTROL_CONTROL_CHANNEL_H_
