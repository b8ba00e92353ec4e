// The session mutator of `mococheck fuzz` and the libFuzzer targets
// (dmc-v2-protocol.txt "Message Format"; the DFMoco line grammar; StackShot 3X
// section 4.1 packets): host traffic is cut into messages, and mutants are made
// per message (bit flips, interesting field values, type/command swaps,
// truncation, extension, splices between messages and sessions, duplication,
// deletion, reordering). Lengths and checksums are then repaired so that most
// mutants get past framing and reach the device's message logic; a small share
// keeps a broken checksum or broken framing on purpose.
#ifndef MOCO_CONFORMANCE_FUZZ_MUTATOR_H_
#define MOCO_CONFORMANCE_FUZZ_MUTATOR_H_

#include <cstdint>
#include <string>
#include <vector>

#include "conformance/rules/catalogue.h"
#include "wire/bytes.h"
#include "wire/protocol.h"

namespace moco::conformance {

// One host message as it goes on the wire: a DMC frame, a DFMoco line with its
// line end, a StackShot packet; or bytes that frame as nothing (noise).
using Messages = std::vector<wire::Bytes>;

// A host byte stream is cut into messages, and a message repaired, by the
// protocol table: wire::SplitMessages(p, wire::Side::kHost, stream),
// wire::JoinMessages, wire::Info(p).repair (wire/protocol.h).

// Deterministic (seeded) structure-aware mutator.
class SessionMutator {
 public:
  // Upper bounds a mutant respects.
  static constexpr size_t kMaxMessages = 256;
  static constexpr size_t kMaxDfmocoLine = 96;

  SessionMutator(Protocol protocol, uint64_t seed);

  // Applies 1..4 mutations to `messages`. `donors` (other sessions' messages,
  // may be empty) feed splices. A message changed in its fields is re-encoded
  // with a correct length and checksum (DFMoco: its line end), except in the
  // rare mutations that break it on purpose (a wrong checksum, a cut message,
  // a missing line end).
  void Mutate(Messages& messages, const std::vector<Messages>& donors);

  // The names of the mutations applied by the last Mutate(), for reports.
  const std::vector<std::string>& last_mutations() const { return last_; }

  uint64_t Next();             // the generator (splitmix64)
  uint64_t Below(uint64_t n);  // uniform in [0, n); n > 0
  bool Chance(uint32_t percent);

 private:
  void MutateOne(Messages& messages, const std::vector<Messages>& donors);
  void MutateDmc(wire::Bytes& m);
  void MutateStackshot(wire::Bytes& m);
  void MutateDfmoco(wire::Bytes& m);
  void MutateDataBytes(wire::Bytes& data);

  Protocol protocol_;
  uint64_t state_;
  std::vector<std::string> last_;
};

}  // namespace moco::conformance

#endif  // MOCO_CONFORMANCE_FUZZ_MUTATOR_H_
