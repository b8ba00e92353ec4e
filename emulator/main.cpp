// mocosim: emulated motion-control devices (DMC-16, DFMoco Arduino, StackShot
// 3X) served over PTY or TCP, and tools for their session recordings.
#include <CLI/CLI.hpp>

#include <algorithm>
#include <cinttypes>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "base/file_io.h"
#include "cli_numbers.h"
#include "control/control_channel.h"
#include "control/scenario.h"
#include "devices/profile.h"
#include "devices/registry.h"
#include "physics/bullet/rig_path_svg.h"
#include "plot/rig_plot.h"
#include "serve/serve.h"
#include "serve/tap.h"
#include "session/pcapng.h"
#include "session/session.h"
#include "transport/control_socket.h"
#include "wire/protocol.h"
#include "wire/transcript.h"

namespace {

using moco::session::LoadSession;
using moco::session::Origin;
using moco::session::Session;
using moco::session::SessionError;
using moco::session::SessionWarning;
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

// "StackShot 3X (DfMoco mode) at 57600 baud": what a device's line can switch
// to (devices/registry.h also_speaks), for help texts.
std::string LineSwitchList() {
  std::string list;
  for (const moco::devices::DeviceModel& m : moco::devices::DeviceModels()) {
    for (const moco::wire::Protocol p : m.also_speaks) {
      if (!list.empty()) list += ", ";
      list += std::string(moco::wire::Info(p).title) + " at " +
              std::to_string(moco::wire::Info(p).line.baud) + " baud";
    }
  }
  return list;
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
      // The traffic after a recorded switch of the line speaks its protocol.
      if (const auto p = moco::session::LineSwitchOf(e)) {
        decoder.SwitchTo(*p);
      } else if (e.event.is_object() && e.event.value("event", "") == "line_switch") {
        // A switch this build cannot follow: the traffic after it is read
        // as before, and says so.
        std::vector<moco::wire::Protocol> known;
        for (const moco::wire::ProtocolInfo& info : moco::wire::Protocols()) {
          known.push_back(info.id);
        }
        std::printf(
            "!! the line_switch names no protocol this mocosim knows (give \"protocol\": "
            "one of %s); the traffic after it is read as %s\n",
            moco::wire::NameList(known).c_str(),
            std::string(ProtocolName(decoder.protocol())).c_str());
        ++problems;
      }
      continue;
    }
    PrintLines(e.t_ns,
               decoder.Feed(e.from == Origin::kHost ? Side::kHost : Side::kDevice, e.bytes, e.t_ns),
               show_time, problems);
  }
  PrintLines(last_t, decoder.Finish(), show_time, problems);
  if (const std::string warning = SessionWarning(s); !warning.empty()) {
    // A cut recording is a problem of the capture (--strict fails on it).
    std::printf("!! %s\n", warning.c_str());
    ++problems;
  }
  std::printf("%zu problem(s) in the traffic\n", problems);
  return strict && problems > 0 ? 1 : 0;
}

// Checks an output before any work (docs/files.md) and prints why it cannot
// be written. `defaulted`: the path was made beside the session because no
// -o was given, so the fix is -o. Returns true when it cannot be written.
bool CheckDefaultOrOutput(const std::string& out, bool defaulted, const char* command,
                          const char* what) {
  if (!defaulted) {
    if (auto error = moco::base::CheckOutputPath(out, "--output")) {
      std::fprintf(stderr, "mocosim %s: %s\n", command, error->c_str());
      return true;
    }
    return false;
  }
  if (auto error = moco::base::CheckOutputPath(out, "")) {
    // The fix here is -o, not the one the check suggests.
    if (const size_t fix = error->rfind("; give"); fix != std::string::npos) error->resize(fix);
    const std::string name = std::filesystem::path(out).filename().string();
    std::fprintf(stderr,
                 "mocosim %s: without -o the %s goes beside the session: %s; give -o FILE "
                 "in a writable folder (e.g. -o /tmp/%s)\n",
                 command, what, error->c_str(), name.c_str());
    return true;
  }
  return false;
}

// `mocosim export --pcapng SESSION -o FILE`: writes the session's traffic as
// a pcapng capture (session/pcapng.h, docs/wireshark.md), atomically. Exit 0
// when written, 1 when writing failed, 2 for bad arguments or files.
int ExportPcapng(const std::string& session_path, const std::string& out_path) {
  const std::string out =
      out_path.empty() ? std::filesystem::path(session_path).replace_extension(".pcapng").string()
                       : out_path;
  if (CheckDefaultOrOutput(out, out_path.empty(), "export", "capture")) return 2;
  if (moco::base::SamePath(out, session_path)) {
    std::fprintf(stderr,
                 "mocosim export: --output %s is the session itself; writing it would destroy "
                 "it: give another -o\n",
                 out.c_str());
    return 2;
  }
  auto loaded = LoadSession(session_path);
  if (const auto* e = std::get_if<SessionError>(&loaded)) {
    std::fprintf(stderr, "mocosim export: %s%s%s\n", session_path.c_str(),
                 e->line ? (":" + std::to_string(e->line) + ": ").c_str() : ": ",
                 e->message.c_str());
    return 2;
  }
  const Session& s = std::get<Session>(loaded);
  if (const std::string w = SessionWarning(s); !w.empty()) {
    std::fprintf(stderr, "mocosim export: %s: %s\n", session_path.c_str(), w.c_str());
  }
  moco::session::PcapngStats stats;
  const std::string capture = moco::session::SessionToPcapng(s, &stats);
  if (auto error = moco::base::WriteFileAtomically(out, capture)) {
    std::fprintf(stderr, "mocosim export: %s\n", error->c_str());
    return 1;
  }
  std::printf("wrote %s%s: %zu packet(s), %zu byte(s) of %s traffic", out.c_str(),
              out_path.empty() ? " (beside the session; -o FILE writes elsewhere)" : "",
              stats.packets, stats.bytes, std::string(ProtocolName(s.header.protocol)).c_str());
  if (stats.events_left_out > 0) {
    std::printf(" (%zu event line(s) left out: a capture holds traffic only)",
                stats.events_left_out);
  }
  std::printf("\n");
  return 0;
}

// Arguments of `mocosim plot`.
struct PlotArgs {
  std::string session_path;
  std::string profile_path;
  std::string out_path;  // empty: the session's path with .svg
  double every_ms = 10;
  std::optional<double> from_s;
  std::optional<double> to_s;
  double tail_s = 2;
  std::string title;  // empty: "<rig name>: <session file name>"
};

// `mocosim plot SESSION --profile PROFILE`: replays the session's host bytes
// into a DMC-16 driving the profile's physical rig and writes the camera
// head's path, commanded against physical, as SVG (atomically). Exit 0 when
// the plot was written, 1 when writing it failed, 2 for bad arguments or
// files (the message names the problem and the fix).
int Plot(const PlotArgs& a) {
  const std::string out =
      a.out_path.empty() ? std::filesystem::path(a.session_path).replace_extension(".svg").string()
                         : a.out_path;
  // The output is checked before the work, and never written over an input.
  if (CheckDefaultOrOutput(out, a.out_path.empty(), "plot", "plot")) return 2;
  for (const std::string& input : {a.session_path, a.profile_path}) {
    if (moco::base::SamePath(out, input)) {
      std::fprintf(stderr,
                   "mocosim plot: --output %s is also an input (%s); writing it would destroy "
                   "it: give another -o\n",
                   out.c_str(), input.c_str());
      return 2;
    }
  }
  auto loaded = LoadSession(a.session_path);
  if (const auto* e = std::get_if<SessionError>(&loaded)) {
    std::fprintf(stderr, "mocosim plot: %s%s%s\n", a.session_path.c_str(),
                 e->line ? (":" + std::to_string(e->line) + ": ").c_str() : ": ",
                 e->message.c_str());
    return 2;
  }
  if (const std::string w = SessionWarning(std::get<Session>(loaded)); !w.empty()) {
    std::fprintf(stderr, "mocosim plot: %s: %s\n", a.session_path.c_str(), w.c_str());
  }
  if (!(std::isfinite(a.every_ms) && a.every_ms >= 0.001 && a.every_ms <= 3.6e6)) {
    std::fprintf(stderr,
                 "mocosim plot: --every-ms must be a sample period of 0.001 .. 3600000 ms "
                 "(e.g. 10), not %g\n",
                 a.every_ms);
    return 2;
  }
  moco::plot::RigPlotOptions options;
  options.period_ns = std::llround(a.every_ms * 1e6);
  options.from_s = a.from_s;
  options.to_s = a.to_s;
  options.tail_s = a.tail_s;
  const moco::plot::RigPlotResult result =
      moco::plot::PlotSession(std::get<Session>(loaded), a.profile_path, options);
  if (!result.ok()) {
    std::fprintf(stderr, "mocosim plot: %s: %s\n", a.session_path.c_str(),
                 result.error().message.c_str());
    return 2;
  }
  const moco::plot::RigPlot& plot = result.value();
  const moco::plot::RigPlotSummary& sum = plot.summary;
  for (const std::string& w : sum.warnings) {
    std::fprintf(stderr, "mocosim plot: note: %s\n", w.c_str());
  }
  const std::string title =
      a.title.empty()
          ? sum.rig_name + ": " + std::filesystem::path(a.session_path).filename().string()
          : a.title;
  if (auto error =
          moco::base::WriteFileAtomically(out, moco::physics::RigPathSvg(plot.samples, title))) {
    std::fprintf(stderr, "mocosim plot: %s\n", error->c_str());
    return 1;
  }
  std::printf("plot %s: rig \"%s\", %zu samples every %g ms, %.3f s .. %.3f s (%.3f s)\n",
              a.session_path.c_str(), sum.rig_name.c_str(), sum.sample_count,
              static_cast<double>(options.period_ns) / 1e6, sum.start_s,
              sum.start_s + sum.duration_s, sum.duration_s);
  std::printf(
      "  peak deviation %.1f mm at %.3f s, final %.1f mm (physical vs commanded nodal "
      "point)\n",
      sum.peak_deviation_mm, sum.peak_time_s, sum.final_deviation_mm);
  std::string lost;
  for (size_t j = 0; j < sum.lost_steps.size(); ++j) {
    if (sum.lost_steps[j] == 0) continue;
    if (!lost.empty()) lost += ", ";
    lost += std::string(moco::physics::kJointNames[j]) + " " + std::to_string(sum.lost_steps[j]);
  }
  std::printf("  lost steps: %s\n", lost.empty() ? "none" : lost.c_str());
  std::printf("  collisions: %" PRId64 "\n", sum.collisions);
  std::printf("  replayed %" PRIu64 " host message(s), %zu control event(s)\n", sum.host_messages,
              sum.control_events_applied);
  if (!sum.recorded_device_events.empty() || !sum.replayed_device_events.empty()) {
    auto list = [](const std::map<std::string, size_t>& counts) {
      std::string s;
      for (const auto& [kind, n] : counts) {
        if (!s.empty()) s += ", ";
        s += kind + " " + std::to_string(n);
      }
      return s.empty() ? std::string("none") : s;
    };
    std::printf("  device events: recorded %s; this replay %s\n",
                list(sum.recorded_device_events).c_str(), list(sum.replayed_device_events).c_str());
    if (sum.recorded_device_events != sum.replayed_device_events) {
      std::fprintf(stderr,
                   "mocosim plot: note: the replay's stalls and collisions differ from the "
                   "recording's; was the session recorded with this profile and rig?\n");
    }
  }
  std::printf("  wrote %s\n", out.c_str());
  return 0;
}

// Runs the emulator until Ctrl-C, with the control socket and the scenario
// when asked for. Exit 0 on a clean stop, 1 when a recording could not be
// completed, 2 when the devices cannot be set up (the message names the
// device, the field and the fix).
int Serve(moco::serve::EmulatorConfig config) {
  using moco::control::ControlChannel;
  try {
    moco::serve::Emulator emulator(std::move(config));
    ControlChannel channel(emulator.scheduler());
    for (size_t i = 0; i < emulator.size(); ++i) {
      channel.AddDevice(emulator.name(i), emulator.device(i), &emulator.link_control(i));
    }
    emulator.AttachControl(channel);
    const auto& cfg = emulator.config();
    std::unique_ptr<moco::control::ScenarioRun> scenario_run;
    if (!cfg.scenario_path.empty()) {
      const auto scenario = moco::control::Scenario::Load(cfg.scenario_path);
      // Times are from power-on (scheduler time 0, when the clock starts).
      scenario_run = scenario.Schedule(channel, emulator.scheduler(), emulator.scheduler().Now());
      emulator.Log(moco::serve::LogLevel::kInfo, "scenario " + cfg.scenario_path + ": " +
                                                     std::to_string(scenario_run->remaining()) +
                                                     " event(s)");
    }
    std::unique_ptr<moco::transport::ControlSocket> socket;
    if (!cfg.control_path.empty()) {
      moco::transport::ControlSocketOptions opts;
      opts.log = [&emulator](std::string_view l) {
        emulator.Log(moco::serve::LogLevel::kWarn, "control socket: " + std::string(l));
      };
      socket = std::make_unique<moco::transport::ControlSocket>(
          emulator.driver(), cfg.control_path,
          [&channel](std::string_view line) { return channel.Handle(line); }, opts);
    }
    moco::serve::EmulatorHooks hooks;
    hooks.on_stopping = [&] {
      if (scenario_run) scenario_run->Cancel();
      if (socket) socket->Stop();
    };
    emulator.SetHooks(hooks);
    emulator.Start();
    if (socket) {
      emulator.Log(moco::serve::LogLevel::kError,
                   "control socket " + socket->path() + " (JSON lines; send {\"cmd\":\"help\"})");
    }
    emulator.Log(moco::serve::LogLevel::kWarn,
                 "serving " + std::to_string(emulator.size()) + " device(s); Ctrl-C stops");
    return emulator.Run();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "mocosim: %s\n", e.what());
    return 2;
  }
}

// `mocosim decode`: its options, then printing the session.
struct DecodeCli {
  CLI::App* cmd = nullptr;
  std::string session_path;
  bool no_time = false;
  bool strict = false;

  void Add(CLI::App& app) {
    cmd = app.add_subcommand(
        "decode",
        "Print a session file (docs/sessions.md) as a human-readable transcript: every frame "
        "checked and decoded, problems marked with !!");
    cmd->add_option("session", session_path, "Session file (.jsonl)")
        ->required()
        ->check(CLI::ExistingFile);
    cmd->add_flag("--no-time", no_time, "Omit the timestamp column");
    cmd->add_flag("--strict", strict,
                  "Exit with status 1 when the traffic has problems (bad checksums, "
                  "unparsable lines, skipped bytes)");
  }
  int Run() const { return Decode(session_path, !no_time, strict); }
};

// `mocosim export`: its options, then writing the capture.
struct ExportCli {
  CLI::App* cmd = nullptr;
  std::string session, out;
  bool pcapng = false;

  void Add(CLI::App& app) {
    cmd = app.add_subcommand(
        "export",
        "Convert a session file to a capture other tools open. --pcapng: one packet per "
        "recorded chunk with its time (ns) and direction (LINKTYPE_USER0, interface 0 host to "
        "device, 1 device to host); open it in Wireshark with tools/wireshark/mocosim.lua "
        "(docs/wireshark.md). Example: mocosim export --pcapng "
        "fixtures/sessions/dmc16-workflow.jsonl -o workflow.pcapng");
    cmd->add_flag("--pcapng", pcapng, "Write pcapng (the one format so far)")->required();
    cmd->add_option("session", session, "Session file (.jsonl)")->required();
    cmd->add_option("-o,--output", out,
                    "File to write, atomically (default: the session's path with .pcapng)")
        ->check(moco::cli::NonEmptyPath());
  }
  int Run() const { return ExportPcapng(session, out); }
};

// `mocosim plot`: its options, then drawing the plot.
struct PlotCli {
  CLI::App* cmd = nullptr;
  PlotArgs args;
  double from_s = 0, to_s = 0;
  CLI::Option* from_opt = nullptr;
  CLI::Option* to_opt = nullptr;

  void Add(CLI::App& app) {
    using moco::cli::AddNumber;
    cmd = app.add_subcommand(
        "plot",
        "Draw the camera head's path during a DMC v2 session as SVG. The session's host bytes "
        "are replayed at their recorded times (virtual time, from power-on) into a DMC-16 "
        "built from PROFILE, which must drive a Bullet-modelled boom rig (\"physical_rig\", "
        "docs/profiles.md); recorded e-stop and limit control events are applied again. The "
        "plot shows the nodal point in a top view (x, y) and a side view (y, z), in metres: "
        "dashed where the commanded motor positions put it (ideal kinematics), solid where "
        "the simulated rig has it (sag, lag, lost steps, collisions), and the distance "
        "between the two in mm over time; a summary goes to stdout. Example: mocosim plot "
        "fixtures/sessions/dmc16-boom-move.jsonl --profile "
        "fixtures/profiles/dmc16-boom.json -o boom.svg");
    cmd->add_option("session", args.session_path, "Session file (.jsonl, protocol dmc)")
        ->required();
    cmd->add_option("--profile", args.profile_path,
                    "DMC-16 profile with a physical_rig, e.g. fixtures/profiles/dmc16-boom.json")
        ->required()
        ->check(CLI::ExistingFile);
    cmd->add_option("-o,--output", args.out_path,
                    "SVG file to write, atomically (default: the session's path with .svg)")
        ->check(moco::cli::NonEmptyPath());
    AddNumber(cmd, "--every-ms", args.every_ms, 0.001, 3.6e6, "Sample period in ms");
    from_opt =
        AddNumber(cmd, "--from-s", from_s, 0.0, 1e6, "Plot from this time, s since power-on");
    to_opt = AddNumber(cmd, "--to-s", to_s, 0.0, 1e6,
                       "Plot up to this time, s (default: the end of the session)");
    to_opt->default_str("the end");
    AddNumber(cmd, "--tail-s", args.tail_s, 0.0, 3600.0,
              "Keep sampling this long after the last entry while the rig settles; "
              "ends earlier once it is at rest");
    cmd->add_option("--title", args.title,
                    "Title of the plot (default: the rig's name and the session file's name)");
  }
  int Run() {
    if (from_opt->count() > 0) args.from_s = from_s;
    if (to_opt->count() > 0) args.to_s = to_s;
    return Plot(args);
  }
};

// `mocosim <model> --pty PATH | --tcp [HOST:]PORT`: one device of a model,
// its options, then serving it.
struct DeviceCli {
  CLI::App* cmd = nullptr;
  CLI::Option* wifi_opt = nullptr;  // models that have a Wi-Fi link
  moco::serve::DeviceConfig config;
  std::string pty_path, tcp_spec, wifi_spec, log_level = "info", control_path, scenario_path;

  // The options of where the device is served: --pty, --tcp and, for a
  // model with a Wi-Fi link, --wifi.
  void AddEndpoint(const moco::devices::DeviceModel& model) {
    auto* pty_opt = cmd->add_option("--pty", pty_path,
                                    "Create a PTY with a stable symlink at this path (mode 0600)");
    auto* tcp_opt = cmd->add_option(
        "--tcp", tcp_spec,
        "Listen on TCP [HOST:]PORT instead (default host 127.0.0.1; port 0 = any free port)");
    pty_opt->excludes(tcp_opt);
    if (model.wifi) {
      wifi_opt = cmd->add_option(
          "--wifi", wifi_spec,
          "Serve over Wi-Fi as the real unit does: hear the host's FINDSTACK on UDP, then "
          "connect to its TCP port. ADDRESS[:UDP_PORT[:HOST_TCP_PORT]], default "
          "127.0.0.1:24869:24870, loopback like --tcp (give \"\" for the defaults, 0.0.0.0 to "
          "hear FINDSTACK from every network)");
      wifi_opt->excludes(pty_opt)->excludes(tcp_opt);
    }
  }

  void Add(CLI::App& app, const moco::devices::DeviceModel& model) {
    const std::string name(model.name);
    config.model = name;
    cmd = app.add_subcommand(name, "Emulate a " + std::string(model.description) +
                                       " on a PTY or a TCP port until Ctrl-C. Example: mocosim " +
                                       name + " --pty /tmp/" + name +
                                       "  (then point the host at /tmp/" + name + ")");
    AddEndpoint(model);
    cmd->add_option("--profile", config.profile_path,
                    "Device profile (JSON; default: built-in, as " +
                        std::string(model.default_profile) + "; fields in docs/profiles.md)")
        ->check(CLI::ExistingFile);
    cmd->add_option("--record", config.record_path,
                    "Record every byte in and out with its time and decoded message to this "
                    "session file (.jsonl, docs/sessions.md; completed on exit)")
        ->check(moco::cli::NonEmptyPath());
    cmd->add_option("--vcd", config.vcd_path,
                    "Write each motor's STEP and DIR from the step model's exact edge times to "
                    "this Value Change Dump on exit (GTKWave, PulseView; docs/pins.md)")
        ->check(moco::cli::NonEmptyPath());
    cmd->add_option("--control", control_path,
                    "Serve the JSON-lines control socket at this path (e-stop, limits, "
                    "inputs, power, faults, state; docs/control.md)")
        ->check(moco::cli::NonEmptyPath());
    if (model.keeps_state) {
      cmd->add_option("--state", config.state_path,
                      "File keeping the device's NVM (settings, slots, serial number, log) "
                      "across runs, written atomically (default: "
                      "$XDG_STATE_HOME/mocosim/<name>.json or ~/.local/state/mocosim/<name>.json)")
          ->check(moco::cli::NonEmptyPath());
    }
    cmd->add_option("--scenario", scenario_path,
                    "Play this scenario file of timed control events (docs/control.md)")
        ->check(CLI::ExistingFile);
    cmd->add_option("--faults", config.faults,
                    "Inject link faults, e.g. seed=42,dir=to-host,drop=0.01 (dir= applies "
                    "to the rates after it)");
    cmd->add_flag("--no-pacing", config.no_pacing,
                  "Deliver bytes at once instead of at the profile's baud rate and in the "
                  "packets of its USB serial bridge (profile field usb_bridge, "
                  "docs/profiles.md)");
    cmd->add_option("--name", config.name,
                    "Name in log lines and on the control socket (default: " + name + ")");
    cmd->add_option("--log-level", log_level,
                    "error, warn, info (default) or debug (every message decoded)")
        ->check(CLI::IsMember({"error", "warn", "info", "debug"}));
  }

  int Run() {
    const std::string name = config.model;
    const bool wifi = wifi_opt != nullptr && wifi_opt->count() > 0;
    if (pty_path.empty() && tcp_spec.empty() && !wifi) {
      std::fprintf(stderr,
                   "mocosim %s: say where to serve the device: --pty /tmp/%s or "
                   "--tcp 127.0.0.1:5000\n",
                   name.c_str(), name.c_str());
      return 2;
    }
    config.endpoint = wifi               ? "wifi:" + wifi_spec
                      : pty_path.empty() ? "tcp:" + tcp_spec
                                         : "pty:" + pty_path;
    moco::serve::EmulatorConfig emulator_config;
    emulator_config.devices.push_back(config);
    emulator_config.control_path = control_path;
    emulator_config.scenario_path = scenario_path;
    emulator_config.log_level = moco::serve::ParseLogLevel(log_level);
    return Serve(std::move(emulator_config));
  }
};

// `mocosim run FILE`: several devices from a run file.
struct RunFileCli {
  CLI::App* cmd = nullptr;
  std::string path;

  void Add(CLI::App& app) {
    cmd = app.add_subcommand(
        "run", "Serve every device of a run file (JSON, see docs/run-files.md) until Ctrl-C");
    cmd->add_option("file", path, "Run file, e.g. fixtures/runs/two-dmc16.json")
        ->required()
        ->check(CLI::ExistingFile);
  }
  int Run() const {
    try {
      return Serve(moco::serve::LoadRunConfig(path));
    } catch (const std::exception& e) {
      std::fprintf(stderr, "mocosim run: %s\n", e.what());
      return 2;
    }
  }
};

// `mocosim models`: lists the device models.
int ListModels() {
  for (const auto& m : moco::devices::DeviceModels()) {
    std::printf("%-12s %s (profile %s)\n", std::string(m.name).c_str(),
                std::string(m.description).c_str(), std::string(m.default_profile).c_str());
  }
  return 0;
}

// `mocosim tap`: a recording proxy between a host and a real device; its
// options, then running it.
struct TapCli {
  CLI::App* cmd = nullptr;
  moco::serve::TapConfig config;
  std::string protocol, pty, tcp, flow = "none";

  // --protocol, checked against the protocols a device starts in.
  void AddProtocol() {
    // A device is tapped from its power-on protocol: one with rules of its
    // own (wire/protocol.h), by name or alias.
    std::vector<moco::wire::Protocol> tappable;
    for (const moco::wire::ProtocolInfo& info : moco::wire::Protocols()) {
      if (!info.rule_prefix.empty()) tappable.push_back(info.id);
    }
    cmd->add_option("--protocol", protocol,
                    "What the device speaks: " + moco::wire::NameList(tappable) +
                        ". Sets the header's protocol, the decoding and the default baud. "
                        "Example: --protocol " +
                        std::string(moco::wire::ProtocolName(tappable.back())))
        ->required()
        ->check(CLI::Validator(
            [tappable](std::string& text) -> std::string {
              const auto p = moco::wire::ParseProtocolOrAlias(text);
              if (p && std::find(tappable.begin(), tappable.end(), *p) != tappable.end()) {
                return "";
              }
              return "'" + text + "' is no protocol a device starts in: give " +
                     moco::wire::NameList(tappable);
            },
            "PROTOCOL"));
  }

  // The header's fields a replay reads: --device-model, --profile, --note
  // and --time-tolerance-ms.
  void AddHeader() {
    cmd->add_option("--device-model", config.device_model,
                    "The header's device: the emulated model a replay builds (default: dmc16, "
                    "dfmoco or stackshot3x by --protocol). Example: --device-model dfmoco");
    cmd->add_option("--profile", config.profile,
                    "Recorded in the header as \"profile\": the device profile a replay of this "
                    "session should use. Example: --profile fixtures/profiles/dmc16.json");
    cmd->add_option("--note", config.note,
                    "The header's note (default: where the tap ran). Example: --note \"rig A, "
                    "first take\"");
    moco::cli::AddNumber(
        cmd, "--time-tolerance-ms", config.time_tolerance_ms, int64_t{0}, int64_t{600000},
        "The header's tolerances.time_ms: how far a replayed reply may be from its "
        "recorded (wall-clock) time. Example: --time-tolerance-ms 100");
  }

  void Add(CLI::App& app) {
    cmd = app.add_subcommand(
        "tap",
        "Record what a host and a real device say to each other (docs/tap.md). The tap sits "
        "between them: the host opens the tap's PTY (or connects to its TCP port) instead of "
        "the device, and the tap opens the device's serial port (or TCP address). Bytes pass "
        "unchanged both ways, and each chunk is recorded with its arrival time and decoded "
        "messages into a session file that mococheck replay/fuzz and mocosim decode/plot read "
        "like a --record'ed one. The tap follows a device's switch to another protocol (" +
            LineSwitchList() +
            ") and a host setting another speed on the PTY; a host closing and reopening "
            "the PTY does not end it; a device going away is reported and looked for again; "
            "Ctrl-C (SIGINT, SIGTERM, SIGHUP) completes the recording.\n"
            "Example: mocosim tap --protocol dmc --device serial:/dev/ttyUSB0 --pty /tmp/dmc16 "
            "--record dragonframe.jsonl  (then point Dragonframe at /tmp/dmc16)\n"
            "Example: mocosim tap --protocol stackshot --device tcp:192.168.1.20:5000 --tcp "
            "5001 --record stack.jsonl");
    AddProtocol();
    cmd->add_option("--device", config.device,
                    "The real device's side: serial:PATH (a serial port, raw 8N1 at --baud; a "
                    "bare path works too) or tcp:HOST:PORT. Example: --device serial:/dev/ttyUSB0")
        ->required();
    auto* pty_opt = cmd->add_option(
        "--pty", pty,
        "The host's side: a PTY with a stable symlink at this path (mode 0600), as `mocosim "
        "dmc16 --pty` makes. Example: --pty /tmp/dmc16");
    auto* tcp_opt = cmd->add_option(
        "--tcp", tcp,
        "The host's side: listen on TCP [HOST:]PORT instead (default host 127.0.0.1; port 0 = "
        "any free port, logged). Example: --tcp 127.0.0.1:5001");
    pty_opt->excludes(tcp_opt);
    moco::cli::AddNumber(cmd, "--baud", config.baud, uint32_t{0}, uint32_t{4000000},
                         "Line speed of a serial device (default 0: the protocol's: " +
                             moco::wire::DefaultBaudList() + "). Example: --baud 57600");
    cmd->add_option("--flow", flow,
                    "Flow control on the serial port: none (default) or rtscts (hardware "
                    "RTS/CTS). Example: --flow rtscts")
        ->check(CLI::IsMember({"none", "rtscts"}));
    cmd->add_option("--record", config.record_path,
                    "Session file to write (.jsonl, docs/sessions.md): lines written through as "
                    "they come, the file completed atomically on exit. Without it the tap only "
                    "passes bytes. Example: --record session.jsonl")
        ->check(moco::cli::NonEmptyPath());
    AddHeader();
  }

  int Run() {
    config.protocol = *moco::wire::ParseProtocolOrAlias(protocol);
    config.rtscts = flow == "rtscts";
    if (pty.empty() && tcp.empty()) {
      std::fprintf(stderr,
                   "mocosim tap: say where the host connects: --pty /tmp/dmc16 or --tcp "
                   "127.0.0.1:5001\n");
      return 2;
    }
    config.host = pty.empty() ? "tcp:" + tcp : "pty:" + pty;
    return moco::serve::RunTap(std::move(config));
  }
};

}  // namespace

int main(int argc, char** argv) {
  // A log line to a closed pipe (`mocosim ... 2>&1 | head -1`) is a failed
  // write, ignored, not a SIGPIPE that kills the emulator before its
  // recording is completed and its PTY symlink removed.
  std::signal(SIGPIPE, SIG_IGN);
  CLI::App app{
      "mocosim: emulated DMC-16, DFMoco Arduino and StackShot 3X devices\n"
      "Exit status (docs/exit-codes.md): 0 done, 1 a recording or plot could not be "
      "completed, 2 a usage, file or set-up error"};
  app.set_version_flag("--version", "mocosim 0.1.0");
  app.require_subcommand(1);

  // The subcommands, in the order --help lists them.
  DecodeCli decode;
  decode.Add(app);
  ExportCli export_cli;
  export_cli.Add(app);
  PlotCli plot;
  plot.Add(app);
  std::vector<std::unique_ptr<DeviceCli>> one_device;
  for (const auto& model : moco::devices::DeviceModels()) {
    one_device.push_back(std::make_unique<DeviceCli>());
    one_device.back()->Add(app, model);
  }
  RunFileCli run;
  run.Add(app);
  auto* models = app.add_subcommand("models", "List the device models that can be emulated");
  TapCli tap;
  tap.Add(app);

  // A parse error is a usage error, exit 2; --help and --version exit 0.
  if (const auto exit_code = moco::cli::ParseCommandLine(app, argc, argv)) return *exit_code;

  if (decode.cmd->parsed()) return decode.Run();
  if (export_cli.cmd->parsed()) return export_cli.Run();
  if (plot.cmd->parsed()) return plot.Run();
  if (tap.cmd->parsed()) return tap.Run();
  if (models->parsed()) return ListModels();
  for (auto& o : one_device) {
    if (o->cmd->parsed()) return o->Run();
  }
  if (run.cmd->parsed()) return run.Run();
  return 0;
}
