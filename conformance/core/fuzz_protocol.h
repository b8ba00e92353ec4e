// What `mococheck fuzz`, `mococheck replay` and the libFuzzer targets need
// from a protocol, and nothing else: how to mutate one host message, how to
// play a mutated session into an in-process device and judge the invariants
// every device keeps whatever the host sends, and when two device messages
// are the same within a replay's tolerances. Each protocol's folder
// (conformance/protocols/*/..._fuzz_hooks.cpp) fills one FuzzHooks per
// protocol it speaks; the shared fuzz code (conformance/fuzz/) finds them in
// the registry (conformance/protocols/registry.h) and never names a protocol.
#ifndef MOCO_CONFORMANCE_CORE_FUZZ_PROTOCOL_H_
#define MOCO_CONFORMANCE_CORE_FUZZ_PROTOCOL_H_

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "conformance/core/pin_judge.h"
#include "conformance/targets/target.h"
#include "wire/bytes.h"
#include "wire/protocol.h"

namespace moco::conformance {

// One host message as it goes on the wire: a DMC frame, a DFMoco line with its
// line end, a StackShot packet; or bytes that frame as nothing (noise). An
// empty message is a pause: the host sends nothing for its protocol's
// FuzzHooks::pause_ns (the mutator's timing mutation; a saved session holds
// it as a `pause` event, docs/sessions.md).
using Messages = std::vector<wire::Bytes>;

// What one run of a mutated session found.
struct FuzzVerdict {
  bool ok = true;
  std::string violation;    // the invariant broken and what was seen; empty when ok
  size_t messages = 0;      // host messages sent
  size_t replies = 0;       // device messages received
  TimeNs simulated_ns = 0;  // the device's time the run took (from its snapshot, if any)
  // What kind of finding a failed run is:
  //  - kInvariant: the protocol's stream laws (framing, every request
  //    answered, replies well formed);
  //  - kHang: the device answers nothing, not even a greeting afterwards,
  //    while its firmware still runs;
  //  - the firmware stopped (Target::FirmwareFaulted): kCrash (an illegal
  //    instruction, the PC past the program, the core halted or stuck),
  //    kStackOverflow (the stack grew into .data/.bss), kStackSmash (a return
  //    address overwritten), kDivisionByZero, kReset (a jump to the reset
  //    vector after start);
  //  - kPinLaw: with a board, a MUST rule of the protocol's pin family broken
  //    at the firmware's pins (position = pulses, the driver's timing).
  enum class Kind {
    kInvariant,
    kHang,
    kCrash,
    kStackOverflow,
    kStackSmash,
    kDivisionByZero,
    kReset,
    kPinLaw
  };
  Kind kind = Kind::kInvariant;
  // Where the firmware was (a stopped or hung firmware under a target that
  // runs it): the PC, then the open frames' call sites, innermost first.
  std::vector<std::string> backtrace;
};

// "invariant", "hang", "crash", "stack-overflow", "stack-smash",
// "division-by-zero", "reset", "pin-law": the finding kinds as reports name them.
std::string_view FindingKindName(FuzzVerdict::Kind kind);
// The finding kind of a firmware fault.
FuzzVerdict::Kind FindingKindOf(FirmwareFaultKind kind);

inline FuzzVerdict Passed(size_t messages, size_t replies) {
  FuzzVerdict v;
  v.messages = messages;
  v.replies = replies;
  return v;
}

inline FuzzVerdict Violation(std::string what, size_t messages, size_t replies) {
  FuzzVerdict v;
  v.ok = false;
  v.violation = std::move(what);
  v.messages = messages;
  v.replies = replies;
  return v;
}

// The seeded generator (splitmix64) a mutator draws from, and the names of the
// mutations it applied, for reports. Deterministic: the same seed gives the
// same mutants.
class MutationSource {
 public:
  explicit MutationSource(uint64_t seed);

  uint64_t Next();
  uint64_t Below(uint64_t n);  // uniform in [0, n); n > 0
  bool Chance(uint32_t percent);

  // Records a mutation by name ("bit-flip", "type", ...).
  void Note(std::string_view name) { applied_.emplace_back(name); }
  const std::vector<std::string>& applied() const { return applied_; }
  void ClearApplied() { applied_.clear(); }

  // One mutation of a binary data section: a bit flip, an interesting value
  // at an integer edge (1, 2 or 4 bytes, little-endian), a random byte,
  // truncation, extension (rarely past a receive buffer), or an int32
  // negated.
  void MutateDataBytes(wire::Bytes& data);

 private:
  uint64_t state_;
  std::vector<std::string> applied_;
};

// Decides, during one replay, whether a recorded device message and an
// observed one are the same within the tolerances.
class ReplayMatcher {
 public:
  virtual ~ReplayMatcher() = default;
  // The host sent `bytes` (one recorded chunk) at recorded time `t_ns`.
  virtual void HostSent(wire::ByteView bytes, TimeNs t_ns) { (void)bytes, (void)t_ns; }
  // `expected` (recorded at `t_ns`) and `observed` differ in their bytes:
  // whether they still match within `position_steps`; `why` says why not.
  virtual bool Match(const wire::Bytes& expected, const wire::Bytes& observed, TimeNs t_ns,
                     int64_t position_steps, std::string& why) = 0;
};

// A matcher that accepts no difference, saying `why` ("the packet differs").
std::unique_ptr<ReplayMatcher> ExactMatcher(std::string why);

// One run of a session, message by message: a protocol's FuzzHooks::start
// makes it on a booted device, Play sends each host message (and waits for
// what the protocol waits for; an empty message: reads for the protocol's
// FuzzHooks::pause_ns and sends nothing), Finish ends the session (liveness, the drain)
// and judges everything the device wrote. Deterministic on a target in
// virtual time, so the state after some messages is the same whether they
// were played in this run or in a snapshot it was forked from (FuzzExecutor).
class FuzzPlay {
 public:
  virtual ~FuzzPlay() = default;
  virtual void Play(Target& target, const wire::Bytes& message) = 0;
  virtual FuzzVerdict Finish(Target& target) = 0;
};

struct FuzzHooks {
  wire::Protocol protocol = wire::Protocol::kDmc;
  // Virtual time a run leaves between two host messages.
  TimeNs gap_ns = 0;
  // How long a pause (an empty message) keeps the host quiet.
  TimeNs pause_ns = 0;
  // Mutates one host message in place (its fields, then re-framed: length,
  // checksum or line end repaired, except where a mutation breaks it on
  // purpose), noting each mutation in `source`.
  void (*mutate)(MutationSource& source, wire::Bytes& message) = nullptr;
  // Waits out the device's start after a restart (a boot greeting), appending
  // what it writes to `out`. nullptr: the device is ready at once. A target
  // that runs firmware boots once, and every run starts from that state
  // (FuzzExecutor).
  void (*boot)(Target& target, wire::Bytes& out) = nullptr;
  // Starts a run on the booted device: its messages go in in virtual time,
  // `gap_ns` apart (or each once its answer has come), and the invariants are
  // judged (FuzzPlay); `boot_out` is what the device wrote while it booted.
  // nullptr: sessions of this protocol are mutated and replayed, not run by
  // the fuzzer.
  // With `pins` (a board's watched pins, may be nullptr), the run also judges
  // the protocol's pin rules over the target's pin trace (a kPinLaw finding).
  std::unique_ptr<FuzzPlay> (*start)(const wire::Bytes& boot_out,
                                     const PinJudgeOptions* pins) = nullptr;
  // A matcher for one replay.
  std::unique_ptr<ReplayMatcher> (*matcher)() = nullptr;
};

}  // namespace moco::conformance

#endif  // MOCO_CONFORMANCE_CORE_FUZZ_PROTOCOL_H_
