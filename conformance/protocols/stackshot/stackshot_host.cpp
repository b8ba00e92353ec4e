// The StackShot 3X host of the conformance runner and its stream checks
// (stackshot-protocol.txt section 2 and 1.2 comm_action_t; ERRATA stackshot
// 1-4, 10; FACTS "StackShot" checksums and host timeouts).
#include "conformance/protocols/stackshot/stackshot_host.h"

#include "base/format.h"
#include "conformance/protocols/stackshot/stackshot_timing.h"

#include <algorithm>
#include <cstdio>

namespace moco::conformance {
namespace {

// A request's kind for HostBase::Unanswered: its command and action
// ("CC_RAIL_MOVE write").
std::string KindOf(const stackshot::Packet& p) {
  return stackshot::CommandName(p.command) + " " +
         std::string(stackshot::ActionName(static_cast<stackshot::Action>(p.action)));
}

using stackshot::Action;
using stackshot::ChecksumAlgorithm;
using stackshot::Command;

constexpr ChecksumAlgorithm kAlgorithms[] = {
    ChecksumAlgorithm::kNegatedSum, ChecksumAlgorithm::kConstant69, ChecksumAlgorithm::kConstant00};

using base::Ms;

// Commands the spec names without a layout (NAND, NOR, WIFI, WAD): any answer
// is theirs to give.
bool IsOpaqueCommand(uint16_t id) {
  const stackshot::CommandInfo* info = stackshot::FindCommand(id);
  return info != nullptr && info->read_request == stackshot::Shape::kRaw;
}

std::string ActionText(uint8_t action) {
  return action < stackshot::kActionMax
             ? std::string(stackshot::ActionName(static_cast<Action>(action)))
             : "action " + std::to_string(action);
}

}  // namespace

stackshot::HostCommand SsRead(Command c, stackshot::Payload payload, uint8_t axis, bool sub_item) {
  stackshot::HostCommand h;
  h.command = stackshot::Id(c);
  h.action = Action::kRead;
  h.axis = axis;
  h.sub_item = sub_item;
  h.payload = std::move(payload);
  return h;
}

stackshot::HostCommand SsWrite(Command c, stackshot::Payload payload, uint8_t axis, bool sub_item) {
  stackshot::HostCommand h = SsRead(c, std::move(payload), axis, sub_item);
  h.action = Action::kWrite;
  return h;
}

std::optional<Action> StatusOf(const SsRecord* rec) {
  if (rec == nullptr) return std::nullopt;
  return static_cast<Action>(rec->packet.action);
}

std::string Show(const SsRecord* rec) {
  if (rec == nullptr) return "no answer";
  if (rec->reply) return stackshot::Describe(*rec->reply);
  return stackshot::Describe(rec->packet) + " (data fits no layout)";
}

SsHost::SsHost(Target& target, Verdicts& verdicts, HostOptions options, ChecksumAlgorithm checksum)
    : HostBase(target, verdicts, std::move(options),
               [this](wire::ByteView bytes) { OnBytes(bytes); }),
      checksum_(checksum),
      decoder_(/*from_device=*/true, ChecksumAlgorithm::kNegatedSum),
      consistent_(std::begin(kAlgorithms), std::end(kAlgorithms)) {}

Evidence SsHost::Ev(const SsRecord& rec, std::string expected, std::string observed) const {
  return Evidence{std::move(expected), std::move(observed), wire::ToHex(rec.raw), rec.t_ns};
}

int SsHost::Record(stackshot::Packet p, wire::Bytes raw) {
  SsRequest r;
  r.sent_ns = Now();
  auto typed = stackshot::DecodeHostPacket(p);
  if (typed) {
    r.cmd = std::move(typed).value();
  } else {
    r.refusal = stackshot::ErrorReplyStatus(typed.error());
  }
  r.packet = std::move(p);
  r.raw = raw;
  requests_.push_back(std::move(r));
  const int index = static_cast<int>(requests_.size() - 1);
  waiting_.push_back(index);
  return index;
}

int SsHost::Send(const stackshot::HostCommand& c) {
  return SendPacket(stackshot::ToPacket(c, checksum_));
}

int SsHost::SendPacket(const stackshot::Packet& p) {
  wire::Bytes bytes;
  stackshot::EncodePacket(p, bytes);
  const int index = Record(p, bytes);
  link_.Write(bytes);  // and reads what the device wrote at once (in-process: the answer)
  return index;
}

int SsHost::SendBytewise(const stackshot::HostCommand& c) {
  const stackshot::Packet p = stackshot::ToPacket(c, checksum_);
  wire::Bytes bytes;
  stackshot::EncodePacket(p, bytes);
  const int index = Record(p, bytes);
  link_.WriteBytewise(bytes);
  return index;
}

void SsHost::SendNoise(wire::ByteView bytes) { link_.Write(bytes); }

void SsHost::OnBytes(wire::ByteView bytes) {
  scratch_.clear();
  decoder_.Feed(bytes, scratch_);
  for (const stackshot::DecodedPacket& d : scratch_) OnPacket(d);
}

void SsHost::OnPacket(const stackshot::DecodedPacket& d) {
  SsRecord rec;
  rec.t_ns = Now();
  rec.packet = d.packet;
  stackshot::EncodePacket(d.packet, rec.raw);
  reported_skipped_ += d.skipped_before;
  verdicts_.Check("SS-PKT-001", d.skipped_before == 0, [&] {
    return Ev(rec, "every byte inside a packet starting 0xAA",
              std::to_string(d.skipped_before) + " byte(s) before this packet outside any packet");
  });
  // The oldest request still waiting is the one this packet answers.
  if (!waiting_.empty()) {
    rec.request = waiting_.front();
    waiting_.pop_front();
  }
  stackshot::ReplyContext context;
  if (rec.request >= 0) {
    const uint8_t a = requests_[static_cast<size_t>(rec.request)].packet.action;
    if (a <= static_cast<uint8_t>(Action::kWrite)) context.request_action = static_cast<Action>(a);
  }
  auto typed = stackshot::DecodeDevicePacket(d.packet, context);
  if (typed) rec.reply = std::move(typed).value();
  const size_t index = records_.size();
  records_.push_back(std::move(rec));
  const SsRecord& r = records_.back();
  CheckChecksum(r);
  const uint8_t status = r.packet.action;
  verdicts_.Check(
      "SS-PKT-003",
      status >= static_cast<uint8_t>(Action::kRspOk) && status < stackshot::kActionMax,
      [&] { return Ev(r, "a response code (2-8) in the low nibble", ActionText(status)); });
  if (const auto* st = PayloadOf<stackshot::RailStatus>(&r);
      st != nullptr && r.packet.command == stackshot::Id(Command::kRailStatus)) {
    verdicts_.Check("SS-STATUS-001", (st->bits & ~0x07u) == 0, [&] {
      return Ev(r, "status bits within 0x07", "status " + base::Hex(st->bits, 2));
    });
  }
  if (r.request < 0) {
    verdicts_.Fail("SS-ANS-002", Ev(r, "no packet without a request waiting for it",
                                    Show(&r) + " with every request answered"));
    return;
  }
  verdicts_.Pass("SS-ANS-002");
  SsRequest& req = requests_[static_cast<size_t>(r.request)];
  req.answer = static_cast<int>(index);
  Answered(KindOf(req.packet));
  CheckReply(req, r);
}

void SsHost::CheckChecksum(const SsRecord& rec) {
  std::set<ChecksumAlgorithm> matching;
  for (ChecksumAlgorithm a : kAlgorithms) {
    if (stackshot::ChecksumMatches(rec.packet, a)) matching.insert(a);
  }
  verdicts_.Check("SS-CSUM-001", matching.count(ChecksumAlgorithm::kNegatedSum) != 0, [&] {
    return Ev(
        rec,
        "checksum " +
            base::Hex(stackshot::ComputeChecksum(ChecksumAlgorithm::kNegatedSum, rec.packet), 2) +
            " (negated sum)",
        "checksum " + base::Hex(rec.packet.checksum, 2));
  });
  std::set<ChecksumAlgorithm> both;
  for (ChecksumAlgorithm a : matching) {
    if (consistent_.count(a) != 0) both.insert(a);
  }
  const bool ok = !both.empty();
  verdicts_.Check("SS-CSUM-002", ok, [&] {
    std::string algos;
    for (ChecksumAlgorithm a : consistent_) {
      algos += (algos.empty() ? "" : " or ") + std::string(stackshot::ChecksumAlgorithmName(a));
    }
    return Ev(rec, "a checksum by " + algos + " as in the packets before",
              "checksum " + base::Hex(rec.packet.checksum, 2));
  });
  // After a mismatch, judge the following packets on their own again.
  consistent_ =
      ok ? both : std::set<ChecksumAlgorithm>(std::begin(kAlgorithms), std::end(kAlgorithms));
}

void SsHost::CheckReply(const SsRequest& req, const SsRecord& rec) {
  const std::string asked =
      req.cmd ? stackshot::Describe(*req.cmd) : stackshot::Describe(req.packet);
  verdicts_.Check("SS-ANS-003", rec.packet.command == req.packet.command, [&] {
    return Ev(rec, "a reply to " + stackshot::CommandName(req.packet.command),
              "a reply with command id " + stackshot::CommandName(rec.packet.command));
  });
  verdicts_.Check("SS-PKT-004",
                  rec.packet.axis == req.packet.axis && rec.packet.sub_item == req.packet.sub_item,
                  [&] {
                    return Ev(rec,
                              "axis " + std::to_string(req.packet.axis) + ", sub-item " +
                                  std::to_string(req.packet.sub_item),
                              "axis " + std::to_string(rec.packet.axis) + ", sub-item " +
                                  std::to_string(rec.packet.sub_item));
                  });
  if (rec.packet.command != req.packet.command) return;

  // Deadlines on the target's clock.
  const TimeNs latency = rec.t_ns - req.sent_ns;
  std::string_view rule = "SS-DL-002", kind = "command";
  if (req.packet.command == stackshot::Id(Command::kSoftwareChecksum)) {
    rule = "SS-DL-003";
    kind = "checksum";
  } else if (req.packet.action == static_cast<uint8_t>(Action::kRead)) {
    rule = "SS-DL-001";
    kind = "query";
  }
  TimeNs deadline = kSsChecksumDeadlineNs;
  if (kind != "checksum") {
    const auto custom = options_.deadline_by_kind_ns.find(kind);
    deadline = custom != options_.deadline_by_kind_ns.end() ? custom->second : options_.deadline_ns;
  }
  verdicts_.Check(rule, latency <= deadline, [&] {
    return Ev(rec, "a reply within " + Ms(deadline) + " (" + std::string(kind) + ")",
              "answered after " + Ms(latency));
  });

  const Action status = static_cast<Action>(rec.packet.action);
  const bool ok = status == Action::kRspOk;
  const bool unknown = req.cmd && std::holds_alternative<stackshot::Unknown>(req.cmd->payload);
  if (req.packet.command == stackshot::Id(Command::kWad)) {
    verdicts_.Check("SS-ERR-004", status == Action::kUnsupportedCmd,
                    [&] { return Ev(rec, "CC_WAD unsupported-cmd", Show(&rec)); });
  }
  if (req.refusal) {
    if (*req.refusal == Action::kUnsupportedAction) {
      verdicts_.Check("SS-ERR-002", status == Action::kUnsupportedAction, [&] {
        return Ev(rec, "unsupported-action for " + asked, ActionText(rec.packet.action));
      });
    } else {
      verdicts_.Check("SS-ERR-003", !ok, [&] {
        return Ev(rec, "a refusal of " + asked + " (its length fits no layout)", Show(&rec));
      });
    }
  } else if (unknown) {
    verdicts_.Check("SS-ERR-001", status == Action::kUnsupportedCmd, [&] {
      return Ev(rec, "unsupported-cmd for an unknown command", ActionText(rec.packet.action));
    });
  }
  if (!ok) {
    verdicts_.Check("SS-LAYOUT-003", rec.packet.data.empty(), [&] {
      return Ev(rec, "an error reply without data",
                std::to_string(rec.packet.data.size()) + " data bytes");
    });
    if (req.refusal || unknown || IsOpaqueCommand(req.packet.command)) return;
    verdicts_.Check(
        "SS-CODE-001", status != Action::kUnsupportedCmd && status != Action::kUnsupportedAction,
        [&] { return Ev(rec, "no unsupported-* for " + asked, ActionText(rec.packet.action)); });
    const bool write = req.cmd->action == Action::kWrite;
    const bool serial_write = write && req.packet.command == stackshot::Id(Command::kSerialNumber);
    verdicts_.Check(
        "SS-CODE-002",
        (status != Action::kBusy || write) && (status != Action::kNotEmpty || serial_write), [&] {
          return Ev(rec, "busy only for a write, not-empty only for the serial number",
                    ActionText(rec.packet.action) + " for " + asked);
        });
    return;
  }
  if (req.refusal || unknown || IsOpaqueCommand(req.packet.command)) return;
  if (req.cmd->action == Action::kRead) {
    const bool layout =
        rec.reply.has_value() && rec.reply->kind == stackshot::ReplyKind::kReadResponse;
    verdicts_.Check("SS-LAYOUT-001", layout, [&] {
      return Ev(rec, "the read-response layout of " + stackshot::CommandName(req.packet.command),
                std::to_string(rec.packet.data.size()) + " data bytes: " + Show(&rec));
    });
    if (!layout) return;
    if (const auto* q = std::get_if<stackshot::UnitsQuery>(&req.cmd->payload); q && q->units) {
      if (const auto* v = PayloadOf<stackshot::UnitsF32>(&rec)) {
        verdicts_.Check("SS-LAYOUT-004", v->units == *q->units, [&] {
          return Ev(rec, std::string("units ") + std::string(stackshot::UnitsName(*q->units)),
                    std::string("units ") + std::string(stackshot::UnitsName(v->units)));
        });
      }
    }
    if (const auto* ping = std::get_if<stackshot::PingRequest>(&req.cmd->payload)) {
      const auto* pong = PayloadOf<stackshot::PingReply>(&rec);
      const stackshot::PingReply want = stackshot::PingAnswer(ping->value);
      verdicts_.Check("SS-PING-001", pong != nullptr && *pong == want, [&] {
        return Ev(rec, "ping reply " + base::Hex(want.value, 2) + " 00", Show(&rec));
      });
    }
  } else {
    verdicts_.Check("SS-LAYOUT-002", rec.packet.data.empty(), [&] {
      return Ev(rec, "a write acknowledgement without data",
                std::to_string(rec.packet.data.size()) + " data bytes");
    });
  }
}

const SsRecord* SsHost::Await(int index) {
  if (index < 0 || static_cast<size_t>(index) >= requests_.size()) return nullptr;
  const size_t i = static_cast<size_t>(index);
  // The kind of a request is its command and action ("CC_RAIL_MOVE WRITE").
  const std::string kind = KindOf(requests_[i].packet);
  const auto fail = [&](std::string observed) {
    SsRequest& req = requests_[i];
    if (req.given_up) return false;
    req.given_up = true;
    waiting_.erase(std::remove(waiting_.begin(), waiting_.end(), index), waiting_.end());
    verdicts_.Fail("SS-ANS-001", Evidence{"a reply to " + stackshot::Describe(req.packet),
                                          std::move(observed), wire::ToHex(req.raw), req.sent_ns});
    return true;
  };
  if (requests_[i].answer < 0 && JudgedWithoutWaiting(kind, fail)) return nullptr;
  const TimeNs give_up = requests_[i].sent_ns + options_.answer_timeout_ns;
  if (!link_.ReadUntil(give_up, [&] { return requests_[i].answer >= 0; })) {
    if (fail(link_.lost() ? "the link closed"
                          : "nothing after " + Ms(options_.answer_timeout_ns))) {
      Unanswered(kind);
    }
    return nullptr;
  }
  verdicts_.Pass("SS-ANS-001");
  return &records_[static_cast<size_t>(requests_[i].answer)];
}

void SsHost::Close() {
  if (closed_) return;
  closed_ = true;
  Idle(options_.quiet_ns);
  if (decoder_.pending_bytes() > 0) {
    verdicts_.Fail("SS-PKT-002",
                   Evidence{"a complete packet",
                            "the device stopped " + std::to_string(decoder_.pending_bytes()) +
                                " byte(s) into a packet",
                            "", Now()});
  } else if (!records_.empty()) {
    verdicts_.Pass("SS-PKT-002");
  }
  // Bytes after the last packet that belong to none.
  const uint64_t stray = decoder_.skipped_total() - reported_skipped_;
  if (stray > 0) {
    verdicts_.Fail("SS-PKT-001", Evidence{"every byte inside a packet starting 0xAA",
                                          std::to_string(stray) +
                                              " byte(s) after the last packet outside any packet",
                                          "", Now()});
  }
}

}  // namespace moco::conformance
