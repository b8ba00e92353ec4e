// mocosim: emulated motion-control devices (DMC-16, DFMoco Arduino, StackShot
// 3X) served over PTY or TCP, and tools for their session recordings.
#include <CLI/CLI.hpp>

#include <cinttypes>
#include <cstdio>
#include <memory>
#include <string>
#include <variant>
#include <vector>

#include "control/control_channel.h"
#include "control/scenario.h"
#include "control/session.h"
#include "devices/profile.h"
#include "devices/registry.h"
#include "transport/control_socket.h"
#include "transport/serve.h"
#include "wire/transcript.h"

namespace {

using moco::control::LoadSession;
using moco::control::Origin;
using moco::control::Session;
using moco::control::SessionError;
using moco::wire::Side;
using moco::wire::TranscriptDecoder;
using moco::wire::TranscriptLine;

void PrintLines(int64_t t_ns, const std::vector<TranscriptLine>& lines, bool show_time,
                size_t& problems) {
  for (const auto& l : lines) {
    if (l.problem) ++problems;
    const char* arrow = l.from == Side::kHost ? "host -> dev " : "dev  -> host";
    if (show_time) {
      std::printf("%12.6f  %s  %s%s\n", static_cast<double>(t_ns) / 1e9, arrow,
                  l.problem ? "!! " : "", l.text.c_str());
    } else {
      std::printf("%s  %s%s\n", arrow, l.problem ? "!! " : "", l.text.c_str());
    }
  }
}

// `mocosim decode SESSION`: prints the session as a transcript. Exit 0 when
// every byte decoded cleanly, 1 when the traffic has problems (they are
// printed with "!!"), 2 when the file cannot be read.
int Decode(const std::string& path, bool show_time, bool strict) {
  auto loaded = LoadSession(path);
  if (const auto* e = std::get_if<SessionError>(&loaded)) {
    std::fprintf(stderr, "mocosim decode: %s%s%s\n", path.c_str(),
                 e->line ? (":" + std::to_string(e->line) + ": ").c_str() : ": ",
                 e->message.c_str());
    return 2;
  }
  const Session& s = std::get<Session>(loaded);
  std::printf("session %s: protocol %s%s%s, %zu entries\n", path.c_str(),
              std::string(ProtocolName(s.header.protocol)).c_str(),
              s.header.device.empty() ? "" : ", device ", s.header.device.c_str(),
              s.entries.size());
  if (!s.header.note.empty()) std::printf("  %s\n", s.header.note.c_str());
  TranscriptDecoder decoder(s.header.protocol);
  size_t problems = 0;
  int64_t last_t = 0;
  for (const auto& e : s.entries) {
    last_t = e.t_ns;
    if (e.is_event) {
      std::printf("%12.6f  event        %s\n", static_cast<double>(e.t_ns) / 1e9,
                  e.event.dump().c_str());
      continue;
    }
    PrintLines(e.t_ns, decoder.Feed(e.from == Origin::kHost ? Side::kHost : Side::kDevice, e.bytes),
               show_time, problems);
  }
  PrintLines(last_t, decoder.Finish(), show_time, problems);
  std::printf("%zu problem(s) in the traffic\n", problems);
  return strict && problems > 0 ? 1 : 0;
}

// Runs the emulator until Ctrl-C, with the control socket and the scenario
// when asked for. Exit 0 on a clean stop, 1 when a recording could not be
// completed, 2 when the devices cannot be set up (the message names the
// device, the field and the fix).
int Serve(moco::transport::EmulatorConfig config) {
  using moco::control::ControlChannel;
  try {
    moco::transport::Emulator emulator(std::move(config));
    ControlChannel channel(emulator.scheduler());
    for (size_t i = 0; i < emulator.size(); ++i) {
      channel.AddDevice(emulator.name(i), emulator.device(i), &emulator.server(i));
    }
    emulator.AttachControl(channel);
    const auto& cfg = emulator.config();
    std::unique_ptr<moco::control::ScenarioRun> scenario_run;
    if (!cfg.scenario_path.empty()) {
      const auto scenario = moco::control::Scenario::Load(cfg.scenario_path);
      // Times are from power-on (scheduler time 0, when the clock starts).
      scenario_run = scenario.Schedule(channel, emulator.scheduler(), emulator.scheduler().Now());
      emulator.Log(moco::transport::LogLevel::kInfo, "scenario " + cfg.scenario_path + ": " +
                                                         std::to_string(scenario_run->remaining()) +
                                                         " event(s)");
    }
    std::unique_ptr<moco::transport::ControlSocket> socket;
    if (!cfg.control_path.empty()) {
      moco::transport::ControlSocketOptions opts;
      opts.log = [&emulator](std::string_view l) {
        emulator.Log(moco::transport::LogLevel::kWarn, "control socket: " + std::string(l));
      };
      socket = std::make_unique<moco::transport::ControlSocket>(
          emulator.driver(), cfg.control_path,
          [&channel](std::string_view line) { return channel.Handle(line); }, opts);
    }
    moco::transport::EmulatorHooks hooks;
    hooks.on_stopping = [&] {
      if (scenario_run) scenario_run->Cancel();
      if (socket) socket->Stop();
    };
    emulator.SetHooks(hooks);
    emulator.Start();
    if (socket) {
      emulator.Log(moco::transport::LogLevel::kError,
                   "control socket " + socket->path() + " (JSON lines; send {\"cmd\":\"help\"})");
    }
    emulator.Log(moco::transport::LogLevel::kWarn,
                 "serving " + std::to_string(emulator.size()) + " device(s); Ctrl-C stops");
    return emulator.Run();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "mocosim: %s\n", e.what());
    return 2;
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"mocosim: emulated DMC-16, DFMoco Arduino and StackShot 3X devices"};
  app.set_version_flag("--version", "mocosim 0.1.0");
  app.require_subcommand(1);

  std::string session_path;
  bool no_time = false;
  bool strict = false;
  auto* decode = app.add_subcommand(
      "decode",
      "Print a session file (docs/sessions.md) as a human-readable transcript: every frame "
      "checked and decoded, problems marked with !!");
  decode->add_option("session", session_path, "Session file (.jsonl)")
      ->required()
      ->check(CLI::ExistingFile);
  decode->add_flag("--no-time", no_time, "Omit the timestamp column");
  decode->add_flag("--strict", strict,
                   "Exit with status 1 when the traffic has problems (bad checksums, "
                   "unparsable lines, skipped bytes)");

  // --- one device: mocosim <model> --pty PATH | --tcp [HOST:]PORT ---
  struct OneDevice {
    CLI::App* cmd = nullptr;
    CLI::Option* wifi_opt = nullptr;  // models that have a Wi-Fi link
    moco::transport::DeviceConfig config;
    std::string pty_path, tcp_spec, wifi_spec, log_level = "info", control_path, scenario_path;
  };
  std::vector<std::unique_ptr<OneDevice>> one_device;
  for (const auto& model : moco::devices::DeviceModels()) {
    auto o = std::make_unique<OneDevice>();
    const std::string name(model.name);
    o->config.model = name;
    o->cmd = app.add_subcommand(
        name, "Emulate a " + std::string(model.description) +
                  " on a PTY or a TCP port until Ctrl-C. Example: mocosim " + name +
                  " --pty /tmp/" + name + "  (then point the host at /tmp/" + name + ")");
    auto* pty_opt = o->cmd->add_option(
        "--pty", o->pty_path, "Create a PTY with a stable symlink at this path (mode 0600)");
    auto* tcp_opt = o->cmd->add_option(
        "--tcp", o->tcp_spec,
        "Listen on TCP [HOST:]PORT instead (default host 127.0.0.1; port 0 = any free port)");
    pty_opt->excludes(tcp_opt);
    if (model.protocol == moco::wire::Protocol::kStackshot) {
      auto* wifi_opt = o->wifi_opt = o->cmd->add_option(
          "--wifi", o->wifi_spec,
          "Serve over Wi-Fi as the real unit does: hear the host's FINDSTACK on UDP, then "
          "connect to its TCP port. ADDRESS[:UDP_PORT[:HOST_TCP_PORT]], default "
          "0.0.0.0:24869:24870 (give \"\" for the defaults)");
      wifi_opt->excludes(pty_opt)->excludes(tcp_opt);
    }
    o->cmd
        ->add_option("--profile", o->config.profile_path,
                     "Device profile (JSON; default: built-in, as " +
                         std::string(model.default_profile) + "; fields in docs/profiles.md)")
        ->check(CLI::ExistingFile);
    o->cmd->add_option("--record", o->config.record_path,
                       "Record every byte in and out with its time and decoded message to this "
                       "session file (.jsonl, docs/sessions.md; completed on exit)");
    o->cmd->add_option("--control", o->control_path,
                       "Serve the JSON-lines control socket at this path (e-stop, limits, "
                       "inputs, power, faults, state; docs/control.md)");
    if (model.keeps_state) {
      o->cmd->add_option(
          "--state", o->config.state_path,
          "File keeping the device's NVM (settings, slots, serial number, log) "
          "across runs, written atomically (default: "
          "$XDG_STATE_HOME/mocosim/<name>.json or ~/.local/state/mocosim/<name>.json)");
    }
    o->cmd
        ->add_option("--scenario", o->scenario_path,
                     "Play this scenario file of timed control events (docs/control.md)")
        ->check(CLI::ExistingFile);
    o->cmd->add_option("--faults", o->config.faults,
                       "Inject link faults, e.g. seed=42,dir=to-host,drop=0.01 (dir= applies "
                       "to the rates after it)");
    o->cmd->add_flag("--no-pacing", o->config.no_pacing,
                     "Deliver bytes at once instead of at the profile's baud rate");
    o->cmd->add_option("--name", o->config.name,
                       "Name in log lines and on the control socket (default: " + name + ")");
    o->cmd
        ->add_option("--log-level", o->log_level,
                     "error, warn, info (default) or debug (every message decoded)")
        ->check(CLI::IsMember({"error", "warn", "info", "debug"}));
    one_device.push_back(std::move(o));
  }

  // --- several devices from a run file ---
  std::string run_path;
  auto* run = app.add_subcommand(
      "run", "Serve every device of a run file (JSON, see docs/run-files.md) until Ctrl-C");
  run->add_option("file", run_path, "Run file, e.g. fixtures/runs/two-dmc16.json")
      ->required()
      ->check(CLI::ExistingFile);

  auto* models = app.add_subcommand("models", "List the device models that can be emulated");

  CLI11_PARSE(app, argc, argv);

  if (decode->parsed()) return Decode(session_path, !no_time, strict);
  if (models->parsed()) {
    for (const auto& m : moco::devices::DeviceModels()) {
      std::printf("%-12s %s (profile %s)\n", std::string(m.name).c_str(),
                  std::string(m.description).c_str(), std::string(m.default_profile).c_str());
    }
    return 0;
  }
  for (auto& o : one_device) {
    if (!o->cmd->parsed()) continue;
    const std::string cmd = o->config.model;
    const bool wifi = o->wifi_opt != nullptr && o->wifi_opt->count() > 0;
    if (o->pty_path.empty() && o->tcp_spec.empty() && !wifi) {
      std::fprintf(stderr,
                   "mocosim %s: say where to serve the device: --pty /tmp/%s or "
                   "--tcp 127.0.0.1:5000\n",
                   cmd.c_str(), cmd.c_str());
      return 2;
    }
    o->config.endpoint = wifi                  ? "wifi:" + o->wifi_spec
                         : o->pty_path.empty() ? "tcp:" + o->tcp_spec
                                               : "pty:" + o->pty_path;
    moco::transport::EmulatorConfig config;
    config.devices.push_back(o->config);
    config.control_path = o->control_path;
    config.scenario_path = o->scenario_path;
    config.log_level = moco::transport::ParseLogLevel(o->log_level);
    return Serve(std::move(config));
  }
  if (run->parsed()) {
    try {
      return Serve(moco::transport::LoadRunConfig(run_path));
    } catch (const std::exception& e) {
      std::fprintf(stderr, "mocosim run: %s\n", e.what());
      return 2;
    }
  }
  return 0;
}
