// Runs one mutated host session against a device in virtual time and judges
// the invariants every device must keep whatever the host sends: no crash,
// every device message well formed, every request answered as its protocol
// says, and the device still answering its greeting afterwards. Each protocol
// states its own in its folder (conformance/protocols/*/*_fuzz_hooks.cpp).
//
// The device is an in-process one (restarted, powered afresh at time 0,
// before every run) or firmware run by a target (simavr). Firmware boots
// once; with Options::fork each run then plays in a child process forked
// from the booted state, so no run re-boots and nothing one run does (its
// memory, its stack, a crash) reaches the next. With Options::snapshots a
// run may also start from a snapshot: a process forked from the booted state
// that has played the session's first messages (the protocol's FuzzPlay, one
// message at a time) and forks each run from there, so a mutant that keeps
// those messages simulates only the rest. A run is deterministic, so its
// verdict is the one a run from boot gives. Where the target can observe the
// firmware's code, every run counts its edges into one coverage map
// (Target::SetCoverageMap) that coverage() shows afterwards.
#ifndef MOCO_CONFORMANCE_FUZZ_EXECUTOR_H_
#define MOCO_CONFORMANCE_FUZZ_EXECUTOR_H_

#include <sys/types.h>

#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <span>
#include <string>

#include "conformance/core/fuzz_protocol.h"
#include "conformance/fuzz/mutator.h"
#include "conformance/targets/target.h"

namespace moco::conformance {

class FuzzExecutor {
 public:
  struct Options {
    // Boot once, then play each run in a child process forked from the
    // booted state (POSIX fork). Off: each run restarts the target and boots.
    bool fork = false;
    // The coverage map's size in bytes (a power of two); 0: no coverage.
    size_t coverage_bytes = 0;
    // With fork: how many snapshots of the device after a session's first
    // messages (a prefix) are kept for Run(messages, prefix), the least
    // recently used given up first; 0: none.
    size_t snapshots = 0;
    // A board's pins to watch and the pin judge's options: each run also
    // judges the protocol's pin rules (FuzzHooks::start). nullopt: none.
    std::optional<PinJudgeOptions> pins;
  };

  // `target` must run on a virtual clock and restart (in-process, simavr).
  FuzzExecutor(Protocol protocol, std::unique_ptr<Target> target);
  FuzzExecutor(Protocol protocol, std::unique_ptr<Target> target, Options options);
  ~FuzzExecutor();
  FuzzExecutor(const FuzzExecutor&) = delete;
  FuzzExecutor& operator=(const FuzzExecutor&) = delete;

  // Opens the target (and boots it when forking); an error message (a bad
  // model or profile, an unreadable firmware, a target on a real clock, a
  // target without coverage when coverage was asked for) or nullopt.
  std::optional<std::string> Open();
  FuzzVerdict Run(const Messages& messages);
  // Runs `messages` from a snapshot of the device after their first `prefix`
  // messages, made on first use: a process forked from the booted state that
  // played them and forks each run from there, so a run simulates only the
  // messages after the prefix. The verdict is the one Run(messages) gives (a
  // run is deterministic), whose coverage map holds what the rest reached.
  // Without snapshots (Options::snapshots), as Run(messages).
  FuzzVerdict Run(const Messages& messages, size_t prefix);
  // Whether Run(messages, prefix) uses snapshots.
  bool snapshots() const { return options_.fork && options_.snapshots > 0; }
  // Whether the protocol's sessions can be run at all (its FuzzHooks::run).
  bool CanRun() const;

  // The last run's edge counts (empty without coverage).
  std::span<const uint8_t> coverage() const;
  // With coverage, for a target that runs a firmware image: what every run
  // since Open() reached of its code (Target::CodeCoverageOf); else nullopt.
  std::optional<CodeCoverage> code_coverage() const;
  // The target's name, as reports show it.
  std::string target_name() const;

 private:
  const PinJudgeOptions* Pins() const { return options_.pins ? &*options_.pins : nullptr; }

  // A process holding the device after one prefix (executor.cpp).
  struct Snapshot {
    pid_t pid = -1;
    int socket = -1;  // the executor's end of a socket pair with it
    uint64_t used = 0;
  };

  FuzzVerdict RunHere(const Messages& messages, const wire::Bytes& boot_out);
  // Ends a run played into `play` since the target's time `start`, with the
  // target's firmware fault if any.
  FuzzVerdict Conclude(FuzzPlay& play, TimeNs start);
  FuzzVerdict RunForked(const Messages& messages);
  // The verdict a forked run wrote back, or why there is none.
  FuzzVerdict ReadBack(bool done, int status, size_t messages);
  // The snapshot after `prefix`, whose Encode()d bytes are `key` (made when
  // missing), or nullptr when it could not be made.
  Snapshot* SnapshotAfter(const std::string& key, std::span<const wire::Bytes> prefix);
  [[noreturn]] void ServeSnapshot(int socket, std::span<const wire::Bytes> prefix);
  void Drop(std::map<std::string, Snapshot>::iterator at);

  Protocol protocol_;
  const FuzzHooks* hooks_;  // nullptr: the protocol has none
  std::unique_ptr<Target> target_;
  Options options_;
  wire::Bytes boot_out_;  // what the device wrote while it booted (fork mode)
  // Memory shared with the forked children: the coverage map, then the
  // verdict a child writes back (see executor.cpp).
  uint8_t* shared_ = nullptr;
  size_t shared_bytes_ = 0;
  // Shared too: the instruction map every run adds to (Target::SetInstructionMap).
  uint8_t* code_ = nullptr;
  size_t code_bytes_ = 0;
  // The snapshots, by their prefix's bytes (each message's length, then it).
  std::map<std::string, Snapshot> snapshots_;
  uint64_t uses_ = 0;
};

}  // namespace moco::conformance

#endif  // MOCO_CONFORMANCE_FUZZ_EXECUTOR_H_
