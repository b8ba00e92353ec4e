// The StackShot 3X CC_RAIL_CONFIG_* handler (stackshot-protocol.txt section
// 2, ERRATA 3.3-3.5): reading and writing the controller's, each axis's and
// each shutter output's settings with their ranges, saving and loading the
// configuration slots, the NVM axis definition and the global mode that
// switches the dialect. The other command groups are in
// stackshot3x_commands.cpp.
#include <cmath>
#include <optional>
#include <string>

#include "devices/stackshot3x/stackshot3x.h"
#include "devices/stackshot3x/stackshot3x_commands_internal.h"

namespace moco::devices {
namespace {

using stackshot::Action;
using stackshot::Command;
using stackshot::Units;
using stackshot3x_commands::As;
using stackshot3x_commands::InRange;

}  // namespace

// ---------------------------------------------------------------------------
// CC_RAIL_CONFIG_*

// One CC_RAIL_CONFIG_* command being answered: the axis and the shutter
// output it addresses, the replies a setting's read or write gets, and one
// step per group of settings. The reply helpers return true (the command is
// handled); a group returns false for a command outside it.
struct Stackshot3x::ConfigCall {
  Stackshot3x& dev;
  const stackshot::Packet& p;
  const stackshot::HostCommand& c;
  const bool read = c.action == Action::kRead;
  const bool axis_ok = p.axis < kAxes;
  const bool shutter_ok = p.axis < kShutters;
  const size_t ax = axis_ok ? Index(p.axis) : 0;
  const size_t sh = shutter_ok ? Index(p.axis) : 0;
  const size_t sub = p.sub_item ? 1 : 0;
  Stackshot3xConfig& cfg = dev.config_;
  Stackshot3xConfig::Axis& a = cfg.axes[ax];

  bool Reply(Action status, stackshot::Payload payload = stackshot::Empty{},
             bool read_response = false) {
    dev.Reply(p, status, std::move(payload), read_response);
    return true;
  }
  bool Ok() { return Reply(Action::kRspOk); }
  bool Bad() { return Reply(Action::kBadParam); }
  bool U8Field(uint8_t& field, uint8_t lo, uint8_t hi) {
    if (read) return Reply(Action::kRspOk, stackshot::U8Value{field}, true);
    const uint8_t v = As<stackshot::U8Value>(c)->value;
    if (v < lo || v > hi) return Bad();
    field = v;
    return Ok();
  }
  bool BoolField(bool& field) {
    if (read) return Reply(Action::kRspOk, stackshot::BoolValue{field}, true);
    field = As<stackshot::BoolValue>(c)->value;
    return Ok();
  }
  bool F32Field(float& field, float lo, float hi, bool lo_open) {
    if (read) return Reply(Action::kRspOk, stackshot::F32Value{field}, true);
    const float v = As<stackshot::F32Value>(c)->value.value();
    if (!InRange(v, lo, hi) || (lo_open && v == lo)) return Bad();
    field = v;
    return Ok();
  }
  // A distance (or speed) kept in mm, read and written in any units.
  bool MmField(double& field_mm, bool positive, bool speed, bool no_steps) {
    if (read) {
      const Units u = As<stackshot::UnitsQuery>(c)->units.value_or(cfg.units);
      if (!stackshot::IsValid(u) || (no_steps && u == Units::kSteps)) return Bad();
      return Reply(
          Action::kRspOk,
          stackshot::UnitsF32{u, dev.ToUnits(p.axis, field_mm * dev.StepsPerMm(p.axis), u)}, true);
    }
    const auto* w = As<stackshot::UnitsF32>(c);
    if (!stackshot::IsValid(w->units) || (no_steps && w->units == Units::kSteps)) return Bad();
    const std::optional<double> mm = dev.ToMm(p.axis, w->value.value(), w->units);
    if (!mm || *mm < 0 || (positive && *mm == 0) ||
        *mm * dev.StepsPerMm(p.axis) > kMaxTravelSteps) {
      return Bad();
    }
    if (speed && *mm * dev.StepsPerMm(p.axis) > dev.profile_.axes[ax].max_speed_steps_per_s) {
      return Bad();
    }
    field_mm = *mm;
    return Ok();
  }

  bool Misaddressed(Command cmd) const;
  bool Controller(Command cmd);
  bool AxisSetting(Command cmd);
  bool ShutterOutput(Command cmd);
  bool Stored(Command cmd);
};

// Whether `cmd` addresses an axis or a shutter output the unit does not have.
bool Stackshot3x::ConfigCall::Misaddressed(Command cmd) const {
  using C = Command;
  switch (cmd) {
    case C::kRailConfigTorque:
    case C::kRailConfigHoldingTorque:
    case C::kRailConfigNumSteps:
    case C::kRailConfigTotalDistance:
    case C::kRailConfigDistancePerStep:
    case C::kRailConfigSpeed:
    case C::kRailConfigSpeedMove:
    case C::kRailConfigRampTime:
    case C::kRailConfigDistancePerRev:
    case C::kRailConfigBacklash:
    case C::kRailConfigPolarity:
    case C::kRailConfigRotaryBacklash:
    case C::kRailConfigRotaryRatio:
    case C::kRailConfigRotaryDegrees:
    case C::kRailConfigShutter:
      return !axis_ok;
    case C::kRailConfigNumPulses:
    case C::kRailConfigPulseTime:
    case C::kRailConfigOffTime:
      return !shutter_ok;
    default:
      return false;
  }
}

// The settings of the whole controller.
bool Stackshot3x::ConfigCall::Controller(Command cmd) {
  using C = Command;
  switch (cmd) {
    case C::kRailConfigName: {
      if (read) {
        // "On read, 0xFF indicates power-on / last saved configuration."
        return Reply(Action::kRspOk,
                     stackshot::Text{cfg.name.empty() ? std::string(1, '\xFF') : cfg.name, true},
                     true);
      }
      const auto* t = As<stackshot::Text>(c);
      if (t->text.size() > kMaxNameBytes) return Bad();
      cfg.name = t->text;
      return Ok();
    }
    case C::kRailConfigBacklight:
      return U8Field(cfg.backlight, 1, 10);
    case C::kRailConfigMode: {
      if (read)
        return Reply(Action::kRspOk, stackshot::EnumValue<stackshot::RailMode>{cfg.mode}, true);
      const auto v = As<stackshot::EnumValue<stackshot::RailMode>>(c)->value;
      if (static_cast<uint8_t>(v) > static_cast<uint8_t>(stackshot::RailMode::kRotary))
        return Bad();
      cfg.mode = v;
      return Ok();
    }
    case C::kRailConfigUnits: {
      if (read) return Reply(Action::kRspOk, stackshot::EnumValue<Units>{cfg.units}, true);
      const auto v = As<stackshot::EnumValue<Units>>(c)->value;
      if (!stackshot::IsValid(v)) return Bad();
      cfg.units = v;
      return Ok();
    }
    case C::kRailConfigSettleTime:
      return F32Field(cfg.settle_time_s, 0, kMaxConfigTimeS, false);
    case C::kRailConfigTimelapse:
      return F32Field(cfg.timelapse_s, 0, 1e7f, false);
    case C::kRailConfigShutterDisable:
      return BoolField(cfg.shutter_disable);
    case C::kRailConfigAutoReturn:
      return BoolField(cfg.auto_return);
    case C::kRailConfigToffFinal:
      return BoolField(cfg.toff_final);
    case C::kRailConfigIoMode: {
      if (read)
        return Reply(Action::kRspOk, stackshot::EnumValue<stackshot::IoMode>{cfg.io_mode}, true);
      const auto v = As<stackshot::EnumValue<stackshot::IoMode>>(c)->value;
      if (!stackshot::IsValid(v)) return Bad();
      cfg.io_mode = v;
      return Ok();
    }
    case C::kRailConfigIoDir: {
      if (read)
        return Reply(Action::kRspOk, stackshot::EnumValue<stackshot::Direction>{cfg.io_dir}, true);
      const auto v = As<stackshot::EnumValue<stackshot::Direction>>(c)->value;
      if (!stackshot::IsValid(v)) return Bad();
      cfg.io_dir = v;
      return Ok();
    }
    default:
      return false;
  }
}

// The settings of the addressed axis.
bool Stackshot3x::ConfigCall::AxisSetting(Command cmd) {
  using C = Command;
  switch (cmd) {
    case C::kRailConfigTorque:
      return U8Field(a.torque, 1, 10);
    case C::kRailConfigHoldingTorque:
      return U8Field(a.holding_torque, 0, 10);
    case C::kRailConfigNumSteps: {
      if (read) return Reply(Action::kRspOk, stackshot::U16Value{a.num_steps}, true);
      const uint16_t v = As<stackshot::U16Value>(c)->value;
      if (v == 0) return Bad();
      a.num_steps = v;
      return Ok();
    }
    case C::kRailConfigTotalDistance:
      return MmField(a.total_distance_mm, false, false, false);
    case C::kRailConfigDistancePerStep:
      return MmField(a.distance_per_step_mm, true, false, false);
    case C::kRailConfigSpeed:
      return MmField(a.speed_mm_per_s, true, true, false);
    case C::kRailConfigSpeedMove:
      return MmField(a.move_speed_mm_per_s, true, true, false);
    case C::kRailConfigRampTime: {
      if (read) return Reply(Action::kRspOk, stackshot::F32Value{a.ramp_time_s}, true);
      const float v = As<stackshot::F32Value>(c)->value.value();
      if (!InRange(v, 0, kMaxRampTimeS)) return Bad();
      a.ramp_time_s = v;
      dev.planners_[ax]->SetRampTime(v);
      return Ok();
    }
    case C::kRailConfigDistancePerRev: {
      // Steps per revolution do not depend on this setting: mils and mm only.
      if (read) {
        // The read table sends no units byte: the answer is in
        // CC_RAIL_CONFIG_UNITS, or in mm while those are steps (a distance
        // per revolution in steps per revolution would be 3200 whatever the
        // rail). An explicit steps byte is still BAD_PARAM.
        const std::optional<Units> asked = As<stackshot::UnitsQuery>(c)->units;
        const Units u = asked.value_or(cfg.units == Units::kSteps ? Units::kMm : cfg.units);
        if (!stackshot::IsValid(u) || u == Units::kSteps) return Bad();
        return Reply(Action::kRspOk,
                     stackshot::UnitsF32{
                         u, dev.ToUnits(p.axis, a.distance_per_rev_mm * dev.StepsPerMm(p.axis), u)},
                     true);
      }
      const auto* w = As<stackshot::UnitsF32>(c);
      if (!stackshot::IsValid(w->units) || w->units == Units::kSteps ||
          !std::isfinite(w->value.value()) || !(w->value.value() > 0)) {
        return Bad();
      }
      a.distance_per_rev_mm =
          w->units == Units::kMils ? w->value.value() * kMmPerMil : w->value.value();
      return Ok();
    }
    case C::kRailConfigBacklash:
      return MmField(a.backlash_mm, false, false, false);
    case C::kRailConfigPolarity:
      return BoolField(a.reverse);
    case C::kRailConfigRotaryBacklash:
      return F32Field(a.rotary_backlash_deg, 0, 360, false);
    case C::kRailConfigRotaryRatio:
      return F32Field(a.rotary_ratio, 0, 1000, true);
    case C::kRailConfigRotaryDegrees:
      return F32Field(a.rotary_degrees, 0, 360, true);
    case C::kRailConfigShutter: {
      if (read) {
        return Reply(Action::kRspOk, stackshot::EnumValue<stackshot::ShutterSetting>{a.shutter},
                     true);
      }
      const auto v = As<stackshot::EnumValue<stackshot::ShutterSetting>>(c)->value;
      if (!stackshot::IsValid(v)) return Bad();
      a.shutter = v;
      return Ok();
    }
    default:
      return false;
  }
}

// The settings of the addressed shutter output.
bool Stackshot3x::ConfigCall::ShutterOutput(Command cmd) {
  using C = Command;
  switch (cmd) {
    case C::kRailConfigNumPulses: {
      uint16_t& field = cfg.shutters[sh].num_pulses;
      if (read) return Reply(Action::kRspOk, stackshot::U16Value{field}, true);
      const uint16_t v = As<stackshot::U16Value>(c)->value;
      if (v == 0) return Bad();
      field = v;
      return Ok();
    }
    case C::kRailConfigOffTime:
      return F32Field(cfg.shutters[sh].off_time_s[sub], 0, kMaxConfigTimeS, false);
    case C::kRailConfigPulseTime:
      return F32Field(cfg.shutters[sh].pulse_time_s[sub], 0, kMaxConfigTimeS, true);
    default:
      return false;
  }
}

// What the unit keeps or switches as a whole: the configuration slots, the
// NVM axis definition and the global mode.
bool Stackshot3x::ConfigCall::Stored(Command cmd) {
  using C = Command;
  switch (cmd) {
    case C::kRailConfigSave: {
      const uint8_t slot = As<stackshot::U8Value>(c)->value;
      if (slot > stackshot::kConfigSlotMax) return Bad();
      dev.slots_[slot] = cfg;
      // "This command commits the data to NVM."
      dev.AddLog("config saved to slot " + std::to_string(slot));
      return Ok();
    }
    case C::kRailConfigLoad: {
      const uint8_t slot = As<stackshot::U8Value>(c)->value;
      if (slot > stackshot::kConfigSlotMax) return Bad();
      // "If the slot is empty, an error will be returned and the load will not
      // complete": the user slots 1-10. Slot 0 is the "power on"
      // configuration, which always exists: the factory defaults until a
      // CC_RAIL_CONFIG_SAVE to slot 0 replaces them (the unit powers on with it).
      if (slot != 0 && !dev.slots_[slot]) return Reply(Action::kFailed);
      if (dev.rig_.AnyMoving() || dev.stack_.active || dev.motion_.pending || dev.MotionPlaying()) {
        return Reply(Action::kBusy);
      }
      Stackshot3xConfig loaded =
          dev.slots_[slot].value_or(Stackshot3xConfig::Defaults(dev.profile_));
      const stackshot::GlobalMode mode = loaded.global_mode;
      loaded.global_mode = cfg.global_mode;
      cfg = loaded;
      for (int i = 0; i < kAxes; ++i)
        dev.planners_[Index(i)]->SetRampTime(cfg.axes[Index(i)].ramp_time_s);
      dev.AddLog("config loaded from slot " + std::to_string(slot));
      Ok();
      dev.EnterMode(mode);
      return true;
    }
    case C::kRailConfigAxis: {
      // NVM register 0 is the axis definition (section 1.1.17).
      if (read) {
        return Reply(Action::kRspOk, stackshot::U8Value{static_cast<uint8_t>(dev.nvm_[0] & 0xFF)},
                     true);
      }
      const uint8_t v = As<stackshot::U8Value>(c)->value;
      if (v > static_cast<uint8_t>(stackshot::RailAxis::kUndefined)) return Bad();
      dev.nvm_[0] = v;
      // "The write immediately commits the change to NVM."
      dev.SaveNvm();
      return Ok();
    }
    case C::kRailConfigGlobalMode: {
      if (read) {
        return Reply(Action::kRspOk, stackshot::EnumValue<stackshot::GlobalMode>{cfg.global_mode},
                     true);
      }
      const auto v = As<stackshot::EnumValue<stackshot::GlobalMode>>(c)->value;
      // GLOBAL_MODE_MOTION_RESERVED: "Reserved, do not use".
      if (!stackshot::IsValid(v) || v == stackshot::GlobalMode::kMotionReserved) return Bad();
      Ok();  // acknowledged in the old dialect, then the line switches
      dev.EnterMode(v);
      return true;
    }
    default:
      return false;
  }
}

void Stackshot3x::HandleConfig(const stackshot::Packet& p, const stackshot::HostCommand& c) {
  ConfigCall call{*this, p, c};
  const auto cmd = static_cast<Command>(c.command);
  // Commands that address an axis or a shutter output.
  if (call.Misaddressed(cmd)) {
    call.Bad();
    return;
  }
  if (call.Controller(cmd) || call.AxisSetting(cmd) || call.ShutterOutput(cmd) ||
      call.Stored(cmd)) {
    return;
  }
  Reply(p, Action::kUnsupportedCmd);
}

}  // namespace moco::devices
