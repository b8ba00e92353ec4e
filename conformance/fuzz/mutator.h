// The session mutator of `mococheck fuzz` and the libFuzzer targets: host
// traffic is cut into messages, and mutants are made per message by the
// protocol (its FuzzHooks::mutate: field values, type or command swaps,
// truncation, extension, then the length and checksum repaired so that most
// mutants reach the device's message logic; a small share keeps broken
// framing on purpose) and across messages here (splices between messages and
// sessions, duplication, deletion, reordering, two messages sent in one write,
// a message cut short, a pause between two messages).
#ifndef MOCO_CONFORMANCE_FUZZ_MUTATOR_H_
#define MOCO_CONFORMANCE_FUZZ_MUTATOR_H_

#include <algorithm>
#include <cstdint>
#include <string>
#include <vector>

#include "conformance/core/fuzz_protocol.h"
#include "conformance/rules/catalogue.h"
#include "wire/bytes.h"
#include "wire/protocol.h"

namespace moco::conformance {

// A host byte stream is cut into messages, and a message repaired, by the
// protocol table: wire::SplitMessages(p, wire::Side::kHost, stream),
// wire::JoinMessages, wire::Info(p).repair (wire/protocol.h).

// Deterministic (seeded) structure-aware mutator.
class SessionMutator : public MutationSource {
 public:
  // Upper bound a mutant respects.
  static constexpr size_t kMaxMessages = 256;
  // Two messages are sent in one write ("burst") only while the write stays
  // within this many bytes.
  static constexpr size_t kMaxBurstBytes = 256;
  // The share of mutations (in percent) that put in a pause unless told
  // otherwise (set_pause_percent), and the most that may.
  static constexpr uint32_t kDefaultPausePercent = 1;
  static constexpr uint32_t kMaxPausePercent = 60;

  SessionMutator(Protocol protocol, uint64_t seed);

  // Applies 1..4 mutations to `messages`. `donors` (other sessions' messages,
  // may be empty) feed splices. A message changed in its fields is re-encoded
  // with a correct length and checksum (DFMoco: its line end), except in the
  // rare mutations that break it on purpose (a wrong checksum, a cut message,
  // a missing line end).
  void Mutate(Messages& messages, const std::vector<Messages>& donors);

  // libFuzzer's custom mutator over a host byte stream of `protocol`: cut into
  // messages, mutated with `seed`, joined again into `data` (at most
  // `max_size` bytes); the new size. A byte stream holds no time: a pause
  // the mutation puts in is gone once joined.
  static size_t MutateStream(Protocol protocol, uint8_t* data, size_t size, size_t max_size,
                             unsigned int seed);

  // The names of the mutations applied by the last Mutate(), for reports.
  const std::vector<std::string>& last_mutations() const { return applied(); }

  // How many of every 100 mutations put in a pause (1-4 empty messages,
  // core/fuzz_protocol.h), taken from those that change a message's fields;
  // at most kMaxPausePercent. 0: none.
  void set_pause_percent(uint32_t percent) { pause_percent_ = std::min(percent, kMaxPausePercent); }

 private:
  void MutateOne(Messages& messages, const std::vector<Messages>& donors);

  Protocol protocol_;
  uint32_t pause_percent_ = kDefaultPausePercent;
  const FuzzHooks* hooks_;  // nullptr: the protocol has none; messages are only rearranged
};

}  // namespace moco::conformance

#endif  // MOCO_CONFORMANCE_FUZZ_MUTATOR_H_
