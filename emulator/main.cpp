// mocosim: emulated motion-control devices (DMC-16, DFMoco Arduino, StackShot
// 3X) served over PTY or TCP, and tools for their session recordings.
#include <CLI/CLI.hpp>

#include <cinttypes>
#include <cstdio>
#include <string>
#include <variant>

#include "control/session.h"
#include "devices/profile.h"
#include "devices/registry.h"
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

// Runs the emulator until Ctrl-C. Exit 0 on a clean stop, 1 when a recording
// could not be completed, 2 when the devices cannot be set up (the message
// names the device, the field and the fix).
int Serve(moco::transport::EmulatorConfig config) {
  try {
    moco::transport::Emulator emulator(std::move(config));
    emulator.Start();
    if (!emulator.config().control_path.empty() || !emulator.config().scenario_path.empty()) {
      // Wired in by the control channel (see docs/control.md).
    }
    std::fprintf(stderr, "mocosim: serving %zu device(s); Ctrl-C stops\n", emulator.size());
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

  // --- one device: mocosim dmc16 --pty PATH | --tcp [HOST:]PORT ---
  moco::transport::DeviceConfig one;
  std::string pty_path, tcp_spec, log_level = "info", control_path, scenario_path, bind;
  auto* dmc16 = app.add_subcommand(
      "dmc16",
      "Emulate a DMC-16 (DMC v2 binary protocol) on a PTY or a TCP port until Ctrl-C. "
      "Example: mocosim dmc16 --pty /tmp/dmc16  (then point the host at /tmp/dmc16)");
  auto* pty_opt = dmc16->add_option("--pty", pty_path,
                                    "Create a PTY with a stable symlink at this path (mode 0600)");
  auto* tcp_opt =
      dmc16->add_option("--tcp", tcp_spec,
                        "Listen on TCP [HOST:]PORT instead (default host 127.0.0.1; port 0 = any)");
  pty_opt->excludes(tcp_opt);
  dmc16
      ->add_option("--profile", one.profile_path,
                   "Device profile (JSON; default: built-in, same as fixtures/profiles/dmc16.json)")
      ->check(CLI::ExistingFile);
  dmc16->add_option("--record", one.record_path,
                    "Record every byte in and out with its time and decoded message to this "
                    "session file (.jsonl; written atomically on exit)");
  dmc16->add_option("--control", control_path,
                    "Serve the JSON-lines control socket at this path (e-stop, limits, inputs, "
                    "power, faults, state; see docs/control.md)");
  dmc16->add_option("--scenario", scenario_path, "Play this scenario file of timed events")
      ->check(CLI::ExistingFile);
  dmc16->add_option("--faults", one.faults,
                    "Inject link faults, e.g. seed=42,drop=0.01,corrupt=0.001,dir=to-host");
  dmc16->add_flag("--no-pacing", one.no_pacing,
                  "Deliver bytes at once instead of at the profile's baud rate");
  dmc16->add_option("--name", one.name, "Name in log lines and on the control socket");
  dmc16
      ->add_option("--log-level", log_level, "error, warn, info (default) or debug (every message)")
      ->check(CLI::IsMember({"error", "warn", "info", "debug"}));

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
  if (dmc16->parsed()) {
    if (pty_path.empty() && tcp_spec.empty()) {
      std::fprintf(stderr,
                   "mocosim dmc16: say where to serve the device: --pty /tmp/dmc16 or "
                   "--tcp 127.0.0.1:5000\n");
      return 2;
    }
    one.model = "dmc16";
    one.endpoint = pty_path.empty() ? "tcp:" + tcp_spec : "pty:" + pty_path;
    moco::transport::EmulatorConfig config;
    config.devices.push_back(one);
    config.control_path = control_path;
    config.scenario_path = scenario_path;
    config.log_level = moco::transport::ParseLogLevel(log_level);
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
