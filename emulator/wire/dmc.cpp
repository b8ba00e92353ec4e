// DMC v2 messages (dmc-v2-protocol.txt "Message Types"; ERRATA dmc 1.3-1.10):
// the dispatch from a frame's type to the struct its data reads as, the ACK
// form, encoding a message into a frame or its data alone, and the helpers of
// the message structs. The layouts of each struct's fields are in
// dmc_layouts.cpp.
#include "wire/dmc.h"

#include <string_view>
#include <type_traits>
#include <utility>

#include "wire/dmc_layouts.h"

namespace moco::dmc {
namespace {

using wire::Reader;
using wire::Writer;
using Kind = DecodeError::Kind;
using layout::Fields;
using layout::Get;
using layout::Put;

// --- Dispatch --------------------------------------------------------------------

template <class T, class Variant>
Result<Variant> DecodeAs(ByteView data, TrailingBytes trailing,
                         MissingFields missing = MissingFields::kError) {
  T m{};
  Reader r(data);
  Fields f(r, trailing, missing);
  Get(f, m);
  if (f.error()) return *f.error();
  if (!r.empty() && trailing == TrailingBytes::kReject) {
    return r.Trailing(TypeName(ToWire(T::kType)));
  }
  return Variant{std::move(m)};
}

template <class Variant>
Result<Variant> DecodeAck(uint16_t type, ByteView data) {
  Ack a;
  a.type = static_cast<uint16_t>(type & ~kFlagAck);
  Reader r(data);
  if (data.size() == 2) {
    uint16_t code = 0;
    r.U16Le(code);
    a.code = code;
    a.width = AckWidth::k16;
  } else if (data.size() == 4) {
    r.U32Le(a.code);
    a.width = AckWidth::k32;
  } else if (data.size() < 2) {
    return r.Truncated("Response Code");
  } else if (data.size() == 3) {
    return DecodeError{Kind::kBadLength, 0, "ACK response code must be 2 or 4 bytes, got 3"};
  } else {
    Reader skip(data);
    ByteView code;
    skip.Take(4, code);
    return skip.Trailing("Response Code");
  }
  return Variant{a};
}

template <class... Ts>
void PutAny(Writer& w, const std::variant<Ts...>& m) {
  std::visit([&w](const auto& x) { Put(w, x); }, m);
}

template <class... Ts>
uint16_t TypeOfAny(const std::variant<Ts...>& m) {
  return std::visit(wire::Overloaded{
                        [](const Ack& a) { return static_cast<uint16_t>(a.type | kFlagAck); },
                        [](const Unknown& u) { return u.type; },
                        [](const auto& x) { return ToWire(std::decay_t<decltype(x)>::kType); },
                    },
                    m);
}

template <class Variant>
void EncodeAny(uint32_t id, const Variant& m, Bytes& out) {
  const size_t start = BeginFrame(id, TypeOfAny(m), out);
  Writer w(out);
  PutAny(w, m);
  EndFrame(start, out);
}

}  // namespace

uint8_t VirtConfig::rig_type() const {
  return std::visit(
      wire::Overloaded{
          [](const VirtRigNone&) { return static_cast<uint8_t>(RigType::kNone); },
          [](const VirtRigBoomSwingTrack&) {
            return static_cast<uint8_t>(RigType::kBoomSwingTrack);
          },
          [](const VirtRigSwingPan&) { return static_cast<uint8_t>(RigType::kSwingPan); },
          [](const VirtRigRaw& r) { return r.type; },
      },
      rig);
}

std::string HiResponse::NameText() const {
  size_t n = 0;
  while (n < name.size() && name[n] != 0) ++n;
  return std::string(name.begin(), name.begin() + static_cast<std::ptrdiff_t>(n));
}

std::array<uint8_t, kHiNameSize> HiResponse::MakeName(std::string_view text) {
  std::array<uint8_t, kHiNameSize> out{};
  for (size_t i = 0; i < text.size() && i < out.size(); ++i) out[i] = static_cast<uint8_t>(text[i]);
  return out;
}

Result<HostMessage> DecodeHostMessage(uint16_t type, ByteView data, TrailingBytes trailing,
                                      MissingFields missing) {
  using M = HostMessage;
  if ((type & kFlagAck) != 0) return DecodeAck<M>(type, data);
  switch (static_cast<MsgType>(type)) {
    case MsgType::kHi:
      return DecodeAs<HiRequest, M>(data, trailing, missing);
    case MsgType::kDmx:
      return DecodeAs<Dmx, M>(data, trailing, missing);
    case MsgType::kGioOut:
      return DecodeAs<GioOut, M>(data, trailing, missing);
    case MsgType::kGioIn:
      return DecodeAs<GioInRequest, M>(data, trailing, missing);
    case MsgType::kGioCam:
      return DecodeAs<GioCam, M>(data, trailing, missing);
    case MsgType::kMotorStatus:
      return DecodeAs<MotorStatusRequest, M>(data, trailing, missing);
    case MsgType::kMotorMove:
      return DecodeAs<MotorMove, M>(data, trailing, missing);
    case MsgType::kMotorStop:
      return DecodeAs<MotorStop, M>(data, trailing, missing);
    case MsgType::kMotorStopAll:
      return DecodeAs<MotorStopAll, M>(data, trailing, missing);
    case MsgType::kMotorGetPosition:
      return DecodeAs<MotorGetPositionRequest, M>(data, trailing, missing);
    case MsgType::kMotorResetPosition:
      return DecodeAs<MotorResetPosition, M>(data, trailing, missing);
    case MsgType::kMotorJog:
      return DecodeAs<MotorJog, M>(data, trailing, missing);
    case MsgType::kMotorConfigure:
      return DecodeAs<MotorConfigure, M>(data, trailing, missing);
    case MsgType::kMotorSetSpeed:
      return DecodeAs<MotorSetSpeed, M>(data, trailing, missing);
    case MsgType::kMotorSetLimits:
      return DecodeAs<MotorSetLimits, M>(data, trailing, missing);
    case MsgType::kRtUploadMoveBegin:
      return DecodeAs<RtUploadMoveBegin, M>(data, trailing, missing);
    case MsgType::kRtUploadMoveAxis:
      return DecodeAs<RtUploadMoveAxis, M>(data, trailing, missing);
    case MsgType::kRtUploadMoveDmx:
      return DecodeAs<RtUploadMoveDmx, M>(data, trailing, missing);
    case MsgType::kRtUploadMoveTriggers:
      return DecodeAs<RtUploadMoveTriggers, M>(data, trailing, missing);
    case MsgType::kRtUploadMoveEnd:
      return DecodeAs<RtUploadMoveEnd, M>(data, trailing, missing);
    case MsgType::kRtPositionFrame:
      return DecodeAs<RtPositionFrame, M>(data, trailing, missing);
    case MsgType::kRtRunMove:
      return DecodeAs<RtRunMove, M>(data, trailing, missing);
    case MsgType::kRtShootFrame:
      return DecodeAs<RtShootFrame, M>(data, trailing, missing);
    case MsgType::kRtShootFrame2:
      return DecodeAs<RtShootFrame2, M>(data, trailing, missing);
    case MsgType::kRtGo:
      return DecodeAs<RtGo, M>(data, trailing, missing);
    case MsgType::kRtStopLoop:
      return DecodeAs<RtStopLoop, M>(data, trailing, missing);
    case MsgType::kRtJogAll:
      return DecodeAs<RtJogAll, M>(data, trailing, missing);
    case MsgType::kVirtConfig:
      return DecodeAs<VirtConfig, M>(data, trailing, missing);
    case MsgType::kVirtMove:
      return DecodeAs<VirtMove, M>(data, trailing, missing);
    case MsgType::kVirtStop:
      return DecodeAs<VirtStop, M>(data, trailing, missing);
    case MsgType::kVirtJog:
      return DecodeAs<VirtJog, M>(data, trailing, missing);
    case MsgType::kVirtJogOnLine:
      return DecodeAs<VirtJogOnLine, M>(data, trailing, missing);
    case MsgType::kVirtGetPosition:
      return DecodeAs<VirtGetPositionRequest, M>(data, trailing, missing);
    case MsgType::kVirtAimPoint:
      return DecodeAs<VirtAimPoint, M>(data, trailing, missing);
    // Sent only by devices: Dragonframe never sends these without kFlagAck.
    case MsgType::kMotorHardStop:
    case MsgType::kRtEnd:
      break;
  }
  return M{Unknown{type, Bytes(data.begin(), data.end())}};
}

Result<HostMessage> DecodeHostMessage(const Frame& frame, TrailingBytes trailing) {
  return DecodeHostMessage(frame.type, frame.data, trailing);
}

Result<DeviceMessage> DecodeDeviceMessage(uint16_t type, ByteView data, TrailingBytes trailing) {
  using M = DeviceMessage;
  if ((type & kFlagAck) != 0) return DecodeAck<M>(type, data);
  switch (static_cast<MsgType>(type)) {
    case MsgType::kHi:
      return DecodeAs<HiResponse, M>(data, trailing);
    case MsgType::kMotorStatus:
      return DecodeAs<MotorStatusResponse, M>(data, trailing);
    case MsgType::kMotorMove:
      return DecodeAs<MotorMoveResponse, M>(data, trailing);
    case MsgType::kMotorGetPosition:
      return DecodeAs<MotorPositionReport, M>(data, trailing);
    case MsgType::kGioIn:
      return DecodeAs<GioInReport, M>(data, trailing);
    case MsgType::kMotorHardStop:
      return DecodeAs<MotorHardStop, M>(data, trailing);
    case MsgType::kRtEnd:
      return DecodeAs<RtEnd, M>(data, trailing);
    case MsgType::kVirtGetPosition:
      return DecodeAs<VirtPositionReport, M>(data, trailing);
    case MsgType::kVirtAimPoint:
      return DecodeAs<VirtAimPoint, M>(data, trailing);
    default:
      break;  // requests only: a device answers them with an ACK
  }
  return M{Unknown{type, Bytes(data.begin(), data.end())}};
}

Result<DeviceMessage> DecodeDeviceMessage(const Frame& frame, TrailingBytes trailing) {
  return DecodeDeviceMessage(frame.type, frame.data, trailing);
}

uint16_t TypeOf(const HostMessage& m) { return TypeOfAny(m); }
uint16_t TypeOf(const DeviceMessage& m) { return TypeOfAny(m); }

void Encode(uint32_t id, const HostMessage& m, Bytes& out) { EncodeAny(id, m, out); }
void Encode(uint32_t id, const DeviceMessage& m, Bytes& out) { EncodeAny(id, m, out); }

Bytes Encode(uint32_t id, const HostMessage& m) {
  Bytes out;
  EncodeAny(id, m, out);
  return out;
}
Bytes Encode(uint32_t id, const DeviceMessage& m) {
  Bytes out;
  EncodeAny(id, m, out);
  return out;
}

void EncodeData(const HostMessage& m, Bytes& out) {
  Writer w(out);
  PutAny(w, m);
}
void EncodeData(const DeviceMessage& m, Bytes& out) {
  Writer w(out);
  PutAny(w, m);
}

AckCode SuggestedAck(const DecodeError& e) {
  switch (e.kind) {
    case Kind::kBadChecksum:
      return AckCode::kErrChecksum;
    case Kind::kUnknown:
      return AckCode::kErrUnsupported;
    case Kind::kBadValue:
      return AckCode::kErrRange;
    case Kind::kTruncated:
    case Kind::kTrailing:
    case Kind::kBadLength:
    case Kind::kBadSyntax:
      break;
  }
  return AckCode::kErrGeneral;
}

}  // namespace moco::dmc
