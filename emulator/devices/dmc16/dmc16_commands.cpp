// The emulated DMC-16's commands (see dmc16.h): MSG_DMX, GIO, the motor
// requests and how the reference firmware departs from the spec in them
// (Dmc16Behaviour). Section names in comments are those of
// dmc-v2-protocol.txt; readings taken are listed in docs/protocol-notes.md.
#include "devices/dmc16/dmc16.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <utility>

namespace moco::devices {

using dmc::AckCode;
using dmc::MsgType;
using sim::kNsPerMs;
using sim::TimeNs;

namespace {
// behaviour.set_speed_checked false: the slowest MAX VELOCITY taken (steps/s).
constexpr double kSetSpeedMinVelocity = 10;
// behaviour.jog_speed_scale kPer10000: the least jog velocity (steps/s) and
// acceleration (steps/s^2).
constexpr double kJogMinRate = 4;
// behaviour.coupling kDrivesNext: a resynchronised count this far (steps)
// from the reported position raises an engine exception.
constexpr int64_t kResyncExceptionSteps = 10;
}  // namespace

// --- real-time and virtual-axis requests --------------------------------------------------

// The MSG_RT_* and MSG_VIRT_* requests (Handle() passes them on), and those
// the device does not know.
void Dmc16::HandleRealTimeAndVirtual(uint32_t id, const dmc::HostMessage& msg) {
  const uint16_t type = dmc::TypeOf(msg);
  std::visit(
      wire::Overloaded{
          [&](const dmc::RtUploadMoveBegin& m) {
            if (playback_.Playing()) {
              Ack(id, type, AckCode::kErrMoving);
              return;
            }
            playback_.OnUploadBegin();
            Ack(id, type, upload_.Begin(m.start_frame, m.end_frame).code);
          },
          // ERR_MOVING: no upload message touches the move being played.
          [&](const dmc::RtUploadMoveAxis& m) {
            Ack(id, type, playback_.Playing() ? AckCode::kErrMoving : upload_.Axis(m).code);
          },
          [&](const dmc::RtUploadMoveDmx& m) {
            Ack(id, type, playback_.Playing() ? AckCode::kErrMoving : upload_.Dmx(m).code);
          },
          [&](const dmc::RtUploadMoveTriggers& m) {
            Ack(id, type, playback_.Playing() ? AckCode::kErrMoving : upload_.Triggers(m).code);
          },
          [&](const dmc::RtUploadMoveEnd&) {
            Ack(id, type, playback_.Playing() ? AckCode::kErrMoving : upload_.End().code);
          },
          [&](const dmc::RtPositionFrame& m) { Ack(id, type, OnPositionFrame(m.frame)); },
          [&](const dmc::RtRunMove& m) { Ack(id, type, playback_.RunMove(m)); },
          [&](const dmc::RtShootFrame& m) {
            // Blur percent of the frame's 360 degrees, centred on the frame
            // (docs/protocol-notes.md); DIRECTION 0 plays B towards A.
            if (m.blur_percent_x10 > 1000) {
              Ack(id, type, AckCode::kErrRange);
              return;
            }
            const double half = 180.0 * m.blur_percent_x10 / 1000.0;
            Ack(id, type,
                playback_.ShootFrame(m.frame, m.direction == dmc::kDirectionBackward ? -1 : 1,
                                     m.exposure_ms, 180.0 - half, 180.0 + half, m.motors));
          },
          [&](const dmc::RtShootFrame2& m) {
            if (m.open_angle_deg > 360 || m.close_angle_deg > 360 ||
                m.close_angle_deg < m.open_angle_deg) {
              Ack(id, type, AckCode::kErrRange);
              return;
            }
            Ack(id, type,
                playback_.ShootFrame(m.frame, 1, m.exposure_ms, m.open_angle_deg, m.close_angle_deg,
                                     m.motors));
          },
          [&](const dmc::RtGo&) { Ack(id, type, playback_.Go()); },
          [&](const dmc::RtStopLoop&) { Ack(id, type, playback_.StopLoop()); },
          [&](const dmc::RtJogAll& m) { Ack(id, type, playback_.JogAll(m)); },
          [&](const dmc::VirtConfig& m) {
            Ack(id, type, playback_.Playing() ? AckCode::kErrMoving : virtual_.Configure(m));
          },
          [&](const dmc::VirtMove& m) {
            Ack(id, type,
                playback_.Playing() ? AckCode::kErrMoving : AfterVirtualMotion(virtual_.Move(m)));
          },
          [&](const dmc::VirtJog& m) {
            Ack(id, type,
                playback_.Playing() ? AckCode::kErrMoving : AfterVirtualMotion(virtual_.Jog(m)));
          },
          [&](const dmc::VirtJogOnLine& m) {
            Ack(id, type,
                playback_.Playing() ? AckCode::kErrMoving
                                    : AfterVirtualMotion(virtual_.JogOnLine(m)));
          },
          [&](const dmc::VirtStop& m) {
            // Stopping during playback ends the run, as MOTOR_STOP does.
            if (playback_.Playing() && m.axis >= 1 && m.axis <= 6) {
              playback_.Abort(true);
              rig_.StopAll();
            }
            Ack(id, type, virtual_.Stop(m));
          },
          [&](const dmc::VirtGetPositionRequest&) {
            const auto r = virtual_.Position();
            if (const auto* p = std::get_if<dmc::VirtPositionReport>(&r)) {
              Send(id, *p);
            } else {
              Ack(id, type, std::get<AckCode>(r));
            }
          },
          [&](const dmc::VirtAimPoint& m) {
            const auto r = virtual_.SetAimPoint(m);
            if (const auto* a = std::get_if<dmc::VirtAimPoint>(&r)) {
              // "The response contains the same data."
              Send(id, *a);
            } else {
              Ack(id, type, std::get<AckCode>(r));
            }
          },
          [&](const dmc::Unknown& m) {
            // behaviour.host_hard_stop false: dmc-lite only sends it.
            if (m.type == dmc::ToWire(MsgType::kMotorHardStop) &&
                profile_.behaviour.host_hard_stop) {
              // Listed among the motor commands a device must handle, with no
              // request data: read as "hard stop everything now".
              virtual_.CancelJog();
              playback_.Abort(true);
              rig_.HardStopAll();
              Ack(id, type, AckCode::kOk);
              return;
            }
            Ack(id, type, AckCode::kErrUnsupported);
          },
          [&](const auto&) { Ack(id, type, AckCode::kErrUnsupported); },
      },
      msg);
}

// --- simple commands ------------------------------------------------------------------------

AckCode Dmc16::OnDmx(const dmc::Dmx& m) {
  const size_t last = size_t{m.start_channel} + m.values.size() - 1;
  if (m.start_channel < 1 || last > profile_.dmx_channels || m.values.empty()) {
    return AckCode::kErrRange;
  }
  if (m.ramp > 1) return AckCode::kErrRange;
  dmx_.Apply(m.ramp == 1, m.start_channel, m.values);
  return AckCode::kOk;
}

AckCode Dmc16::OnGioOut(const dmc::GioOut& m) {
  // Bits past the advertised GIO OUT COUNT name outputs the device lacks.
  if ((m.triggers & ~GioMask(profile_.gio_outputs)) != 0) return AckCode::kErrRange;
  gio_.SetOutputs(m.triggers);
  return AckCode::kOk;
}

void Dmc16::OnMotorMove(uint32_t id, const dmc::MotorMove& m) {
  const uint16_t type = dmc::ToWire(MsgType::kMotorMove);
  AckCode code = AckCode::kOk;
  bool standing = false;
  if (!MotorValid(m.motor)) {
    code = AckCode::kErrRange;
  } else if (playback_.Playing()) {
    code = AckCode::kErrMoving;
  } else {
    const sim::StepperMotor& motor = rig_.motor(m.motor);
    standing = !motor.IsMoving() && ReportedPosition(m.motor) == m.position_steps;
    code = MoveMotor(m.motor, m.position_steps);
  }
  if (code != AckCode::kOk) {
    Ack(id, type, code);
    return;
  }
  // behaviour.position_confirm kBeforeAck: a move to the step the motor
  // stands on sends the positions before the answer.
  if (standing &&
      profile_.behaviour.position_confirm == Dmc16Behaviour::PositionConfirm::kBeforeAck) {
    SendPositionUpdate();
  }
  playback_.OnDirectMotion();
  virtual_.CancelJog();  // a motor commanded directly leaves the line
  // MSG_MOTOR_MOVE "Response Data: MOTOR STATUS"; dmc-lite answers ACK OK.
  if (profile_.behaviour.move_response) {
    Send(id, dmc::MotorMoveResponse{static_cast<uint8_t>(rig_.motor(m.motor).IsMoving() ? 1 : 0)});
  } else {
    Ack(id, type, AckCode::kOk);
  }
  EnsurePositionReports();
}

AckCode Dmc16::OnMotorStop(const dmc::MotorStop& m) {
  if (!MotorValid(m.motor)) return AckCode::kErrRange;
  virtual_.CancelJog();
  if (playback_.Playing()) {
    // Stopping one motor of a synchronised run ends the run.
    playback_.Abort(true);
    rig_.StopAll();
  } else {
    // A coupled motor stops with the motor that drives it.
    rig_.motor(rig_.Root(m.motor)).Stop();
  }
  return AckCode::kOk;
}

AckCode Dmc16::OnStopAll(const dmc::MotorStopAll& m) {
  const TimeNs now = scheduler_.Now();
  // behaviour.stop_all_lockout_ms (FACTS "DMC v2": dmc-lite): a STOP_ALL
  // without flags that stops moving motors sets the hard-stop state.
  if (profile_.behaviour.stop_all_lockout_ms > 0 && rig_.AnyMoving() && m.flags.value_or(0) == 0) {
    hard_stop_lock_ = true;
    hard_stop_lock_ns_ = now;
  }
  // hard_stop_window_ms 0: never (dmc-lite: a motor already stopping keeps
  // its deceleration).
  const bool second = profile_.hard_stop_window_ms > 0 && last_stop_all_ns_ >= 0 &&
                      now - last_stop_all_ns_ <= TimeNs{profile_.hard_stop_window_ms} * kNsPerMs;
  last_stop_all_ns_ = now;
  virtual_.CancelJog();
  silent_stop_ = m.flags.has_value() && (*m.flags & dmc::kStopAllSilent) != 0;
  const bool playing = playback_.Playing();
  playback_.Abort(true);
  playback_.Disarm();
  const double within_s = profile_.behaviour.stop_all_within_ms / 1000.0;
  // "If the device gets a second STOP_ALL soon after a first, it should HARD STOP."
  if (second) {
    rig_.HardStopAll();
  } else if (Tick() > 0 && !playing) {
    // With a velocity tick the stop starts at the next tick, from the
    // motion then (a run's end is the run's own).
    rig_.StopAllAt(NextTickNs(), within_s);
  } else {
    rig_.StopAll(within_s);
  }
  return AckCode::kOk;
}

AckCode Dmc16::OnResetPosition(const dmc::MotorResetPosition& m) {
  if (!MotorValid(m.motor)) return AckCode::kErrRange;
  // ERR_MOVING "while the rig is moving": a live run, a shot or a jog-all
  // plays the rig as a whole, so no position is renamed under it.
  if (playback_.Playing()) return AckCode::kErrMoving;
  // behaviour.reset_refused_while_any_moves: dmc-lite checks one moving flag.
  if (profile_.behaviour.reset_refused_while_any_moves && rig_.AnyMoving()) {
    return AckCode::kErrMoving;
  }
  const AckCode code = AckForMoveStatus(rig_.motor(m.motor).ResetPosition(m.position_steps));
  if (code == AckCode::kOk) {
    const size_t i = static_cast<size_t>(m.motor - 1);
    // The count and the reported position agree again (behaviour.coupling).
    uncounted_[i] = 0;
    if (follow_origin_[i]) follow_origin_[i] = m.position_steps;
    playback_.ForgetFrame();
    // The count is renamed, nothing moves: the physical joint stays put.
    if (physical_) physical_->Rebase();
  }
  return code;
}

AckCode Dmc16::OnJog(const dmc::MotorJog& m) {
  if (!MotorValid(m.motor)) return AckCode::kErrRange;
  // "SPEED WORD 1=inching, 10000=jog at max velocity". With
  // jog_speed_checked false any SPEED is taken; on the spec's scale 0 then
  // jogs as 1 and above 10000 as 10000 (sim::JogSpeedFraction), on
  // jog_speed_scale kPer10000 it scales on without bound.
  uint16_t speed = m.speed;
  const bool per_10000 =
      profile_.behaviour.jog_speed_scale == Dmc16Behaviour::JogSpeedScale::kPer10000;
  if (profile_.behaviour.jog_speed_checked) {
    if (speed < dmc::kJogSpeedInch || speed > dmc::kJogSpeedMax) return AckCode::kErrRange;
  } else if (!per_10000) {
    speed = std::clamp(speed, dmc::kJogSpeedInch, dmc::kJogSpeedMax);
  }
  if (playback_.Playing()) {
    return AckCode::kErrMoving;
  }
  if (IgnoresMotion(m.motor)) return AckCode::kOk;
  sim::StepperMotor& motor = rig_.motor(m.motor);
  const sim::MotionProfile& mp = motor.profile();
  int64_t destination = m.destination_steps + UncountedSteps(m.motor);
  double velocity = 0;
  double accel = 0;
  if (per_10000) {
    // dmc-lite: the max velocity and acceleration times SPEED/10000, no
    // upper bound, at least kJogMinRate each; the acceleration no less
    // than brings the present speed to rest in max velocity / max accel.
    const double share = speed / static_cast<double>(dmc::kJogSpeedMax);
    velocity = std::max(kJogMinRate, mp.max_velocity_steps_per_s * share);
    accel = std::max(
        {kJogMinRate, mp.max_accel_steps_per_s2 * share,
         std::abs(motor.Velocity()) * mp.max_accel_steps_per_s2 / mp.max_velocity_steps_per_s});
  } else {
    velocity = mp.max_velocity_steps_per_s * sim::JogSpeedFraction(speed);
    accel = mp.max_accel_steps_per_s2 * sim::JogSpeedFraction(speed);
  }
  sim::MoveStatus status = sim::MoveStatus::kOk;
  if (profile_.behaviour.jog_horizon_ms == 0 || motor.following()) {
    status = motor.JogAt(destination, velocity, accel);
  } else {
    // behaviour.jog_horizon_ms: the jog goes no further than where, having
    // sped up towards its velocity for at most the horizon (then kept it for
    // the rest of it), it would brake to rest; against the present motion
    // it only stops the motor.
    const int64_t at = motor.Position();
    const double v0 = motor.Velocity();
    const int dir = destination > at ? 1 : -1;
    if (v0 * dir < 0) {
      motor.Stop();
    } else if (destination != at) {
      const double horizon_s = profile_.behaviour.jog_horizon_ms / 1000.0;
      const double vi = std::abs(v0);
      double t_accel = 0;
      double t_cruise = horizon_s;
      if (vi < velocity) {
        t_accel = std::min((velocity - vi) / accel, horizon_s);
        t_cruise = horizon_s - t_accel;
      }
      const double v_top = vi + accel * t_accel;
      const double reach = vi * t_accel + 0.5 * accel * t_accel * t_accel + v_top * t_cruise +
                           0.5 * v_top * v_top / accel;
      const auto far = static_cast<int64_t>(std::llround(static_cast<double>(at) + dir * reach));
      destination = dir > 0 ? std::min(destination, far) : std::max(destination, far);
      status = motor.JogAt(destination, velocity, accel);
    }
  }
  const AckCode code = AckForMoveStatus(status);
  if (code == AckCode::kOk) {
    playback_.OnDirectMotion();
    virtual_.CancelJog();
    EnsurePositionReports();
  }
  return code;
}

AckCode Dmc16::OnConfigure(const dmc::MotorConfigure& m) {
  if (!MotorValid(m.motor)) return AckCode::kErrRange;
  if (profile_.behaviour.coupling == Dmc16Behaviour::Coupling::kDrivesNext) {
    return ConfigureDrivingNext(m);
  }
  // Couple motors (capability 0x0100; FACTS "DMC v2": dmc-lite's flags 0x10
  // coupled, 0x20 coupled reversed). The request names no second motor, so
  // a coupled motor follows the motor before it (docs/protocol-notes.md);
  // motor 1 has none. Without the capability the bits are unknown flags.
  const bool couple = profile_.Has(dmc::kCapCoupleMotors) &&
                      (m.flags & (dmc::kMotorCoupled | dmc::kMotorCoupledReversed)) != 0;
  const int leader = couple ? m.motor - 1 : 0;
  const bool reversed = couple && (m.flags & dmc::kMotorCoupledReversed) != 0;
  if (couple && leader < 1) return AckCode::kErrRange;
  if (leader != rig_.leader(m.motor) || reversed != rig_.coupled_reversed(m.motor)) {
    const sim::MoveStatus s =
        leader != 0 ? rig_.Couple(m.motor, leader, reversed) : rig_.Uncouple(m.motor);
    if (s != sim::MoveStatus::kOk) return AckForMoveStatus(s);
  }
  // FACTS: other bits (0x04 axis used in virtuals, 0x08 live control) are
  // accepted without error; they are kept in State().
  config_flags_[static_cast<size_t>(m.motor - 1)] = m.flags;
  rig_.motor(m.motor).SetEnabled((m.flags & dmc::kMotorEnabled) != 0);
  rig_.motor(m.motor).SetBlur((m.flags & dmc::kMotorBlurEnabled) != 0);
  return AckCode::kOk;
}

AckCode Dmc16::OnSetSpeed(const dmc::MotorSetSpeed& m) {
  if (!MotorValid(m.motor)) return AckCode::kErrRange;
  double velocity = m.max_velocity_steps_per_s;
  double accel = m.max_accel_steps_per_s2;
  if (profile_.behaviour.set_speed_checked) {
    if (velocity == 0 || accel == 0) return AckCode::kErrRange;
  } else {
    // dmc-lite: no MAX VELOCITY under 10 steps/s; MAX ACCEL 0 is half of it.
    velocity = std::max(velocity, kSetSpeedMinVelocity);
    if (accel == 0) accel = velocity / 2;
  }
  sim::MotionProfile p = rig_.motor(m.motor).profile();
  p.max_velocity_steps_per_s = velocity;
  p.max_accel_steps_per_s2 = accel;
  return AckForMoveStatus(rig_.motor(m.motor).SetProfile(p));
}

AckCode Dmc16::OnSetLimits(const dmc::MotorSetLimits& m) {
  if (!MotorValid(m.motor)) return AckCode::kErrRange;
  if (m.lower_enable > 1 || m.upper_enable > 1) return AckCode::kErrRange;
  if (m.lower_enable != 0 && m.upper_enable != 0 && m.lower_limit_steps > m.upper_limit_steps) {
    return AckCode::kErrRange;
  }
  const sim::HardLimitBinding binding = sim::HardLimitBinding::FromWire(m.hw_set);
  if (binding.set > profile_.hw_limit_sets) return AckCode::kErrRange;
  sim::SoftLimits soft;
  soft.lower_enabled = m.lower_enable != 0;
  soft.lower_steps = m.lower_limit_steps;
  soft.upper_enabled = m.upper_enable != 0;
  soft.upper_steps = m.upper_limit_steps;
  rig_.motor(m.motor).SetSoftLimits(soft);
  return AckForMoveStatus(rig_.BindLimits(m.motor, binding));
}

// --- motion and the reference firmware's departures ---------------------------------------

AckCode Dmc16::ConfigureDrivingNext(const dmc::MotorConfigure& m) {
  // behaviour.coupling kDrivesNext (dmc-lite): with every motor's flags, a
  // flagged motor drives the motor after it unless it is itself driven; the
  // last motor drives none.
  std::vector<uint8_t> flags = config_flags_;
  flags[static_cast<size_t>(m.motor - 1)] = m.flags;
  const int count = rig_.motor_count();
  std::vector<int> leader(static_cast<size_t>(count + 1), 0);
  std::vector<bool> reversed(static_cast<size_t>(count + 1), false);
  const uint8_t kCoupleBits = dmc::kMotorCoupled | dmc::kMotorCoupledReversed;
  if (profile_.Has(dmc::kCapCoupleMotors)) {
    for (int k = 1; k < count; ++k) {
      const uint8_t f = flags[static_cast<size_t>(k - 1)];
      if ((f & kCoupleBits) == 0) continue;
      leader[static_cast<size_t>(k + 1)] = k;
      reversed[static_cast<size_t>(k + 1)] = (f & dmc::kMotorCoupledReversed) != 0;
      ++k;  // the driven motor's own flags drive nothing
    }
  }
  const auto changes = [&](int k) {
    return leader[static_cast<size_t>(k)] != rig_.leader(k) ||
           reversed[static_cast<size_t>(k)] != rig_.coupled_reversed(k);
  };
  // Nothing changes while a motor it concerns moves (sim::Rig::Couple).
  for (int k = 1; k <= count; ++k) {
    if (!changes(k)) continue;
    const int old_leader = rig_.leader(k), new_leader = leader[static_cast<size_t>(k)];
    if (rig_.motor(k).IsMoving() || (old_leader != 0 && rig_.motor(old_leader).IsMoving()) ||
        (new_leader != 0 && rig_.motor(new_leader).IsMoving())) {
      return AckCode::kErrMoving;
    }
  }
  for (int k = 1; k <= count; ++k) {
    if (!changes(k)) continue;
    const size_t i = static_cast<size_t>(k - 1);
    const int64_t at = rig_.motor(k).Position();
    // The steps a driven motor makes are not counted in its reported
    // position: they are set aside when it is let go.
    if (follow_origin_[i]) uncounted_[i] += at - *follow_origin_[i];
    follow_origin_[i].reset();
    const int new_leader = leader[static_cast<size_t>(k)];
    const sim::MoveStatus s = new_leader != 0
                                  ? rig_.Couple(k, new_leader, reversed[static_cast<size_t>(k)])
                                  : rig_.Uncouple(k);
    if (s != sim::MoveStatus::kOk) return AckForMoveStatus(s);
    if (new_leader != 0) follow_origin_[i] = at;
  }
  config_flags_ = std::move(flags);
  rig_.motor(m.motor).SetEnabled((m.flags & dmc::kMotorEnabled) != 0);
  rig_.motor(m.motor).SetBlur((m.flags & dmc::kMotorBlurEnabled) != 0);
  return AckCode::kOk;
}

int64_t Dmc16::UncountedSteps(int motor) const {
  const size_t i = static_cast<size_t>(motor - 1);
  int64_t n = uncounted_[i];
  if (follow_origin_[i]) n += rig_.motor(motor).Position() - *follow_origin_[i];
  return n;
}

void Dmc16::ResyncUncounted(int motor) {
  // behaviour.coupling kDrivesNext: a motor's own motion ending reads its
  // step count again, the steps it made while driven included; a jump of
  // more than kResyncExceptionSteps is reported once per power-on as an
  // engine exception (MOTOR_HARD_STOP REASON 100), and everything stops.
  const size_t i = static_cast<size_t>(motor - 1);
  if (uncounted_[i] == 0 || follow_origin_[i]) return;
  const int64_t jump = uncounted_[i];
  uncounted_[i] = 0;
  if (engine_exception_sent_ || std::abs(jump) <= kResyncExceptionSteps) return;
  engine_exception_sent_ = true;
  SendUnsolicited(dmc::MotorHardStop{static_cast<uint8_t>(dmc::HardStopReason::kEngineException),
                                     static_cast<uint8_t>(motor)});
  virtual_.CancelJog();
  playback_.Abort(true);
  rig_.StopAll();
}

AckCode Dmc16::MoveMotor(int motor, int64_t target_steps) {
  if (IgnoresMotion(motor)) return AckCode::kOk;
  // The target is in reported steps (behaviour.coupling: steps made while
  // driven are not counted in them).
  sim::StepperMotor& m = rig_.motor(motor);
  const int64_t target = target_steps + UncountedSteps(motor);
  // With a velocity tick the move starts at the next tick (one to the step
  // a resting motor stands on is none).
  const bool none = !m.IsMoving() && m.Position() == target;
  return AckForMoveStatus(Tick() > 0 && !none ? m.MoveToAt(NextTickNs(), target)
                                              : m.MoveTo(target));
}

AckCode Dmc16::OnPositionFrame(uint32_t frame) { return playback_.PositionFrame(frame); }

// behaviour.positions_truncate: dmc-lite reports its position (a float
// between steps while moving) truncated toward zero, not the nearest step.
// With a velocity tick a moving motor reads where the device sent it for the
// tick under way, the plan at the next tick (dmc-lite reports its motion
// core's position, the end of the segment its stepping core is running). A
// live run on the tick reports the position the engine sent the motor to.
int64_t Dmc16::ReportedPosition(int motor) const {
  if (const std::optional<int64_t> p = playback_.ModelPosition(motor)) return *p;
  const sim::StepperMotor& m = rig_.motor(motor);
  // Steps made while driven are not counted (behaviour.coupling).
  const int64_t uncounted = UncountedSteps(motor);
  const TimeNs at = Tick() > 0 && m.IsMoving() ? NextTickNs() : scheduler_.Now();
  if (!profile_.behaviour.positions_truncate || !m.IsMoving()) {
    return m.PositionAt(at) - uncounted;
  }
  const double x =
      static_cast<double>(m.CurrentPlan().origin_steps()) + m.CurrentPlan().StateAt(at).x_steps;
  return static_cast<int64_t>(std::trunc(x)) - uncounted;
}

bool Dmc16::LockoutActive() const {
  if (!hard_stop_lock_) return false;
  // dmc-lite counts its velocity updates from the STOP_ALL and ends the
  // state at the first one past ~100 with the motors still.
  if (rig_.AnyMoving()) return true;
  return scheduler_.Now() - hard_stop_lock_ns_ <
         TimeNs{profile_.behaviour.stop_all_lockout_ms} * kNsPerMs;
}

bool Dmc16::HardStopLockout(uint16_t type) {
  if (!hard_stop_lock_) return false;
  if (!LockoutActive()) {
    hard_stop_lock_ = false;
    return false;
  }
  // Every request from MSG_MOTOR_MOVE (0x0031) up, MOTOR_GET_POSITION aside.
  return type >= dmc::ToWire(MsgType::kMotorMove) &&
         type != dmc::ToWire(MsgType::kMotorGetPosition);
}

}  // namespace moco::devices
