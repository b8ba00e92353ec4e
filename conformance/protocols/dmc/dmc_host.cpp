// The Dragonframe-style DMC v2 host of the conformance runner and its stream
// checks (dmc-v2-protocol.txt "Message Format", "MSG_FLAG_ACK", "MSG_HI",
// "MSG_MOTOR_STATUS", "MSG_MOTOR_GET_POSITION"; ERRATA 1.1-1.6, 1.9).
#include "conformance/protocols/dmc/dmc_host.h"

#include "base/format.h"

#include <algorithm>

namespace moco::conformance {
namespace {

using dmc::AckCode;
using dmc::MsgType;
using dmc::ToWire;

bool HasSpecificResponse(uint16_t type) {
  switch (static_cast<MsgType>(type)) {
    case MsgType::kHi:
    case MsgType::kMotorStatus:
    case MsgType::kMotorMove:
    case MsgType::kMotorGetPosition:
    case MsgType::kGioIn:
    case MsgType::kVirtGetPosition:
    case MsgType::kVirtAimPoint:
      return true;
    default:
      return false;
  }
}

bool IsUnsolicitedKind(uint16_t type) {
  switch (static_cast<MsgType>(type)) {
    case MsgType::kHi:
    case MsgType::kMotorGetPosition:
    case MsgType::kGioIn:
    case MsgType::kMotorHardStop:
    case MsgType::kRtEnd:
    case MsgType::kVirtAimPoint:
      return true;
    default:
      return false;
  }
}

// The codes MSG_FLAG_ACK lists; 0x0019 is the reference firmware's own
// (FACTS DMC v2), noted by DMC-ACK-012 instead.
bool IsKnownCode(uint32_t code) {
  return (code >= 0x0010 && code <= 0x0018) || (code >= 0x0020 && code <= 0x0023);
}
constexpr uint32_t kAimPointFailure = 0x0019;

bool IsMotionRequest(uint16_t type) {
  switch (static_cast<MsgType>(type)) {
    case MsgType::kMotorMove:
    case MsgType::kMotorJog:
    case MsgType::kMotorResetPosition:
    case MsgType::kMotorSetLimits:
    case MsgType::kRtPositionFrame:
    case MsgType::kRtRunMove:
    case MsgType::kRtShootFrame:
    case MsgType::kRtShootFrame2:
    case MsgType::kRtGo:
    case MsgType::kRtJogAll:
    case MsgType::kVirtMove:
    case MsgType::kVirtJog:
    case MsgType::kVirtJogOnLine:
    case MsgType::kVirtAimPoint:
      return true;
    default:
      return false;
  }
}

bool IsRealTimeOrVirtual(uint16_t type) { return type >= 0x0100 && type < 0x0300; }

// The DMC-DL rule and deadline kind of a request type.
std::pair<std::string_view, std::string_view> DeadlineRule(uint16_t type) {
  if (type == ToWire(MsgType::kHi)) return {"DMC-DL-001", "hi"};
  switch (static_cast<MsgType>(type)) {
    case MsgType::kMotorStatus:
    case MsgType::kMotorGetPosition:
    case MsgType::kGioIn:
    case MsgType::kVirtGetPosition:
      return {"DMC-DL-002", "query"};
    default:
      break;
  }
  if (type >= 0x0100 && type <= 0x0104) return {"DMC-DL-004", "upload"};
  if (type >= 0x0110 && type < 0x0200) return {"DMC-DL-005", "rt"};
  return {"DMC-DL-003", "command"};
}

using base::Ms;

}  // namespace

std::optional<uint32_t> AckCodeOf(const DmcRecord* rec) {
  if (const auto* a = As<dmc::Ack>(rec)) return a->code;
  return std::nullopt;
}

std::string Show(const DmcRecord* rec) {
  if (rec == nullptr) return "no answer";
  if (!rec->msg) return dmc::TypeName(rec->type) + " (data fits no layout)";
  return dmc::Describe(*rec->msg);
}

DmcHost::DmcHost(Target& target, Verdicts& verdicts, HostOptions options)
    : HostBase(target, verdicts, std::move(options),
               [this](wire::ByteView bytes) { OnBytes(bytes); }) {}

Evidence DmcHost::Ev(const DmcRecord& rec, std::string expected, std::string observed) const {
  return Evidence{std::move(expected), std::move(observed), wire::ToHex(rec.raw), rec.t_ns};
}

uint32_t DmcHost::SendRaw(uint32_t id, uint16_t type, wire::Bytes bytes, bool bad_checksum) {
  DmcRequest r;
  r.id = id;
  r.type = type;
  r.sent_ns = Now();
  r.raw = bytes;
  r.bad_checksum = bad_checksum;
  if (!bad_checksum) {
    auto f = dmc::DecodeFrame(bytes);
    r.well_formed = f.ok() && dmc::DecodeHostMessage(f.value()).ok();
  }
  requests_.push_back(std::move(r));
  link_.Write(bytes);  // and reads what the device wrote at once (in-process: the answer)
  return id;
}

uint32_t DmcHost::Send(const dmc::HostMessage& m) {
  const uint32_t id = next_id_++;
  return SendRaw(id, dmc::TypeOf(m), dmc::Encode(id, m), false);
}

uint32_t DmcHost::SendFrame(uint16_t type, wire::ByteView data, bool corrupt_checksum) {
  const uint32_t id = next_id_++;
  wire::Bytes bytes;
  dmc::EncodeFrame(id, type, data, bytes);
  if (corrupt_checksum) bytes.back() = static_cast<uint8_t>(bytes.back() ^ 0x5a);
  return SendRaw(id, type, std::move(bytes), corrupt_checksum);
}

void DmcHost::SendNoise(wire::ByteView bytes) { link_.Write(bytes); }

uint32_t DmcHost::SendBytewise(const dmc::HostMessage& m) {
  const uint32_t id = next_id_++;
  const wire::Bytes bytes = dmc::Encode(id, m);
  DmcRequest r;
  r.id = id;
  r.type = dmc::TypeOf(m);
  r.sent_ns = Now();
  r.raw = bytes;
  r.well_formed = true;
  requests_.push_back(std::move(r));
  link_.WriteBytewise(bytes);
  return id;
}

void DmcHost::OnBytes(wire::ByteView bytes) {
  // Byte by byte, so that an event's frame ends at the byte just fed and the
  // bytes of a bad frame can be quoted from the history.
  for (uint8_t b : bytes) {
    history_.push_back(b);
    decoder_.Feed(wire::ByteView(&b, 1), [&](const dmc::FrameEvent& e) {
      if (const auto* f = std::get_if<dmc::FrameRef>(&e)) {
        OnFrame(*f);
      } else if (const auto* c = std::get_if<dmc::ChecksumError>(&e)) {
        for (DmcRequest& r : requests_) {
          if (r.id == c->id && r.answer < 0) r.garbled_answer = true;
        }
        const size_t n = std::min(history_.size(), dmc::kHeaderSize + c->length + dmc::kCheckSize);
        const wire::ByteView raw(history_.data() + history_.size() - n, n);
        verdicts_.Fail("DMC-CSUM-001", Evidence{"Fletcher-16 over the frame = 0",
                                                "checksum not zero in " + dmc::TypeName(c->type) +
                                                    " id=" + std::to_string(c->id),
                                                wire::ToHex(raw), Now()});
      } else if (const auto* fe = std::get_if<dmc::FramingError>(&e)) {
        if (fe->kind == dmc::FramingError::Kind::kSkipped) {
          skipped_bytes_ += fe->bytes;
          const size_t n = std::min(history_.size(), fe->bytes + 1);
          verdicts_.Fail(
              "DMC-FRAME-001",
              Evidence{"every byte inside a frame starting 'D' 'F'",
                       std::to_string(fe->bytes) + " byte(s) outside any frame",
                       wire::ToHex(wire::ByteView(history_.data() + history_.size() - n, n)),
                       Now()});
        } else if (fe->kind == dmc::FramingError::Kind::kOversize) {
          verdicts_.Fail(
              "DMC-FRAME-002",
              Evidence{"Length <= 1036", "Length " + std::to_string(fe->length), "", Now()});
        } else {
          verdicts_.Fail("DMC-FRAME-003", Evidence{"a complete frame",
                                                   "stream ended " + std::to_string(fe->bytes) +
                                                       " byte(s) into a frame of Length " +
                                                       std::to_string(fe->length),
                                                   "", Now()});
        }
      }
    });
  }
  if (history_.size() > 16384) history_.erase(history_.begin(), history_.end() - 4096);
}

void DmcHost::OnFrame(const dmc::FrameRef& f) {
  verdicts_.Pass("DMC-CSUM-001");
  DmcRecord rec;
  rec.t_ns = Now();
  rec.id = f.id;
  rec.type = f.type;
  rec.raw.assign(f.raw.begin(), f.raw.end());
  auto decoded = dmc::DecodeDeviceMessage(f.type, f.data);
  if (decoded.ok()) rec.msg = decoded.value();
  verdicts_.Check("DMC-FRAME-004", dmc::HasReferenceParserType(f.type),
                  [&] { return Ev(rec, "Type within 0x83FF", "Type " + base::Hex(f.type, 4)); });
  verdicts_.Check("DMC-FRAME-005", decoded.ok(), [&] {
    return Ev(rec, "data fitting the layout of " + dmc::TypeName(f.type),
              wire::Describe(decoded.error()));
  });

  // Which request does it answer?
  int req_index = -1;
  for (size_t i = requests_.size(); i-- > 0;) {
    if (requests_[i].id == f.id) {
      req_index = static_cast<int>(i);
      break;
    }
  }
  const size_t rec_index = records_.size();
  if (req_index >= 0) rec.request = req_index;
  records_.push_back(std::move(rec));
  const DmcRecord& r = records_.back();
  if (const auto* hi = As<dmc::HiResponse>(&r)) {
    previous_hi_ = hi_;
    hi_ = *hi;
  }

  if (req_index >= 0) {
    DmcRequest& req = requests_[static_cast<size_t>(req_index)];
    verdicts_.Pass("DMC-ACK-003");
    ++req.answers;
    if (verdicts_.Check("DMC-ACK-002", req.answers == 1, [&] {
          return Ev(r, "one answer to " + dmc::TypeName(req.type) + " id=" + std::to_string(req.id),
                    "answer number " + std::to_string(req.answers));
        })) {
      req.answer = static_cast<int>(rec_index);
      Answered(dmc::TypeName(req.type));
      CheckAnswer(req, r);
    }
    return;
  }
  const bool ack_flag = (f.type & dmc::kFlagAck) != 0;
  if (ack_flag && acked_ids_.count(f.id) != 0) {
    verdicts_.Fail("DMC-UNS-004", Ev(r, "no answer to the host's ACK of an unsolicited message",
                                     dmc::TypeName(f.type) + " id=" + std::to_string(f.id)));
    return;
  }
  if (ack_flag || !IsUnsolicitedKind(f.type)) {
    // An answer under a wrong ID: the oldest request still waiting for an
    // answer of this Type takes it. The wrong echo fails DMC-ACK-003, and the
    // case goes on at the device's pace instead of waiting out the answer
    // timeout of every request (a device that echoes IDs wrongly would
    // otherwise take minutes to judge, and fail every rule behind an answer).
    // An ERR_CHECKSUM carries the ID and Type as received, which may be the
    // corrupted bytes themselves ("The response should use the message Type
    // and ID from the received message"): it answers no request but the
    // corrupted one, so it is never taken by Type.
    const uint16_t plain = static_cast<uint16_t>(f.type & ~dmc::kFlagAck);
    const std::optional<uint32_t> code = AckCodeOf(&r);
    const bool checksum_error = code && *code == ToWire(AckCode::kErrChecksum);
    int waiting = -1;
    for (size_t i = 0; i < requests_.size() && waiting < 0 && !checksum_error; ++i) {
      if (requests_[i].answers == 0 && requests_[i].type == plain) waiting = static_cast<int>(i);
    }
    if (waiting >= 0) {
      DmcRequest& req = requests_[static_cast<size_t>(waiting)];
      verdicts_.Fail("DMC-ACK-003", Ev(r,
                                       "the answer to " + dmc::TypeName(req.type) +
                                           " id=" + std::to_string(req.id) + " carrying that ID",
                                       dmc::TypeName(f.type) + " with id=" + std::to_string(f.id)));
      records_.back().request = waiting;
      ++req.answers;
      req.answer = static_cast<int>(rec_index);
      Answered(dmc::TypeName(req.type));
      CheckAnswer(req, r);
      return;
    }
    verdicts_.Fail("DMC-ACK-003", Ev(r, "an answer carrying the ID of a request sent",
                                     dmc::TypeName(f.type) + " with id=" + std::to_string(f.id) +
                                         ", which no request had"));
    verdicts_.Fail("DMC-UNS-001", Ev(r, "unsolicited frames of the listed kinds only",
                                     dmc::TypeName(f.type) + " id=" + std::to_string(f.id)));
    return;
  }
  verdicts_.Pass("DMC-UNS-001");
  CheckUnsolicited(r);
  if (ack_unsolicited_) {
    wire::Bytes ack = dmc::Encode(f.id, dmc::DeviceMessage{dmc::Ack{f.type, ToWire(AckCode::kOk)}});
    acked_ids_.insert(f.id);
    link_.WriteWithoutReading(ack);
  }
}

void DmcHost::CheckAnswer(DmcRequest& req, const DmcRecord& rec) {
  const uint16_t plain = static_cast<uint16_t>(rec.type & ~dmc::kFlagAck);
  const bool is_ack = (rec.type & dmc::kFlagAck) != 0;
  verdicts_.Check("DMC-ACK-004", plain == req.type, [&] {
    return Ev(
        rec,
        dmc::TypeName(req.type) + " or its ACK (" + base::Hex(req.type | dmc::kFlagAck, 4) + ")",
        dmc::TypeName(rec.type));
  });
  if (plain != req.type) return;
  const TimeNs latency = rec.t_ns - req.sent_ns;
  // (Named copies, not a structured binding: the lambda below captures them.)
  const auto rule_and_kind = DeadlineRule(req.type);
  const auto rule = rule_and_kind.first;
  const auto kind = rule_and_kind.second;
  const auto custom = options_.deadline_by_kind_ns.find(kind);
  const TimeNs deadline =
      custom != options_.deadline_by_kind_ns.end() ? custom->second : options_.deadline_ns;
  verdicts_.Check(rule, latency <= deadline, [&] {
    return Ev(rec, "an answer within " + Ms(deadline) + " (" + std::string(kind) + ")",
              "answered after " + Ms(latency));
  });
  if (is_ack) {
    const size_t len = rec.raw.size() - dmc::kHeaderSize - dmc::kCheckSize;
    verdicts_.Check("DMC-ACK-005", len == 2 || len == 4, [&] {
      return Ev(rec, "a 2-byte response code", std::to_string(len) + " data bytes");
    });
    verdicts_.Check("DMC-ACK-006", len != 4, [&] { return Ev(rec, "16-bit code", "32-bit code"); });
    const std::optional<uint32_t> code = AckCodeOf(&rec);
    if (!code) return;
    verdicts_.Check("DMC-ACK-012", *code != kAimPointFailure,
                    [&] { return Ev(rec, "a listed response code", base::Hex(*code, 4)); });
    if (*code != kAimPointFailure) {
      verdicts_.Check("DMC-ACK-007", IsKnownCode(*code),
                      [&] { return Ev(rec, "a listed response code", base::Hex(*code, 4)); });
    }
    if (HasSpecificResponse(req.type)) {
      verdicts_.Check("DMC-ACK-008", *code != ToWire(AckCode::kOk), [&] {
        return Ev(rec, "the specific " + dmc::TypeName(req.type) + " response", "ACK OK");
      });
      if (req.type == ToWire(MsgType::kHi) && req.well_formed) {
        verdicts_.Fail("DMC-HI-001", Ev(rec, "HI response", Show(&rec)));
      }
      // The message's own layout clause is broken too by an ACK OK in its place.
      if (req.type == ToWire(MsgType::kMotorMove) && *code == ToWire(AckCode::kOk)) {
        verdicts_.Fail("DMC-MOVE-001", Ev(rec, "the 1-byte MOTOR_MOVE response", "ACK OK"));
      }
      // GIO_IN refused by a device that advertises inputs: the request it
      // must answer ("Dragonframe may request the input state").
      if (req.type == ToWire(MsgType::kGioIn) && req.well_formed && hi_ && hi_->gio_in_count >= 1) {
        verdicts_.Fail("DMC-GIO-001", Ev(rec,
                                         "a 4-byte GIO_IN response (the device advertises " +
                                             std::to_string(hi_->gio_in_count) + " input(s))",
                                         "ACK " + dmc::AckCodeName(*code)));
      }
    }
    if (!req.bad_checksum) {
      verdicts_.Check("DMC-CSUM-004", *code != ToWire(AckCode::kErrChecksum), [&] {
        return Ev(rec, "no ERR_CHECKSUM for a frame whose checksum is zero", "ACK ERR_CHECKSUM");
      });
    }
    bool fits = true;
    const bool limit = *code >= 0x0020 && *code <= 0x0023;
    const bool rt = *code >= 0x0016 && *code <= 0x0019;
    if (limit && !IsMotionRequest(req.type)) fits = false;
    if (rt && !IsRealTimeOrVirtual(req.type)) fits = false;
    verdicts_.Check("DMC-ACK-010", fits, [&] {
      return Ev(rec, "a code that fits " + dmc::TypeName(req.type), dmc::AckCodeName(*code));
    });
    return;
  }
  // A plain Type: the specific response.
  if (!HasSpecificResponse(req.type)) {
    verdicts_.Fail("DMC-ACK-009", Ev(rec, "ACK " + dmc::TypeName(req.type),
                                     dmc::TypeName(rec.type) + " without the ACK flag"));
    return;
  }
  verdicts_.Pass("DMC-ACK-009");
  CheckSpecific(req, rec);
}

void DmcHost::CheckSpecific(const DmcRequest& req, const DmcRecord& rec) {
  const size_t len = rec.raw.size() - dmc::kHeaderSize - dmc::kCheckSize;
  switch (static_cast<MsgType>(req.type)) {
    case MsgType::kHi:
      verdicts_.Pass("DMC-HI-001");
      if (const auto* hi = As<dmc::HiResponse>(&rec)) {
        CheckHi(rec, *hi);
      } else {
        verdicts_.Fail("DMC-HI-002", Ev(rec, "51 data bytes", std::to_string(len) + " data bytes"));
      }
      break;
    case MsgType::kMotorStatus: {
      const auto* st = As<dmc::MotorStatusResponse>(&rec);
      verdicts_.Check("DMC-STAT-001", st != nullptr && len == 5,
                      [&] { return Ev(rec, "5 data bytes", std::to_string(len) + " data bytes"); });
      if (st == nullptr) break;
      if (hi_) {
        const uint32_t allowed =
            hi_->motor_count >= 32 ? 0xffffffffu : ((1u << hi_->motor_count) - 1u);
        verdicts_.Check("DMC-STAT-002", (st->moving_bits & ~allowed) == 0, [&] {
          return Ev(rec, "bits only for motors 1-" + std::to_string(hi_->motor_count),
                    "moving bits " + base::Hex(st->moving_bits, 4));
        });
      }
      verdicts_.Check("DMC-STAT-003", st->dmx_adjusting <= 1, [&] {
        return Ev(rec, "DMX STATUS 0 or 1", std::to_string(st->dmx_adjusting));
      });
      break;
    }
    case MsgType::kMotorMove: {
      const auto* mv = As<dmc::MotorMoveResponse>(&rec);
      verdicts_.Check("DMC-MOVE-001", mv != nullptr && len == 1 && mv->moving <= 1, [&] {
        return Ev(rec, "1 data byte, 0 or 1", std::to_string(len) + " data bytes");
      });
      break;
    }
    case MsgType::kMotorGetPosition:
      CheckUnsolicited(rec);  // same layout as the update
      break;
    case MsgType::kGioIn:
      CheckGioIn(rec);
      break;
    case MsgType::kVirtGetPosition:
      verdicts_.Check("DMC-VIRT-001", len == 24 || len == 37, [&] {
        return Ev(rec, "24 or 37 data bytes", std::to_string(len) + " data bytes");
      });
      break;
    default:
      break;
  }
}

// MSG_GIO_IN, answered or sent on an input change (ERRATA 1.6: the same
// layout both ways): TRIGGERS is a DWORD with bits only for the inputs the
// device advertises.
void DmcHost::CheckGioIn(const DmcRecord& rec) {
  const size_t len = rec.raw.size() - dmc::kHeaderSize - dmc::kCheckSize;
  const auto* g = As<dmc::GioInReport>(&rec);
  verdicts_.Check("DMC-GIO-001", g != nullptr && len == 4,
                  [&] { return Ev(rec, "4 data bytes", std::to_string(len) + " data bytes"); });
  if (g != nullptr && hi_ && hi_->gio_in_count >= 1) {
    const uint32_t allowed =
        hi_->gio_in_count >= 32 ? 0xffffffffu : ((1u << hi_->gio_in_count) - 1u);
    verdicts_.Check("DMC-GIO-002", (g->triggers & ~allowed) == 0, [&] {
      return Ev(rec, "bits only for inputs 1-" + std::to_string(hi_->gio_in_count),
                base::Hex(g->triggers, 4));
    });
  }
}

void DmcHost::CheckUnsolicited(const DmcRecord& rec) {
  const size_t len = rec.raw.size() - dmc::kHeaderSize - dmc::kCheckSize;
  if (const auto* hi = As<dmc::HiResponse>(&rec)) {
    CheckHi(rec, *hi);
  } else if (rec.type == ToWire(MsgType::kMotorGetPosition)) {
    if (hi_) {
      const size_t want = 4 + 4 * static_cast<size_t>(hi_->motor_count);
      verdicts_.Check("DMC-POS-001", len == want, [&] {
        return Ev(rec,
                  std::to_string(want) + " data bytes (MOVE TIME + " +
                      std::to_string(hi_->motor_count) + " positions)",
                  std::to_string(len) + " data bytes");
      });
    }
  } else if (rec.type == ToWire(MsgType::kMotorHardStop)) {
    const auto* hs = As<dmc::MotorHardStop>(&rec);
    bool ok = hs != nullptr;
    if (ok) {
      const bool known = hs->reason <= 2 || hs->reason == 100;
      ok = known && (dmc::HardStopHasMotor(hs->reason) == hs->motor.has_value());
    }
    verdicts_.Check("DMC-UNS-003", ok, [&] {
      return Ev(rec, "REASON 0/1/2/100, MOTOR with 1 or 2 only", Show(&rec));
    });
  } else if (rec.type == ToWire(MsgType::kGioIn)) {
    CheckGioIn(rec);
  } else if (rec.type == ToWire(MsgType::kRtEnd)) {
    verdicts_.Check("DMC-RT-006", len == 0, [&] {
      return Ev(rec, "RT_END without data", std::to_string(len) + " data bytes");
    });
  }
}

void DmcHost::CheckHi(const DmcRecord& rec, const dmc::HiResponse& hi) {
  const size_t len = rec.raw.size() - dmc::kHeaderSize - dmc::kCheckSize;
  verdicts_.Check("DMC-HI-002", len == 51 || len == 49,
                  [&] { return Ev(rec, "51 data bytes", std::to_string(len) + " data bytes"); });
  verdicts_.Check("DMC-HI-003", len != 49,
                  [&] { return Ev(rec, "51 data bytes", "49 data bytes"); });
  auto range = [&](std::string_view id, const char* field, uint32_t v, uint32_t max) {
    verdicts_.Check(id, v <= max, [&] {
      return Ev(rec, std::string(field) + " 0-" + std::to_string(max),
                std::string(field) + " " + std::to_string(v));
    });
  };
  range("DMC-HI-004", "MOTOR COUNT", hi.motor_count, 32);
  range("DMC-HI-005", "DMX COUNT", hi.dmx_count, 512);
  range("DMC-HI-006", "GIO OUT COUNT", hi.gio_out_count, 32);
  range("DMC-HI-007", "GIO INPUT COUNT", hi.gio_in_count, 32);
  range("DMC-HI-008", "HW LIMIT COUNT", hi.hw_limit_count, 32);
  if (hi.protocol_version) {
    verdicts_.Check("DMC-HI-009", *hi.protocol_version == 2, [&] {
      return Ev(rec, "PROTOCOL VERSION 2", std::to_string(*hi.protocol_version));
    });
  } else {
    verdicts_.NotExercised("DMC-HI-009",
                           "the HI response ends without PROTOCOL VERSION (49 bytes, DMC-HI-003)");
  }
  size_t end = 0;
  while (end < hi.name.size() && hi.name[end] != 0) ++end;
  bool filled = true;
  for (size_t i = end; i < hi.name.size(); ++i) filled = filled && hi.name[i] == 0;
  bool utf8 = true;
  for (size_t i = 0; i < end;) {
    const uint8_t c = hi.name[i];
    size_t n = c < 0x80 ? 1 : (c >> 5) == 0x6 ? 2 : (c >> 4) == 0xe ? 3 : (c >> 3) == 0x1e ? 4 : 0;
    if (n == 0 || i + n > end) {
      utf8 = false;
      break;
    }
    for (size_t k = 1; k < n; ++k) utf8 = utf8 && (hi.name[i + k] >> 6) == 0x2;
    i += n;
  }
  verdicts_.Check("DMC-HI-010", filled && utf8, [&] {
    return Ev(rec, "UTF-8 name, \\0 to the end of the 32 bytes",
              !utf8 ? "not UTF-8" : "bytes after the first \\0 are not \\0");
  });
  verdicts_.Check("DMC-HI-013", (hi.capabilities & ~0x07ffu) == 0, [&] {
    return Ev(rec, "capabilities within 0x07FF", base::Hex(hi.capabilities, 4));
  });
  if ((hi.capabilities & dmc::kCapRealTime) != 0) {
    verdicts_.Check("DMC-HI-014", hi.upload_frame_count > 0,
                    [&] { return Ev(rec, "UPLOAD FRAME COUNT > 0", "0"); });
  }
  const uint32_t needs_rt =
      dmc::kCapGoMotion | dmc::kCapGoMotion2 | dmc::kCapRtLooping | dmc::kCapRtCameraTrigger;
  verdicts_.Check(
      "DMC-HI-015", (hi.capabilities & needs_rt) == 0 || (hi.capabilities & dmc::kCapRealTime) != 0,
      [&] {
        return Ev(rec, "real-time (0x0001) with " + base::Hex(hi.capabilities & needs_rt, 4),
                  "capabilities " + base::Hex(hi.capabilities, 4));
      });
  // Against the HI before this one (hi_ is this one already).
  if (previous_hi_ && rec.request >= 0) {
    dmc::HiResponse a = *previous_hi_, b = hi;
    verdicts_.Check("DMC-HI-012", a == b,
                    [&] { return Ev(rec, "the same HI as before", Show(&rec)); });
  }
}

const DmcRecord* DmcHost::Await(uint32_t id, std::optional<TimeNs> timeout_ns) {
  int index = -1;
  for (size_t i = requests_.size(); i-- > 0;) {
    if (requests_[i].id == id) {
      index = static_cast<int>(i);
      break;
    }
  }
  if (index < 0) return nullptr;
  const auto at = static_cast<size_t>(index);
  const std::string kind = dmc::TypeName(requests_[at].type);
  const TimeNs timeout = timeout_ns.value_or(options_.answer_timeout_ns);
  // The host's first HI has a rule of its own (a device that misses it is
  // asked again, as Dragonframe does after its timeout).
  const auto unanswered_rule = [&] {
    bool first_hi = requests_[at].type == dmc::ToWire(dmc::MsgType::kHi);
    for (size_t i = 0; first_hi && i < at; ++i) {
      first_hi = requests_[i].type != dmc::ToWire(dmc::MsgType::kHi);
    }
    return first_hi ? "DMC-HI-016" : "DMC-ACK-001";
  };
  const auto fail = [&](std::string observed) {
    const DmcRequest& req = requests_[at];
    verdicts_.Fail(unanswered_rule(),
                   Evidence{"an answer to " + dmc::TypeName(req.type) + " id=" + std::to_string(id),
                            std::move(observed), wire::ToHex(req.raw), req.sent_ns});
  };
  if (requests_[at].answer < 0 && JudgedWithoutWaiting(kind, fail)) return nullptr;
  // An answer that came with a bad checksum is as good as none: when the host
  // gives up on unanswered requests, it does not wait out the timeout for it.
  const bool stop_at_garbled = gives_up();
  if (!link_.ReadUntil(requests_[at].sent_ns + timeout,
                       [&] {
                         return requests_[at].answer >= 0 ||
                                (stop_at_garbled && requests_[at].garbled_answer);
                       }) ||
      requests_[at].answer < 0) {
    fail(link_.lost()                   ? "the link closed"
         : requests_[at].garbled_answer ? "only a frame with this ID whose checksum failed"
                                        : "nothing after " + Ms(timeout));
    Unanswered(kind);
    return nullptr;
  }
  verdicts_.Pass("DMC-ACK-001");
  if (requests_[at].type == dmc::ToWire(dmc::MsgType::kHi)) verdicts_.Pass("DMC-HI-016");
  return &records_[static_cast<size_t>(requests_[at].answer)];
}

int DmcHost::WaitFor(size_t from, TimeNs timeout_ns,
                     const std::function<bool(const DmcRecord&)>& pred) {
  return link_.WaitFor(records_, from, timeout_ns, pred);
}

void DmcHost::Close() {
  if (closed_) return;
  closed_ = true;
  Idle(options_.quiet_ns);
  decoder_.Finish([&](const dmc::FrameEvent& e) {
    if (const auto* fe = std::get_if<dmc::FramingError>(&e)) {
      if (fe->kind == dmc::FramingError::Kind::kTruncated) {
        verdicts_.Fail("DMC-FRAME-003",
                       Evidence{"a complete frame",
                                "the device stopped " + std::to_string(fe->bytes) +
                                    " byte(s) into a frame of Length " + std::to_string(fe->length),
                                "", Now()});
      } else if (fe->kind == dmc::FramingError::Kind::kSkipped) {
        verdicts_.Fail(
            "DMC-FRAME-001",
            Evidence{"every byte inside a frame",
                     std::to_string(fe->bytes) + " byte(s) outside any frame", "", Now()});
      }
    }
  });
  if (!acked_ids_.empty()) verdicts_.Pass("DMC-UNS-004");
  if (!records_.empty()) {
    verdicts_.Pass("DMC-FRAME-001");
    verdicts_.Pass("DMC-FRAME-002");
    verdicts_.Pass("DMC-FRAME-003");
  }
}

}  // namespace moco::conformance
