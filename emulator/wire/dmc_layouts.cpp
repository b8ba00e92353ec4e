// DMC v2 message layouts (dmc-v2-protocol.txt "Message Types", each MSG_*
// section's Request Data / Response Data tables; ERRATA dmc 1.3-1.10): one Put
// (encode) and one Get (decode) per message struct, host requests first, then
// device messages, declared in dmc_layouts.h. Which struct a frame's type
// reads as, and the ACK form, are chosen by the dispatch in dmc.cpp.
#include "wire/dmc_layouts.h"

#include <vector>

namespace moco::dmc::layout {
namespace {

using Kind = DecodeError::Kind;

void StartIndexOut(Writer& w, uint32_t index, bool last) {
  w.U32Le((index & kStartIndexMask) | (last ? kLastSetFlag : 0u));
}

}  // namespace

// --- Layouts: Put (encode) and Get (decode) per struct ----------------------------------

void Put(Writer& w, const Ack& m) {
  if (m.width == AckWidth::k32) {
    w.U32Le(m.code);
  } else {
    w.U16Le(static_cast<uint16_t>(m.code));
  }
}

void Put(Writer& w, const Unknown& m) { w.Raw(m.data); }

void Put(Writer& w, const VirtAimPoint& m) {
  w.U8(m.enable);
  w.I32Le(m.x_x1000);
  w.I32Le(m.y_x1000);
  w.I32Le(m.z_x1000);
}
void Get(Fields& f, VirtAimPoint& m) {
  f.U8(m.enable, "ENABLE").I32(m.x_x1000, "AIM-X").I32(m.y_x1000, "AIM-Y").I32(m.z_x1000, "AIM-Z");
}

void Put(Writer& w, const Dmx& m) {
  w.U8(m.ramp);
  w.U16Le(m.start_channel);
  w.Raw(m.values);
}
void Get(Fields& f, Dmx& m) {
  f.U8(m.ramp, "RAMP").U16(m.start_channel, "START CHANNEL").NotEmpty("LIGHT VALUE");
  if (f.ok()) {
    const ByteView rest = f.reader().Rest();
    m.values.assign(rest.begin(), rest.end());
  }
}

void Put(Writer& w, const GioOut& m) { w.U32Le(m.triggers); }
void Get(Fields& f, GioOut& m) { f.U32(m.triggers, "TRIGGERS"); }

void Put(Writer& w, const GioCam& m) { w.U32Le(m.flags); }
void Get(Fields& f, GioCam& m) { f.U32(m.flags, "TRIGGERS"); }

void Put(Writer& w, const MotorMove& m) {
  w.U8(m.motor);
  w.I32Le(m.position_steps);
}
void Get(Fields& f, MotorMove& m) { f.U8(m.motor, "MOTOR").I32(m.position_steps, "POSITION"); }

void Put(Writer& w, const MotorStop& m) { w.U8(m.motor); }
void Get(Fields& f, MotorStop& m) { f.U8(m.motor, "MOTOR"); }

void Put(Writer& w, const MotorStopAll& m) {
  if (m.flags) w.U32Le(*m.flags);
}
void Get(Fields& f, MotorStopAll& m) {
  if (!f.Has(4)) return;
  uint32_t flags = 0;
  f.U32(flags, "Flags");
  if (f.ok()) m.flags = flags;
}

void Put(Writer& w, const MotorResetPosition& m) {
  w.U8(m.motor);
  w.I32Le(m.position_steps);
}
void Get(Fields& f, MotorResetPosition& m) {
  f.U8(m.motor, "MOTOR").I32(m.position_steps, "POSITION");
}

void Put(Writer& w, const MotorJog& m) {
  w.U8(m.motor);
  w.U16Le(m.speed);
  w.I32Le(m.destination_steps);
}
void Get(Fields& f, MotorJog& m) {
  f.U8(m.motor, "MOTOR").U16(m.speed, "SPEED").I32(m.destination_steps, "DESTINATION");
}

void Put(Writer& w, const MotorConfigure& m) {
  w.U8(m.motor);
  w.U8(m.flags);
}
void Get(Fields& f, MotorConfigure& m) { f.U8(m.motor, "MOTOR").U8(m.flags, "FLAGS"); }

void Put(Writer& w, const MotorSetSpeed& m) {
  w.U8(m.motor);
  w.U32Le(m.max_velocity_steps_per_s);
  w.U32Le(m.max_accel_steps_per_s2);
}
void Get(Fields& f, MotorSetSpeed& m) {
  f.U8(m.motor, "MOTOR")
      .U32(m.max_velocity_steps_per_s, "MAX VELOCITY")
      .U32(m.max_accel_steps_per_s2, "MAX ACCEL");
}

void Put(Writer& w, const MotorSetLimits& m) {
  w.U8(m.motor);
  w.U8(m.lower_enable);
  w.I32Le(m.lower_limit_steps);
  w.U8(m.upper_enable);
  w.I32Le(m.upper_limit_steps);
  w.U8(m.hw_set);
}
void Get(Fields& f, MotorSetLimits& m) {
  f.U8(m.motor, "MOTOR")
      .U8(m.lower_enable, "LOWER ENABLE")
      .I32(m.lower_limit_steps, "LOWER LIMIT")
      .U8(m.upper_enable, "UPPER ENABLE")
      .I32(m.upper_limit_steps, "UPPER LIMIT")
      .U8(m.hw_set, "HW SET");
}

void Put(Writer& w, const RtUploadMoveBegin& m) {
  w.U32Le(m.start_frame);
  w.U32Le(m.end_frame);
}
void Get(Fields& f, RtUploadMoveBegin& m) {
  f.U32(m.start_frame, "START FRAME").U32(m.end_frame, "END FRAME");
}

void Put(Writer& w, const RtUploadMoveAxis& m) {
  w.U8(m.motor);
  StartIndexOut(w, m.start_index, m.last_set);
  for (int32_t p : m.positions_steps) w.I32Le(p);
}
void Get(Fields& f, RtUploadMoveAxis& m) {
  f.U8(m.motor, "MOTOR")
      .StartIndex(m.start_index, m.last_set, "START INDEX")
      .NotEmpty("POSITION", 4);
  m.positions_steps.reserve(f.reader().remaining() / 4);
  while (f.ok() && f.Has(4)) {
    int32_t p = 0;
    f.I32(p, "POSITION");
    if (f.ok()) m.positions_steps.push_back(p);
  }
}

void Put(Writer& w, const RtUploadMoveDmx& m) {
  w.U16Le(m.channel);
  StartIndexOut(w, m.start_index, m.last_set);
  w.Raw(m.levels);
}
void Get(Fields& f, RtUploadMoveDmx& m) {
  f.U16(m.channel, "CHANNEL")
      .StartIndex(m.start_index, m.last_set, "START INDEX")
      .NotEmpty("LEVEL");
  if (f.ok()) {
    const ByteView rest = f.reader().Rest();
    m.levels.assign(rest.begin(), rest.end());
  }
}

void Put(Writer& w, const RtUploadMoveTriggers& m) {
  w.U32Le(m.mask);
  for (const TriggerPoint& p : m.points) {
    w.U32Le(p.frame_index);
    w.U32Le(p.values);
  }
}
void Get(Fields& f, RtUploadMoveTriggers& m) {
  f.U32(m.mask, "MASK");
  m.points.reserve(f.reader().remaining() / 8);
  while (f.ok() && f.Has(8)) {
    TriggerPoint p;
    f.U32(p.frame_index, "FRAME").U32(p.values, "VALUES");
    if (f.ok()) m.points.push_back(p);
  }
}

void Put(Writer& w, const RtPositionFrame& m) { w.U32Le(m.frame); }
void Get(Fields& f, RtPositionFrame& m) { f.U32(m.frame, "FRAME"); }

void Put(Writer& w, const RtRunMove& m) {
  w.U32Le(m.fps_x1000);
  w.U32Le(m.start_frame);
  w.U32Le(m.end_frame);
  w.U32Le(m.preroll_ms);
  w.U32Le(m.postroll_ms);
  w.U8(m.sync_dmx);
  w.U32Le(m.bloop_outputs);
  w.U16Le(m.bloop_dmx_channel);
  w.U16Le(m.bloop_time_ms);
  // Each optional field only with all before it (ERRATA 1.7).
  if (!m.flags) return;
  w.U16Le(*m.flags);
  if (!m.camera_open_angle_deg) return;
  w.U16Le(*m.camera_open_angle_deg);
  if (!m.camera_close_angle_deg) return;
  w.U16Le(*m.camera_close_angle_deg);
}
void Get(Fields& f, RtRunMove& m) {
  f.U32(m.fps_x1000, "FPS")
      .U32(m.start_frame, "START FRAME")
      .U32(m.end_frame, "END FRAME")
      .U32(m.preroll_ms, "PRE-ROLL TIME")
      .U32(m.postroll_ms, "POST-ROLL TIME")
      .U8(m.sync_dmx, "SYNC DMX")
      .U32(m.bloop_outputs, "BLOOP LOCATION")
      .U16(m.bloop_dmx_channel, "BLOOP DMX CHANNEL")
      .U16(m.bloop_time_ms, "BLOOP TIME")
      .Optional(m.flags, "FLAGS")
      .Optional(m.camera_open_angle_deg, "CAMERA OPEN ANGLE")
      .Optional(m.camera_close_angle_deg, "CAMERA CLOSE ANGLE");
}

namespace {

void PutMotors(Writer& w, const std::vector<BlurMotor>& motors) {
  for (const BlurMotor& b : motors) {
    w.U8(b.motor);
    w.I32Le(b.pos_a_steps);
    w.I32Le(b.pos_b_steps);
  }
}
void GetMotors(Fields& f, std::vector<BlurMotor>& motors) {
  motors.reserve(f.reader().remaining() / 9);
  while (f.ok() && f.Has(9)) {
    BlurMotor b;
    f.U8(b.motor, "MOTOR").I32(b.pos_a_steps, "POS A").I32(b.pos_b_steps, "POS B");
    if (f.ok()) motors.push_back(b);
  }
}

}  // namespace

void Put(Writer& w, const RtShootFrame& m) {
  w.U32Le(m.frame);
  w.U8(m.direction);
  w.U32Le(m.exposure_ms);
  w.U16Le(m.blur_percent_x10);
  PutMotors(w, m.motors);
}
void Get(Fields& f, RtShootFrame& m) {
  f.U32(m.frame, "FRAME")
      .U8(m.direction, "DIRECTION")
      .U32(m.exposure_ms, "EXPOSURE TIME")
      .U16(m.blur_percent_x10, "BLUR PERCENT");
  GetMotors(f, m.motors);
}

void Put(Writer& w, const RtShootFrame2& m) {
  w.U32Le(m.frame);
  w.U32Le(m.exposure_ms);
  w.U16Le(m.open_angle_deg);
  w.U16Le(m.close_angle_deg);
  PutMotors(w, m.motors);
}
void Get(Fields& f, RtShootFrame2& m) {
  f.U32(m.frame, "FRAME")
      .U32(m.exposure_ms, "EXPOSURE TIME")
      .U16(m.open_angle_deg, "OPEN ANGLE")
      .U16(m.close_angle_deg, "CLOSE ANGLE");
  GetMotors(f, m.motors);
}

void Put(Writer& w, const RtJogAll& m) {
  w.U32Le(m.fps_x1000);
  w.U32Le(m.destination_frame);
}
void Get(Fields& f, RtJogAll& m) {
  f.U32(m.fps_x1000, "FPS").U32(m.destination_frame, "DESTINATION");
}

namespace {

constexpr size_t kCompensationSize = kBoomCompensationEntries * 4;

}  // namespace

void Put(Writer& w, const VirtConfig& m) {
  w.U8(m.rig_type());
  std::visit(
      wire::Overloaded{
          [](const VirtRigNone&) {},
          [&w](const VirtRigBoomSwingTrack& r) {
            for (const VirtAxisSetup* a : {&r.boom, &r.swing, &r.track, &r.pan, &r.tilt, &r.roll}) {
              w.U32Le(a->motor);
              w.I32Le(a->steps_per_unit);
              w.I32Le(a->position_x100000);
            }
            w.I32Le(r.boom_length_x1000);
            w.I32Le(r.boom_ext_x1000);
            w.I32Le(r.nodal_x_x1000);
            w.I32Le(r.nodal_y_x1000);
            w.I32Le(r.nodal_z_x1000);
            if (r.compensation) {
              for (int32_t v : *r.compensation) w.I32Le(v);
            }
            if (r.safe_distance_x1000) w.I32Le(*r.safe_distance_x1000);
          },
          [&w](const VirtRigSwingPan& r) {
            w.U32Le(r.swing.motor);
            w.I32Le(r.swing.steps_per_unit);
            w.U32Le(r.pan.motor);
            w.I32Le(r.pan.steps_per_unit);
          },
          [&w](const VirtRigRaw& r) { w.Raw(r.data); },
      },
      m.rig);
}

void Get(Fields& f, VirtConfig& m) {
  uint8_t type = 0;
  f.U8(type, "TYPE");
  if (!f.ok()) return;
  Reader& r = f.reader();
  switch (type) {
    case static_cast<uint8_t>(RigType::kNone):
      m.rig = VirtRigNone{};
      return;
    case static_cast<uint8_t>(RigType::kBoomSwingTrack): {
      VirtRigBoomSwingTrack b;
      static constexpr const char* kAxis[6][3] = {
          {"BOOM motor", "BOOM spu", "BOOM pos"},    {"SWING motor", "SWING spu", "SWING pos"},
          {"TRACK motor", "TRACK spu", "TRACK pos"}, {"PAN motor", "PAN spu", "PAN pos"},
          {"TILT motor", "TILT spu", "TILT pos"},    {"ROLL motor", "ROLL spu", "ROLL pos"}};
      VirtAxisSetup* axes[6] = {&b.boom, &b.swing, &b.track, &b.pan, &b.tilt, &b.roll};
      for (int i = 0; i < 6; ++i) {
        f.U32(axes[i]->motor, kAxis[i][0])
            .I32(axes[i]->steps_per_unit, kAxis[i][1])
            .I32(axes[i]->position_x100000, kAxis[i][2]);
      }
      f.I32(b.boom_length_x1000, "BOOM LENGTH")
          .I32(b.boom_ext_x1000, "BOOM EXT")
          .I32(b.nodal_x_x1000, "NODAL OFF X")
          .I32(b.nodal_y_x1000, "NODAL OFF Y")
          .I32(b.nodal_z_x1000, "NODAL OFF Z");
      if (!f.ok()) return;
      // ERRATA 1.7: the table and SAFE DISTANCE are each optional; the four
      // possible lengths are distinct, so the form is known from the length.
      // Ignoring trailing bytes, the longest form that fits is read.
      size_t rest = r.remaining();
      if (f.ignoring_trailing()) {
        for (const size_t form : {kCompensationSize + 4, kCompensationSize, size_t{4}, size_t{0}}) {
          if (rest >= form) {
            rest = form;
            break;
          }
        }
      }
      if (rest != 0 && rest != 4 && rest != kCompensationSize && rest != kCompensationSize + 4) {
        f.Fail(DecodeError{Kind::kBadLength, r.offset(),
                           "boom-swing-track: expected 0, 4, 484 or 488 bytes after NODAL OFF Z, "
                           "got " +
                               std::to_string(rest)});
        return;
      }
      if (rest >= kCompensationSize) {
        b.compensation.emplace();
        for (int32_t& v : *b.compensation) f.I32(v, "Boom Compensation Table");
      }
      if (rest == 4 || rest == kCompensationSize + 4) {
        int32_t safe = 0;
        f.I32(safe, "SAFE DISTANCE");
        b.safe_distance_x1000 = safe;
      }
      m.rig = std::move(b);
      return;
    }
    case static_cast<uint8_t>(RigType::kSwingPan): {
      VirtRigSwingPan s;
      f.U32(s.swing.motor, "SWING motor")
          .I32(s.swing.steps_per_unit, "SWING spu")
          .U32(s.pan.motor, "PAN motor")
          .I32(s.pan.steps_per_unit, "PAN spu");
      m.rig = s;
      return;
    }
    default: {
      // No layout in the spec (3, 4) or not a spec type (8 and others): kept raw.
      VirtRigRaw raw;
      raw.type = type;
      const ByteView rest = r.Rest();
      raw.data.assign(rest.begin(), rest.end());
      m.rig = std::move(raw);
      return;
    }
  }
}

void Put(Writer& w, const VirtMove& m) {
  w.U8(m.axis);
  w.I32Le(m.position_x100000);
}
void Get(Fields& f, VirtMove& m) {
  f.U8(m.axis, "VIRTUAL MOTOR").I32(m.position_x100000, "POSITION");
}

void Put(Writer& w, const VirtStop& m) { w.U8(m.axis); }
void Get(Fields& f, VirtStop& m) { f.U8(m.axis, "VIRTUAL MOTOR"); }

void Put(Writer& w, const VirtJog& m) {
  w.U8(m.axis);
  w.U16Le(m.speed);
  w.I32Le(m.destination_x100000);
}
void Get(Fields& f, VirtJog& m) {
  f.U8(m.axis, "MOTOR").U16(m.speed, "SPEED").I32(m.destination_x100000, "DESTINATION");
}

void Put(Writer& w, const VirtJogOnLine& m) {
  w.U8(m.axis);
  w.I16Le(m.speed);
}
void Get(Fields& f, VirtJogOnLine& m) { f.U8(m.axis, "AXIS").I16(m.speed, "SPEED"); }

// Device side.

void Put(Writer& w, const HiResponse& m) {
  w.Raw(ByteView(m.name));
  w.U8(m.fw_major);
  w.U8(m.fw_minor);
  w.U8(m.fw_rev);
  w.U8(m.motor_count);
  w.U16Le(m.dmx_count);
  w.U8(m.gio_out_count);
  w.U8(m.gio_in_count);
  w.U8(m.hw_limit_count);
  w.U32Le(m.upload_frame_count);
  w.U32Le(m.capabilities);
  if (m.protocol_version) w.U16Le(*m.protocol_version);
}
void Get(Fields& f, HiResponse& m) {
  ByteView name;
  if (!f.reader().Take(kHiNameSize, name)) {
    f.Fail(f.reader().Truncated("NAME"));
    return;
  }
  std::copy(name.begin(), name.end(), m.name.begin());
  f.U8(m.fw_major, "FW MAJOR")
      .U8(m.fw_minor, "FW MINOR")
      .U8(m.fw_rev, "FW REV")
      .U8(m.motor_count, "MOTOR COUNT")
      .U16(m.dmx_count, "DMX COUNT")
      .U8(m.gio_out_count, "GIO OUT COUNT")
      .U8(m.gio_in_count, "GIO INPUT COUNT")
      .U8(m.hw_limit_count, "HW LIMIT COUNT")
      .U32(m.upload_frame_count, "UPLOAD FRAME COUNT")
      .U32(m.capabilities, "CAPABILITIES")
      .Optional(m.protocol_version, "PROTOCOL VERSION");
}

void Put(Writer& w, const MotorStatusResponse& m) {
  w.U32Le(m.moving_bits);
  w.U8(m.dmx_adjusting);
}
void Get(Fields& f, MotorStatusResponse& m) {
  f.U32(m.moving_bits, "MOTOR STATUS").U8(m.dmx_adjusting, "DMX STATUS");
}

void Put(Writer& w, const MotorMoveResponse& m) { w.U8(m.moving); }
void Get(Fields& f, MotorMoveResponse& m) { f.U8(m.moving, "MOTOR STATUS"); }

void Put(Writer& w, const MotorPositionReport& m) {
  w.U32Le(m.move_time_x1000);
  for (int32_t p : m.positions_steps) w.I32Le(p);
}
void Get(Fields& f, MotorPositionReport& m) {
  f.U32(m.move_time_x1000, "MOVE TIME");
  m.positions_steps.reserve(f.reader().remaining() / 4);
  while (f.ok() && f.Has(4)) {
    int32_t p = 0;
    f.I32(p, "MOTOR POS");
    if (f.ok()) m.positions_steps.push_back(p);
  }
}

void Put(Writer& w, const GioInReport& m) { w.U32Le(m.triggers); }
void Get(Fields& f, GioInReport& m) { f.U32(m.triggers, "TRIGGERS"); }

void Put(Writer& w, const MotorHardStop& m) {
  w.U8(m.reason);
  if (m.motor) {
    w.U8(*m.motor);
  } else if (HardStopHasMotor(m.reason)) {
    w.U8(0);  // REQUIRES violated: keep the layout the reason demands
  }
}
void Get(Fields& f, MotorHardStop& m) {
  f.U8(m.reason, "REASON");
  if (!f.ok()) return;
  if (HardStopHasMotor(m.reason) || !f.reader().empty()) {
    uint8_t motor = 0;
    f.U8(motor, "MOTOR");
    if (f.ok()) m.motor = motor;
  }
}

void Put(Writer& w, const VirtPositionReport& m) {
  w.I32Le(m.track_x100000);
  w.I32Le(m.ew_x100000);
  w.I32Le(m.ns_x100000);
  w.I32Le(m.pan_x100000);
  w.I32Le(m.tilt_x100000);
  w.I32Le(m.roll_x100000);
  if (m.aim) {
    w.U8(m.aim->enabled);
    w.I32Le(m.aim->x_x1000);
    w.I32Le(m.aim->y_x1000);
    w.I32Le(m.aim->z_x1000);
  }
}
void Get(Fields& f, VirtPositionReport& m) {
  f.I32(m.track_x100000, "vTrack POS")
      .I32(m.ew_x100000, "vEW POS")
      .I32(m.ns_x100000, "vNS POS")
      .I32(m.pan_x100000, "vPan POS")
      .I32(m.tilt_x100000, "vTilt POS")
      .I32(m.roll_x100000, "vRoll POS");
  if (!f.ok() || !f.Has(13)) return;
  VirtAim aim;
  f.U8(aim.enabled, "Aim pt enabled")
      .I32(aim.x_x1000, "aim-x")
      .I32(aim.y_x1000, "aim-y")
      .I32(aim.z_x1000, "aim-z");
  if (f.ok()) m.aim = aim;
}

}  // namespace moco::dmc::layout
