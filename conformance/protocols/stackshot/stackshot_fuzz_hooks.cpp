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

FuzzVerdict Run(Target& target, const Messages& messages, TimeNs gap_ns,
                const wire::Bytes& /*boot_out*/) {
  using stackshot::Action;
  using stackshot::Command;
  wire::Bytes out;
  stackshot::PacketDecoder requests(false);
  std::vector<stackshot::DecodedPacket> sent;
  bool mode_switch = false;
  for (const wire::Bytes& m : messages) {
    target.Send(m);
    requests.Feed(m, sent);
    target.Receive(target.Now() + gap_ns, out);
    requests.Flush();  // the inter-frame gap ends a partial packet on both sides
  }
  for (const auto& p : sent) {
    const uint16_t c = p.packet.command;
    if (c == stackshot::Id(Command::kRailConfigGlobalMode) ||
        c == stackshot::Id(Command::kReflash) || c == stackshot::Id(Command::kReset) ||
        c == stackshot::Id(Command::kWifi) || c == stackshot::Id(Command::kClose)) {
      mode_switch = true;
    }
  }
  // Liveness: a PING is answered (unless the session left the packet protocol).
  size_t ping_index = sent.size();
  if (!mode_switch) {
    stackshot::Packet ping;
    ping.command = stackshot::Id(Command::kPing);
    ping.action = static_cast<uint8_t>(Action::kRead);
    ping.data = {0x5a};
    stackshot::Seal(ping, stackshot::kDefaultChecksum);
    wire::Bytes bytes;
    stackshot::EncodePacket(ping, bytes);
    target.Send(bytes);
    requests.Feed(bytes, sent);
  }
  target.Receive(target.Now() + kSsFuzzPingAnswerNs, out);
  while (true) {
    const size_t n = out.size();
    target.Receive(target.Now() + kSsFuzzDrainQuietNs, out);
    if (out.size() == n) break;
  }

  stackshot::PacketDecoder decoder(true);
  std::vector<stackshot::DecodedPacket> replies;
  decoder.Feed(out, replies);
  if (decoder.skipped_total() != 0 || decoder.pending_bytes() != 0) {
    return Violation("packet framing: " + std::to_string(decoder.skipped_total()) +
                         " device byte(s) outside packets, " +
                         std::to_string(decoder.pending_bytes()) + " left in a partial packet",
                     messages.size(), replies.size());
  }
  if (replies.size() > sent.size()) {
    return Violation("one reply per request: " + std::to_string(replies.size()) + " replies to " +
                         std::to_string(sent.size()) + " request packets",
                     messages.size(), replies.size());
  }
  // Replies come in request order: each answers a later request with its command.
  size_t next = 0;
  bool ping_answered = false;
  for (const auto& r : replies) {
    if (!r.checksum_ok) {
      return Violation("checksum: a device packet for " + stackshot::CommandName(r.packet.command) +
                           " carries a wrong checksum",
                       messages.size(), replies.size());
    }
    if (r.packet.action < static_cast<uint8_t>(Action::kRspOk) ||
        r.packet.action >= stackshot::kActionMax) {
      return Violation("status: " + stackshot::CommandName(r.packet.command) +
                           " answered with comm_action_t " + std::to_string(r.packet.action) +
                           ", not a response status",
                       messages.size(), replies.size());
    }
    while (next < sent.size() && sent[next].packet.command != r.packet.command) ++next;
    if (next == sent.size()) {
      return Violation("command echo: a reply for " + stackshot::CommandName(r.packet.command) +
                           " answers no request sent before it",
                       messages.size(), replies.size());
    }
    if (next == ping_index) ping_answered = true;
    ++next;
  }
  if (!mode_switch && !ping_answered) {
    return Violation("liveness: CC_PING after the session got no reply", messages.size(),
                     replies.size());
  }
  return Passed(messages.size(), replies.size());
}

const FuzzHooks kHooks[] = {{
    .protocol = Protocol::kStackshot,
    .gap_ns = kSsFuzzGapNs,
    .mutate = &Mutate,
    .run = &Run,
    .matcher = []() { return ExactMatcher("the packet differs"); },
}};

}  // namespace

std::span<const FuzzHooks> StackshotProtocol::Fuzz() { return kHooks; }

}  // namespace moco::conformance
