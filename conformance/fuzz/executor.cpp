// The fuzz executor (see executor.h). DMC v2 runs through the conformance
// host, so every stream rule of the catalogue is an invariant; DFMoco and
// StackShot 3X are judged with their codecs.
#include "conformance/fuzz/executor.h"

#include <string_view>

#include "conformance/protocols/dmc/dmc_host.h"
#include "wire/dfmoco.h"
#include "wire/dmc_frame.h"
#include "wire/stackshot.h"
#include "wire/stackshot_constants.h"

namespace moco::conformance {
namespace {

constexpr TimeNs kMs = sim::kNsPerMs;

FuzzVerdict Violation(std::string what, size_t messages, size_t replies) {
  return FuzzVerdict{false, std::move(what), messages, replies};
}

// A frame the device must answer: marker, header and a Length within the
// receive buffer (ERRATA 1.2: an oversize Length is dropped unanswered, and
// the scan resumes inside it, so it counts as noise).
bool WholeDmcFrame(const wire::Bytes& m) {
  return m.size() >= dmc::kHeaderSize + dmc::kCheckSize && m.size() <= dmc::kMaxFrameSize &&
         m[0] == dmc::kMarker0 && m[1] == dmc::kMarker1 &&
         static_cast<size_t>(m[8] | (m[9] << 8)) + dmc::kHeaderSize + dmc::kCheckSize == m.size();
}

// A frame with a bad checksum whose bytes after its marker hold another 'D'
// 'F': the device rescans from the byte after a rejected candidate's 'D'
// ("Message Format" resync, FACTS), so it may find and answer a frame inside.
bool HidesAFrame(const wire::Bytes& m) {
  if (dmc::DecodeFrame(m).ok()) return false;
  for (size_t i = 1; i + 1 < m.size(); ++i) {
    if (m[i] == dmc::kMarker0 && m[i + 1] == dmc::kMarker1) return true;
  }
  return false;
}

}  // namespace

FuzzExecutor::FuzzExecutor(Protocol protocol, std::unique_ptr<InProcessTarget> target)
    : protocol_(protocol),
      target_(std::move(target)),
      gap_ns_(protocol == Protocol::kStackshot ? 3 * kMs : 1 * kMs) {}

FuzzExecutor::~FuzzExecutor() = default;

std::optional<std::string> FuzzExecutor::Open() { return target_->Open(); }

FuzzVerdict FuzzExecutor::Run(const Messages& messages) {
  target_->Restart();
  switch (protocol_) {
    case Protocol::kDmc:
      return RunDmc(messages);
    case Protocol::kDfmoco:
      return RunDfmoco(messages);
    case Protocol::kStackshot:
      return RunStackshot(messages);
    case Protocol::kStackshotDfmoco:
      break;
  }
  return {false, "the " + std::string(wire::Info(protocol_).title) + " protocol is not fuzzed", 0,
          0};
}

FuzzVerdict FuzzExecutor::RunDmc(const Messages& messages) {
  // Whole frames go through the host as requests (renumbered: the ID is
  // echo-only, and distinct IDs let every answer be matched); anything else
  // is noise. A stream with noise or cut frames may legitimately leave a
  // frame swallowed or pending, so only the framing rules and liveness judge it.
  bool strict = true;
  for (const wire::Bytes& m : messages) {
    strict = strict && WholeDmcFrame(m) && !HidesAFrame(m);
  }
  Verdicts verdicts(strict ? std::string() : std::string("DMC-FRAME-*,DMC-CSUM-*"));
  HostOptions options;
  options.quiet_ns = 20 * kMs;
  DmcHost host(*target_, verdicts, options);
  std::vector<uint32_t> ids;
  for (const wire::Bytes& m : messages) {
    if (WholeDmcFrame(m)) {
      const uint16_t type = static_cast<uint16_t>(m[6] | (m[7] << 8));
      const bool good = dmc::DecodeFrame(m).ok();
      const uint32_t id =
          host.SendFrame(type, wire::ByteView(m).subspan(dmc::kHeaderSize, m.size() - 12), !good);
      // A frame with the ACK flag is the host's acknowledgement, not a
      // request: nothing answers it ("MSG_FLAG_ACK"), even when damaged. A
      // damaged frame whose Type no request has (bits outside 0x83FF) is a
      // false "DF" to the device, dropped unanswered (PlausibleRequestHeader).
      if (dmc::PlausibleRequestHeader(type) || (good && (type & dmc::kFlagAck) == 0)) {
        ids.push_back(id);
      }
    } else {
      host.SendNoise(m);
    }
    host.Idle(gap_ns_);
  }
  if (!strict) {
    // Complete whatever candidate frame the noise opened (its data is zeros,
    // so its check fails and the device resynchronises) before asking again.
    host.SendNoise(wire::Bytes(dmc::kMaxFrameSize, 0));
    host.Idle(gap_ns_);
  }
  // Every request answered (DMC-ACK-001); in a noisy stream one may be swallowed.
  if (strict) {
    for (uint32_t id : ids) host.Await(id);
  }
  const uint32_t hi_id = host.Send(dmc::HiRequest{});
  const DeviceRecord* hi = host.Await(hi_id);
  host.Close();
  const size_t replies = host.records().size();
  if (hi == nullptr || As<dmc::HiResponse>(hi) == nullptr) {
    return Violation(
        "liveness: the device did not answer MSG_HI after the session (got " + Show(hi) + ")",
        messages.size(), replies);
  }
  for (const auto& [id, o] : verdicts.outcomes()) {
    const Rule* r = FindRule(id);
    if (o.status != Status::kFail || r == nullptr || r->level != Level::kMust) continue;
    std::string what = id + " " + std::string(r->title);
    if (!o.evidence.empty()) {
      const Evidence& e = o.evidence.front();
      what += ": expected " + e.expected + ", observed " + e.observed;
      if (!e.hex.empty()) what += " [" + e.hex + "]";
    }
    return Violation(what, messages.size(), replies);
  }
  return FuzzVerdict{true, "", messages.size(), replies};
}

FuzzVerdict FuzzExecutor::RunDfmoco(const Messages& messages) {
  wire::Bytes out;
  // The boot greeting (the sketch starts after its boot delay).
  const TimeNs boot_deadline = target_->Now() + 3000 * kMs;
  while (out.empty() && target_->Now() < boot_deadline) target_->Receive(boot_deadline, out);
  // A host waits for the answer before the next command (the sketch's 57600
  // baud line and 16-message queue cannot keep up with more): after each
  // message, read until the device has been quiet for 5 ms (at most 100 ms).
  auto settle = [&] {
    const TimeNs limit = target_->Now() + 100 * kMs;
    while (target_->Now() < limit) {
      const size_t n = out.size();
      target_->Receive(std::min(limit, target_->Now() + 5 * kMs), out);
      if (out.size() == n) break;
    }
  };
  for (const wire::Bytes& m : messages) {
    target_->Send(m);
    target_->Receive(target_->Now() + gap_ns_, out);
    settle();
  }
  // End any unterminated line, then greet.
  const std::string_view tail = "\r\nhi\r\n";
  const size_t before_hi = out.size();
  target_->Send(wire::ByteView(reinterpret_cast<const uint8_t*>(tail.data()), tail.size()));
  const TimeNs deadline = target_->Now() + 2000 * kMs;
  while (target_->Now() < deadline) {
    target_->Receive(deadline, out);
    if (out.size() > before_hi && out.back() == '\n') {
      // Stop once a hi reply has come after the greeting was sent.
      const std::string_view s(reinterpret_cast<const char*>(out.data()) + before_hi,
                               out.size() - before_hi);
      if (s.find("hi ") != std::string_view::npos) break;
    }
  }
  target_->Receive(target_->Now() + 20 * kMs, out);

  const std::string_view text(reinterpret_cast<const char*>(out.data()), out.size());
  dfmoco::Dialect dialect;
  bool have_dialect = false;
  bool hi_after = false;
  size_t replies = 0;
  size_t start = 0;
  while (start < text.size()) {
    const size_t nl = text.find('\n', start);
    if (nl == std::string_view::npos) {
      return Violation("line grammar: the device left an unterminated line \"" +
                           std::string(text.substr(start)) + "\"",
                       messages.size(), replies);
    }
    if (nl == start || text[nl - 1] != '\r') {
      return Violation(
          "line grammar: a device line does not end in CR LF at byte " + std::to_string(nl),
          messages.size(), replies);
    }
    const std::string_view line = text.substr(start, nl - 1 - start);
    for (char c : line) {
      if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) > 0x7e) {
        return Violation(
            "line grammar: a control or non-ASCII byte in \"" + std::string(line) + "\"",
            messages.size(), replies);
      }
    }
    auto parsed = dfmoco::ParseDeviceLine(line, dialect);
    if (!parsed.ok()) {
      return Violation("reply grammar: \"" + std::string(line) + "\" is no DFMoco reply (" +
                           parsed.error().detail + ")",
                       messages.size(), replies);
    }
    if (const auto* h = std::get_if<dfmoco::HelloReply>(&parsed.value())) {
      dialect = dfmoco::DialectFrom(*h, false);
      have_dialect = true;
      if (start >= before_hi) hi_after = true;
    } else if (const auto* ms = std::get_if<dfmoco::MotorStatusReply>(&parsed.value())) {
      if (have_dialect && static_cast<int32_t>(ms->moving.size()) != dialect.motor_count) {
        return Violation("ms width: \"" + std::string(line) + "\" has " +
                             std::to_string(ms->moving.size()) + " digits for " +
                             std::to_string(dialect.motor_count) + " motors",
                         messages.size(), replies);
      }
    }
    ++replies;
    start = nl + 1;
  }
  if (!hi_after) {
    return Violation("liveness: no `hi` reply to the greeting sent after the session",
                     messages.size(), replies);
  }
  return FuzzVerdict{true, "", messages.size(), replies};
}

FuzzVerdict FuzzExecutor::RunStackshot(const Messages& messages) {
  using stackshot::Action;
  using stackshot::Command;
  wire::Bytes out;
  stackshot::PacketDecoder requests(false);
  std::vector<stackshot::DecodedPacket> sent;
  bool mode_switch = false;
  for (const wire::Bytes& m : messages) {
    target_->Send(m);
    requests.Feed(m, sent);
    target_->Receive(target_->Now() + gap_ns_, out);
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
    target_->Send(bytes);
    requests.Feed(bytes, sent);
  }
  target_->Receive(target_->Now() + 500 * kMs, out);
  while (true) {
    const size_t n = out.size();
    target_->Receive(target_->Now() + 50 * kMs, out);
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
  return FuzzVerdict{true, "", messages.size(), replies.size()};
}

}  // namespace moco::conformance
