// StackShot 3X under the fuzzer (core/fuzz_protocol.h): packets mutated in
// their command, action, axis and data, then sealed again
// (stackshot-protocol.txt section 2), sessions judged by the reply laws
// (section 4.1: one reply per request, in order, a legal status, a correct
// checksum) and a PING answered after the session; replays byte-exact.
#include "conformance/protocols/stackshot/stackshot_protocol.h"
#include "conformance/protocols/stackshot/stackshot_timing.h"
#include "wire/stackshot.h"
#include "wire/stackshot_constants.h"

namespace moco::conformance {
namespace {

void Mutate(MutationSource& s, wire::Bytes& m) {
  auto peeked = stackshot::PeekHostPacket(m);
  if (!peeked) {
    if (!m.empty()) m[s.Below(m.size())] ^= static_cast<uint8_t>(1u << s.Below(8));
    s.Note("noise-flip");
    return;
  }
  stackshot::Packet& p = *peeked;
  switch (s.Below(5)) {
    case 0: {
      const auto all = stackshot::AllCommands();
      p.command = s.Chance(80) && !all.empty() ? all[s.Below(all.size())].id
                                               : static_cast<uint16_t>(s.Next());
      s.Note("command");
      break;
    }
    case 1:
      p.action = static_cast<uint8_t>(s.Below(16));
      s.Note("action");
      break;
    case 2:
      p.axis = static_cast<uint8_t>(s.Below(4));
      p.sub_item = s.Chance(20);
      s.Note("axis");
      break;
    default:
      s.MutateDataBytes(p.data);
      break;
  }
  if (p.data.size() > stackshot::kMaxDataBytes) p.data.resize(stackshot::kMaxDataBytes);
  stackshot::Seal(p, stackshot::kDefaultChecksum);
  m.clear();
  stackshot::EncodePacket(p, m);
}

// One run: each packet sent, then the inter-frame gap waited out.
class StackshotPlay final : public FuzzPlay {
 public:
  void Play(Target& target, const wire::Bytes& m) override {
    if (m.empty()) {  // a pause: what the device sends meanwhile is read
      const TimeNs until = target.Now() + kSsFuzzPauseNs;
      while (target.Now() < until && target.Receive(until, out_)) {
      }
      return;
    }
    target.Send(m);
    requests_.Feed(m, sent_);
    target.Receive(target.Now() + kSsFuzzGapNs, out_);
    requests_.Flush();  // the inter-frame gap ends a partial packet on both sides
    ++messages_;
  }
  FuzzVerdict Finish(Target& target) override;

 private:
  wire::Bytes out_;
  stackshot::PacketDecoder requests_{false};
  std::vector<stackshot::DecodedPacket> sent_;
  size_t messages_ = 0;
};

FuzzVerdict StackshotPlay::Finish(Target& target) {
  using stackshot::Action;
  using stackshot::Command;
  bool mode_switch = false;
  for (const auto& p : sent_) {
    const uint16_t c = p.packet.command;
    if (c == stackshot::Id(Command::kRailConfigGlobalMode) ||
        c == stackshot::Id(Command::kReflash) || c == stackshot::Id(Command::kReset) ||
        c == stackshot::Id(Command::kWifi) || c == stackshot::Id(Command::kClose)) {
      mode_switch = true;
    }
  }
  // Liveness: a PING is answered (unless the session left the packet protocol).
  size_t ping_index = sent_.size();
  if (!mode_switch) {
    stackshot::Packet ping;
    ping.command = stackshot::Id(Command::kPing);
    ping.action = static_cast<uint8_t>(Action::kRead);
    ping.data = {0x5a};
    stackshot::Seal(ping, stackshot::kDefaultChecksum);
    wire::Bytes bytes;
    stackshot::EncodePacket(ping, bytes);
    target.Send(bytes);
    requests_.Feed(bytes, sent_);
  }
  target.Receive(target.Now() + kSsFuzzPingAnswerNs, out_);
  while (true) {
    const size_t n = out_.size();
    target.Receive(target.Now() + kSsFuzzDrainQuietNs, out_);
    if (out_.size() == n) break;
  }

  stackshot::PacketDecoder decoder(true);
  std::vector<stackshot::DecodedPacket> replies;
  decoder.Feed(out_, replies);
  if (decoder.skipped_total() != 0 || decoder.pending_bytes() != 0) {
    return Violation("packet framing: " + std::to_string(decoder.skipped_total()) +
                         " device byte(s) outside packets, " +
                         std::to_string(decoder.pending_bytes()) + " left in a partial packet",
                     messages_, replies.size());
  }
  if (replies.size() > sent_.size()) {
    return Violation("one reply per request: " + std::to_string(replies.size()) + " replies to " +
                         std::to_string(sent_.size()) + " request packets",
                     messages_, replies.size());
  }
  // Replies come in request order: each answers a later request with its command.
  size_t next = 0;
  bool ping_answered = false;
  for (const auto& r : replies) {
    if (!r.checksum_ok) {
      return Violation("checksum: a device packet for " + stackshot::CommandName(r.packet.command) +
                           " carries a wrong checksum",
                       messages_, replies.size());
    }
    if (r.packet.action < static_cast<uint8_t>(Action::kRspOk) ||
        r.packet.action >= stackshot::kActionMax) {
      return Violation("status: " + stackshot::CommandName(r.packet.command) +
                           " answered with comm_action_t " + std::to_string(r.packet.action) +
                           ", not a response status",
                       messages_, replies.size());
    }
    while (next < sent_.size() && sent_[next].packet.command != r.packet.command) ++next;
    if (next == sent_.size()) {
      return Violation("command echo: a reply for " + stackshot::CommandName(r.packet.command) +
                           " answers no request sent_ before it",
                       messages_, replies.size());
    }
    if (next == ping_index) ping_answered = true;
    ++next;
  }
  if (!mode_switch && !ping_answered) {
    return Violation("liveness: CC_PING after the session got no reply", messages_, replies.size());
  }
  return Passed(messages_, replies.size());
}

const FuzzHooks kHooks[] = {{
    .protocol = Protocol::kStackshot,
    .gap_ns = kSsFuzzGapNs,
    .pause_ns = kSsFuzzPauseNs,
    .mutate = &Mutate,
    // The pin rules are DFMoco's (no DMC or StackShot firmware runs under simavr).
    .start = [](const wire::Bytes&, const PinJudgeOptions*) -> std::unique_ptr<FuzzPlay> {
      return std::make_unique<StackshotPlay>();
    },
    .matcher = []() { return ExactMatcher("the packet differs"); },
}};

}  // namespace

std::span<const FuzzHooks> StackshotProtocol::Fuzz() { return kHooks; }

}  // namespace moco::conformance
