// DMC v2 framing and the names of the wire constants (dmc-v2-protocol.txt
// "Message Format", "Message Types", "Computing and Validating the Checksum").
#include "wire/dmc_frame.h"

#include <algorithm>
#include <cstring>

#include "base/format.h"

namespace moco::dmc {
namespace {

using base::Hex;

const char* PlainTypeName(uint16_t type) {
  switch (static_cast<MsgType>(type)) {
    case MsgType::kHi:
      return "HI";
    case MsgType::kDmx:
      return "DMX";
    case MsgType::kGioOut:
      return "GIO_OUT";
    case MsgType::kGioIn:
      return "GIO_IN";
    case MsgType::kGioCam:
      return "GIO_CAM";
    case MsgType::kMotorStatus:
      return "MOTOR_STATUS";
    case MsgType::kMotorMove:
      return "MOTOR_MOVE";
    case MsgType::kMotorStop:
      return "MOTOR_STOP";
    case MsgType::kMotorStopAll:
      return "MOTOR_STOP_ALL";
    case MsgType::kMotorGetPosition:
      return "MOTOR_GET_POSITION";
    case MsgType::kMotorResetPosition:
      return "MOTOR_RESET_POSITION";
    case MsgType::kMotorJog:
      return "MOTOR_JOG";
    case MsgType::kMotorConfigure:
      return "MOTOR_CONFIGURE";
    case MsgType::kMotorSetSpeed:
      return "MOTOR_SET_SPEED";
    case MsgType::kMotorSetLimits:
      return "MOTOR_SET_LIMITS";
    case MsgType::kMotorHardStop:
      return "MOTOR_HARD_STOP";
    case MsgType::kRtUploadMoveBegin:
      return "RT_UPLOAD_MOVE_BEGIN";
    case MsgType::kRtUploadMoveAxis:
      return "RT_UPLOAD_MOVE_AXIS";
    case MsgType::kRtUploadMoveDmx:
      return "RT_UPLOAD_MOVE_DMX";
    case MsgType::kRtUploadMoveEnd:
      return "RT_UPLOAD_MOVE_END";
    case MsgType::kRtUploadMoveTriggers:
      return "RT_UPLOAD_MOVE_TRIGGERS";
    case MsgType::kRtPositionFrame:
      return "RT_POSITION_FRAME";
    case MsgType::kRtRunMove:
      return "RT_RUN_MOVE";
    case MsgType::kRtShootFrame:
      return "RT_SHOOT_FRAME";
    case MsgType::kRtGo:
      return "RT_GO";
    case MsgType::kRtEnd:
      return "RT_END";
    case MsgType::kRtShootFrame2:
      return "RT_SHOOT_FRAME2";
    case MsgType::kRtStopLoop:
      return "RT_STOP_LOOP";
    case MsgType::kRtJogAll:
      return "RT_JOG_ALL";
    case MsgType::kVirtConfig:
      return "VIRT_CONFIG";
    case MsgType::kVirtMove:
      return "VIRT_MOVE";
    case MsgType::kVirtStop:
      return "VIRT_STOP";
    case MsgType::kVirtJog:
      return "VIRT_JOG";
    case MsgType::kVirtGetPosition:
      return "VIRT_GET_POSITION";
    case MsgType::kVirtJogOnLine:
      return "VIRT_JOG_ON_LINE";
    case MsgType::kVirtAimPoint:
      return "VIRT_AIM_POINT";
  }
  return nullptr;
}

}  // namespace

bool IsKnownType(uint16_t type) { return PlainTypeName(type) != nullptr; }

std::string TypeName(uint16_t type) {
  const bool ack = (type & kFlagAck) != 0;
  const uint16_t plain = static_cast<uint16_t>(type & ~kFlagAck);
  const char* name = PlainTypeName(plain);
  std::string s = ack ? "ACK " : "";
  s += name != nullptr ? std::string(name) : Hex(plain, 4);
  return s;
}

std::string AckCodeName(uint32_t code) {
  switch (code) {
    case ToWire(AckCode::kOk):
      return "OK";
    case ToWire(AckCode::kErrChecksum):
      return "ERR_CHECKSUM";
    case ToWire(AckCode::kErrMoving):
      return "ERR_MOVING";
    case ToWire(AckCode::kErrUnsupported):
      return "ERR_UNSUPPORTED";
    case ToWire(AckCode::kErrRange):
      return "ERR_RANGE";
    case ToWire(AckCode::kErrGeneral):
      return "ERR_GENERAL";
    case ToWire(AckCode::kErrNotInPosition):
      return "ERR_NOT_IN_POSITION";
    case ToWire(AckCode::kErrPreroll):
      return "ERR_PREROLL";
    case ToWire(AckCode::kErrPostroll):
      return "ERR_POSTROLL";
    case ToWire(AckCode::kErrAimPoint):
      return "ERR_AIM_POINT";
    case ToWire(AckCode::kErrSoftUp):
      return "ERR_SOFT_UP";
    case ToWire(AckCode::kErrSoftLow):
      return "ERR_SOFT_LOW";
    case ToWire(AckCode::kErrHardUp):
      return "ERR_HARD_UP";
    case ToWire(AckCode::kErrHardLow):
      return "ERR_HARD_LOW";
    default:
      break;
  }
  return Hex(code, code > 0xffff ? 8 : 4);
}

std::string HardStopReasonName(uint8_t reason) {
  switch (static_cast<HardStopReason>(reason)) {
    case HardStopReason::kEStop:
      return "E_STOP";
    case HardStopReason::kUpperLimit:
      return "UPPER_LIMIT";
    case HardStopReason::kLowerLimit:
      return "LOWER_LIMIT";
    case HardStopReason::kEngineException:
      return "ENGINE_EXCEPTION";
  }
  return std::to_string(reason);
}

uint16_t Fletcher16(ByteView bytes) {
  // 32-bit sums hold the same values as the spec's alt_u16 ones: within a
  // block of 20 they stay below 58885, so no reduction differs.
  uint32_t sum1 = 0;
  uint32_t sum2 = 0;
  const uint8_t* data = bytes.data();
  size_t left = bytes.size();
  while (left != 0) {
    size_t tlen = left >= kFletcherBlock ? kFletcherBlock : left;
    left -= tlen;
    do {
      sum1 += *data++;
      sum2 += sum1;
    } while (--tlen != 0);
    sum1 %= kFletcherModulus;
    sum2 %= kFletcherModulus;
  }
  return static_cast<uint16_t>((sum2 << 8) | sum1);
}

std::array<uint8_t, 2> CheckBytes(uint16_t sum) {
  const unsigned f0 = sum & 0xffu;
  const unsigned f1 = (sum >> 8) & 0xffu;
  const unsigned c0 = 0xffu - ((f0 + f1) % 0xffu);
  const unsigned c1 = 0xffu - ((f0 + c0) % 0xffu);
  return {static_cast<uint8_t>(c0), static_cast<uint8_t>(c1)};
}

size_t BeginFrame(uint32_t id, uint16_t type, Bytes& out) {
  const size_t start = out.size();
  wire::Writer w(out);
  w.U8(kMarker0);
  w.U8(kMarker1);
  w.U32Le(id);
  w.U16Le(type);
  w.U16Le(0);  // Length, filled in by EndFrame
  return start;
}

void EndFrame(size_t start, Bytes& out) {
  const size_t length = std::min<size_t>(out.size() - start - kHeaderSize, 0xffff);
  out.resize(start + kHeaderSize + length);
  uint8_t* p = out.data() + start;
  p[8] = static_cast<uint8_t>(length);
  p[9] = static_cast<uint8_t>(length >> 8);
  const auto check = CheckBytes(Fletcher16(ByteView(p, kHeaderSize + length)));
  out.push_back(check[0]);
  out.push_back(check[1]);
}

void EncodeFrame(uint32_t id, uint16_t type, ByteView data, Bytes& out) {
  const size_t start = BeginFrame(id, type, out);
  out.insert(out.end(), data.begin(), data.begin() + std::min<size_t>(data.size(), 0xffff));
  EndFrame(start, out);
}

Bytes EncodeFrame(const Frame& f) {
  Bytes out;
  out.reserve(kHeaderSize + f.data.size() + kCheckSize);
  EncodeFrame(f, out);
  return out;
}

namespace {

uint32_t LoadU32(const uint8_t* p) {
  return static_cast<uint32_t>(p[0]) | (static_cast<uint32_t>(p[1]) << 8) |
         (static_cast<uint32_t>(p[2]) << 16) | (static_cast<uint32_t>(p[3]) << 24);
}
uint16_t LoadU16(const uint8_t* p) { return static_cast<uint16_t>(p[0] | (p[1] << 8)); }

}  // namespace

std::optional<FrameHeader> PeekHeader(ByteView b) {
  if (b.size() < kHeaderSize || b[0] != kMarker0 || b[1] != kMarker1) return std::nullopt;
  FrameHeader h;
  h.id = static_cast<uint32_t>(b[kIdOffset]) | (static_cast<uint32_t>(b[kIdOffset + 1]) << 8) |
         (static_cast<uint32_t>(b[kIdOffset + 2]) << 16) |
         (static_cast<uint32_t>(b[kIdOffset + 3]) << 24);
  h.type = static_cast<uint16_t>(b[kTypeOffset] | (b[kTypeOffset + 1] << 8));
  h.length = static_cast<uint16_t>(b[kLengthOffset] | (b[kLengthOffset + 1] << 8));
  return h;
}

size_t WholeFrameAt(ByteView b) {
  const auto h = PeekHeader(b);
  if (!h || h->length > kMaxDataLength) return 0;
  const size_t total = kHeaderSize + h->length + kCheckSize;
  return total <= b.size() ? total : 0;
}

Result<Frame> DecodeFrame(ByteView bytes) {
  using Kind = DecodeError::Kind;
  if (bytes.size() < kHeaderSize + kCheckSize) {
    return DecodeError{
        Kind::kTruncated, bytes.size(),
        "truncated: a frame has at least 12 bytes, got " + std::to_string(bytes.size())};
  }
  if (bytes[0] != kMarker0 || bytes[1] != kMarker1) {
    return DecodeError{Kind::kBadValue, 0, "marker is not 'D' 'F'"};
  }
  const uint16_t length = LoadU16(bytes.data() + kLengthOffset);
  if (length > kMaxDataLength) {
    return DecodeError{Kind::kBadLength, kLengthOffset,
                       "length " + std::to_string(length) + " exceeds 1036"};
  }
  const size_t total = kHeaderSize + length + kCheckSize;
  if (bytes.size() < total) {
    return DecodeError{Kind::kTruncated, bytes.size(),
                       "truncated: length " + std::to_string(length) + " needs " +
                           std::to_string(total) + " bytes"};
  }
  if (bytes.size() > total) {
    return DecodeError{Kind::kTrailing, total,
                       std::to_string(bytes.size() - total) + " byte(s) after the check bytes"};
  }
  if (!ChecksumIsZero(bytes)) {
    return DecodeError{Kind::kBadChecksum, kHeaderSize + length, "checksum is not zero"};
  }
  return Frame{LoadU32(bytes.data() + kIdOffset), LoadU16(bytes.data() + kTypeOffset),
               Bytes(bytes.begin() + kHeaderSize, bytes.begin() + kHeaderSize + length)};
}

StreamEvent ToStreamEvent(const FrameEvent& e) {
  if (const auto* f = std::get_if<FrameRef>(&e)) return f->ToFrame();
  if (const auto* c = std::get_if<ChecksumError>(&e)) return *c;
  return std::get<FramingError>(e);
}

FrameDecoder::FrameDecoder(FrameDecoderOptions options)
    : max_data_length_(
          std::clamp(options.max_frame_bytes, kHeaderSize + kCheckSize, kLargestReceiveBuffer) -
          kHeaderSize - kCheckSize),
      rescan_(options.rescan_rejected) {}

void FrameDecoder::Emit(const FrameEvent& e, Sink sink, void* ctx) {
  if (skipped_ != 0) {
    FramingError skipped;
    skipped.kind = FramingError::Kind::kSkipped;
    skipped.bytes = skipped_;
    skipped_ = 0;
    sink(ctx, skipped);
  }
  sink(ctx, e);
}

FrameDecoder::Step FrameDecoder::Examine(const uint8_t* p, size_t avail, size_t& need, Sink sink,
                                         void* ctx) {
  if (avail < kMarkerSize) {
    need = kMarkerSize;
    return Step::kNeedMore;
  }
  if (p[1] != kMarker1) {
    need = 1;  // the byte after 'D' may start the next candidate
    return Step::kReject;
  }
  if (avail < kHeaderSize) {
    need = kHeaderSize;
    return Step::kNeedMore;
  }
  const uint16_t length = LoadU16(p + kLengthOffset);
  if (length > max_data_length_) {
    FramingError e;
    e.kind = FramingError::Kind::kOversize;
    e.length = length;
    e.id = LoadU32(p + kIdOffset);
    e.type = LoadU16(p + kTypeOffset);
    Emit(e, sink, ctx);
    need = rescan_ ? 1 : kHeaderSize;
    return Step::kReject;
  }
  const size_t total = kHeaderSize + length + kCheckSize;
  if (avail < total) {
    need = total;
    return Step::kNeedMore;
  }
  if (!ChecksumIsZero(ByteView(p, total))) {
    Emit(ChecksumError{LoadU32(p + kIdOffset), LoadU16(p + kTypeOffset), length}, sink, ctx);
    need = rescan_ ? 1 : total;
    return Step::kReject;
  }
  need = total;
  Emit(FrameRef{LoadU32(p + kIdOffset), LoadU16(p + kTypeOffset), ByteView(p + kHeaderSize, length),
                ByteView(p, total)},
       sink, ctx);
  return Step::kGood;
}

void FrameDecoder::ScanSpan(const uint8_t* p, size_t n, bool at_end, Sink sink, void* ctx) {
  size_t pos = 0;
  while (pos < n) {
    const void* d = std::memchr(p + pos, kMarker0, n - pos);
    if (d == nullptr) {
      skipped_ += n - pos;
      return;
    }
    const size_t at = static_cast<size_t>(static_cast<const uint8_t*>(d) - p);
    skipped_ += at - pos;
    pos = at;
    size_t need = 0;
    switch (Examine(p + pos, n - pos, need, sink, ctx)) {
      case Step::kGood:
        pos += need;
        break;
      case Step::kReject:
        skipped_ += need;
        pos += need;
        break;
      case Step::kNeedMore:
        if (at_end) {
          FramingError e;
          e.kind = FramingError::Kind::kTruncated;
          e.bytes = n - pos;
          if (n - pos >= kHeaderSize) {
            e.length = LoadU16(p + pos + kLengthOffset);
            e.id = LoadU32(p + pos + kIdOffset);
            e.type = LoadU16(p + pos + kTypeOffset);
          }
          Emit(e, sink, ctx);
          // The pending bytes will not be completed: rescan them, or drop
          // them all as the reference parser does.
          const size_t drop = rescan_ ? 1 : n - pos;
          skipped_ += drop;
          pos += drop;
        } else {
          // An incomplete candidate is shorter than a whole frame, so it fits.
          std::memcpy(buf_.data(), p + pos, n - pos);
          buf_len_ = n - pos;
          return;
        }
        break;
    }
  }
}

void FrameDecoder::FeedImpl(ByteView chunk, Sink sink, void* ctx) {
  // An empty chunk changes nothing (and its data() may be null).
  if (chunk.empty()) return;
  const uint8_t* in = chunk.data();
  const size_t n = chunk.size();
  size_t pos = 0;
  // Buffered mode: a candidate started in an earlier chunk. Copy only as many
  // bytes as the next decision needs.
  while (buf_len_ != 0) {
    size_t need = 0;
    const Step step = Examine(buf_.data(), buf_len_, need, sink, ctx);
    if (step == Step::kNeedMore) {
      const size_t take = std::min(need - buf_len_, n - pos);
      std::memcpy(buf_.data() + buf_len_, in + pos, take);
      buf_len_ += take;
      pos += take;
      if (buf_len_ < need) return;  // chunk exhausted
      continue;
    }
    // After a good frame the buffer may hold bytes past it (left from a
    // rescan); after a rejection, everything after the bytes it drops.
    size_t from = need;
    if (step == Step::kReject) skipped_ += need;
    const void* d =
        buf_len_ > from ? std::memchr(buf_.data() + from, kMarker0, buf_len_ - from) : nullptr;
    if (d == nullptr) {
      skipped_ += buf_len_ > from ? buf_len_ - from : 0;
      buf_len_ = 0;
      break;
    }
    const size_t at = static_cast<size_t>(static_cast<const uint8_t*>(d) - buf_.data());
    skipped_ += at - from;
    std::memmove(buf_.data(), buf_.data() + at, buf_len_ - at);
    buf_len_ -= at;
  }
  ScanSpan(in + pos, n - pos, /*at_end=*/false, sink, ctx);
}

void FrameDecoder::FinishImpl(Sink sink, void* ctx) {
  // With at_end, ScanSpan never writes to buf_, so it can scan it in place.
  const size_t n = buf_len_;
  buf_len_ = 0;
  ScanSpan(buf_.data(), n, /*at_end=*/true, sink, ctx);
  if (skipped_ != 0) {
    FramingError e;
    e.kind = FramingError::Kind::kSkipped;
    e.bytes = skipped_;
    skipped_ = 0;
    sink(ctx, e);
  }
}

std::vector<StreamEvent> DecodeStream(ByteView stream, bool finish, FrameDecoderOptions options) {
  std::vector<StreamEvent> events;
  FrameDecoder dec(options);
  auto collect = [&events](const FrameEvent& e) { events.push_back(ToStreamEvent(e)); };
  dec.Feed(stream, collect);
  if (finish) dec.Finish(collect);
  return events;
}

}  // namespace moco::dmc
