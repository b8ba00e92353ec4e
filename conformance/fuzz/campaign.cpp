// The fuzz campaign (see campaign.h).
#include "conformance/fuzz/campaign.h"

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <set>
#include <span>
#include <vector>

#include "conformance/core/sequence.h"
#include "conformance/protocols/registry.h"
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

// How many messages `a` and `b` share from their start.
size_t CommonPrefix(const Messages& a, const Messages& b) {
  size_t n = 0;
  while (n < a.size() && n < b.size() && a[n] == b[n]) ++n;
  return n;
}

// Shrinks a failing mutant while it still fails with a finding of the same
// kind: messages dropped (keeping at least one), then bytes dropped within
// each message (keeping at least one), at most kByteBudget runs for the
// bytes. `verdict` becomes the shrunk mutant's. Each attempt runs from a
// snapshot after the messages it shares with the mutant so far, where the
// executor keeps them.
Messages Shrink(FuzzExecutor& executor, Messages messages, FuzzVerdict& verdict, uint64_t& runs) {
  constexpr int kNoBudget = 1 << 30;
  constexpr int kByteBudget = 200;
  Messages current = messages;  // the shortest failing mutant so far
  auto still_fails = [&](const Messages& fewer) {
    if (fewer.empty() || StopRequested() != 0) return false;
    ++runs;
    FuzzVerdict v = executor.Run(fewer, CommonPrefix(fewer, current));
    // A run a stop request cut short proves nothing.
    if (v.ok || v.kind != verdict.kind || StopRequested() != 0) return false;
    verdict = std::move(v);
    current = fewer;
    return true;
  };
  ShrinkSequence(std::move(messages), kNoBudget, still_fails);
  int budget = kByteBudget;
  for (size_t i = 0; i < current.size() && budget > 0; ++i) {
    ShrinkSequence(current[i], budget, [&](const wire::Bytes& fewer_bytes) {
      --budget;
      if (fewer_bytes.empty()) return false;
      Messages candidate = current;
      candidate[i] = fewer_bytes;
      return still_fails(candidate);
    });
  }
  return current;
}

// One finding per kind, law and place: the violation up to its first ':'
// (the law it names: "reply grammar", "every request answered", "the firmware
// stopped"), and for a firmware the function it stopped in. Many mutants break
// one law the same way (lines run into each other), and listing each would
// hide the other findings.
std::string FindingKey(const FuzzVerdict& verdict) {
  std::string key = std::string(FindingKindName(verdict.kind)) + " " +
                    verdict.violation.substr(0, verdict.violation.find(':'));
  if (!verdict.backtrace.empty()) {
    const std::string& pc = verdict.backtrace.front();
    const size_t open = pc.find('('), plus = pc.find('+', open);
    key += " in " + (open == std::string::npos
                         ? pc
                         : pc.substr(open + 1, std::min(plus, pc.find(')', open)) - open - 1));
  }
  return key;
}

// A snapshot campaign's mutants come in batches of kBatch from one corpus
// entry and one point in it: the messages before the point are kept (and
// played from a snapshot, made once per batch), the messages after it are
// mutated: a window of kWindow or fewer, or in kWholeRestPercent of the
// mutants all the rest. (Measured on our firmware, docs/benchmarks.md
// "Firmware fuzzing": windows of 1-2 and 6 % ran 290 mutants a second to
// 190 for windows of 1-4 and 25 %, and both reached the same code in 2 min.)
constexpr size_t kBatch = 32;
constexpr uint64_t kWindow = 2;
constexpr uint32_t kWholeRestPercent = 6;

// A mutant's pause as a saved session holds it (docs/sessions.md "pause").
constexpr std::string_view kPauseEvent = "pause";

bool IsPause(const session::SessionEntry& e) {
  return e.is_event && e.event.is_object() && e.event.value("event", "") == kPauseEvent;
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
  // The host's bytes between two pauses are cut into messages apart from
  // those after the pause; a pause is an empty message (core/fuzz_protocol.h).
  Messages messages;
  wire::Bytes host;
  auto cut = [&] {
    if (as_written || host.empty()) return;
    for (wire::Bytes& m : wire::SplitMessages(*protocol, wire::Side::kHost, host)) {
      messages.push_back(std::move(m));
    }
    host.clear();
  };
  for (const session::SessionEntry& e : s.entries) {
    if (IsPause(e)) {
      cut();
      messages.emplace_back();
    } else if (!e.is_event && e.from == session::Origin::kHost && !e.bytes.empty()) {
      if (as_written) {
        messages.push_back(e.bytes);
      } else {
        host.insert(host.end(), e.bytes.begin(), e.bytes.end());
      }
    }
  }
  cut();
  Seed seed;
  seed.path = path;
  seed.protocol = *protocol;
  seed.device = s.header.device;
  seed.messages = std::move(messages);
  seed.warning = session::SessionWarning(s);
  if (std::ranges::all_of(seed.messages, [](const wire::Bytes& m) { return m.empty(); })) {
    return path + ": the session holds no host traffic to mutate";
  }
  return seed;
}

std::string SaveMessages(const std::string& path, Protocol protocol, const std::string& device,
                         const std::string& note, const Messages& messages) {
  try {
    session::SessionHeader h;
    h.protocol = protocol;
    h.device = device;
    h.clock = "virtual";
    h.note = note;
    session::SessionWriter w(path, h);
    const FuzzHooks* hooks = FindFuzzHooks(protocol);
    const TimeNs gap_ns = hooks == nullptr ? 0 : hooks->gap_ns;
    const TimeNs pause_ns = hooks == nullptr ? 0 : hooks->pause_ns;
    TimeNs t = 0;
    for (const wire::Bytes& m : messages) {
      if (m.empty()) {
        w.Append(session::SessionEntry::Event(
            {{"t_ns", t}, {"event", std::string(kPauseEvent)}, {"ns", pause_ns}}));
        t += pause_ns;
        continue;
      }
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
  mutator.set_pause_percent(options.pause_percent);
  std::vector<Messages> donors;
  for (const Seed& s : seeds) donors.push_back(s.messages);
  std::set<std::string> seen;  // findings reported, by FindingKey (before and after shrinking)

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
                    FuzzVerdict verdict, bool from_snapshot) {
    // A finding already reported is not shrunk again: a firmware that breaks
    // one law often (the real sketch's interleaved replies) would spend the
    // campaign shrinking the same finding.
    const std::string first = FindingKey(verdict);
    if (!seen.insert(first).second) return;
    if (from_snapshot) {
      // The finding as a fresh boot shows it: the saved session reruns so.
      ++report.shrink_runs;
      FuzzVerdict whole = executor.Run(messages);
      if (whole.ok || whole.kind != verdict.kind) {
        verdict.violation += " (from a snapshot; the whole session from boot gave " +
                             (whole.ok ? std::string("no finding") : whole.violation) + ")";
      } else {
        verdict = std::move(whole);
      }
    }
    messages = Shrink(executor, std::move(messages), verdict, report.shrink_runs);
    const std::string key = FindingKey(verdict);
    if (key != first && !seen.insert(key).second) return;  // shrunk into one reported before
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
      const std::string err = SaveMessages(path, protocol, options.device, note, f.messages);
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
    report.simulated_ns += v.simulated_ns;
    if (report.coverage) MergeCoverage(executor.coverage(), covered, report.edges);
    report.corpus = corpus.size();
    if (!v.ok) record(s.messages, {"none (the recorded session itself)"}, v, false);
  }

  Messages mutant;
  size_t base = 0;        // the corpus entry this batch mutates (snapshots)
  size_t point = 0;       // the messages of it kept as they are
  size_t batch_left = 0;  // mutants left in this batch
  while (report.failures.size() < options.max_failures && report.interrupted_by == 0) {
    if (options.runs > 0
            ? report.execs >= options.runs + seeds.size()
            : std::chrono::duration<double>(Clock::now() - t0).count() >= options.seconds) {
      break;
    }
    size_t kept = 0;
    if (executor.snapshots()) {
      if (batch_left == 0) {
        base = mutator.Below(corpus.size());
        point = mutator.Below(corpus[base].size() + 1);
        batch_left = kBatch;
      }
      --batch_left;
      const Messages& from = corpus[base];
      const size_t end = mutator.Chance(kWholeRestPercent)
                             ? from.size()
                             : std::min(from.size(), point + 1 + mutator.Below(kWindow));
      Messages window(from.begin() + static_cast<ptrdiff_t>(point),
                      from.begin() + static_cast<ptrdiff_t>(end));
      mutator.Mutate(window, donors);
      mutant.assign(from.begin(), from.begin() + static_cast<ptrdiff_t>(point));
      mutant.insert(mutant.end(), window.begin(), window.end());
      if (mutant.size() > SessionMutator::kMaxMessages) mutant.resize(SessionMutator::kMaxMessages);
      kept = std::min(point, mutant.size());
      if (kept > 0) ++report.snapshot_runs;
    } else {
      mutant = corpus[mutator.Below(corpus.size())];
      mutator.Mutate(mutant, donors);
    }
    const FuzzVerdict v = executor.Run(mutant, kept);
    if (stopped()) break;
    ++report.execs;
    report.messages += v.messages;
    report.simulated_ns += v.simulated_ns;
    if (v.ok) {
      note_coverage(mutant);
    } else {
      record(mutant, mutator.last_mutations(), v, kept > 0);
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
