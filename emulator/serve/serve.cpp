// Serving emulated devices in one process (see serve.h).
#include "serve/serve.h"

#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "base/file_io.h"
#include "base/vcd.h"
#include "devices/profile.h"
#include "devices/registry.h"
#include "serve/file_state_store.h"
#include "serve/link_control_adapter.h"
#include "serve/session_tap.h"
#include "session/session.h"
#include "sim/rig.h"
#include "sim/step_trace.h"
#include "transport/link_faults.h"
#include "wire/transcript.h"

namespace moco::serve {

using transport::DeviceServer;
using transport::Direction;
using transport::ErrorCode;
using transport::FaultConfig;
using transport::LogFn;
using transport::LogToStderr;
using transport::ParseFaultConfig;
using transport::ServeOptions;
using transport::TrafficObserver;
namespace asio = transport::asio;

LogLevel ParseLogLevel(std::string_view text) {
  if (text == "error") return LogLevel::kError;
  if (text == "warn") return LogLevel::kWarn;
  if (text == "info") return LogLevel::kInfo;
  if (text == "debug") return LogLevel::kDebug;
  throw std::invalid_argument("unknown log level \"" + std::string(text) +
                              "\"; use error, warn, info or debug");
}

namespace {

// Sends a link's traffic to several observers.
class TeeObserver final : public TrafficObserver {
 public:
  void Add(TrafficObserver* o) { observers_.push_back(o); }
  bool empty() const { return observers_.empty(); }
  void OnTraffic(sim::TimeNs t, Direction d, wire::ByteView b) override {
    for (TrafficObserver* o : observers_) o->OnTraffic(t, d, b);
  }
  void OnLinkEvent(sim::TimeNs t, std::string_view k, std::string_view d) override {
    for (TrafficObserver* o : observers_) o->OnLinkEvent(t, k, d);
  }
  void OnLineSwitch(sim::TimeNs t, wire::Protocol p, const wire::LineSettings& l) override {
    for (TrafficObserver* o : observers_) o->OnLineSwitch(t, p, l);
  }

 private:
  std::vector<TrafficObserver*> observers_;
};

// --log-level debug: every message in and out as a transcript line.
class DebugTap final : public TrafficObserver {
 public:
  DebugTap(wire::Protocol p, std::string name, LogFn log)
      : decoder_(p), name_(std::move(name)), log_(std::move(log)) {}
  void OnTraffic(sim::TimeNs t, Direction d, wire::ByteView b) override {
    const wire::Side side = d == Direction::kToDevice ? wire::Side::kHost : wire::Side::kDevice;
    for (const wire::TranscriptLine& l : decoder_.Feed(side, b)) {
      char stamp[32];
      std::snprintf(stamp, sizeof stamp, "%.6f", static_cast<double>(t) / 1e9);
      log_(name_ + " " + stamp + (side == wire::Side::kHost ? " host -> dev  " : " dev  -> host ") +
           (l.problem ? "!! " : "") + l.text);
    }
  }
  void OnLineSwitch(sim::TimeNs, wire::Protocol p, const wire::LineSettings&) override {
    decoder_.SwitchTo(p);
  }

 private:
  wire::TranscriptDecoder decoder_;
  std::string name_;
  LogFn log_;
};

// Refuses, before anything is opened, every output that cannot be written (a
// directory, a socket, a missing directory) and every output that is another
// output, an input or a path the emulator serves (a PTY's symlink, the
// control socket), by any spelling (base::SamePath): one would overwrite the
// other, and a recording written into the device's own PTY blocks the
// emulator on its own port. Each role names its option (or run-file key).
void CheckFiles(const EmulatorConfig& c) {
  struct File {
    std::string path;
    std::string role;
  };
  const bool run_file = !c.run_file_path.empty();
  // "--record", "a's --record" (more than one device) or "device \"a\"'s \"record\"".
  auto role = [&](const DeviceConfig& d, std::string_view option, std::string_view key) {
    if (run_file) return "device \"" + d.name + "\"'s \"" + std::string(key) + "\"";
    return c.devices.size() > 1 ? d.name + "'s " + std::string(option) : std::string(option);
  };
  std::vector<File> outputs;
  std::vector<File> inputs;
  std::vector<File> served;
  for (const DeviceConfig& d : c.devices) {
    if (!d.record_path.empty()) outputs.push_back({d.record_path, role(d, "--record", "record")});
    if (!d.vcd_path.empty()) outputs.push_back({d.vcd_path, role(d, "--vcd", "vcd")});
    if (!d.state_path.empty()) outputs.push_back({d.state_path, role(d, "--state", "state")});
    if (!d.profile_path.empty())
      inputs.push_back({d.profile_path, role(d, "--profile", "profile")});
    if (d.endpoint.starts_with("pty:")) {
      served.push_back({d.endpoint.substr(4), role(d, "--pty", "endpoint")});
    }
  }
  if (!c.scenario_path.empty()) {
    inputs.push_back({c.scenario_path, run_file ? "\"scenario\"" : "--scenario"});
  }
  if (run_file) inputs.push_back({c.run_file_path, "the run file"});
  if (!c.control_path.empty()) {
    served.push_back({c.control_path, run_file ? "\"control\"" : "--control"});
  }
  for (const File& o : outputs) {
    if (auto error = base::CheckOutputPath(o.path, "")) throw ConfigError(o.role + " " + *error);
  }
  auto clash = [](const File& a, const File& b, std::string_view why, std::string_view fix) {
    throw ConfigError(a.role + " " + a.path + " is also " + b.role + " " + b.path + ": " +
                      std::string(why) + "; " + std::string(fix));
  };
  for (size_t i = 0; i < outputs.size(); ++i) {
    for (size_t j = i + 1; j < outputs.size(); ++j) {
      if (base::SamePath(outputs[i].path, outputs[j].path)) {
        clash(outputs[j], outputs[i], "one would overwrite the other",
              "give each its own file (e.g. " + outputs[j].role + " " + outputs[j].path + ".2)");
      }
    }
    for (const File& in : inputs) {
      if (base::SamePath(outputs[i].path, in.path)) {
        clash(outputs[i], in, "writing the output would destroy the input",
              "give " + outputs[i].role + " another path");
      }
    }
    for (const File& port : served) {
      if (base::SamePath(outputs[i].path, port.path)) {
        clash(outputs[i], port,
              "the emulator serves a port there (a PTY's link, the control socket), which the "
              "output would be written into or replace",
              "give " + outputs[i].role + " a path of its own");
      }
    }
  }
  for (size_t i = 0; i < served.size(); ++i) {
    for (size_t j = i + 1; j < served.size(); ++j) {
      if (base::SamePath(served[i].path, served[j].path)) {
        clash(served[j], served[i], "two ports cannot share one path", "give each its own path");
      }
    }
    for (const File& in : inputs) {
      if (base::SamePath(served[i].path, in.path)) {
        clash(served[i], in, "serving the port there would replace the input",
              "give " + served[i].role + " another path");
      }
    }
  }
}

}  // namespace

// $XDG_STATE_HOME/mocosim/<name>.json, else ~/.local/state/mocosim/<name>.json,
// else ./<name>.state.json.
std::string DefaultStatePath(const std::string& name) {
  namespace fs = std::filesystem;
  if (const char* x = std::getenv("XDG_STATE_HOME"); x != nullptr && *x == '/') {
    return (fs::path(x) / "mocosim" / (name + ".json")).string();
  }
  if (const char* h = std::getenv("HOME"); h != nullptr && *h == '/') {
    return (fs::path(h) / ".local" / "state" / "mocosim" / (name + ".json")).string();
  }
  return name + ".state.json";
}

struct Emulator::Served {
  DeviceConfig config;
  bool default_state = false;             // state_path is DefaultStatePath(name)
  std::unique_ptr<FileStateStore> store;  // outlives `device`
  std::unique_ptr<session::SessionWriter> writer;
  std::unique_ptr<SessionTap> tap;
  std::unique_ptr<DebugTap> debug;
  TeeObserver tee;
  std::unique_ptr<DeviceServer> server;
  std::unique_ptr<DeviceServerLink> link;  // the server as control reaches it
  std::unique_ptr<devices::Device> device;
  // --vcd: per motor a STEP and a DIR wire, fed by step traces on the rig.
  std::vector<base::VcdWire> vcd_wires;
  std::vector<std::unique_ptr<sim::StepTrace>> step_traces;  // after `device`: destroyed first
  size_t vcd_changes = 0;

  // --vcd: a STEP and a DIR wire per motor of `rig`, fed by a step trace each.
  void TraceSteps(sim::Rig& rig);
};

namespace {

// Each step of the model as a pulse at its exact edge time (kVcdPulseNs wide),
// DIR set kVcdDirLeadNs before the step that needs it (docs/pins.md).
constexpr int64_t kVcdPulseNs = 2'000;
constexpr int64_t kVcdDirLeadNs = 1'000;
constexpr size_t kVcdMaxChanges = size_t{16} << 20;

}  // namespace

void Emulator::Served::TraceSteps(sim::Rig& rig) {
  Served* served = this;
  for (int id = 1; id <= rig.motor_count(); ++id) {
    const size_t step = served->vcd_wires.size();
    served->vcd_wires.push_back({"m" + std::to_string(id) + "_step", false, {}});
    served->vcd_wires.push_back({"m" + std::to_string(id) + "_dir", true, {}});
    served->step_traces.push_back(std::make_unique<sim::StepTrace>(
        rig.motor(id), 1, 0, sim::kTimeNever, [served, step](const sim::StepEdge& e) {
          if (served->vcd_changes >= kVcdMaxChanges) return;
          base::VcdWire& dir = served->vcd_wires[step + 1];
          const bool up = e.direction > 0;
          const bool was = dir.changes.empty() ? dir.initial : dir.changes.back().second;
          if (up != was) dir.changes.emplace_back(e.time_ns - kVcdDirLeadNs, up);
          auto& pulses = served->vcd_wires[step].changes;
          pulses.emplace_back(e.time_ns, true);
          pulses.emplace_back(e.time_ns + kVcdPulseNs, false);
          served->vcd_changes += 3;
        }));
  }
}

namespace {

// Names the devices that have no name ("dmc16", "dmc16-2", ...), each name
// unique, and gives a model that keeps state the default state file when it
// has none (creating its folder). The names of those so defaulted.
std::set<std::string> NameDevices(std::vector<DeviceConfig>& configs) {
  std::set<std::string> names;
  std::set<std::string> defaulted_state;
  std::map<std::string, int> per_model;
  for (DeviceConfig& d : configs) {
    if (d.name.empty()) {
      const int n = ++per_model[d.model];
      d.name = n == 1 ? d.model : d.model + "-" + std::to_string(n);
    }
    if (!names.insert(d.name).second) {
      throw ConfigError("two devices are named \"" + d.name + "\"; give each a unique \"name\"");
    }
    const devices::DeviceModel* model = devices::FindDeviceModel(d.model);
    if (model != nullptr && !model->keeps_state && !d.state_path.empty()) {
      throw ConfigError(d.name + ": a " + d.model + " keeps no state, so it takes no state file (" +
                        d.state_path + "); remove \"state\" (only stackshot3x has NVM)");
    }
    if (model != nullptr && model->keeps_state && d.state_path.empty()) {
      // The shared default: the lock taken below keeps two processes off it.
      d.state_path = DefaultStatePath(d.name);
      defaulted_state.insert(d.name);
      std::error_code ec;
      std::filesystem::create_directories(std::filesystem::path(d.state_path).parent_path(), ec);
    }
  }
  return defaulted_state;
}

}  // namespace

Emulator::Emulator(EmulatorConfig config, LogFn log)
    : config_(std::move(config)), log_(std::move(log)), driver_(io_, scheduler_) {
  if (!log_) log_ = LogToStderr;
  // SIGHUP (the terminal closed) stops as cleanly as SIGINT and SIGTERM:
  // recordings completed, symlinks and the control socket removed. Caught
  // from here on, before any PTY link exists or a line is logged, so a
  // signal sent as soon as the device appears is never the default death;
  // one that arrives before Run() is handled as Run() starts.
  signals_ = std::make_unique<asio::signal_set>(io_, SIGINT, SIGTERM, SIGHUP);
  signals_->async_wait([this](const ErrorCode& ec, int sig) {
    if (ec) return;
    Log(LogLevel::kInfo, std::string("stopping on ") + (sig == SIGINT   ? "SIGINT"
                                                        : sig == SIGHUP ? "SIGHUP"
                                                                        : "SIGTERM"));
    Stop();
  });
  if (config_.devices.empty()) {
    throw ConfigError("no device to serve; give at least one (e.g. --pty /tmp/dmc16)");
  }
  const std::set<std::string> defaulted_state = NameDevices(config_.devices);
  CheckFiles(config_);
  try {
    for (const DeviceConfig& d : config_.devices) {
      const devices::DeviceModel* model = devices::FindDeviceModel(d.model);
      if (model == nullptr) {
        std::string known;
        for (const auto& m : devices::DeviceModels())
          known += (known.empty() ? "" : ", ") + std::string(m.name);
        throw ConfigError(d.name + ": unknown model \"" + d.model + "\"; the models are " + known);
      }
      auto s = std::make_unique<Served>();
      s->config = d;
      s->default_state = defaulted_state.count(d.name) > 0;
      if (config_.log_level >= LogLevel::kDebug) {
        s->debug = std::make_unique<DebugTap>(model->protocol, d.name, log_);
        s->tee.Add(s->debug.get());
      }
      ServeOptions opts;
      opts.no_pacing = d.no_pacing;
      opts.bind_address = config_.bind_address;
      if (!d.faults.empty()) {
        auto parsed = ParseFaultConfig(d.faults);
        if (const auto* err = std::get_if<std::string>(&parsed)) {
          throw ConfigError(d.name + ": bad fault config \"" + d.faults + "\": " + *err);
        }
        opts.faults = std::get<FaultConfig>(parsed);
      }
      // The recording's tap joins the tee below, once everything else has started.
      opts.observer = s->tee.empty() && d.record_path.empty() ? nullptr : &s->tee;
      const std::string name = d.name;
      const LogLevel level = config_.log_level;
      LogFn sink = log_;
      opts.log = [name, level, sink](std::string_view line) {
        if (level >= LogLevel::kInfo) sink(name + ": " + std::string(line));
      };
      try {
        s->server = std::make_unique<DeviceServer>(driver_, d.endpoint, opts);
        s->link = std::make_unique<DeviceServerLink>(*s->server);
      } catch (const std::exception& e) {
        throw std::runtime_error(d.name + ": " + e.what());
      }
      if (model->keeps_state) {
        s->store = std::make_unique<FileStateStore>(s->config.state_path);
        devices::StateLoad first;
        if (auto error = s->store->Open(&first)) throw ConfigError(d.name + ": " + *error);
        if (first.status == devices::StateLoad::Status::kCorrupt) {
          Log(LogLevel::kWarn, d.name + ": " + first.message);
        }
      }
      try {
        s->device = devices::CreateDevice(d.model, d.profile_path, scheduler_, s->server->sink(),
                                          s->store.get());
      } catch (const devices::ProfileError&) {
        throw;
      } catch (const std::exception& e) {
        throw ConfigError(d.name + ": " + e.what());
      }
      // A device served over Wi-Fi frames (and, a StackShot, speaks) as its
      // network link does.
      if (s->server->wifi() != nullptr) s->device->SetHostLink(devices::HostLink::kWifi);
      if (!d.vcd_path.empty() && s->device->rig() != nullptr) s->TraceSteps(*s->device->rig());
      // Last, so that a device failing to start leaves no recording behind.
      if (!d.record_path.empty()) {
        session::SessionHeader h;
        h.protocol = model->protocol;
        h.device = std::string(model->name);
        h.clock = "virtual";
        h.note = "recorded by mocosim from " + s->server->Where();  // the bound port, not :0
        s->writer = std::make_unique<session::SessionWriter>(d.record_path, h);
        s->tap = std::make_unique<SessionTap>(*s->writer, model->protocol);
        s->tee.Add(s->tap.get());
        if (s->writer->replaces_existing()) {
          Log(LogLevel::kWarn, d.name + ": " + d.record_path +
                                   " exists; the recording replaces it when mocosim stops");
        }
      }
      served_.push_back(std::move(s));
    }
  } catch (...) {
    for (auto& s : served_) {
      if (s->server) s->server->Stop();
      // A start that failed records nothing: an earlier file at the path stays.
      if (s->writer) s->writer->Abandon();
    }
    throw;
  }
}

Emulator::~Emulator() { Stop(); }

const std::string& Emulator::name(size_t i) const { return served_[i]->config.name; }
devices::Device& Emulator::device(size_t i) { return *served_[i]->device; }
DeviceServer& Emulator::server(size_t i) { return *served_[i]->server; }
control::LinkControl& Emulator::link_control(size_t i) { return *served_[i]->link; }
const std::string& Emulator::state_path(size_t i) const { return served_[i]->config.state_path; }

void Emulator::RecordEvent(const std::string& name, const session::SessionEntry& entry) {
  for (auto& s : served_) {
    if (s->config.name == name && s->writer && !stopped_) s->writer->Append(entry);
  }
}

void Emulator::AttachControl(control::ControlChannel& channel) {
  channel.SetActionListener([this](const control::ControlEvent& e) {
    Log(LogLevel::kInfo, "control: " + e.SessionLine().dump());
    const std::string cmd = e.request.value("cmd", "");
    if (cmd == "power_cycle" || cmd == "cut_link") return;
    std::string device = e.request.value("device", "");
    if (device.empty() && size() == 1) device = name(0);
    RecordEvent(device, e.ToSessionEntry());
  });
  // What the simulated hardware did by itself: the host hears nothing of it,
  // the log and the recording do.
  channel.SetDeviceEventListener([this](const control::DeviceEvent& e) {
    Log(LogLevel::kWarn, e.device + ": " + e.SessionLine().dump());
    RecordEvent(e.device, e.ToSessionEntry());
  });
}

void Emulator::Log(LogLevel level, std::string_view line) const {
  if (level <= config_.log_level) log_(line);
}

void Emulator::Start() {
  for (auto& s : served_) {
    s->server->Serve(*s->device);
  }
  driver_.Start();
  for (auto& s : served_) {
    driver_.Sync();
    s->device->PowerOn();
    Log(LogLevel::kError,
        s->config.name + " (" + s->config.model + ") on " + s->server->Where() +
            (s->config.state_path.empty() ? "" : ", state " + s->config.state_path) +
            (s->default_state ? " (the default for this name; --state PATH for another)" : ""));
  }
  driver_.Kick();
  if (hooks_.on_started) hooks_.on_started();
}

int Emulator::Run() {
  io_.run();
  Stop();
  return exit_code_;
}

void Emulator::Stop() {
  if (stopped_) return;
  stopped_ = true;
  if (hooks_.on_stopping) hooks_.on_stopping();
  if (signals_) {
    ErrorCode ignored;
    signals_->cancel(ignored);
  }
  for (auto& s : served_) {
    if (s->server) s->server->Stop();
  }
  driver_.Stop();
  for (auto& s : served_) {
    if (s->config.vcd_path.empty() || s->vcd_wires.empty()) continue;
    for (auto& t : s->step_traces) t->Sync();
    const std::string text =
        base::VcdText(s->config.name, "mocosim " + s->config.model + " step model", s->vcd_wires);
    if (auto error = base::WriteFileAtomically(s->config.vcd_path, text)) {
      Log(LogLevel::kError, s->config.name + ": VCD not written: " + *error);
      exit_code_ = 1;
    } else {
      Log(LogLevel::kInfo, s->config.name + ": wrote " + s->config.vcd_path);
    }
  }
  for (auto& s : served_) {
    if (s->writer) {
      std::string error;
      if (!s->writer->Finish(&error)) {
        Log(LogLevel::kError, s->config.name + ": recording not completed: " + error);
        exit_code_ = 1;
      } else {
        Log(LogLevel::kInfo,
            s->config.name + ": recorded " + s->writer->path().string() +
                (s->writer->replaces_existing() ? " (replacing the previous file)" : ""));
      }
    }
  }
  io_.stop();
}

// --- run files ----------------------------------------------------------------------------------

EmulatorConfig ParseRunConfig(const nlohmann::json& j, const std::string& where,
                              const std::string& base_dir) {
  EmulatorConfig c;
  auto path_of = [&](const std::string& p) {
    if (p.empty()) return p;
    std::filesystem::path fp(p);
    return fp.is_absolute() ? p : (std::filesystem::path(base_dir) / fp).string();
  };
  try {
    devices::ProfileReader r(j, where, "", "docs/run-files.md");
    c.control_path = path_of(r.GetString("control", ""));
    c.scenario_path = path_of(r.GetString("scenario", ""));
    c.bind_address = r.GetString("bind", c.bind_address);
    const std::string level = r.GetString("log_level", "info");
    try {
      c.log_level = ParseLogLevel(level);
    } catch (const std::invalid_argument&) {
      r.Fail("log_level", "is \"" + level + "\"", "use error, warn, info or debug");
    }
    const nlohmann::json& devs = r.GetRaw("devices");
    if (!devs.is_array() || devs.empty()) {
      r.Fail("devices", devs.is_null() ? "is missing" : "must be a non-empty array",
             "list the devices: \"devices\": [{\"model\": \"dmc16\", \"endpoint\": "
             "\"pty:/tmp/dmc16\"}]");
    }
    for (size_t i = 0; i < devs.size(); ++i) {
      devices::ProfileReader d(devs[i], where, "devices[" + std::to_string(i) + "]",
                               "docs/run-files.md");
      DeviceConfig dc;
      dc.model = d.GetString("model", "dmc16");
      if (devices::FindDeviceModel(dc.model) == nullptr) {
        std::string known;
        for (const auto& m : devices::DeviceModels())
          known += (known.empty() ? "" : ", ") + std::string(m.name);
        d.Fail("model", "is \"" + dc.model + "\", not a known model", "use one of: " + known);
      }
      dc.name = d.GetString("name", "");
      dc.endpoint = d.GetString("endpoint", "");
      if (dc.endpoint.empty()) {
        d.Fail("endpoint", "is missing", "give \"pty:/path\" or \"tcp:127.0.0.1:5000\"");
      }
      if (dc.endpoint.rfind("pty:", 0) == 0) {
        dc.endpoint = "pty:" + path_of(dc.endpoint.substr(4));
      }
      dc.profile_path = path_of(d.GetString("profile", ""));
      dc.record_path = path_of(d.GetString("record", ""));
      dc.state_path = path_of(d.GetString("state", ""));
      if (!dc.state_path.empty() && !devices::FindDeviceModel(dc.model)->keeps_state) {
        d.Fail("state", "is given, but a " + dc.model + " keeps no state",
               "remove it (only stackshot3x keeps its NVM in a state file)");
      }
      dc.no_pacing = d.GetBool("no_pacing", false);
      dc.faults = d.GetString("faults", "");
      d.Finish();
      c.devices.push_back(dc);
    }
    r.Finish();
  } catch (const devices::ProfileError& e) {
    throw ConfigError(e.what());
  }
  return c;
}

EmulatorConfig LoadRunConfig(const std::string& path) {
  const std::string where = "run file " + path;
  std::string text;
  if (auto error = base::ReadFileBounded(path, &text)) throw ConfigError(where + " " + *error);
  try {
    const nlohmann::json j = devices::ParseProfileText(text, where);
    EmulatorConfig c = ParseRunConfig(j, where, std::filesystem::path(path).parent_path().string());
    c.run_file_path = path;
    return c;
  } catch (const devices::ProfileError& e) {
    throw ConfigError(e.what());
  }
}

}  // namespace moco::serve
