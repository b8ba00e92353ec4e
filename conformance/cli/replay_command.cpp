// `mococheck replay`: a recorded session's host side resent to a device, the
// device side compared (docs/sessions.md).
#include <algorithm>
#include <cstdio>
#include <iostream>
#include <memory>

#include "cli_numbers.h"
#include "conformance/cli/commands.h"
#include "conformance/cli/run_setup.h"
#include "conformance/fuzz/campaign.h"
#include "conformance/fuzz/executor.h"
#include "conformance/fuzz/replay.h"
#include "session/session.h"

namespace moco::conformance::cli {
namespace {

struct ReplayArgs {
  std::string session, target, profile, board_path, driver;
  int64_t steps = -1, ms = -1;
  uint32_t baud = 0;
};

// A session with host traffic only (a finding `mococheck fuzz` saved): there is
// nothing recorded to compare, so it is run as the fuzzer runs a mutant, from a
// fresh boot, one message per recorded write, and the device's invariants are
// judged; under simavr the run is the fuzzer's, cycle for cycle.
int Rejudge(const std::string& path, FuzzExecutor& executor) {
  auto loaded = LoadSeed(path, /*as_written=*/true);
  if (const auto* err = std::get_if<std::string>(&loaded)) return Fail(*err);
  if (auto err = executor.Open()) return Fail(*err);
  const Messages& messages = std::get<Seed>(loaded).messages;
  const FuzzVerdict v = executor.Run(messages);
  const auto pauses = std::ranges::count(messages, wire::Bytes());
  std::cout << "mococheck replay: " << path << " -> " << executor.target_name() << "\n"
            << "the session records no device side: its " << v.messages << " host write(s)"
            << (pauses > 0 ? " and " + std::to_string(pauses) + " pause(s)" : std::string())
            << " run as `mococheck fuzz` runs a mutant, the device's invariants judged ("
            << v.replies << " device line(s) or message(s))\n";
  if (v.ok) {
    std::cout << "result: PASS (no invariant broken)\n";
    return 0;
  }
  std::cout << "FAIL [" << FindingKindName(v.kind) << "] " << v.violation << "\n";
  for (size_t i = 0; i < v.backtrace.size(); ++i) {
    std::cout << (i == 0 ? "  at " : "  called from ") << v.backtrace[i] << "\n";
  }
  std::cout << "result: FINDING\n";
  return 1;
}

int Replay(const ReplayArgs& a) {
  auto loaded = session::LoadSession(a.session);
  if (const auto* err = std::get_if<session::SessionError>(&loaded)) {
    return Fail(a.session + (err->line ? ":" + std::to_string(err->line) : std::string()) + ": " +
                err->message);
  }
  const session::Session& session = std::get<session::Session>(loaded);
  if (const std::string w = session::SessionWarning(session); !w.empty()) {
    std::fprintf(stderr, "mococheck: %s: %s\n", a.session.c_str(), w.c_str());
  }
  const Protocol proto = session.header.protocol;
  if (std::ranges::find(kAllProtocols, proto) == std::end(kAllProtocols)) {
    return Fail(a.session + ": protocol " + std::string(ProtocolName(proto)) +
                " cannot be replayed; sessions in " + wire::NameList(kAllProtocols) + " can");
  }
  TargetRequest request;
  request.text = a.target;
  request.session_device = session.header.device;
  request.profile = a.profile;
  request.baud = a.baud;
  request.protocol = proto;
  request.no_device_message = a.session + ": the session names no emulated device (\"" +
                              session.header.device + "\"); give --target";
  auto resolved = ResolveTarget(request);
  if (const auto* err = std::get_if<std::string>(&resolved)) return Fail(*err);
  std::unique_ptr<Target> target = std::move(std::get<ResolvedTarget>(resolved).target);
  const bool host_only =
      std::none_of(session.entries.begin(), session.entries.end(),
                   [](const auto& e) { return !e.is_event && e.from == session::Origin::kDevice; });
  if (a.board_path.empty() && !a.driver.empty()) {
    return Fail("--driver needs --board: give the board profile naming the watched pins");
  }
  FuzzExecutor::Options rerun;
  if (!a.board_path.empty()) {
    if (!host_only) {
      return Fail(
          "--board judges the pins of a rerun fuzz finding (a session with no device "
          "side); to judge a device's pins, use mococheck run --board");
    }
    auto pins = LoadPinJudge(a.board_path, a.driver);
    if (const auto* err = std::get_if<std::string>(&pins)) return Fail(*err);
    rerun.pins = std::get<PinJudgeOptions>(pins);
  }
  if (host_only && target->VirtualClock() && target->CanRestart()) {
    FuzzExecutor executor(proto, std::move(target), rerun);
    if (executor.CanRun()) return Rejudge(a.session, executor);
    return Fail(a.session + ": the session records no device side to compare, and " +
                std::string(ProtocolName(proto)) +
                " sessions are not run by the fuzzer; record the device side too");
  }
  if (auto err = target->Open()) return Fail(*err);
  ReplayOptions options;
  if (a.steps >= 0) options.position_steps = a.steps;
  if (a.ms >= 0) options.time_ms = a.ms;
  const ReplayResult r = conformance::Replay(session, proto, *target, options);
  std::cout << "mococheck replay: " << a.session << " -> " << target->Name() << "\n"
            << ReplayText(r) << std::flush;
  if (const auto lost = target->LinkLost()) {
    return Fail("target error: " + target->Name() + ": " + *lost +
                "; the comparison proves nothing about the device");
  }
  return r.ok() ? 0 : 1;
}

}  // namespace

Runner AddReplayCommand(CLI::App& app, CLI::App*& sub) {
  using moco::cli::AddNumber;
  auto a = std::make_shared<ReplayArgs>();
  CLI::App* replay = app.add_subcommand(
      "replay",
      "Resend a recorded session's host side and compare the device side (docs/sessions.md); "
      "a session with no device side (a fuzz finding) is rerun and the device's invariants "
      "judged");
  sub = replay;
  replay->add_option("session", a->session, "Session file (JSON Lines)")->required();
  replay->add_option("--target", a->target,
                     "in-process:MODEL (default: the session's device), simavr:FIRMWARE.elf, "
                     "pty:PATH, serial:PATH or "
                     "tcp:HOST:PORT");
  replay->add_option("--profile", a->profile, "Device profile for an in-process target")
      ->check(CLI::ExistingFile);
  AddNumber(replay, "--baud", a->baud, uint32_t{0}, uint32_t{4000000},
            "Baud rate of a pty:/serial: target (default 0: the protocol's)");
  AddNumber(replay, "--position-tolerance", a->steps, int64_t{0}, int64_t{1} << 31,
            "Steps a reported position may differ (default: the session's, else 0)")
      ->default_str("the session's");
  AddNumber(replay, "--time-tolerance-ms", a->ms, int64_t{0}, int64_t{3600000},
            "How far a device message may arrive from its recorded time (default: the "
            "session's, else 0 in-process and 50 on a real link)")
      ->default_str("the session's");
  AddPinOptions(replay, a->board_path, a->driver);
  return [a] { return Replay(*a); };
}

}  // namespace moco::conformance::cli
