// The StackShot 3X command handlers: CC_RAIL_*, system commands and
// CC_MOTION_* (stackshot-protocol.txt section 2, ERRATA 3.3-3.5, 3.10), and
// the DfMoco dialect (section 3, ERRATA 3.9). CC_RAIL_CONFIG_* is in
// stackshot3x_config_commands.cpp.
#include <algorithm>
#include <cmath>
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

constexpr uint16_t Cmd(Command c) { return static_cast<uint16_t>(c); }

float Bounded(float v, float lo, float hi) {
  if (std::isnan(v)) return lo;
  return std::clamp(v, lo, hi);
}

int32_t ClampI32(int64_t v) {
  return static_cast<int32_t>(std::clamp<int64_t>(v, INT32_MIN, INT32_MAX));
}

}  // namespace

// ---------------------------------------------------------------------------
// CC_RAIL_*

void Stackshot3x::HandleRail(const stackshot::Packet& p, const stackshot::HostCommand& c) {
  const int axis = p.axis;
  const bool axis_ok = axis < kAxes;
  switch (static_cast<Command>(c.command)) {
    case Command::kRailMove: {
      const auto* m = As<stackshot::RailMove>(c);
      if (!axis_ok || !stackshot::IsValid(m->direction) || !stackshot::IsValid(m->units) ||
          !(m->distance.value() >= 0) || !std::isfinite(m->distance.value())) {
        return Reply(p, Action::kBadParam);
      }
      // "COMM_STATUS_BUSY StackShot is currently moving. The move request was rejected."
      if (AxisMoving(axis)) return Reply(p, Action::kBusy);
      const double steps_d = m->distance.value() * StepsPerUnit(axis, m->units);
      if (!(steps_d <= kMaxTravelSteps)) return Reply(p, Action::kBadParam);
      const int64_t steps = std::llround(steps_d);
      const int sign = m->direction == stackshot::Direction::kBack ? -1 : 1;
      // Relative to the target position: two 10 mm moves make 20 mm.
      const int64_t target = axes_[Index(axis)].target_rail_steps + sign * steps;
      const double v = SpeedStepsPerS(axis, config_.axes[Index(axis)].speed_mm_per_s);
      return Reply(p, MoveAxisTo(axis, target, v, m->backlash) == sim::MoveStatus::kOk
                          ? Action::kRspOk
                          : Action::kFailed);
    }
    case Command::kRailMoveAtSpeed: {
      const auto* m = As<stackshot::RailMoveAtSpeed>(c);
      const float f = m->speed_fraction.value();
      if (!axis_ok || !stackshot::IsValid(m->direction) || !stackshot::IsValid(m->units) ||
          !(m->distance.value() >= 0) || !std::isfinite(m->distance.value()) || !(f > 0) ||
          !(f <= 1)) {
        return Reply(p, Action::kBadParam);
      }
      // A running stack or motion owns the axis; a plain move is re-aimed.
      if ((stack_.active && stack_.used[Index(axis)]) ||
          (motion_.pending && motion_.axes[Index(axis)]) || motion_.playing[Index(axis)]) {
        return Reply(p, Action::kBusy);
      }
      const double steps_d = m->distance.value() * StepsPerUnit(axis, m->units);
      if (!(steps_d <= kMaxTravelSteps)) return Reply(p, Action::kBadParam);
      const int64_t steps = std::llround(steps_d);
      const int sign = m->direction == stackshot::Direction::kBack ? -1 : 1;
      // Relative to the rail's immediate position.
      const int64_t target = RailPosition(axis) + sign * steps;
      const double v = f * profile_.axes[Index(axis)].max_speed_steps_per_s;
      return Reply(p, MoveAxisTo(axis, target, v, /*backlash=*/false) == sim::MoveStatus::kOk
                          ? Action::kRspOk
                          : Action::kFailed);
    }
    case Command::kRailPositionTarget:
    case Command::kRailPositionCurrent: {
      const auto* q = As<stackshot::UnitsQuery>(c);
      const Units u = q->units.value_or(config_.units);
      if (!axis_ok || !stackshot::IsValid(u)) return Reply(p, Action::kBadParam);
      const int64_t steps = c.command == Cmd(Command::kRailPositionTarget)
                                ? axes_[Index(axis)].target_rail_steps
                                : RailPosition(axis);
      return Reply(p, Action::kRspOk,
                   stackshot::UnitsF32{u, ToUnits(axis, static_cast<double>(steps), u)}, true);
    }
    case Command::kRailPositionZero: {
      if (!axis_ok) return Reply(p, Action::kBadParam);
      // "This command will be rejected with COMM_STATUS_BUSY if the motor is moving."
      if (AxisMoving(axis)) return Reply(p, Action::kBusy);
      Motor(axis).ResetPosition(0);
      axes_[Index(axis)].offset_steps = 0;
      axes_[Index(axis)].takeup = Takeup{};
      axes_[Index(axis)].target_rail_steps = 0;
      return Reply(p, Action::kRspOk);
    }
    case Command::kRailShutterFire: {
      // Bits 4-5 name the shutter output (section 2).
      if (axis >= kShutters) return Reply(p, Action::kBadParam);
      const auto* f = As<stackshot::ShutterFire>(c);
      if (shutter_runs_[Index(axis)].active) return Reply(p, Action::kBusy);
      // "If a parameter is out of bounds it will be bounded to the minimum/maximum allowed."
      const uint16_t pulses = std::max(f->pulses, kShutterMinPulses);
      const float on = Bounded(f->on_time_s.value(), kShutterMinS, kShutterMaxS);
      const float off = Bounded(f->off_time_s.value(), kShutterMinS, kShutterMaxS);
      FireShutter(axis, pulses, {on, on}, {off, off}, config_.toff_final && pulses > 1);
      return Reply(p, Action::kRspOk);
    }
    case Command::kRailStatus: {
      if (!axis_ok) return Reply(p, Action::kBadParam);
      uint32_t bits = stackshot::kRailStatusIdle;
      if (AxisMoving(axis)) bits |= stackshot::kRailStatusMoving;
      if (ShutterFiring()) bits |= stackshot::kRailStatusShutter;
      AxisState& s = axes_[Index(axis)];
      if (s.user_aborted) bits |= stackshot::kRailStatusUserAborted;
      s.user_aborted = false;  // sticky until read
      return Reply(p, Action::kRspOk, stackshot::RailStatus{bits}, true);
    }
    case Command::kRailStop:
    case Command::kRailStopRamp: {
      if (!axis_ok) return Reply(p, Action::kBadParam);
      if (stack_.active && stack_.used[Index(axis)]) AbortStack("stack stopped by the host");
      if (motion_.pending && motion_.axes[Index(axis)]) motion_ = MotionRun{};
      motion_.playing[Index(axis)] = false;  // before the halt: no next run starts
      if (c.command == Cmd(Command::kRailStop)) {
        Motor(axis).EmergencyHalt();
      } else {
        // Soft ramp: decelerate over the ramp time from full speed.
        Motor(axis).Stop();
      }
      return Reply(p, Action::kRspOk);
    }
    case Command::kRailStack: {
      const auto* s = As<stackshot::RailStack>(c);
      if (s->mode > static_cast<uint32_t>(stackshot::RailMode::kRotary)) {
        return Reply(p, Action::kBadParam);
      }
      if (stack_.active || motion_.pending || MotionPlaying() || ShutterFiring() ||
          rig_.AnyMoving()) {
        return Reply(p, Action::kBusy);
      }
      std::optional<StackRun> run = PlanStack(*s, axis);
      if (!run) return Reply(p, Action::kBadParam);
      stack_ = *run;
      Reply(p, Action::kRspOk);
      AddLog("stack start, " + std::to_string(stack_.frames) + " frames");
      StackMoveTo(0);
      return;
    }
    case Command::kRailStackStatus: {
      uint32_t bits = stackshot::kRailStatusIdle;
      if (stack_.active) bits |= stackshot::kRailStatusMoving;
      if (ShutterFiring()) bits |= stackshot::kRailStatusShutter;
      return Reply(p, Action::kRspOk, stackshot::RailStatus{bits}, true);
    }
    case Command::kRailStackPosition:
      return Reply(p, Action::kRspOk, stackshot::U32Value{stack_.frames_shot}, true);
    default:
      break;
  }
  Reply(p, Action::kUnsupportedCmd);
}

// ---------------------------------------------------------------------------
// System commands

void Stackshot3x::HandleSystem(const stackshot::Packet& p, const stackshot::HostCommand& c) {
  const bool read = c.action == Action::kRead;
  switch (static_cast<Command>(c.command)) {
    case Command::kReset: {
      // "Performs a software reset on the module": acknowledged, then the
      // controller restarts exactly as after a power cycle.
      Reply(p, Action::kRspOk);
      AddLog("reset");
      PowerOff();
      PowerOn();
      return;
    }
    case Command::kReflash:
      // The emulator has no bootloader to launch: refused, nothing changes.
      AddLog("reflash refused");
      return Reply(p, Action::kFailed);
    case Command::kSoftwareString:
      return Reply(p, Action::kRspOk, stackshot::Text{profile_.software_string, true}, true);
    case Command::kSoftwareId:
      return Reply(p, Action::kRspOk, stackshot::U32Value{profile_.software_id}, true);
    case Command::kHardwareId:
      return Reply(p, Action::kRspOk, stackshot::U32Value{profile_.hardware_id}, true);
    case Command::kBootloaderId:
      return Reply(p, Action::kRspOk, stackshot::U32Value{profile_.bootloader_id}, true);
    case Command::kSoftwareChecksum: {
      // "The checksum is performed upon command issue so a delay in the
      // response is to be expected": later packets wait for it.
      if (profile_.checksum_delay_ms == 0) {
        return Reply(p, Action::kRspOk, stackshot::U32Value{profile_.software_checksum}, true);
      }
      busy_ = true;
      busy_timer_ = scheduler_.After(profile_.checksum_delay_ms * sim::kNsPerMs, [this, p] {
        busy_timer_ = sim::Scheduler::kNoTimer;
        busy_ = false;
        Reply(p, Action::kRspOk, stackshot::U32Value{profile_.software_checksum}, true);
        DrainQueue();
      });
      return;
    }
    case Command::kSerialNumber: {
      if (read) return Reply(p, Action::kRspOk, stackshot::U32Value{serial_number_}, true);
      const uint32_t v = As<stackshot::U32Value>(c)->value;
      // "Returns COMM_ACTION_FAILED if a second write is attempted."
      if (serial_number_ != stackshot::kUnprogrammed && !faults_.serial_rewritable) {
        return Reply(p, Action::kFailed);
      }
      if (v == stackshot::kUnprogrammed) return Reply(p, Action::kBadParam);
      serial_number_ = v;
      AddLog("serial number " + std::to_string(v) + " programmed");
      return Reply(p, Action::kRspOk);
    }
    case Command::kNvmAccess: {
      if (read) {
        const uint8_t reg = As<stackshot::NvmRead>(c)->reg;
        if (reg >= nvm_.size()) return Reply(p, Action::kBadParam);
        return Reply(p, Action::kRspOk, stackshot::U32Value{nvm_[reg]}, true);
      }
      const auto* w = As<stackshot::NvmWrite>(c);
      if (w->reg >= nvm_.size()) return Reply(p, Action::kBadParam);
      nvm_[w->reg] = w->value;
      SaveNvm();
      return Reply(p, Action::kRspOk);
    }
    case Command::kLog: {
      // "increment this value until COMM_ACTION_BAD_PARAM is returned"
      const uint32_t index = As<stackshot::LogRequest>(c)->index;
      if (index >= log_.size()) return Reply(p, Action::kBadParam);
      return Reply(p, Action::kRspOk, stackshot::Text{log_[index], true}, true);
    }
    case Command::kClose:
      // Leaves USB mode on the display; motion in progress runs on.
      return Reply(p, Action::kRspOk);
    case Command::kNandAccess:  // "(unimplemented)"
    case Command::kNorAccess:   // "(unimplemented)"
    case Command::kWifi:        // no documented layout; Wi-Fi set-up is on the panel
    default:
      break;
  }
  Reply(p, Action::kUnsupportedCmd);
}

// ---------------------------------------------------------------------------
// CC_MOTION_CONFIG / CC_MOTION_START

void Stackshot3x::HandleMotion(const stackshot::Packet& p, const stackshot::HostCommand& c) {
  if (c.command == Cmd(Command::kMotionConfig)) {
    if (p.axis >= kAxes) return Reply(p, Action::kBadParam);
    const auto* m = As<stackshot::MotionConfig>(c);
    if (!stackshot::IsValid(m->axis_type) || !stackshot::ValidateMotionConfig(*m).ok()) {
      return Reply(p, Action::kBadParam);
    }
    sim::MotionCurves curves{};
    for (size_t k = 0; k < curves.size(); ++k) {
      for (size_t i = 0; i < 4; ++i) {
        curves[k].p[i] = sim::BezierPoint{m->curves[k].p[i].x.value(), m->curves[k].p[i].y.value()};
      }
    }
    const int axis = p.axis;
    const Stackshot3xConfig::Axis& a = config_.axes[Index(axis)];
    // y is mm for a slider or rail, degrees of the table for a rotary axis.
    const double steps_per_unit =
        m->axis_type == stackshot::AxisType::kRotary
            ? profile_.axes[Index(axis)].steps_per_rev * static_cast<double>(a.rotary_ratio) / 360.0
            : StepsPerMm(axis);
    for (const stackshot::BezierCurve& curve : m->curves) {
      for (const stackshot::BezierPoint& pt : curve.p) {
        if (!(std::fabs(pt.y.value()) * steps_per_unit <= kMaxTravelSteps)) {
          return Reply(p, Action::kBadParam);
        }
      }
    }
    // The document requires time continuity only ("A curve's initial P0.x
    // must match the previous curves P3.x"): a position jump between curves
    // is accepted (the rail travels it at full speed, see MotionAxisNext), as
    // is a curve faster than the axis allows (played slowed, see MakeRuns).
    std::optional<std::vector<sim::BezierSpline>> runs = MakeRuns(curves, steps_per_unit, axis);
    if (!runs) return Reply(p, Action::kBadParam);
    axes_[Index(axis)].runs = std::move(*runs);
    return Reply(p, Action::kRspOk);
  }
  const auto* start = As<stackshot::MotionStart>(c);
  const std::array<bool, 3> want = {start->x, start->y, start->z};
  if (!want[0] && !want[1] && !want[2]) return Reply(p, Action::kBadParam);
  for (int a = 0; a < kAxes; ++a) {
    if (!want[Index(a)]) continue;
    if (AxisMoving(a) || stack_.active) return Reply(p, Action::kBusy);
    if (axes_[Index(a)].runs.empty()) return Reply(p, Action::kFailed);  // no curve configured
  }
  motion_ = MotionRun{true, want};
  for (int a = 0; a < kAxes; ++a) {
    if (!want[Index(a)]) continue;
    AxisState& s = axes_[Index(a)];
    // The spline is in rail steps: let the motor count the rail's steps.
    FinishTakeup(a);
    const int64_t rail = RailPosition(a);
    Motor(a).ResetPosition(rail);
    s.offset_steps = 0;
    if (rail != s.runs.front().StartStep()) {
      MoveAxisTo(a, s.runs.front().StartStep(),
                 SpeedStepsPerS(a, config_.axes[Index(a)].move_speed_mm_per_s), false);
    }
  }
  Reply(p, Action::kRspOk);
  MotionAdvance();
}

// ---------------------------------------------------------------------------
// Modes and the DfMoco dialect

void Stackshot3x::SetGlobalModeFromPanel(stackshot::GlobalMode mode) {
  if (!powered_ || !stackshot::IsValid(mode) || mode == stackshot::GlobalMode::kMotionReserved) {
    return;
  }
  EnterMode(mode);
  // The menu's settings are the power-on settings: the mode goes into slot 0.
  Stackshot3xConfig power_on = slots_[0].value_or(Stackshot3xConfig::Defaults(profile_));
  power_on.global_mode = mode;
  slots_[0] = power_on;
  SaveNvm();
}

void Stackshot3x::SetPowerOnMode(stackshot::GlobalMode mode) {
  const bool was_powered = powered_;
  const wire::Protocol announced = announced_;
  if (!was_powered) PowerOn();
  SetGlobalModeFromPanel(mode);
  if (was_powered) return;
  PowerOff();
  // Nobody heard this power cycle: the next power-on announces the line it
  // starts in.
  announced_ = announced;
}

void Stackshot3x::EnterMode(stackshot::GlobalMode mode) {
  const bool was = SpeaksDfmoco();
  const bool was_mode = InDfmocoMode();
  config_.global_mode = mode;
  const bool now = SpeaksDfmoco();
  if (was == now) {
    // Wi-Fi: the mode is taken (it reads back, and the USB port speaks DfMoco)
    // but this link keeps the binary protocol (section 3, "runs over USB").
    if (was_mode != InDfmocoMode()) {
      AddLog(InDfmocoMode() ? "DfMoco mode: on USB only, Wi-Fi stays binary" : "DfMoco mode left");
    }
    return;
  }
  decoder_.Flush();
  framer_.Reset();
  queue_.clear();
  scheduler_.Cancel(gap_timer_);
  gap_timer_ = sim::Scheduler::kNoTimer;
  for (AxisState& s : axes_) {
    scheduler_.Cancel(s.dfmoco_timer);
    s.dfmoco_timer = sim::Scheduler::kNoTimer;
  }
  AddLog(std::string("serial dialect: ") + (now ? "DfMoco, " : "binary, ") +
         std::to_string(Line().serial.baud) + " baud");
  AnnounceSpeaking();
}

void Stackshot3x::SendLine(const dfmoco::DeviceReply& reply) {
  std::string text;
  dfmoco::AppendDevice(reply, text);
  sink_.Write(wire::ByteView(reinterpret_cast<const uint8_t*>(text.data()), text.size()));
}

void Stackshot3x::ArmDfmocoReport(int axis) {
  AxisState& s = axes_[Index(axis)];
  scheduler_.Cancel(s.dfmoco_timer);
  s.dfmoco_timer = scheduler_.After(profile_.dfmoco_report_ms * sim::kNsPerMs, [this, axis] {
    axes_[Index(axis)].dfmoco_timer = sim::Scheduler::kNoTimer;
    if (!SpeaksDfmoco() || !Motor(axis).IsMoving()) return;
    SendLine(dfmoco::MoveReply{axis + 1, ClampI32(RailPosition(axis))});
    ArmDfmocoReport(axis);
  });
}

void Stackshot3x::OnDfmocoLine(std::string_view line) {
  const auto parsed = dfmoco::ParseHostLine(line, dialect_);
  if (!parsed) return SendLine(dfmoco::ErrorReply(parsed.error()));
  const dfmoco::HostCommand& cmd = *parsed;
  if (const auto m = dfmoco::AddressedMotor(cmd); m && !dfmoco::MotorInRange(*m, dialect_)) {
    return SendLine(dfmoco::ParseErrorReply{});
  }
  auto pos = [this](int axis) { return ClampI32(RailPosition(axis)); };
  auto rate = [this](int axis) { return static_cast<double>(dfmoco_rate_[Index(axis)]); };
  auto set_position = [this](int axis, int64_t steps) {
    Motor(axis).EmergencyHalt();
    FinishTakeup(axis);
    Motor(axis).ResetPosition(steps);
    axes_[Index(axis)].offset_steps = 0;
    axes_[Index(axis)].target_rail_steps = steps;
  };
  std::visit(
      [&](const auto& v) {
        using T = std::decay_t<decltype(v)>;
        if constexpr (std::is_same_v<T, dfmoco::Hello>) {
          SendLine(dfmoco::HelloFor(dialect_));
        } else if constexpr (std::is_same_v<T, dfmoco::MotorStatusQuery>) {
          dfmoco::MotorStatusReply r;
          for (int a = 0; a < kAxes; ++a) r.moving.push_back(Motor(a).IsMoving());
          SendLine(r);
        } else if constexpr (std::is_same_v<T, dfmoco::MoveMotor>) {
          const int a = v.motor - 1;
          if (!Motor(a).IsMoving() && RailPosition(a) == v.position_steps) {
            SendLine(dfmoco::PositionReply{v.motor, pos(a)});
            return;
          }
          MoveAxisTo(a, v.position_steps, rate(a), false);
          SendLine(dfmoco::MoveReply{v.motor, pos(a)});
          ArmDfmocoReport(a);
        } else if constexpr (std::is_same_v<T, dfmoco::PositionQuery>) {
          SendLine(dfmoco::PositionReply{v.motor, pos(v.motor - 1)});
        } else if constexpr (std::is_same_v<T, dfmoco::PositionQueryAll>) {
          for (int a = 0; a < kAxes; ++a) SendLine(dfmoco::PositionReply{a + 1, pos(a)});
        } else if constexpr (std::is_same_v<T, dfmoco::StopMotor>) {
          Motor(v.motor - 1).Stop();
          SendLine(dfmoco::StopMotorReply{v.motor});
        } else if constexpr (std::is_same_v<T, dfmoco::StopAll>) {
          for (int a = 0; a < kAxes; ++a) Motor(a).Stop();
          SendLine(dfmoco::StopAllReply{});
        } else if constexpr (std::is_same_v<T, dfmoco::JogMotor>) {
          MoveAxisTo(v.motor - 1, v.destination_steps, rate(v.motor - 1), false);
          SendLine(dfmoco::JogReply{v.motor});
        } else if constexpr (std::is_same_v<T, dfmoco::InchMotor>) {
          const int a = v.motor - 1;
          MoveAxisTo(a, v.destination_steps,
                     std::max(1.0, kInchFraction * profile_.axes[Index(a)].max_speed_steps_per_s),
                     false);
          SendLine(dfmoco::InchReply{v.motor});
        } else if constexpr (std::is_same_v<T, dfmoco::SetPulseRate>) {
          const int a = v.motor - 1;
          // "If the requested speed is faster than the controller is
          // allowing, then the controller will respond with the maximum speed."
          const auto max = static_cast<int32_t>(profile_.axes[Index(a)].max_speed_steps_per_s);
          dfmoco_rate_[Index(a)] = std::clamp(v.rate_steps_per_s, 1, std::max(max, 1));
          SendLine(dfmoco::PulseRateReply{v.motor, dfmoco_rate_[Index(a)]});
        } else if constexpr (std::is_same_v<T, dfmoco::ZeroMotor>) {
          set_position(v.motor - 1, 0);
          SendLine(dfmoco::PositionReply{v.motor, 0});  // ERRATA 3.9: `mp`, once
        } else if constexpr (std::is_same_v<T, dfmoco::NewPosition>) {
          const int a = v.motor - 1;
          // "Set a new target position. If the motor is currently moving it
          // will go to that position"; at rest the position is set.
          if (Motor(a).IsMoving()) {
            MoveAxisTo(a, v.position_steps, rate(a), false);
          } else {
            set_position(a, v.position_steps);
          }
          SendLine(dfmoco::PositionReply{v.motor, pos(a)});  // "(yes, that is a "m")"
        } else {
          // bf / go (no real-time motion: "It can only be used for
          // shoot-move-shoot applications") and unknown words: no answer.
        }
      },
      cmd);
}

// ---------------------------------------------------------------------------
// State

nlohmann::json Stackshot3x::State() const {
  nlohmann::json axes = nlohmann::json::array();
  for (int a = 0; a < kAxes; ++a) {
    const AxisState& s = axes_[Index(a)];
    axes.push_back({{"axis", stackshot::AxisName(static_cast<uint8_t>(a))},
                    {"position_steps", RailPosition(a)},
                    {"motor_steps", Motor(a).Position()},
                    {"target_steps", s.target_rail_steps},
                    {"moving", AxisMoving(a)},
                    {"user_aborted", s.user_aborted},
                    {"spline", !s.runs.empty()}});
  }
  nlohmann::json j = {
      {"model", "stackshot3x"},
      {"powered", powered_},
      {"ready", ready_},
      {"mode", SpeaksDfmoco() ? "dfmoco" : "binary"},
      {"link", host_link_ == HostLink::kWifi ? "wifi" : "serial"},
      {"serial_number", serial_number_},
      {"axes", axes},
      {"shutter_firing", ShutterFiring()},
      {"stack",
       {{"active", stack_.active}, {"frames", stack_.frames}, {"frames_shot", stack_.frames_shot}}},
      {"config", config_.ToJson()}};
  if (!store_error_.empty()) j["store_error"] = store_error_;
  return j;
}

}  // namespace moco::devices
