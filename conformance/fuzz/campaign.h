// `mococheck fuzz`: mutates the host side of recorded sessions (docs/sessions.md)
// and runs every mutant against a device in virtual time: an in-process one,
// or firmware under simavr (see mutator.h and executor.h). A mutant that
// breaks an invariant or stops the firmware is shrunk (messages dropped, then
// bytes within each message, while it still fails with a finding of the same
// kind) and saved as a session file `mococheck replay` reruns. Where the
// executor observes the firmware's code, a mutant that reaches an edge (or an
// edge's hit count class) no run reached before joins the corpus the next
// mutants are made from. Where it keeps snapshots, mutants come in batches
// from one corpus entry and one point in it: the messages before the point are
// kept and played from a snapshot, a window of one or two after it (or, in one
// mutant of sixteen, all the rest) is mutated.
#ifndef MOCO_CONFORMANCE_FUZZ_CAMPAIGN_H_
#define MOCO_CONFORMANCE_FUZZ_CAMPAIGN_H_

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "conformance/fuzz/executor.h"
#include "conformance/fuzz/mutator.h"

namespace moco::conformance {

// The host messages of one session file.
struct Seed {
  std::string path;
  Protocol protocol = Protocol::kDmc;
  std::string device;  // the header's device model, may be empty
  Messages messages;
  std::string warning;  // session::SessionWarning of the file (a cut last line), or empty
};

// Reads a session file and cuts its host traffic into messages (as_written:
// one message per recorded host write, as a saved finding holds them). On
// failure the message names the file, the line and the fix.
std::variant<Seed, std::string> LoadSeed(const std::string& path, bool as_written = false);

struct FuzzOptions {
  uint64_t seed = 1;
  uint64_t runs = 0;        // mutants to run; 0: until `seconds` pass
  double seconds = 10;      // wall-clock budget when runs == 0
  std::string crash_dir;    // where failing mutants are saved; empty: not saved
  std::string device;       // the model name written into saved sessions
  size_t max_failures = 5;  // stop after this many distinct failures
  // Of every 100 mutations, how many put in a pause (SessionMutator::set_pause_percent).
  uint32_t pause_percent = SessionMutator::kDefaultPausePercent;
};

struct FuzzFailure {
  Messages messages;  // shrunk
  std::vector<std::string> mutations;
  std::string violation;
  std::string saved_path;  // empty when not saved
  FuzzVerdict::Kind kind = FuzzVerdict::Kind::kInvariant;
  std::vector<std::string> backtrace;  // FuzzVerdict::backtrace of the shrunk mutant
};

struct FuzzReport {
  uint64_t execs = 0;
  uint64_t messages = 0;  // host messages sent over all execs
  double wall_s = 0;
  bool coverage = false;  // the executor observed the code
  size_t edges = 0;       // distinct edges reached over all runs
  size_t corpus = 0;      // sessions mutants are made from: the seeds and every new-coverage mutant
  uint64_t snapshot_runs = 0;        // mutants run from a snapshot (FuzzExecutor::snapshots())
  uint64_t shrink_runs = 0;          // runs made to shrink findings (not in execs)
  TimeNs simulated_ns = 0;           // the device's time the execs took, summed
  std::optional<CodeCoverage> code;  // of a firmware image: FuzzExecutor::code_coverage()
  std::vector<FuzzFailure> failures;
  int interrupted_by = 0;  // the signal that stopped the campaign (StopRequested), or 0
  double ExecsPerSecond() const { return wall_s > 0 ? static_cast<double>(execs) / wall_s : 0; }
};

// Runs each seed once unmutated, then mutants until the budget is spent.
// `progress` (may be empty) is called about once a second with the report so far.
FuzzReport RunFuzz(FuzzExecutor& executor, Protocol protocol, const std::vector<Seed>& seeds,
                   const FuzzOptions& options,
                   const std::function<void(const FuzzReport&)>& progress = {});

// Writes `messages` as a session file (host traffic only, one message every
// FuzzHooks::gap_ns of the protocol; a pause, an empty message, as a `pause`
// event of its FuzzHooks::pause_ns that the next message comes after),
// atomically. Returns an error message or "".
std::string SaveMessages(const std::string& path, Protocol protocol, const std::string& device,
                         const std::string& note, const Messages& messages);

}  // namespace moco::conformance

#endif  // MOCO_CONFORMANCE_FUZZ_CAMPAIGN_H_
