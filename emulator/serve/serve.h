// Serving emulated devices in one process (`mocosim dmc16`, `mocosim run`):
// the io_context, the real-time driver of the one clock, one DeviceServer per
// device, session recordings, the control socket and scenario, and a clean
// shutdown on SIGINT/SIGTERM/SIGHUP (symlinks removed, recordings closed).
#ifndef MOCO_SERVE_SERVE_H_
#define MOCO_SERVE_SERVE_H_

#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "control/control_channel.h"
#include "control/link_control.h"
#include "devices/device.h"
#include "session/session.h"
#include "sim/scheduler.h"
#include "transport/asio.h"
#include "transport/device_server.h"
#include "transport/realtime_driver.h"

namespace moco::serve {

enum class LogLevel { kError, kWarn, kInfo, kDebug };
// "error", "warn", "info", "debug"; throws std::invalid_argument otherwise.
LogLevel ParseLogLevel(std::string_view text);

// One device to serve.
struct DeviceConfig {
  std::string name;  // unique in the run; defaults to the model name (+ "-2", ...)
  std::string model = "dmc16";
  std::string endpoint;      // "pty:/tmp/dmc16", "tcp:127.0.0.1:5000", "tcp:5000"
  std::string profile_path;  // empty: the model's built-in profile
  std::string record_path;   // empty: no recording
  // Each motor's STEP and DIR from the step model's exact edge times, written
  // as a Value Change Dump when mocosim stops; empty: none.
  std::string vcd_path;
  // Models with NVM (StackShot): the state file; empty: the default
  // $XDG_STATE_HOME/mocosim/<name>.json (~/.local/state/mocosim/<name>.json).
  std::string state_path;
  bool no_pacing = false;
  std::string faults;  // link fault config, e.g. "seed=1,drop=0.01"; empty: off
};

struct EmulatorConfig {
  std::vector<DeviceConfig> devices;
  std::string control_path;   // JSON-lines control socket; empty: none
  std::string scenario_path;  // timed events; empty: none
  std::string bind_address = "127.0.0.1";
  LogLevel log_level = LogLevel::kInfo;
  // The run file the config came from (an input no output may replace; its
  // keys name the files in messages); empty: the command line's options.
  std::string run_file_path;
};

// A run file (`mocosim run devices.json`) that cannot be used; what() names
// the field and the fix.
class ConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Parses a run file:
//   {"devices": [{"model": "dmc16", "endpoint": "pty:/tmp/dmc16", "name": "a",
//                 "profile": "...", "record": "...", "state": "...", "no_pacing": false,
//                 "faults": "..."}, ...],
//    "control": "/tmp/mocosim.sock", "scenario": "...", "bind": "127.0.0.1",
//    "log_level": "info"}
// Relative paths are taken relative to `base_dir`. Throws ConfigError.
EmulatorConfig ParseRunConfig(const nlohmann::json& j, const std::string& where,
                              const std::string& base_dir);
EmulatorConfig LoadRunConfig(const std::string& path);

// Hooks for the control socket and scenario, set up by the caller (mocosim's
// main.cpp builds the control channel, socket and scenario run).
struct EmulatorHooks {
  // Called after Start() with every device served; may return a handler for
  // control-socket lines (nullptr: none). Runs on the io thread.
  std::function<void()> on_started;
  std::function<void()> on_stopping;
};

class Emulator {
 public:
  // Builds every device and opens every endpoint. Throws std::runtime_error
  // (ProfileError, ConfigError, a taken port, an unusable PTY path) with a
  // message naming the device and the fix; nothing is left open then.
  Emulator(EmulatorConfig config, transport::LogFn log = transport::LogToStderr);
  ~Emulator();
  Emulator(const Emulator&) = delete;
  Emulator& operator=(const Emulator&) = delete;

  // Powers every device on and starts the clock; logs where each one is.
  void Start();
  // Runs the io loop until Stop() or SIGINT/SIGTERM/SIGHUP; returns the exit code
  // (0, or 1 when a recording could not be completed).
  int Run();
  // Stops serving: endpoints closed, symlinks removed, recordings completed.
  // Idempotent; safe from an io handler.
  void Stop();

  transport::asio::io_context& io() { return io_; }
  sim::Scheduler& scheduler() { return scheduler_; }
  transport::RealtimeDriver& driver() { return driver_; }
  size_t size() const { return served_.size(); }
  // REQUIRES: i < size().
  const std::string& name(size_t i) const;
  devices::Device& device(size_t i);
  transport::DeviceServer& server(size_t i);
  // The link of device i as the control channel reaches it
  // (ControlChannel::AddDevice).
  control::LinkControl& link_control(size_t i);
  // The state file in use for device i ("" for models without NVM).
  const std::string& state_path(size_t i) const;
  const EmulatorConfig& config() const { return config_; }
  void Log(LogLevel level, std::string_view line) const;
  void SetHooks(EmulatorHooks hooks) { hooks_ = std::move(hooks); }
  // Appends an event line to the recording of device `name` (if it records).
  void RecordEvent(const std::string& name, const session::SessionEntry& entry);
  // Logs and records what happens through `channel`: every executed action
  // (info; power cycles and link cuts are recorded by the link itself) and
  // every device event (warn: a stall, a collision), each in the recording
  // of the device it concerns. REQUIRES: `channel` serves this emulator's
  // devices under their names and is destroyed before the emulator.
  void AttachControl(control::ControlChannel& channel);

 private:
  struct Served;

  EmulatorConfig config_;
  transport::LogFn log_;
  EmulatorHooks hooks_;
  transport::asio::io_context io_;
  sim::Scheduler scheduler_;
  transport::RealtimeDriver driver_;
  std::vector<std::unique_ptr<Served>> served_;
  std::unique_ptr<transport::asio::signal_set> signals_;
  bool stopped_ = false;
  int exit_code_ = 0;
};

}  // namespace moco::serve

#endif  // MOCO_SERVE_SERVE_H_
