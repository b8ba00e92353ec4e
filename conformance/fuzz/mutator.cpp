// The session mutator (see mutator.h): one message mutated by its protocol's
// hooks, or the session rearranged.
#include "conformance/fuzz/mutator.h"

#include <cstring>

#include "conformance/protocols/registry.h"

namespace moco::conformance {
namespace {

// The share of mutations (in percent) that change one message's fields or,
// set_pause_percent() of them, put in a pause (core/fuzz_protocol.h). A
// pause costs a run the protocol's pause in the device's time (DFMoco:
// 250 ms, ten times a run's usual 25 ms), so it is rare; docs/benchmarks.md
// "Firmware fuzzing" gives what the default was chosen by.
constexpr uint64_t kFieldOrPausePercent = SessionMutator::kMaxPausePercent;
// A pause mutation puts in 1 to this many pauses in a row (DFMoco: up to 1 s,
// what a move of a few thousand steps takes).
constexpr uint64_t kMaxPauses = 4;

}  // namespace

SessionMutator::SessionMutator(Protocol protocol, uint64_t seed)
    : MutationSource(seed), protocol_(protocol), hooks_(FindFuzzHooks(protocol)) {}

void SessionMutator::Mutate(Messages& messages, const std::vector<Messages>& donors) {
  ClearApplied();
  const uint64_t rounds = 1 + Below(4);
  for (uint64_t r = 0; r < rounds; ++r) MutateOne(messages, donors);
  if (messages.size() > kMaxMessages) messages.resize(kMaxMessages);
}

size_t SessionMutator::MutateStream(Protocol protocol, uint8_t* data, size_t size, size_t max_size,
                                    unsigned int seed) {
  Messages messages = wire::SplitMessages(protocol, wire::Side::kHost, {data, size});
  SessionMutator mutator(protocol, seed);
  mutator.Mutate(messages, {});
  wire::Bytes out = wire::JoinMessages(messages);
  if (out.size() > max_size) out.resize(max_size);
  if (!out.empty()) std::memcpy(data, out.data(), out.size());
  return out.size();
}

void SessionMutator::MutateOne(Messages& messages, const std::vector<Messages>& donors) {
  if (messages.empty()) messages.push_back(wire::Info(protocol_).greeting());
  const uint64_t pick = Below(100);
  const size_t at = Below(messages.size());
  if (pick < kFieldOrPausePercent - pause_percent_) {
    // A pause has no fields: the first message from `at` on (round) that is
    // not one is mutated.
    for (size_t k = 0; k < messages.size(); ++k) {
      wire::Bytes& m = messages[(at + k) % messages.size()];
      if (m.empty()) continue;
      if (hooks_ != nullptr) hooks_->mutate(*this, m);
      break;
    }
  } else if (pick < kFieldOrPausePercent) {  // a pause (1-4 empty messages) between two messages
    messages.insert(messages.begin() + static_cast<ptrdiff_t>(Below(messages.size() + 1)),
                    1 + Below(kMaxPauses), wire::Bytes());
    Note("pause");
  } else if (pick < 70) {  // duplicate
    messages.insert(messages.begin() + static_cast<ptrdiff_t>(at), messages[at]);
    Note("duplicate");
  } else if (pick < 78) {  // delete
    if (messages.size() > 1) messages.erase(messages.begin() + static_cast<ptrdiff_t>(at));
    Note("delete");
  } else if (pick < 85) {  // swap two
    std::swap(messages[at], messages[Below(messages.size())]);
    Note("swap");
  } else if (pick < 91) {  // two messages in one write (a read that takes both)
    if (at + 1 < messages.size() &&
        messages[at].size() + messages[at + 1].size() <= kMaxBurstBytes) {
      messages[at].insert(messages[at].end(), messages[at + 1].begin(), messages[at + 1].end());
      messages.erase(messages.begin() + static_cast<ptrdiff_t>(at) + 1);
    }
    Note("burst");
  } else if (pick < 97) {  // splice a message from another session (or this one)
    const Messages* from = &messages;
    if (!donors.empty()) {
      const Messages& d = donors[Below(donors.size())];
      if (!d.empty()) from = &d;
    }
    wire::Bytes copy = (*from)[Below(from->size())];
    messages.insert(messages.begin() + static_cast<ptrdiff_t>(Below(messages.size() + 1)),
                    std::move(copy));
    Note("splice");
  } else {  // cut a message short in the middle of the stream (framing resync)
    wire::Bytes& m = messages[at];
    if (m.size() > 1) m.resize(1 + Below(m.size() - 1));
    Note("cut");
  }
}

}  // namespace moco::conformance
