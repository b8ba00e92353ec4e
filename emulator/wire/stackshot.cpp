// Typed codec for the Cognisys StackShot / StackShot 3X binary protocol
// (stackshot-protocol.txt section 2; ERRATA.md part 3): packet data <->
// typed payloads by the command table, and CC_MOTION_CONFIG validation.
// Packet framing and checksums are in stackshot_frame.cpp, the table in
// stackshot_table.cpp, the describe text in stackshot_describe.cpp.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <type_traits>

#include "wire/stackshot.h"

namespace moco::stackshot {
namespace {

using wire::Reader;
using wire::Writer;

// ---------------------------------------------------------------------------
// Shape parsing
// ---------------------------------------------------------------------------
DecodeError LengthError(std::string_view name, std::string_view what, size_t want_lo,
                        size_t want_hi, size_t got) {
  std::string detail(name);
  detail += ' ';
  detail += what;
  detail += " expects ";
  detail += std::to_string(want_lo);
  if (want_hi != want_lo) detail += (want_hi == SIZE_MAX) ? "+" : " or " + std::to_string(want_hi);
  detail += " data byte(s), got ";
  detail += std::to_string(got);
  return {DecodeError::Kind::kBadLength, kOffsetLength, std::move(detail)};
}

// Every fixed-size layout's byte count, or 0 for variable ones.
size_t FixedSize(Shape s) {
  switch (s) {
    case Shape::kEmpty:
      return 0;
    case Shape::kU8:
    case Shape::kBool:
    case Shape::kUnits:
    case Shape::kRailMode:
    case Shape::kGlobalMode:
    case Shape::kShutterSetting:
    case Shape::kIoMode:
    case Shape::kDirection:
    case Shape::kNvmRead:
    case Shape::kPingRequest:
      return 1;
    case Shape::kU16:
    case Shape::kPingReply:
      return 2;
    case Shape::kU32:
    case Shape::kF32:
    case Shape::kRailStatus:
      return 4;
    case Shape::kUnitsF32:
    case Shape::kNvmWrite:
      return 5;
    case Shape::kRailMove:
      return kRailMoveBytes;
    case Shape::kRailMoveAtSpeed:
      return kRailMoveAtSpeedBytes;
    case Shape::kShutterFire:
      return kShutterFireBytes;
    case Shape::kMotionConfig:
      return kMotionConfigBytes;
    case Shape::kMotionStart:
      return kMotionStartBytes;
    default:
      return SIZE_MAX;  // variable
  }
}

F32 ReadF32(Reader& r) {
  uint32_t bits = 0;
  r.U32Le(bits);
  return F32::FromBits(bits);
}
uint8_t ReadU8(Reader& r) {
  uint8_t v = 0;
  r.U8(v);
  return v;
}
uint16_t ReadU16(Reader& r) {
  uint16_t v = 0;
  r.U16Le(v);
  return v;
}
uint32_t ReadU32(Reader& r) {
  uint32_t v = 0;
  r.U32Le(v);
  return v;
}

Result<Payload> ParseText(ByteView data) {
  if (data.empty()) return Payload{Text{"", false}};
  const auto* nul = static_cast<const uint8_t*>(std::memchr(data.data(), 0, data.size()));
  if (nul == nullptr) {
    return Payload{Text{std::string(data.begin(), data.end()), false}};
  }
  const size_t n = static_cast<size_t>(nul - data.data());
  if (n + 1 != data.size()) {
    return DecodeError{
        DecodeError::Kind::kTrailing, kOffsetData + n + 1,
        std::to_string(data.size() - n - 1) + " byte(s) after the string's terminating NUL"};
  }
  return Payload{
      Text{std::string(data.begin(), data.begin() + static_cast<std::ptrdiff_t>(n)), true}};
}

// Parses `data` (which starts at packet offset kOffsetData) as shape s.
// REQUIRES: s != kNone.
Result<Payload> ParseShape(Shape s, ByteView data, std::string_view name, std::string_view what) {
  const bool padded = s == Shape::kMotionStart && data.size() == kMotionStartListedBytes;
  if (padded) {
    // The table's header says Length 132 while listing three bools: a host
    // that pads to the header's length is read by its first three bytes.
    data = data.first(kMotionStartBytes);
  }
  const size_t fixed = FixedSize(s);
  if (fixed != SIZE_MAX && data.size() != fixed) {
    return LengthError(name, what, fixed, fixed, data.size());
  }
  Reader r(data, kOffsetData);
  switch (s) {
    case Shape::kNone:
    case Shape::kEmpty:
      return Payload{Empty{}};
    case Shape::kUnitsQuery:
      if (data.size() > 1) return LengthError(name, what, 0, 1, data.size());
      if (data.empty()) return Payload{UnitsQuery{}};
      return Payload{UnitsQuery{static_cast<Units>(data[0])}};
    case Shape::kU8:
      return Payload{U8Value{ReadU8(r)}};
    case Shape::kBool:
      return Payload{BoolValue{ReadU8(r) != 0}};
    case Shape::kU16:
      return Payload{U16Value{ReadU16(r)}};
    case Shape::kU32:
      return Payload{U32Value{ReadU32(r)}};
    case Shape::kF32:
      return Payload{F32Value{ReadF32(r)}};
    case Shape::kUnitsF32: {
      UnitsF32 v;
      v.units = static_cast<Units>(ReadU8(r));
      v.value = ReadF32(r);
      return Payload{v};
    }
    case Shape::kText:
      return ParseText(data);
    case Shape::kUnits:
      return Payload{EnumValue<Units>{static_cast<Units>(ReadU8(r))}};
    case Shape::kRailMode:
      return Payload{EnumValue<RailMode>{static_cast<RailMode>(ReadU8(r))}};
    case Shape::kGlobalMode:
      return Payload{EnumValue<GlobalMode>{static_cast<GlobalMode>(ReadU8(r))}};
    case Shape::kShutterSetting:
      return Payload{EnumValue<ShutterSetting>{static_cast<ShutterSetting>(ReadU8(r))}};
    case Shape::kIoMode:
      return Payload{EnumValue<IoMode>{static_cast<IoMode>(ReadU8(r))}};
    case Shape::kDirection:
      return Payload{EnumValue<Direction>{static_cast<Direction>(ReadU8(r))}};
    case Shape::kRailMove: {
      RailMove m;
      m.direction = static_cast<Direction>(ReadU8(r));
      m.units = static_cast<Units>(ReadU8(r));
      m.backlash = ReadU8(r) != 0;
      m.distance = ReadF32(r);
      return Payload{m};
    }
    case Shape::kRailMoveAtSpeed: {
      RailMoveAtSpeed m;
      m.direction = static_cast<Direction>(ReadU8(r));
      m.units = static_cast<Units>(ReadU8(r));
      m.distance = ReadF32(r);
      m.speed_fraction = ReadF32(r);
      return Payload{m};
    }
    case Shape::kShutterFire: {
      ShutterFire f;
      f.pulses = ReadU16(r);
      f.on_time_s = ReadF32(r);
      f.off_time_s = ReadF32(r);
      return Payload{f};
    }
    case Shape::kRailStack: {
      if (data.size() != kRailStackBytes && data.size() != kRailStackListedBytes) {
        return LengthError(name, what, kRailStackListedBytes, kRailStackBytes, data.size());
      }
      RailStack st;
      st.mode = ReadU32(r);
      st.num_steps = ReadU32(r);
      st.distance = ReadU32(r);
      st.pano_start_steps = ReadU32(r);
      st.pano_stop_steps = ReadU32(r);
      st.x_start = ReadU32(r);
      st.x_end = ReadU32(r);
      st.y_start = ReadU32(r);
      st.y_end = ReadU32(r);
      st.z_start = ReadU32(r);
      st.z_end = ReadU32(r);
      if (!r.empty()) st.reserved = ReadU32(r);
      return Payload{st};
    }
    case Shape::kRailStatus:
      return Payload{RailStatus{ReadU32(r)}};
    case Shape::kNvmRead:
      return Payload{NvmRead{ReadU8(r)}};
    case Shape::kNvmWrite: {
      NvmWrite w;
      w.reg = ReadU8(r);
      w.value = ReadU32(r);
      return Payload{w};
    }
    case Shape::kPingRequest:
      return Payload{PingRequest{ReadU8(r)}};
    case Shape::kPingReply: {
      PingReply p;
      p.value = ReadU8(r);
      p.reserved = ReadU8(r);
      return Payload{p};
    }
    case Shape::kLogRequest:
      if (data.size() == 1) return Payload{LogRequest{ReadU8(r), 1}};
      if (data.size() == 4) return Payload{LogRequest{ReadU32(r), 4}};
      return LengthError(name, what, 1, 4, data.size());
    case Shape::kMotionConfig: {
      MotionConfig m;
      m.axis_type = static_cast<AxisType>(ReadU32(r));
      for (auto& curve : m.curves) {
        for (auto& point : curve.p) {
          point.x = ReadF32(r);
          point.y = ReadF32(r);
        }
      }
      return Payload{m};
    }
    case Shape::kMotionStart: {
      MotionStart m;
      m.x = ReadU8(r) != 0;
      m.y = ReadU8(r) != 0;
      m.z = ReadU8(r) != 0;
      m.padded = padded;
      return Payload{m};
    }
    case Shape::kRaw:
      return Payload{Raw{Bytes(data.begin(), data.end())}};
  }
  return Payload{Raw{Bytes(data.begin(), data.end())}};
}

bool IsPingAtTableId(const Packet& p, const DecodeOptions& options) {
  return options.ping_at_table_id && p.command == kPingTableId;
}

// ---------------------------------------------------------------------------
// Encoding
// ---------------------------------------------------------------------------
struct PayloadWriter {
  Writer& w;
  void F(F32 v) { w.U32Le(v.bits()); }
  void operator()(const Empty& e) { w.Raw(e.ignored); }
  void operator()(const UnitsQuery& q) {
    if (q.units) w.U8(static_cast<uint8_t>(*q.units));
  }
  void operator()(const U8Value& v) { w.U8(v.value); }
  void operator()(const BoolValue& v) { w.U8(v.value ? 1 : 0); }
  void operator()(const U16Value& v) { w.U16Le(v.value); }
  void operator()(const U32Value& v) { w.U32Le(v.value); }
  void operator()(const F32Value& v) { F(v.value); }
  void operator()(const UnitsF32& v) {
    w.U8(static_cast<uint8_t>(v.units));
    F(v.value);
  }
  void operator()(const Text& t) {
    w.Raw(t.text);
    if (t.terminated) w.U8(0);
  }
  template <typename En>
  void operator()(const EnumValue<En>& v) {
    w.U8(static_cast<uint8_t>(v.value));
  }
  void operator()(const RailMove& m) {
    w.U8(static_cast<uint8_t>(m.direction));
    w.U8(static_cast<uint8_t>(m.units));
    w.U8(m.backlash ? 1 : 0);
    F(m.distance);
  }
  void operator()(const RailMoveAtSpeed& m) {
    w.U8(static_cast<uint8_t>(m.direction));
    w.U8(static_cast<uint8_t>(m.units));
    F(m.distance);
    F(m.speed_fraction);
  }
  void operator()(const ShutterFire& f) {
    w.U16Le(f.pulses);
    F(f.on_time_s);
    F(f.off_time_s);
  }
  void operator()(const RailStack& s) {
    for (uint32_t v : {s.mode, s.num_steps, s.distance, s.pano_start_steps, s.pano_stop_steps,
                       s.x_start, s.x_end, s.y_start, s.y_end, s.z_start, s.z_end}) {
      w.U32Le(v);
    }
    if (s.reserved) w.U32Le(*s.reserved);
  }
  void operator()(const RailStatus& s) { w.U32Le(s.bits); }
  void operator()(const NvmRead& n) { w.U8(n.reg); }
  void operator()(const NvmWrite& n) {
    w.U8(n.reg);
    w.U32Le(n.value);
  }
  void operator()(const PingRequest& p) { w.U8(p.value); }
  void operator()(const PingReply& p) {
    w.U8(p.value);
    w.U8(p.reserved);
  }
  void operator()(const LogRequest& l) {
    if (l.width == 4) {
      w.U32Le(l.index);
    } else {
      w.U8(static_cast<uint8_t>(l.index));
    }
  }
  void operator()(const MotionConfig& m) {
    w.U32Le(static_cast<uint32_t>(m.axis_type));
    for (const auto& curve : m.curves) {
      for (const auto& point : curve.p) {
        F(point.x);
        F(point.y);
      }
    }
  }
  void operator()(const MotionStart& m) {
    w.U8(m.x ? 1 : 0);
    w.U8(m.y ? 1 : 0);
    w.U8(m.z ? 1 : 0);
    if (m.padded) {
      for (size_t i = kMotionStartBytes; i < kMotionStartListedBytes; ++i) w.U8(0);
    }
  }
  void operator()(const Raw& r) { w.Raw(r.data); }
  void operator()(const Unknown& u) { w.Raw(u.data); }
};

bool Finite(F32 v) { return std::isfinite(v.value()); }

}  // namespace

// ---------------------------------------------------------------------------
// Typed decode / encode
// ---------------------------------------------------------------------------
Result<HostCommand> DecodeHostPacket(const Packet& p, const DecodeOptions& options) {
  HostCommand c;
  c.command = p.command;
  c.action = static_cast<Action>(p.action);
  c.axis = p.axis;
  c.sub_item = p.sub_item;
  c.reserved_bit6 = p.reserved_bit6;
  const bool is_read = c.action == Action::kRead;
  const bool is_write = c.action == Action::kWrite;
  const CommandInfo* info = FindCommand(p.command);
  if (info == nullptr) {
    c.payload = Unknown{p.data};
    return c;
  }
  if (!is_read && !is_write) {
    return DecodeError{DecodeError::Kind::kBadValue, kOffsetAction,
                       std::string(info->name) + ": host action " + std::to_string(p.action) +
                           " is neither READ nor WRITE"};
  }
  if (is_read && IsPingAtTableId(p, options) && p.data.size() == 1) {
    c.payload = PingRequest{p.data[0]};
    return c;
  }
  const Shape shape = is_read ? info->read_request : info->write_request;
  if (is_read && p.command == Id(Command::kRailConfigAutoReturn) && p.data.size() == 1) {
    // The garbled AUTO_RETURN read table lists a bool under "Cmd Data":
    // a read carrying one byte is a read all the same.
    c.payload = Empty{Bytes(p.data.begin(), p.data.end())};
    return c;
  }
  if (shape == Shape::kNone) {
    return DecodeError{DecodeError::Kind::kBadValue, kOffsetAction,
                       std::string(info->name) + " is " + (is_read ? "write" : "read") + "-only"};
  }
  auto payload = ParseShape(shape, p.data, info->name, is_read ? "read request" : "write request");
  if (!payload) return payload.error();
  c.payload = std::move(payload).value();
  return c;
}

Result<DeviceReply> DecodeDevicePacket(const Packet& p, const ReplyContext& context,
                                       const DecodeOptions& options) {
  DeviceReply r;
  r.command = p.command;
  r.status = static_cast<Action>(p.action);
  r.axis = p.axis;
  r.sub_item = p.sub_item;
  r.reserved_bit6 = p.reserved_bit6;
  if (r.status != Action::kRspOk) {
    r.kind = ReplyKind::kError;
    r.payload = Raw{p.data};
    return r;
  }
  if (IsPingAtTableId(p, options) && p.data.size() == FixedSize(Shape::kPingReply) &&
      context.request_action.value_or(Action::kRead) == Action::kRead) {
    r.kind = ReplyKind::kReadResponse;
    r.payload = PingReply{p.data[0], p.data[1]};
    return r;
  }
  const CommandInfo* info = FindCommand(p.command);
  if (info == nullptr) {
    r.kind = ReplyKind::kOpaque;
    r.payload = Unknown{p.data};
    return r;
  }
  if (info->read_response == Shape::kRaw) {
    r.kind = ReplyKind::kOpaque;
    r.payload = Raw{p.data};
    return r;
  }
  bool read_response;
  if (info->read_response == Shape::kNone) {
    read_response = false;
  } else if (info->write_request == Shape::kNone) {
    read_response = true;
  } else if (context.request_action) {
    read_response = *context.request_action == Action::kRead;
  } else {
    read_response = !p.data.empty();
  }
  if (!read_response) {
    if (!p.data.empty()) {
      return LengthError(info->name, "write acknowledgement", 0, 0, p.data.size());
    }
    r.kind = ReplyKind::kWriteAck;
    r.payload = Empty{};
    return r;
  }
  auto payload = ParseShape(info->read_response, p.data, info->name, "read response");
  if (!payload) return payload.error();
  r.kind = ReplyKind::kReadResponse;
  r.payload = std::move(payload).value();
  return r;
}

Action ErrorReplyStatus(const DecodeError& e) {
  if (e.kind == DecodeError::Kind::kUnknown) return Action::kUnsupportedCmd;
  if (e.offset == kOffsetAction) return Action::kUnsupportedAction;
  return Action::kBadParam;
}

Bytes EncodePayload(const Payload& payload) {
  Bytes out;
  Writer w(out);
  std::visit(PayloadWriter{w}, payload);
  return out;
}

Packet ToPacket(const HostCommand& c, ChecksumAlgorithm checksum) {
  Packet p;
  p.from_device = false;
  p.command = c.command;
  p.action = static_cast<uint8_t>(static_cast<uint8_t>(c.action) & kActionMask);
  p.axis = c.axis & 0x3;
  p.sub_item = c.sub_item;
  p.reserved_bit6 = c.reserved_bit6;
  p.data = EncodePayload(c.payload);
  Seal(p, checksum);
  return p;
}

Packet ToPacket(const DeviceReply& r, ChecksumAlgorithm checksum) {
  Packet p;
  p.from_device = true;
  p.command = r.command;
  p.action = static_cast<uint8_t>(static_cast<uint8_t>(r.status) & kActionMask);
  p.axis = r.axis & 0x3;
  p.sub_item = r.sub_item;
  p.reserved_bit6 = r.reserved_bit6;
  p.data = EncodePayload(r.payload);
  Seal(p, checksum);
  return p;
}

bool EncodeHostCommand(const HostCommand& c, Bytes& out, ChecksumAlgorithm checksum) {
  return EncodePacket(ToPacket(c, checksum), out);
}

bool EncodeDeviceReply(const DeviceReply& r, Bytes& out, ChecksumAlgorithm checksum) {
  return EncodePacket(ToPacket(r, checksum), out);
}

// ---------------------------------------------------------------------------
// Range checks
// ---------------------------------------------------------------------------
bool IsValid(Direction d) { return static_cast<uint8_t>(d) < kDirectionMax; }
bool IsValid(Units u) { return static_cast<uint8_t>(u) < kUnitsMaxSpec; }
bool IsValid(GlobalMode m) { return static_cast<uint8_t>(m) < kGlobalModeMax; }
bool IsValid(ShutterSetting s) { return static_cast<uint8_t>(s) < kShutterSettingMax; }
bool IsValid(IoMode m) { return static_cast<uint8_t>(m) < kIoModeMax; }
bool IsValid(AxisType t) { return static_cast<uint32_t>(t) < kAxisTypeMax; }

// ---------------------------------------------------------------------------
// CC_MOTION_CONFIG validation
// ---------------------------------------------------------------------------
std::string_view MotionRuleName(MotionRule rule) {
  switch (rule) {
    case MotionRule::kOk:
      return "ok";
    case MotionRule::kNotFinite:
      return "not-finite";
    case MotionRule::kCurve0StartNotZero:
      return "curve0-start-not-zero";
    case MotionRule::kContinuity:
      return "continuity";
    case MotionRule::kTimeReversed:
      return "time-reversed";
    case MotionRule::kP1BeforeP0:
      return "p1-before-p0";
    case MotionRule::kP2AfterP3:
      return "p2-after-p3";
    case MotionRule::kControlOutOfSpan:
      return "control-out-of-span";
    case MotionRule::kCurveAfterEnd:
      return "curve-after-end";
  }
  return "?";
}

int UsedCurves(const MotionConfig& config) {
  int used = 1;
  while (used < static_cast<int>(kBezierCurves) &&
         config.curves[static_cast<size_t>(used)].p[0].x.value() != 0.0f) {
    ++used;
  }
  return used;
}

MotionCheck ValidateMotionConfig(const MotionConfig& config) {
  const int used = UsedCurves(config);
  for (int c = 0; c < used; ++c) {
    const auto& p = config.curves[static_cast<size_t>(c)].p;
    for (const auto& pt : p) {
      if (!Finite(pt.x) || !Finite(pt.y)) return {MotionRule::kNotFinite, c};
    }
    const float x0 = p[0].x.value();
    const float x1 = p[1].x.value();
    const float x2 = p[2].x.value();
    const float x3 = p[3].x.value();
    if (c == 0 && x0 != 0.0f) return {MotionRule::kCurve0StartNotZero, 0};
    if (c > 0 && x0 != config.curves[static_cast<size_t>(c - 1)].p[3].x.value()) {
      return {MotionRule::kContinuity, c};
    }
    if (x3 < x0) return {MotionRule::kTimeReversed, c};
    if (x1 < x0) return {MotionRule::kP1BeforeP0, c};
    if (x2 > x3) return {MotionRule::kP2AfterP3, c};
    if (x1 > x3 || x2 < x0) return {MotionRule::kControlOutOfSpan, c};
  }
  // The first unused curve ends the motion; anything set after it is ignored
  // by the spline and most likely a host mistake.
  for (int c = used + 1; c < static_cast<int>(kBezierCurves); ++c) {
    if (config.curves[static_cast<size_t>(c)].p[0].x.value() != 0.0f) {
      return {MotionRule::kCurveAfterEnd, c};
    }
  }
  return {};
}

}  // namespace moco::stackshot
