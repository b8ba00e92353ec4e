// The session mutator (see mutator.h): one message mutated by its protocol's
// hooks, or the session rearranged.
#include "conformance/fuzz/mutator.h"

#include "conformance/protocols/registry.h"

namespace moco::conformance {

SessionMutator::SessionMutator(Protocol protocol, uint64_t seed)
    : MutationSource(seed), protocol_(protocol), hooks_(FindFuzzHooks(protocol)) {}

void SessionMutator::Mutate(Messages& messages, const std::vector<Messages>& donors) {
  ClearApplied();
  const uint64_t rounds = 1 + Below(4);
  for (uint64_t r = 0; r < rounds; ++r) MutateOne(messages, donors);
  if (messages.size() > kMaxMessages) messages.resize(kMaxMessages);
}

void SessionMutator::MutateOne(Messages& messages, const std::vector<Messages>& donors) {
  if (messages.empty()) messages.push_back(wire::Info(protocol_).greeting());
  const uint64_t pick = Below(100);
  const size_t at = Below(messages.size());
  if (pick < 60) {
    if (hooks_ != nullptr) hooks_->mutate(*this, messages[at]);
  } else if (pick < 70) {  // duplicate
    messages.insert(messages.begin() + static_cast<ptrdiff_t>(at), messages[at]);
    Note("duplicate");
  } else if (pick < 78) {  // delete
    if (messages.size() > 1) messages.erase(messages.begin() + static_cast<ptrdiff_t>(at));
    Note("delete");
  } else if (pick < 85) {  // swap two
    std::swap(messages[at], messages[Below(messages.size())]);
    Note("swap");
  } else if (pick < 95) {  // splice a message from another session (or this one)
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
