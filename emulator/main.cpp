// mocosim: emulated motion-control devices (DMC-16, DFMoco Arduino, StackShot
// 3X) served over PTY or TCP, and tools for their session recordings.
#include <CLI/CLI.hpp>

#include <cinttypes>
#include <cstdio>
#include <string>
#include <variant>

#include "control/session.h"
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

  CLI11_PARSE(app, argc, argv);

  if (decode->parsed()) return Decode(session_path, !no_time, strict);
  return 0;
}
