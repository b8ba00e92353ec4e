// Codec for the Cognisys StackShot / StackShot 3X binary protocol
// (stackshot-protocol.txt sections 2 and 4; ERRATA.md part 3).
#include "wire/stackshot.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstring>
#include <type_traits>

#include "base/format.h"

namespace moco::stackshot {
namespace {

using base::Hex;
using wire::Reader;
using wire::Writer;

// ---------------------------------------------------------------------------
// The command table (section 2 tables, with the decisions for the commands
// the spec lists without a table).
// ---------------------------------------------------------------------------
constexpr Shape N = Shape::kNone;
constexpr Shape E = Shape::kEmpty;

// clang-format off
constexpr CommandInfo kCommands[] = {
  {0x1000, "CC_RAIL_MOVE",                   N, N, Shape::kRailMove, "", "2 CC_RAIL_MOVE"},
  {0x1001, "CC_RAIL_POSITION_TARGET",        Shape::kUnitsQuery, Shape::kUnitsF32, N, "position",
   "2 CC_RAIL_POSITION_TARGET; ERRATA 3.4 (response 5 bytes)"},
  {0x1002, "CC_RAIL_POSITION_CURRENT",       Shape::kUnitsQuery, Shape::kUnitsF32, N, "position",
   "2 CC_RAIL_POSITION_CURRENT; examples send no units byte"},
  {0x1003, "CC_RAIL_POSITION_ZERO",          N, N, E, "", "2 CC_RAIL_POSITION_ZERO"},
  {0x1004, "CC_RAIL_SHUTTER_FIRE",           N, N, Shape::kShutterFire, "", "2 CC_RAIL_SHUTTER_FIRE"},
  {0x1005, "CC_RAIL_STATUS",                 E, Shape::kRailStatus, N, "status", "2 CC_RAIL_STATUS"},
  // No table: StackShot_Stop (1.1.7) takes no parameters; write, no data.
  {0x1006, "CC_RAIL_STOP",                   N, N, E, "", "1.1.7 (no table)"},
  {0x1007, "CC_RAIL_MOVE_AT_SPEED",          N, N, Shape::kRailMoveAtSpeed, "", "2 CC_RAIL_MOVE_AT_SPEED"},
  {0x1008, "CC_RAIL_STACK",                  N, N, Shape::kRailStack, "", "2 CC_RAIL_STACK (48 bytes, 44 listed)"},
  // No table: read-only; the reply is taken to be a status bit field like
  // CC_RAIL_STATUS.
  {0x1009, "CC_RAIL_STACK_STATUS",           E, Shape::kRailStatus, N, "status", "1.2 enum only (decided)"},
  // No table: read-only; the reply is taken to be a u32 count of the stack
  // steps taken so far.
  {0x100A, "CC_RAIL_STACK_POSITION",         E, Shape::kU32, N, "step", "1.2 enum only (decided)"},
  // No table: like CC_RAIL_STOP, with a soft ramp; write, no data.
  {0x100B, "CC_RAIL_STOP_RAMP",              N, N, E, "", "1.2 enum only (decided)"},

  {0x1080, "CC_RAIL_CONFIG_NAME",            E, Shape::kText, Shape::kText, "name", "2 CC_RAIL_CONFIG_NAME"},
  {0x1081, "CC_RAIL_CONFIG_BACKLIGHT",       E, Shape::kU8, Shape::kU8, "level", "2 CC_RAIL_CONFIG_BACKLIGHT"},
  {0x1082, "CC_RAIL_CONFIG_MODE",            E, Shape::kRailMode, Shape::kRailMode, "mode", "2 CC_RAIL_CONFIG_MODE"},
  {0x1083, "CC_RAIL_CONFIG_UNITS",           E, Shape::kUnits, Shape::kUnits, "units", "2 CC_RAIL_CONFIG_UNITS"},
  {0x1084, "CC_RAIL_CONFIG_TORQUE",          E, Shape::kU8, Shape::kU8, "level", "2 CC_RAIL_CONFIG_TORQUE"},
  {0x1085, "CC_RAIL_CONFIG_NUM_STEPS",       E, Shape::kU16, Shape::kU16, "steps",
   "2 CC_RAIL_CONFIG_NUM_STEPS; ERRATA 3.4 (u16)"},
  {0x1086, "CC_RAIL_CONFIG_NUM_PULSES",      E, Shape::kU16, Shape::kU16, "pulses", "2 CC_RAIL_CONFIG_NUM_PULSES"},
  {0x1087, "CC_RAIL_CONFIG_TOTAL_DISTANCE",  Shape::kUnitsQuery, Shape::kUnitsF32, Shape::kUnitsF32, "distance",
   "2 CC_RAIL_CONFIG_TOTAL_DISTANCE"},
  {0x1088, "CC_RAIL_CONFIG_DISTANCE_PER_STEP", Shape::kUnitsQuery, Shape::kUnitsF32, Shape::kUnitsF32, "distance",
   "2 CC_RAIL_CONFIG_DISTANCE_PER_STEP"},
  {0x1089, "CC_RAIL_CONFIG_SETTLE_TIME",     E, Shape::kF32, Shape::kF32, "seconds", "2 CC_RAIL_CONFIG_SETTLE_TIME"},
  {0x108A, "CC_RAIL_CONFIG_OFF_TIME",        E, Shape::kF32, Shape::kF32, "seconds", "2 CC_RAIL_CONFIG_OFF_TIME"},
  {0x108B, "CC_RAIL_CONFIG_SPEED",           Shape::kUnitsQuery, Shape::kUnitsF32, Shape::kUnitsF32, "speed",
   "2 CC_RAIL_CONFIG_STACK_SPEED"},
  {0x108C, "CC_RAIL_CONFIG_RAMP_TIME",       E, Shape::kF32, Shape::kF32, "seconds", "2 CC_RAIL_CONFIG_RAMP_TIME"},
  {0x108D, "CC_RAIL_CONFIG_DISTANCE_PER_REV", Shape::kUnitsQuery, Shape::kUnitsF32, Shape::kUnitsF32, "distance",
   "2 CC_RAIL_CONFIG_DISTANCE_PER_REV (read table: no units byte)"},
  {0x108E, "CC_RAIL_CONFIG_SHUTTER_DISABLE", E, Shape::kBool, Shape::kBool, "enabled", "2 CC_RAIL_CONFIG_SHUTTER_DISABLE"},
  {0x108F, "CC_RAIL_CONFIG_AUTO_RETURN",     E, Shape::kBool, Shape::kBool, "enabled",
   "2 CC_RAIL_CONFIG_AUTO_RETURN (read table garbled: bool in the request)"},
  {0x1090, "CC_RAIL_CONFIG_SAVE",            N, N, Shape::kU8, "slot", "2 CC_RAIL_CONFIG_SAVE"},
  {0x1091, "CC_RAIL_CONFIG_LOAD",            N, N, Shape::kU8, "slot", "2 CC_RAIL_CONFIG_LOAD"},
  {0x1092, "CC_RAIL_CONFIG_AXIS",            E, Shape::kU8, Shape::kU8, "axis", "2 CC_RAIL_CONFIG_AXIS"},
  {0x1093, "CC_RAIL_CONFIG_TIMELAPSE",       E, Shape::kF32, Shape::kF32, "seconds", "2 CC_RAIL_CONFIG_TIMELAPSE"},
  {0x1094, "CC_RAIL_CONFIG_PULSE_TIME",      E, Shape::kF32, Shape::kF32, "seconds", "2 CC_RAIL_CONFIG_PULSE_TIME"},
  {0x1095, "CC_RAIL_CONFIG_BACKLASH",        Shape::kUnitsQuery, Shape::kUnitsF32, Shape::kUnitsF32, "distance",
   "2 CC_RAIL_CONFIG_BACKLASH"},
  {0x1096, "CC_RAIL_CONFIG_HOLDING_TORQUE",  E, Shape::kU8, Shape::kU8, "level", "2 CC_RAIL_CONFIG_HOLDING_TORQUE"},
  {0x1097, "CC_RAIL_CONFIG_SPEED_MOVE",      Shape::kUnitsQuery, Shape::kUnitsF32, Shape::kUnitsF32, "speed",
   "2 CC_RAIL_CONFIG_MOVE_SPEED"},
  {0x1098, "CC_RAIL_CONFIG_POLARITY",        E, Shape::kBool, Shape::kBool, "reverse", "2 CC_RAIL_CONFIG_POLARITY"},
  // No table: one byte each, values from the enum comments.
  {0x1099, "CC_RAIL_CONFIG_IO_MODE",         E, Shape::kIoMode, Shape::kIoMode, "io-mode", "1.2 enum only (decided)"},
  {0x109A, "CC_RAIL_CONFIG_IO_DIR",          E, Shape::kDirection, Shape::kDirection, "io-dir", "1.2 enum only (decided)"},
  {0x109B, "CC_RAIL_CONFIG_ROTARY_BACKLASH", E, Shape::kF32, Shape::kF32, "degrees", "2 CC_RAIL_CONFIG_ROTARY_BACKLASH"},
  {0x109C, "CC_RAIL_CONFIG_ROTARY_RATIO",    E, Shape::kF32, Shape::kF32, "ratio", "2 CC_RAIL_CONFIG_ROTARY_RATIO"},
  {0x109D, "CC_RAIL_CONFIG_ROTARY_DEGREES",  E, Shape::kF32, Shape::kF32, "degrees", "2 CC_RAIL_CONFIG_ROTARY_DEGREES"},
  {0x109E, "CC_RAIL_CONFIG_GLOBAL_MODE",     E, Shape::kGlobalMode, Shape::kGlobalMode, "global-mode",
   "2 CC_RAIL_CONFIG_GLOBAL_MODE"},
  {0x109F, "CC_RAIL_CONFIG_TOFF_FINAL",      E, Shape::kBool, Shape::kBool, "enabled", "2 CC_RAIL_CONFIG_TOFF_FINAL"},
  {0x10A0, "CC_RAIL_CONFIG_SHUTTER",         E, Shape::kShutterSetting, Shape::kShutterSetting, "shutter",
   "2 CC_RAIL_CONFIG_SHUTTER"},

  {0x1100, "CC_RESET",                       N, N, E, "", "2 CC_RESET"},
  {0x1101, "CC_REFLASH",                     N, N, E, "", "2 CC_REFLASH"},
  {0x1102, "CC_SOFTWARE_STRING",             E, Shape::kText, N, "version", "2 CC_SOFTWARE_STRING"},
  {0x1103, "CC_SOFTWARE_ID",                 E, Shape::kU32, N, "id", "2 CC_SOFTWARE_ID"},
  {0x1104, "CC_HARDWARE_ID",                 E, Shape::kU32, N, "id", "2 CC_HARDWARE_ID"},
  {0x1105, "CC_BOOTLOADER_ID",               E, Shape::kU32, N, "id", "2 CC_BOOTLOADER_ID"},
  {0x1106, "CC_SOFTWARE_CHECKSUM",           E, Shape::kU32, N, "checksum", "2 CC_SOFTWARE_CHECKSUM"},
  {0x1107, "CC_SERIAL_NUMBER",               E, Shape::kU32, Shape::kU32, "serial", "2 CC_SERIAL_NUMBER"},
  {0x1108, "CC_NVM_ACCESS",                  Shape::kNvmRead, Shape::kU32, Shape::kNvmWrite, "value",
   "2 CC_NVM_ACCESS (registers 0-127; 1.1.17 says 0-31)"},
  // Unimplemented on the device: no layout, data carried as is.
  {0x1109, "CC_NAND_ACCESS",                 Shape::kRaw, Shape::kRaw, Shape::kRaw, "", "1.2 enum (unimplemented)"},
  {0x110A, "CC_NOR_ACCESS",                  Shape::kRaw, Shape::kRaw, Shape::kRaw, "", "1.2 enum (unimplemented)"},
  {0x110B, "CC_PING",                        Shape::kPingRequest, Shape::kPingReply, N, "",
   "2 CC_PING (table id 0x110A, enum 0x110B)"},
  {0x110C, "CC_LOG",                         Shape::kLogRequest, Shape::kText, N, "entry", "2 CC_LOG"},
  {0x110D, "CC_WIFI",                        Shape::kRaw, Shape::kRaw, Shape::kRaw, "", "1.2 enum only (no layout)"},
  {0x110E, "CC_CLOSE",                       N, N, E, "", "2 CC_CLOSE"},
  {0x1200, "CC_WAD",                         Shape::kRaw, Shape::kRaw, Shape::kRaw, "", "ERRATA 3.10 (no layout)"},
  {0x1600, "CC_MOTION_CONFIG",               N, N, Shape::kMotionConfig, "", "2 CC_MOTION_CONFIG; ERRATA 3.5"},
  {0x1601, "CC_MOTION_START",                N, N, Shape::kMotionStart, "", "2 CC_MOTION_START (3 bytes)"},
};
// clang-format on

constexpr bool TableSorted() {
  for (size_t i = 1; i < std::size(kCommands); ++i) {
    if (kCommands[i - 1].id >= kCommands[i].id) return false;
  }
  return true;
}
static_assert(TableSorted(), "FindCommand binary-searches the table");

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
  void operator()(const Empty&) {}
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
  }
  void operator()(const Raw& r) { w.Raw(r.data); }
  void operator()(const Unknown& u) { w.Raw(u.data); }
};

// ---------------------------------------------------------------------------
// Describe helpers
// ---------------------------------------------------------------------------
template <typename En>
std::string EnumText(En v, std::string_view name) {
  if (!name.empty()) return std::string(name);
  std::string out = "#";
  out += std::to_string(static_cast<uint32_t>(v));
  return out;
}

std::string QuoteText(const std::string& s) {
  std::string out = "\"";
  for (char ch : s) {
    const auto c = static_cast<unsigned char>(ch);
    if (c == '"' || c == '\\') {
      out.push_back('\\');
      out.push_back(ch);
    } else if (c >= 0x20 && c < 0x7F) {
      out.push_back(ch);
    } else {
      out += "\\x";
      out += Hex(c, 2).substr(2);
    }
  }
  out.push_back('"');
  return out;
}

std::string StatusBitsText(uint32_t bits) {
  if (bits == kRailStatusIdle) return "idle";
  std::string out;
  auto add = [&](std::string_view s) {
    if (!out.empty()) out.push_back('|');
    out += s;
  };
  if (bits & kRailStatusMoving) add("moving");
  if (bits & kRailStatusShutter) add("shutter");
  if (bits & kRailStatusUserAborted) add("user-aborted");
  const uint32_t rest = bits & ~(kRailStatusMoving | kRailStatusShutter | kRailStatusUserAborted);
  if (rest != 0) add(Hex(rest, 8));
  return out;
}

// "a..b" (built with += : GCC 12 at -O3 warns falsely on operator+ chains).
std::string Span(uint32_t a, uint32_t b) {
  std::string out = std::to_string(a);
  out += "..";
  out += std::to_string(b);
  return out;
}

std::string PointText(const BezierPoint& p) {
  std::string out = "(";
  out += FormatF32(p.x);
  out.push_back(',');
  out += FormatF32(p.y);
  out.push_back(')');
  return out;
}

struct PayloadDescriber {
  std::string_view field;
  std::string& out;

  void Put(std::string_view key, const std::string& value) {
    out.push_back(' ');
    out += key;
    out.push_back('=');
    out += value;
  }
  std::string_view Field(std::string_view fallback) const {
    return field.empty() ? fallback : field;
  }
  static std::string Bool(bool b) { return b ? "true" : "false"; }

  void operator()(const Empty&) {}
  void operator()(const UnitsQuery& q) {
    if (q.units) Put("units", EnumText(*q.units, UnitsName(*q.units)));
  }
  void operator()(const U8Value& v) { Put(Field("value"), std::to_string(v.value)); }
  void operator()(const BoolValue& v) { Put(Field("value"), Bool(v.value)); }
  void operator()(const U16Value& v) { Put(Field("value"), std::to_string(v.value)); }
  void operator()(const U32Value& v) {
    if (field == "step") {
      Put(field, std::to_string(v.value));
    } else {
      Put(Field("value"), Hex(v.value, 8));
    }
  }
  void operator()(const F32Value& v) { Put(Field("value"), FormatF32(v.value)); }
  void operator()(const UnitsF32& v) {
    Put("units", EnumText(v.units, UnitsName(v.units)));
    Put(Field("value"), FormatF32(v.value));
  }
  void operator()(const Text& t) {
    Put(Field("text"), QuoteText(t.text));
    if (!t.terminated) out += " unterminated";
  }
  void operator()(const EnumValue<Units>& v) {
    Put("units", EnumText(v.value, UnitsName(v.value)));
  }
  void operator()(const EnumValue<RailMode>& v) {
    Put("mode", EnumText(v.value, RailModeName(v.value)));
  }
  void operator()(const EnumValue<GlobalMode>& v) {
    Put("global-mode", EnumText(v.value, GlobalModeName(v.value)));
  }
  void operator()(const EnumValue<ShutterSetting>& v) {
    Put("shutter", EnumText(v.value, ShutterSettingName(v.value)));
  }
  void operator()(const EnumValue<IoMode>& v) {
    Put("io-mode", EnumText(v.value, IoModeName(v.value)));
  }
  void operator()(const EnumValue<Direction>& v) {
    Put(Field("dir"), EnumText(v.value, DirectionName(v.value)));
  }
  void operator()(const RailMove& m) {
    Put("dir", EnumText(m.direction, DirectionName(m.direction)));
    Put("units", EnumText(m.units, UnitsName(m.units)));
    Put("backlash", Bool(m.backlash));
    Put("distance", FormatF32(m.distance));
  }
  void operator()(const RailMoveAtSpeed& m) {
    Put("dir", EnumText(m.direction, DirectionName(m.direction)));
    Put("units", EnumText(m.units, UnitsName(m.units)));
    Put("distance", FormatF32(m.distance));
    Put("speed", FormatF32(m.speed_fraction));
  }
  void operator()(const ShutterFire& f) {
    Put("pulses", std::to_string(f.pulses));
    Put("on-s", FormatF32(f.on_time_s));
    Put("off-s", FormatF32(f.off_time_s));
  }
  void operator()(const RailStack& s) {
    const auto mode = static_cast<RailMode>(s.mode);
    Put("mode", s.mode <= 0xFF ? EnumText(mode, RailModeName(mode)) : EnumText(s.mode, {}));
    Put("steps", std::to_string(s.num_steps));
    Put("distance", std::to_string(s.distance));
    Put("pano", Span(s.pano_start_steps, s.pano_stop_steps));
    Put("x", Span(s.x_start, s.x_end));
    Put("y", Span(s.y_start, s.y_end));
    Put("z", Span(s.z_start, s.z_end));
    if (s.reserved) Put("reserved", Hex(*s.reserved, 8));
  }
  void operator()(const RailStatus& s) { Put("status", StatusBitsText(s.bits)); }
  void operator()(const NvmRead& n) { Put("reg", std::to_string(n.reg)); }
  void operator()(const NvmWrite& n) {
    Put("reg", std::to_string(n.reg));
    Put("value", Hex(n.value, 8));
  }
  void operator()(const PingRequest& p) { Put("value", Hex(p.value, 2)); }
  void operator()(const PingReply& p) {
    Put("value", Hex(p.value, 2));
    if (p.reserved != 0) Put("reserved", Hex(p.reserved, 2));
  }
  void operator()(const LogRequest& l) {
    Put("index", std::to_string(l.index));
    if (l.width != 1) Put("width", std::to_string(l.width));
  }
  void operator()(const MotionConfig& m) {
    Put("axis-type", EnumText(m.axis_type, AxisTypeName(m.axis_type)));
    const int used = UsedCurves(m);
    Put("curves", std::to_string(used));
    for (int c = 0; c < static_cast<int>(kBezierCurves); ++c) {
      const BezierCurve& curve = m.curves[static_cast<size_t>(c)];
      // Unused curves are shown only when they hold anything but zeros.
      if (c >= used && curve == BezierCurve{}) continue;
      std::string pts;
      for (const auto& p : curve.p) pts += PointText(p);
      std::string key = "c";
      key += std::to_string(c);
      Put(key, pts);
    }
  }
  void operator()(const MotionStart& m) {
    Put("x", Bool(m.x));
    Put("y", Bool(m.y));
    Put("z", Bool(m.z));
  }
  void operator()(const Raw& r) {
    if (!r.data.empty()) Put("data", wire::ToHex(r.data));
  }
  void operator()(const Unknown& u) {
    if (!u.data.empty()) Put("data", wire::ToHex(u.data));
  }
};

// The name shown for a typed message: a ping received at CC_PING's table id
// (NOR_ACCESS by the enum) is shown as "CC_PING(0x110a)".
std::string TypedName(uint16_t command, const Payload& payload) {
  if (command == kPingTableId && (std::holds_alternative<PingRequest>(payload) ||
                                  std::holds_alternative<PingReply>(payload))) {
    return "CC_PING(" + Hex(command, 4) + ")";
  }
  return CommandName(command);
}

void DescribeHeader(std::string& out, std::string name, std::string_view action, uint8_t axis,
                    bool sub_item, bool bit6) {
  out = std::move(name);
  out.push_back(' ');
  out += action;
  out += " axis=";
  out += AxisName(axis);
  if (sub_item) out += " item=2";
  if (bit6) out += " bit6=1";
}

std::string ActionText(Action a) {
  const std::string_view n = ActionName(a);
  if (!n.empty()) return std::string(n);
  return "action#" + std::to_string(static_cast<unsigned>(a));
}

bool Finite(F32 v) { return std::isfinite(v.value()); }

}  // namespace

// ---------------------------------------------------------------------------
// Checksum
// ---------------------------------------------------------------------------
std::string_view ChecksumAlgorithmName(ChecksumAlgorithm algorithm) {
  switch (algorithm) {
    case ChecksumAlgorithm::kNegatedSum:
      return "negated-sum";
    case ChecksumAlgorithm::kConstant69:
      return "constant-0x69";
    case ChecksumAlgorithm::kConstant00:
      return "constant-0x00";
  }
  return "?";
}

std::optional<ChecksumAlgorithm> ParseChecksumAlgorithm(std::string_view name) {
  for (auto a : {ChecksumAlgorithm::kNegatedSum, ChecksumAlgorithm::kConstant69,
                 ChecksumAlgorithm::kConstant00}) {
    if (ChecksumAlgorithmName(a) == name) return a;
  }
  return std::nullopt;
}

uint8_t ActionByte(const Packet& p) {
  return static_cast<uint8_t>((p.action & kActionMask) | ((p.axis << kAxisShift) & kAxisMask) |
                              (p.reserved_bit6 ? kReservedBit6 : 0) |
                              (p.sub_item ? kSubItemBit : 0));
}

uint8_t ComputeChecksum(ChecksumAlgorithm algorithm, const Packet& p) {
  switch (algorithm) {
    case ChecksumAlgorithm::kConstant69:
      return 0x69;
    case ChecksumAlgorithm::kConstant00:
      return 0x00;
    case ChecksumAlgorithm::kNegatedSum:
      break;
  }
  unsigned sum = (p.command >> 8) + (p.command & 0xFFu) + ActionByte(p) +
                 static_cast<unsigned>(p.data.size() & 0xFF);
  for (uint8_t b : p.data) sum += b;
  return static_cast<uint8_t>(0x100u - (sum & 0xFFu));
}

void Seal(Packet& p, ChecksumAlgorithm algorithm) { p.checksum = ComputeChecksum(algorithm, p); }

bool ChecksumMatches(const Packet& p, ChecksumAlgorithm algorithm) {
  return p.checksum == ComputeChecksum(algorithm, p);
}

// ---------------------------------------------------------------------------
// Framing
// ---------------------------------------------------------------------------
bool EncodePacket(const Packet& p, Bytes& out) {
  if (p.data.size() > kMaxDataBytes) return false;
  Writer w(out);
  w.U8(p.from_device ? kSyncDevice : kSyncHost);
  w.U16Be(p.command);
  w.U8(ActionByte(p));
  w.U8(static_cast<uint8_t>(p.data.size()));
  w.Raw(p.data);
  w.U8(p.checksum);
  return true;
}

namespace {
Packet PacketFromFrame(const uint8_t* f, size_t data_len) {
  Packet p;
  p.from_device = f[kOffsetSync] == kSyncDevice;
  p.command = static_cast<uint16_t>((f[kOffsetCommand] << 8) | f[kOffsetCommand + 1]);
  const uint8_t a = f[kOffsetAction];
  p.action = a & kActionMask;
  p.axis = static_cast<uint8_t>((a & kAxisMask) >> kAxisShift);
  p.reserved_bit6 = (a & kReservedBit6) != 0;
  p.sub_item = (a & kSubItemBit) != 0;
  p.data.assign(f + kOffsetData, f + kOffsetData + data_len);
  p.checksum = f[kOffsetData + data_len];
  return p;
}
}  // namespace

Result<Packet> DecodePacket(ByteView frame) {
  if (frame.empty()) return DecodeError{DecodeError::Kind::kTruncated, 0, "empty frame"};
  if (frame[0] != kSyncHost && frame[0] != kSyncDevice) {
    return DecodeError{DecodeError::Kind::kBadValue, 0,
                       "sync byte " + Hex(frame[0], 2) + " is neither 0x55 nor 0xaa"};
  }
  if (frame.size() < kMinPacketBytes) {
    return DecodeError{DecodeError::Kind::kTruncated, frame.size(),
                       "a packet has at least 6 bytes"};
  }
  const size_t data_len = frame[kOffsetLength];
  const size_t total = kMinPacketBytes + data_len;
  if (frame.size() < total) {
    return DecodeError{DecodeError::Kind::kTruncated, frame.size(),
                       "length byte announces " + std::to_string(data_len) + " data bytes"};
  }
  if (frame.size() > total) {
    return DecodeError{DecodeError::Kind::kTrailing, total,
                       std::to_string(frame.size() - total) + " byte(s) after the checksum"};
  }
  return PacketFromFrame(frame.data(), data_len);
}

PacketDecoder::PacketDecoder(bool from_device, ChecksumAlgorithm checksum)
    : sync_(from_device ? kSyncDevice : kSyncHost), checksum_(checksum) {}

size_t PacketDecoder::Feed(ByteView bytes, std::vector<DecodedPacket>& out) {
  const size_t before = out.size();
  const uint8_t* in = bytes.data();
  const size_t n = bytes.size();
  size_t i = 0;
  while (i < n) {
    if (len_ == 0) {
      const void* hit = std::memchr(in + i, sync_, n - i);
      if (hit == nullptr) {
        skipped_pending_ += n - i;
        skipped_total_ += n - i;
        break;
      }
      const auto pos = static_cast<size_t>(static_cast<const uint8_t*>(hit) - in);
      skipped_pending_ += pos - i;
      skipped_total_ += pos - i;
      buf_[0] = sync_;
      len_ = 1;
      i = pos + 1;
      continue;
    }
    const size_t need = len_ < kHeaderBytes ? kHeaderBytes : kMinPacketBytes + buf_[kOffsetLength];
    const size_t take = std::min(need - len_, n - i);
    std::memcpy(buf_.data() + len_, in + i, take);
    len_ += take;
    i += take;
    if (len_ >= kHeaderBytes && len_ == kMinPacketBytes + buf_[kOffsetLength]) Complete(out);
  }
  return out.size() - before;
}

void PacketDecoder::Complete(std::vector<DecodedPacket>& out) {
  DecodedPacket d;
  d.packet = PacketFromFrame(buf_.data(), buf_[kOffsetLength]);
  d.expected_checksum = ComputeChecksum(checksum_, d.packet);
  d.checksum_ok = d.expected_checksum == d.packet.checksum;
  d.skipped_before = skipped_pending_;
  out.push_back(std::move(d));
  skipped_pending_ = 0;
  len_ = 0;
  ++packets_total_;
}

size_t PacketDecoder::Flush() {
  const size_t dropped = len_;
  skipped_pending_ += dropped;
  skipped_total_ += dropped;
  len_ = 0;
  return dropped;
}

Result<std::vector<Bytes>> SplitForWifi(ByteView stream, size_t max_bytes) {
  std::vector<Bytes> writes;
  Bytes current;
  size_t pos = 0;
  while (pos < stream.size()) {
    if (stream[pos] != kSyncHost && stream[pos] != kSyncDevice) {
      return DecodeError{DecodeError::Kind::kBadValue, pos, "no sync byte where a packet starts"};
    }
    if (stream.size() - pos < kHeaderBytes) {
      return DecodeError{DecodeError::Kind::kTruncated, stream.size(), "partial packet header"};
    }
    const size_t total = kMinPacketBytes + stream[pos + kOffsetLength];
    if (stream.size() - pos < total) {
      return DecodeError{DecodeError::Kind::kTruncated, stream.size(), "partial packet"};
    }
    if (total > max_bytes) {
      return DecodeError{DecodeError::Kind::kBadLength, pos,
                         "a " + std::to_string(total) + "-byte packet exceeds the " +
                             std::to_string(max_bytes) + "-byte write limit"};
    }
    if (current.size() + total > max_bytes) {
      writes.push_back(std::move(current));
      current.clear();
    }
    current.insert(current.end(), stream.begin() + static_cast<std::ptrdiff_t>(pos),
                   stream.begin() + static_cast<std::ptrdiff_t>(pos + total));
    pos += total;
  }
  if (!current.empty()) writes.push_back(std::move(current));
  return writes;
}

// ---------------------------------------------------------------------------
// Command table access
// ---------------------------------------------------------------------------
const CommandInfo* FindCommand(uint16_t id) {
  const auto* it = std::lower_bound(std::begin(kCommands), std::end(kCommands), id,
                                    [](const CommandInfo& c, uint16_t v) { return c.id < v; });
  if (it == std::end(kCommands) || it->id != id) return nullptr;
  return it;
}

std::span<const CommandInfo> AllCommands() { return kCommands; }

std::string CommandName(uint16_t id) {
  if (const CommandInfo* c = FindCommand(id)) return std::string(c->name);
  return "UNKNOWN(" + Hex(id, 4) + ")";
}

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
// Names
// ---------------------------------------------------------------------------
std::string_view ActionName(Action a) {
  switch (a) {
    case Action::kRead:
      return "read";
    case Action::kWrite:
      return "write";
    case Action::kRspOk:
      return "ok";
    case Action::kBadParam:
      return "bad-param";
    case Action::kUnsupportedAction:
      return "unsupported-action";
    case Action::kUnsupportedCmd:
      return "unsupported-cmd";
    case Action::kFailed:
      return "failed";
    case Action::kNotEmpty:
      return "not-empty";
    case Action::kBusy:
      return "busy";
  }
  return "";
}

std::string_view UnitsName(Units u) {
  switch (u) {
    case Units::kMils:
      return "mils";
    case Units::kMm:
      return "mm";
    case Units::kSteps:
      return "steps";
    case Units::kDegrees:
      return "deg";
  }
  return "";
}

std::string_view DirectionName(Direction d) {
  switch (d) {
    case Direction::kForward:
      return "fwd";
    case Direction::kBack:
      return "back";
  }
  return "";
}

std::string_view RailModeName(RailMode m) {
  switch (m) {
    case RailMode::kAutoStep:
      return "auto-step";
    case RailMode::kAutoDist:
      return "auto-dist";
    case RailMode::kTotalDistance:
      return "total-distance";
    case RailMode::kDistancePerStep:
      return "distance-per-step";
    case RailMode::kManual:
      return "manual";
    case RailMode::kContinuous:
      return "continuous";
    case RailMode::kManualDistance:
      return "manual-distance";
    case RailMode::kRotary:
      return "rotary";
  }
  return "";
}

std::string_view GlobalModeName(GlobalMode m) {
  switch (m) {
    case GlobalMode::kAdvanced:
      return "advanced";
    case GlobalMode::kStackPano2x:
      return "stack-pano-2x";
    case GlobalMode::kStackPano3x:
      return "stack-pano-3x";
    case GlobalMode::kStackRotate2x:
      return "stack-rotate-2x";
    case GlobalMode::kStackRotate3x:
      return "stack-rotate-3x";
    case GlobalMode::kPano1x:
      return "pano-1x";
    case GlobalMode::kPano2x:
      return "pano-2x";
    case GlobalMode::kPano1x360:
      return "pano-1x-360";
    case GlobalMode::kMotionDfMoco:
      return "motion-dfmoco";
    case GlobalMode::kMotionReserved:
      return "motion-reserved";
    case GlobalMode::kMotionContinuous:
      return "motion-continuous";
    case GlobalMode::kMotionContTimelapse:
      return "motion-cont-timelapse";
    case GlobalMode::kMotionSms:
      return "motion-sms";
  }
  return "";
}

std::string_view ShutterSettingName(ShutterSetting s) {
  switch (s) {
    case ShutterSetting::kNone:
      return "none";
    case ShutterSetting::kShutter1:
      return "1";
    case ShutterSetting::kShutter2:
      return "2";
    case ShutterSetting::kBoth:
      return "both";
  }
  return "";
}

std::string_view IoModeName(IoMode m) {
  switch (m) {
    case IoMode::kNormal:
      return "normal";
    case IoMode::kMaster:
      return "master";
    case IoMode::kSlave:
      return "slave";
  }
  return "";
}

std::string_view AxisTypeName(AxisType t) {
  switch (t) {
    case AxisType::kSlider:
      return "slider";
    case AxisType::kRail:
      return "rail";
    case AxisType::kRotary:
      return "rotary";
  }
  return "";
}

std::string AxisName(uint8_t axis) {
  switch (axis) {
    case kAxisX:
      return "X";
    case kAxisY:
      return "Y";
    case kAxisZ:
      return "Z";
    default:
      return std::to_string(axis);
  }
}

std::string FormatF32(F32 v) {
  char buf[32];
  const auto res = std::to_chars(buf, buf + sizeof(buf), v.value());
  return std::string(buf, res.ptr);
}

bool IsValid(Direction d) { return static_cast<uint8_t>(d) < kDirectionMax; }
bool IsValid(Units u) { return static_cast<uint8_t>(u) < kUnitsMaxSpec; }
bool IsValid(GlobalMode m) { return static_cast<uint8_t>(m) < kGlobalModeMax; }
bool IsValid(ShutterSetting s) { return static_cast<uint8_t>(s) < kShutterSettingMax; }
bool IsValid(IoMode m) { return static_cast<uint8_t>(m) < kIoModeMax; }
bool IsValid(AxisType t) { return static_cast<uint32_t>(t) < kAxisTypeMax; }

std::string Describe(const HostCommand& c) {
  std::string out;
  DescribeHeader(out, TypedName(c.command, c.payload), ActionText(c.action), c.axis, c.sub_item,
                 c.reserved_bit6);
  const CommandInfo* info = FindCommand(c.command);
  std::visit(PayloadDescriber{info ? info->field : std::string_view{}, out}, c.payload);
  return out;
}

std::string Describe(const DeviceReply& r) {
  std::string out;
  DescribeHeader(out, TypedName(r.command, r.payload), ActionText(r.status), r.axis, r.sub_item,
                 r.reserved_bit6);
  const CommandInfo* info = FindCommand(r.command);
  std::visit(PayloadDescriber{info ? info->field : std::string_view{}, out}, r.payload);
  return out;
}

std::string Describe(const Packet& p) {
  std::string out;
  DescribeHeader(out, CommandName(p.command), ActionText(static_cast<Action>(p.action)), p.axis,
                 p.sub_item, p.reserved_bit6);
  if (!p.data.empty()) {
    out += " data=";
    out += wire::ToHex(p.data);
  }
  return out;
}

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
