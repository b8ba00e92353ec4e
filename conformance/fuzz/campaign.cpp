// The fuzz campaign (see campaign.h).
#include "conformance/fuzz/campaign.h"

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <set>
#include <span>
#include <vector>

#include "conformance/core/sequence.h"
#include "session/session.h"

namespace moco::conformance {
namespace {

// AFL's hit-count classes: a slot's count becomes one bit, so a mutant that
// runs an edge 4-7 times where every run before ran it once is new.
uint8_t CountClass(uint8_t count) {
  if (count == 0) return 0;
  if (count <= 3) return static_cast<uint8_t>(1u << (count - 1));
  if (count <= 7) return 8;
  if (count <= 15) return 16;
  if (count <= 31) return 32;
  if (count <= 127) return 64;
  return 128;
}

// Adds a run's edge counts to `seen` (per slot, the classes reached so far);
// true when the run reached something new. `edges` counts the slots reached.
bool MergeCoverage(std::span<const uint8_t> run, std::vector<uint8_t>& seen, size_t& edges) {
  bool fresh = false;
  for (size_t i = 0; i < run.size(); ++i) {
    if (run[i] == 0) continue;
    const uint8_t c = CountClass(run[i]);
    if ((seen[i] & c) == c) continue;
    if (seen[i] == 0) ++edges;
    seen[i] |= c;
    fresh = true;
  }
  return fresh;
}

// Drops messages while the mutant still fails with a finding of the same kind,
// keeping at least one; `verdict` becomes the shrunk mutant's.
Messages Shrink(FuzzExecutor& executor, Messages messages, FuzzVerdict& verdict) {
  constexpr int kNoBudget = 1 << 30;
  return ShrinkSequence(std::move(messages), kNoBudget, [&](const Messages& fewer) {
    if (fewer.empty() || StopRequested() != 0) return false;
    FuzzVerdict v = executor.Run(fewer);
    // A run a stop request cut short proves nothing.
    if (v.ok || v.kind != verdict.kind || StopRequested() != 0) return false;
    verdict = std::move(v);
    return true;
  });
}

}  // namespace

std::variant<Seed, std::string> LoadSeed(const std::string& path, bool as_written) {
  auto loaded = session::LoadSession(path);
  if (const auto* err = std::get_if<session::SessionError>(&loaded)) {
    return path + (err->line ? ":" + std::to_string(err->line) : std::string()) + ": " +
           err->message;
  }
  const session::Session& s = std::get<session::Session>(loaded);
  const std::optional<Protocol> protocol = s.header.protocol;
  if (std::ranges::find(kAllProtocols, *protocol) == std::end(kAllProtocols)) {
    return path + ": protocol " + std::string(wire::ProtocolName(s.header.protocol)) +
           " is not fuzzed; record the session in the device's packet protocol";
  }
  wire::Bytes host;
  Messages writes;
  for (const session::SessionEntry& e : s.entries) {
    if (!e.is_event && e.from == session::Origin::kHost) {
      host.insert(host.end(), e.bytes.begin(), e.bytes.end());
      writes.push_back(e.bytes);
    }
  }
  Seed seed;
  seed.path = path;
  seed.protocol = *protocol;
  seed.device = s.header.device;
  seed.messages =
      as_written ? std::move(writes) : wire::SplitMessages(*protocol, wire::Side::kHost, host);
  seed.warning = session::SessionWarning(s);
  if (seed.messages.empty()) return path + ": the session holds no host traffic to mutate";
  return seed;
}

std::string SaveMessages(const std::string& path, Protocol protocol, const std::string& device,
                         const std::string& note, const Messages& messages, TimeNs gap_ns) {
  try {
    session::SessionHeader h;
    h.protocol = protocol;
    h.device = device;
    h.clock = "virtual";
    h.note = note;
    session::SessionWriter w(path, h);
    TimeNs t = 0;
    for (const wire::Bytes& m : messages) {
      session::SessionEntry e;
      e.t_ns = t;
      e.from = session::Origin::kHost;
      e.bytes = m;
      w.Append(e);
      t += gap_ns;
    }
    std::string error;
    if (!w.Finish(&error)) return error;
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

FuzzReport RunFuzz(FuzzExecutor& executor, Protocol protocol, const std::vector<Seed>& seeds,
                   const FuzzOptions& options,
                   const std::function<void(const FuzzReport&)>& progress) {
  using Clock = std::chrono::steady_clock;
  const auto t0 = Clock::now();
  auto last_progress = t0;
  FuzzReport report;
  SessionMutator mutator(protocol, options.seed);
  std::vector<Messages> donors;
  for (const Seed& s : seeds) donors.push_back(s.messages);
  std::set<std::string> seen;  // violations reported, by their first 60 characters

  std::vector<Messages> corpus = donors;
  std::vector<uint8_t> covered(executor.coverage().size(), 0);
  report.coverage = !covered.empty();
  auto note_coverage = [&](const Messages& messages) {
    if (report.coverage && MergeCoverage(executor.coverage(), covered, report.edges)) {
      corpus.push_back(messages);
    }
    report.corpus = corpus.size();
  };

  auto record = [&](Messages messages, const std::vector<std::string>& mutations,
                    FuzzVerdict verdict) {
    messages = Shrink(executor, std::move(messages), verdict);
    // One finding per kind, law and place: the violation up to its first ':'
    // (the law it names: "reply grammar", "every request answered", "the
    // firmware stopped"), and for a firmware the function it stopped in. Many
    // mutants break one law the same way (lines run into each other), and
    // listing each would hide the other findings.
    std::string key = std::string(FindingKindName(verdict.kind)) + " " +
                      verdict.violation.substr(0, verdict.violation.find(':'));
    if (!verdict.backtrace.empty()) {
      const std::string& pc = verdict.backtrace.front();
      const size_t open = pc.find('('), plus = pc.find('+', open);
      key += " in " + (open == std::string::npos
                           ? pc
                           : pc.substr(open + 1, std::min(plus, pc.find(')', open)) - open - 1));
    }
    if (!seen.insert(key).second) return;
    FuzzFailure f{
        std::move(messages),         mutations, std::move(verdict.violation), "", verdict.kind,
        std::move(verdict.backtrace)};
    if (!options.crash_dir.empty()) {
      std::error_code ec;
      std::filesystem::create_directories(options.crash_dir, ec);
      const std::string path = options.crash_dir + "/mutant-" + std::to_string(options.seed) + "-" +
                               std::to_string(report.execs) + ".jsonl";
      std::string note = "mococheck fuzz seed " + std::to_string(options.seed) + ": [" +
                         std::string(FindingKindName(f.kind)) + "] " + f.violation + " (mutations:";
      for (const std::string& m : f.mutations) note += " " + m;
      note += ")";
      if (!f.backtrace.empty()) {
        note += "; backtrace:";
        for (const std::string& frame : f.backtrace) note += " " + frame + ";";
        note.pop_back();
      }
      const std::string err =
          SaveMessages(path, protocol, options.device, note, f.messages, executor.gap_ns());
      f.saved_path = err.empty() ? path : "not saved: " + err;
    }
    report.failures.push_back(std::move(f));
  };

  // A stop request (a signal) ends the campaign; the run it cut short is not judged.
  auto stopped = [&] {
    report.interrupted_by = StopRequested();
    return report.interrupted_by != 0;
  };
  for (const Seed& s : seeds) {
    const FuzzVerdict v = executor.Run(s.messages);
    if (stopped()) break;
    ++report.execs;
    report.messages += v.messages;
    if (report.coverage) MergeCoverage(executor.coverage(), covered, report.edges);
    report.corpus = corpus.size();
    if (!v.ok) record(s.messages, {"none (the recorded session itself)"}, v);
  }

  Messages mutant;
  while (report.failures.size() < options.max_failures && report.interrupted_by == 0) {
    if (options.runs > 0
            ? report.execs >= options.runs + seeds.size()
            : std::chrono::duration<double>(Clock::now() - t0).count() >= options.seconds) {
      break;
    }
    mutant = corpus[mutator.Below(corpus.size())];
    mutator.Mutate(mutant, donors);
    const FuzzVerdict v = executor.Run(mutant);
    if (stopped()) break;
    ++report.execs;
    report.messages += v.messages;
    if (v.ok) {
      note_coverage(mutant);
    } else {
      record(mutant, mutator.last_mutations(), v);
    }
    if (progress) {
      const auto now = Clock::now();
      if (now - last_progress >= std::chrono::seconds(1)) {
        last_progress = now;
        report.wall_s = std::chrono::duration<double>(now - t0).count();
        progress(report);
      }
    }
  }
  report.wall_s = std::chrono::duration<double>(Clock::now() - t0).count();
  report.code = executor.code_coverage();
  return report;
}

}  // namespace moco::conformance
