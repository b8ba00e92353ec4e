// Names and one-line descriptions of StackShot messages for transcripts
// and logs (stackshot-protocol.txt section 2: each command's fields, named
// as its table names them), apart from the codec in stackshot.cpp.
#include <charconv>
#include <cmath>
#include <string>
#include <string_view>

#include "base/format.h"
#include "wire/stackshot.h"

namespace moco::stackshot {
namespace {

// ---------------------------------------------------------------------------
// Describe helpers
// ---------------------------------------------------------------------------
using base::Hex;

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

}  // namespace

std::string CommandName(uint16_t id) {
  if (const CommandInfo* c = FindCommand(id)) return std::string(c->name);
  return "UNKNOWN(" + Hex(id, 4) + ")";
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

}  // namespace moco::stackshot
