// The one-line text of DMC v2 messages for transcripts and logs
// (dmc-v2-protocol.txt "Message Types": each MSG_* section's fields, named
// as the spec names them), apart from the codec in dmc.cpp and dmc_layouts.cpp.
#include <cstdio>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>

#include "base/format.h"
#include "wire/dmc.h"

namespace moco::dmc {
namespace {

class Line {
 public:
  explicit Line(std::string head) : s_(std::move(head)) {}
  template <class T>
  Line& Num(const char* key, T v) {
    s_ += ' ';
    s_ += key;
    s_ += '=';
    s_ += std::to_string(v);
    return *this;
  }
  Line& Hex(const char* key, uint32_t v, int digits) {
    s_ += ' ';
    s_ += key;
    s_ += '=';
    s_ += base::Hex(v, digits);
    return *this;
  }
  Line& Text(const char* key, std::string_view v) {
    s_ += ' ';
    s_ += key;
    s_ += '=';
    s_ += v;
    return *this;
  }
  template <class Seq>
  Line& List(const char* key, const Seq& seq) {
    s_ += ' ';
    s_ += key;
    s_ += "=[";
    bool first = true;
    for (const auto& v : seq) {
      if (!first) s_ += ',';
      first = false;
      s_ += std::to_string(v);
    }
    s_ += ']';
    return *this;
  }
  std::string& str() { return s_; }

 private:
  std::string s_;
};

std::string Name(MsgType t) { return TypeName(ToWire(t)); }

std::string Text(const Ack& m) {
  Line l("ACK " + TypeName(m.type));
  l.Text("code", AckCodeName(m.code));
  if (m.width == AckWidth::k32) l.Num("code_bytes", 4);
  return l.str();
}
std::string Text(const Unknown& m) {
  return Line("UNKNOWN").Hex("type", m.type, 4).Text("data", wire::ToHex(m.data)).str();
}
template <class T>
requires(std::is_empty_v<T>) std::string Text(const T&) { return Name(T::kType); }
std::string Text(const VirtAimPoint& m) {
  return Line(Name(m.kType))
      .Num("enable", m.enable)
      .Num("x", m.x_x1000)
      .Num("y", m.y_x1000)
      .Num("z", m.z_x1000)
      .str();
}
std::string Text(const Dmx& m) {
  return Line(Name(m.kType))
      .Num("ramp", m.ramp)
      .Num("start_channel", m.start_channel)
      .List("values", m.values)
      .str();
}
std::string Text(const GioOut& m) {
  return Line(Name(m.kType)).Hex("triggers", m.triggers, 8).str();
}
std::string Text(const GioCam& m) { return Line(Name(m.kType)).Hex("flags", m.flags, 8).str(); }
std::string Text(const MotorMove& m) {
  return Line(Name(m.kType)).Num("motor", m.motor).Num("position", m.position_steps).str();
}
std::string Text(const MotorStop& m) { return Line(Name(m.kType)).Num("motor", m.motor).str(); }
std::string Text(const MotorStopAll& m) {
  Line l(Name(m.kType));
  if (m.flags) l.Hex("flags", *m.flags, 8);
  return l.str();
}
std::string Text(const MotorResetPosition& m) {
  return Line(Name(m.kType)).Num("motor", m.motor).Num("position", m.position_steps).str();
}
std::string Text(const MotorJog& m) {
  return Line(Name(m.kType))
      .Num("motor", m.motor)
      .Num("speed", m.speed)
      .Num("destination", m.destination_steps)
      .str();
}
std::string Text(const MotorConfigure& m) {
  return Line(Name(m.kType)).Num("motor", m.motor).Hex("flags", m.flags, 2).str();
}
std::string Text(const MotorSetSpeed& m) {
  return Line(Name(m.kType))
      .Num("motor", m.motor)
      .Num("max_velocity", m.max_velocity_steps_per_s)
      .Num("max_accel", m.max_accel_steps_per_s2)
      .str();
}
std::string Text(const MotorSetLimits& m) {
  return Line(Name(m.kType))
      .Num("motor", m.motor)
      .Num("lower_enable", m.lower_enable)
      .Num("lower", m.lower_limit_steps)
      .Num("upper_enable", m.upper_enable)
      .Num("upper", m.upper_limit_steps)
      .Hex("hw_set", m.hw_set, 2)
      .str();
}
std::string Text(const RtUploadMoveBegin& m) {
  return Line(Name(m.kType)).Num("start_frame", m.start_frame).Num("end_frame", m.end_frame).str();
}
std::string Text(const RtUploadMoveAxis& m) {
  return Line(Name(m.kType))
      .Num("motor", m.motor)
      .Num("start_index", m.start_index)
      .Num("last", m.last_set ? 1 : 0)
      .List("positions", m.positions_steps)
      .str();
}
std::string Text(const RtUploadMoveDmx& m) {
  return Line(Name(m.kType))
      .Num("channel", m.channel)
      .Num("start_index", m.start_index)
      .Num("last", m.last_set ? 1 : 0)
      .List("levels", m.levels)
      .str();
}
std::string Text(const RtUploadMoveTriggers& m) {
  Line l(Name(m.kType));
  l.Hex("mask", m.mask, 8);
  std::string points = "[";
  for (size_t i = 0; i < m.points.size(); ++i) {
    if (i != 0) points += ',';
    points += std::to_string(m.points[i].frame_index) + ':' + base::Hex(m.points[i].values, 8);
  }
  points += ']';
  l.Text("points", points);
  return l.str();
}
std::string Text(const RtPositionFrame& m) {
  return Line(Name(m.kType)).Num("frame", m.frame).str();
}
std::string Text(const RtRunMove& m) {
  Line l(Name(m.kType));
  l.Num("fps", m.fps_x1000)
      .Num("start_frame", m.start_frame)
      .Num("end_frame", m.end_frame)
      .Num("preroll_ms", m.preroll_ms)
      .Num("postroll_ms", m.postroll_ms)
      .Num("sync_dmx", m.sync_dmx)
      .Hex("bloop_outputs", m.bloop_outputs, 8)
      .Num("bloop_dmx_channel", m.bloop_dmx_channel)
      .Num("bloop_ms", m.bloop_time_ms);
  if (m.flags) {
    l.Hex("flags", *m.flags, 4);
    if (m.camera_open_angle_deg) {
      l.Num("open_angle", *m.camera_open_angle_deg);
      if (m.camera_close_angle_deg) l.Num("close_angle", *m.camera_close_angle_deg);
    }
  }
  return l.str();
}
std::string MotorsText(const std::vector<BlurMotor>& motors) {
  std::string s = "[";
  for (size_t i = 0; i < motors.size(); ++i) {
    if (i != 0) s += ',';
    s += std::to_string(motors[i].motor) + ':' + std::to_string(motors[i].pos_a_steps) + ':' +
         std::to_string(motors[i].pos_b_steps);
  }
  return s + ']';
}
std::string Text(const RtShootFrame& m) {
  return Line(Name(m.kType))
      .Num("frame", m.frame)
      .Num("direction", m.direction)
      .Num("exposure_ms", m.exposure_ms)
      .Num("blur", m.blur_percent_x10)
      .Text("motors", MotorsText(m.motors))
      .str();
}
std::string Text(const RtShootFrame2& m) {
  return Line(Name(m.kType))
      .Num("frame", m.frame)
      .Num("exposure_ms", m.exposure_ms)
      .Num("open_angle", m.open_angle_deg)
      .Num("close_angle", m.close_angle_deg)
      .Text("motors", MotorsText(m.motors))
      .str();
}
std::string Text(const RtJogAll& m) {
  return Line(Name(m.kType)).Num("fps", m.fps_x1000).Num("destination", m.destination_frame).str();
}
std::string SetupText(const VirtAxisSetup& a) {
  return std::to_string(a.motor) + ':' + std::to_string(a.steps_per_unit) + ':' +
         std::to_string(a.position_x100000);
}
std::string Text(const VirtConfig& m) {
  Line l(Name(m.kType));
  l.Num("type", m.rig_type());
  std::visit(wire::Overloaded{
                 [](const VirtRigNone&) {},
                 [&l](const VirtRigBoomSwingTrack& r) {
                   l.Text("boom", SetupText(r.boom))
                       .Text("swing", SetupText(r.swing))
                       .Text("track", SetupText(r.track))
                       .Text("pan", SetupText(r.pan))
                       .Text("tilt", SetupText(r.tilt))
                       .Text("roll", SetupText(r.roll))
                       .Num("boom_length", r.boom_length_x1000)
                       .Num("boom_ext", r.boom_ext_x1000)
                       .Text("nodal", std::to_string(r.nodal_x_x1000) + ',' +
                                          std::to_string(r.nodal_y_x1000) + ',' +
                                          std::to_string(r.nodal_z_x1000));
                   if (r.compensation) l.List("compensation", *r.compensation);
                   if (r.safe_distance_x1000) l.Num("safe_distance", *r.safe_distance_x1000);
                 },
                 [&l](const VirtRigSwingPan& r) {
                   l.Text("swing", std::to_string(r.swing.motor) + ':' +
                                       std::to_string(r.swing.steps_per_unit))
                       .Text("pan", std::to_string(r.pan.motor) + ':' +
                                        std::to_string(r.pan.steps_per_unit));
                 },
                 [&l](const VirtRigRaw& r) { l.Text("data", wire::ToHex(r.data)); },
             },
             m.rig);
  return l.str();
}
std::string Text(const VirtMove& m) {
  return Line(Name(m.kType)).Num("axis", m.axis).Num("position", m.position_x100000).str();
}
std::string Text(const VirtStop& m) { return Line(Name(m.kType)).Num("axis", m.axis).str(); }
std::string Text(const VirtJog& m) {
  return Line(Name(m.kType))
      .Num("axis", m.axis)
      .Num("speed", m.speed)
      .Num("destination", m.destination_x100000)
      .str();
}
std::string Text(const VirtJogOnLine& m) {
  return Line(Name(m.kType)).Num("axis", m.axis).Num("speed", m.speed).str();
}

std::string Quoted(const std::string& s) {
  std::string out = "\"";
  for (unsigned char c : s) {
    if (c >= 0x20 && c < 0x7f && c != '"' && c != '\\') {
      out += static_cast<char>(c);
    } else {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\x%02x", c);
      out += buf;
    }
  }
  return out + '"';
}
std::string Text(const HiResponse& m) {
  Line l(Name(m.kType));
  l.Text("name", Quoted(m.NameText()))
      .Text("fw", std::to_string(m.fw_major) + '.' + std::to_string(m.fw_minor) + '.' +
                      std::to_string(m.fw_rev))
      .Num("motors", m.motor_count)
      .Num("dmx", m.dmx_count)
      .Num("gio_out", m.gio_out_count)
      .Num("gio_in", m.gio_in_count)
      .Num("hw_limits", m.hw_limit_count)
      .Num("upload_frames", m.upload_frame_count)
      .Hex("caps", m.capabilities, 8);
  if (m.protocol_version) l.Num("protocol", *m.protocol_version);
  return l.str();
}
std::string Text(const MotorStatusResponse& m) {
  return Line(Name(m.kType)).Hex("moving", m.moving_bits, 8).Num("dmx", m.dmx_adjusting).str();
}
std::string Text(const MotorMoveResponse& m) {
  return Line(Name(m.kType)).Num("moving", m.moving).str();
}
std::string Text(const MotorPositionReport& m) {
  return Line(Name(m.kType))
      .Num("time", m.move_time_x1000)
      .List("positions", m.positions_steps)
      .str();
}
std::string Text(const GioInReport& m) {
  return Line(Name(m.kType)).Hex("triggers", m.triggers, 8).str();
}
std::string Text(const MotorHardStop& m) {
  Line l(Name(m.kType));
  l.Text("reason", HardStopReasonName(m.reason));
  if (m.motor) l.Num("motor", *m.motor);
  return l.str();
}
std::string Text(const VirtPositionReport& m) {
  Line l(Name(m.kType));
  l.Num("track", m.track_x100000)
      .Num("ew", m.ew_x100000)
      .Num("ns", m.ns_x100000)
      .Num("pan", m.pan_x100000)
      .Num("tilt", m.tilt_x100000)
      .Num("roll", m.roll_x100000);
  if (m.aim) {
    l.Num("aim_enabled", m.aim->enabled)
        .Text("aim", std::to_string(m.aim->x_x1000) + ',' + std::to_string(m.aim->y_x1000) + ',' +
                         std::to_string(m.aim->z_x1000));
  }
  return l.str();
}

}  // namespace

std::string Describe(const HostMessage& m) {
  return std::visit([](const auto& x) { return Text(x); }, m);
}
std::string Describe(const DeviceMessage& m) {
  return std::visit([](const auto& x) { return Text(x); }, m);
}

}  // namespace moco::dmc
