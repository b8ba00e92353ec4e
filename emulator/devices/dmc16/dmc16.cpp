// The emulated DMC-16 (see dmc16.h). Section names in comments are those of
// dmc-v2-protocol.txt; readings taken are listed in docs/protocol-notes.md.
#include "devices/dmc16/dmc16.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace moco::devices {

using dmc::AckCode;
using dmc::MsgType;
using sim::kNsPerMs;
using sim::kNsPerSecond;
using sim::TimeNs;

namespace {

// Frame intervals planned per motor at a time during playback: bounds the
// plan's memory whatever the length of the move.
constexpr uint32_t kWindowFrames = 32;
constexpr double kNsPerSecondF = 1e9;

int Sign(double v) { return v > 0 ? 1 : (v < 0 ? -1 : 0); }

sim::Segment Seg(double duration_s, double v0, double a) {
  sim::Segment s;
  s.duration_s = duration_s;
  s.v0_steps_per_s = v0;
  s.a_steps_per_s2 = a;
  return s;
}

// The bits of `count` GIO lines (MSG_HI GIO OUT / INPUT COUNT, 0-32).
uint32_t GioMask(int count) { return count >= 32 ? 0xffffffffu : (1u << count) - 1u; }

TimeNs CeilNs(double seconds) { return static_cast<TimeNs>(std::ceil(seconds * kNsPerSecondF)); }

}  // namespace

Dmc16::Dmc16(sim::Scheduler& scheduler, ByteSink& out, Dmc16Profile profile)
    : scheduler_(scheduler),
      out_(out),
      profile_(std::move(profile)),
      rig_(scheduler, profile_.motor_count, profile_.hw_limit_sets),
      gio_(scheduler, TimeNs{profile_.gio_debounce_ms} * kNsPerMs),
      dmx_(scheduler, profile_.dmx_ramp_rate_per_s),
      camera_(scheduler),
      upload_(profile_.upload_frame_count, profile_.motor_count, profile_.dmx_channels),
      virtual_(scheduler, rig_, planners_, profile_.virtual_axes, profile_.Advertised(),
               &Dmc16::FromMoveStatus),
      decoder_(std::make_unique<dmc::FrameDecoder>()) {
  for (int m = 1; m <= rig_.motor_count(); ++m) {
    auto planner = std::make_unique<ScriptPlanner>();
    planners_.push_back(planner.get());
    rig_.motor(m).SetPlanner(std::move(planner));
  }
  for (const Dmc16LimitSet& s : profile_.limit_sets) {
    rig_.SetLimitPlacement(s.set, sim::LimitSetPlacement{s.low_steps, s.high_steps});
  }
}

Dmc16::~Dmc16() {
  rig_.SetObserver(nullptr);
  gio_.SetListener(nullptr);
  physical_.reset();
  CancelAllTimers();
}

LineSettings Dmc16::Line() const {
  LineSettings l;
  l.baud = profile_.baud;
  return l;
}

// --- lifecycle ------------------------------------------------------------------------

void Dmc16::ResetState() {
  CancelAllTimers();
  for (ScriptPlanner* p : planners_) p->Drop();
  for (int m = 1; m <= rig_.motor_count(); ++m) {
    sim::StepperMotor& motor = rig_.motor(m);
    motor.EmergencyHalt();
    motor.ResetPosition(0);
    sim::MotionProfile mp;
    mp.max_velocity_steps_per_s = profile_.max_velocity_steps_per_s;
    mp.max_accel_steps_per_s2 = profile_.max_accel_steps_per_s2;
    mp.hard_stop_multiple = profile_.hard_stop_multiple;
    motor.SetProfile(mp);
    motor.SetEnabled(profile_.motors_enabled);
    motor.SetBlur(false);
    motor.SetSoftLimits({});
    rig_.BindLimits(m, {});
  }
  gio_.SetOutputs(0);
  camera_.SetFlags(0);
  for (int ch = 1; ch <= sim::DmxUniverse::kChannels; ++ch) dmx_.Set(ch, 0);
  upload_.Clear();
  virtual_.Reset();
  decoder_ = std::make_unique<dmc::FrameDecoder>();
  mode_ = Mode::kIdle;
  run_.reset();
  blur_.clear();
  stop_loop_ = false;
  passes_done_ = 0;
  on_frame_.reset();
  move_time_x1000_ = 0;
  last_stop_all_ns_ = -1;
  silent_stop_ = false;
  reposition_pending_ = false;
  reported_inputs_ = gio_.inputs() & GioMask(profile_.gio_inputs);
}

void Dmc16::PowerOn() {
  if (powered_) return;
  powered_ = true;
  rig_.SetObserver(nullptr);
  ResetState();
  rig_.SetObserver(this);
  gio_.SetListener([this](uint32_t inputs, uint32_t, TimeNs) { OnGioInputs(inputs); });
  StartPhysicalRig();
  // MSG_HI: "the device should issue a MSG_HI whenever it starts up".
  SendUnsolicited(profile_.Hi());
}

void Dmc16::OnMotionStarted(int /*motor_id*/, sim::TimeNs /*time_ns*/) {
  // Whatever started it (a request, a playback frame, a shot, a jog), the
  // physical rig follows the motors again (it sleeps while nothing moves).
  if (physical_) physical_->Wake();
}

void Dmc16::StartPhysicalRig() {
  if (!profile_.physical_rig.enabled) return;
  if (physical_) {
    // A power cycle restarts the step counts at 0 but the rig stands where
    // it stopped (open loop: the device no longer knows where that is).
    physical_->Rebase();
    return;
  }
  physics::PhysicalRig::Callbacks callbacks;
  callbacks.on_collision = [this](const physics::CollisionEvent& e) {
    // The camera head hit the floor or an obstacle: the rig's e-stop chain
    // trips (every motor halts, MOTOR_HARD_STOP with REASON 0 goes out) and
    // re-arms, as a bumper switch on a real rig would.
    // A head already at rest against it (a renewed contact while settling)
    // has nothing left to stop.
    ++stats_.collisions;
    last_collision_ = e.what;
    bool moving = false;
    for (int m = 1; m <= rig_.motor_count(); ++m) moving = moving || rig_.motor(m).IsMoving();
    EmitEvent({{"event", "collision"},
               {"with", e.what},
               {"began_ns", e.time_ns},
               {"halted_motors", moving}});
    if (!moving) return;
    rig_.EngageEStop();
    rig_.ReleaseEStop();
  };
  // A planned pause inside a move (a blurred axis waiting for the others to
  // reach speed) is not rest: the rig stays awake while a driving motor has
  // motion planned.
  callbacks.motion_planned = [this] {
    for (const int m : profile_.physical_rig.motors) {
      if (m != 0 && rig_.motor(m).IsMoving()) return true;
    }
    return false;
  };
  callbacks.on_stall = [this](const physics::StallEvent& e) {
    // An open-loop stepper slipped: the device's count and the joint differ
    // by `lost_steps` from now on, and nothing on the wire says so.
    ++stats_.stalls;
    const size_t j = static_cast<size_t>(e.joint);
    EmitEvent({{"event", "stall"},
               {"joint", std::string(physics::kJointNames[j])},
               {"motor", profile_.physical_rig.motors[j]},
               {"lost_steps", e.lost_steps},
               {"began_ns", e.time_ns},
               {"ended_ns", e.end_ns}});
  };
  physical_ = std::make_unique<physics::PhysicalRig>(
      scheduler_, profile_.physical_rig.rig,
      [this] {
        physics::StepCounts counts{};
        for (size_t j = 0; j < physics::kJointCount; ++j) {
          const int m = profile_.physical_rig.motors[j];
          counts[j] = m == 0 ? 0 : rig_.motor(m).Position();
        }
        return counts;
      },
      std::move(callbacks));
}

void Dmc16::PowerOff() {
  if (!powered_) return;
  powered_ = false;
  rig_.SetObserver(nullptr);
  gio_.SetListener(nullptr);
  CancelAllTimers();
  virtual_.CancelJog();
  for (int m = 1; m <= rig_.motor_count(); ++m) rig_.motor(m).EmergencyHalt();
  camera_.SetFlags(0);
  decoder_ = std::make_unique<dmc::FrameDecoder>();
  mode_ = Mode::kIdle;
  run_.reset();
}

void Dmc16::OnHostLink(bool open) {
  // A frame cut by the host closing the port is not completed by the next
  // session's bytes.
  if (!open) decoder_ = std::make_unique<dmc::FrameDecoder>();
}

void Dmc16::CancelTimer(sim::Scheduler::TimerId& id) {
  if (id != sim::Scheduler::kNoTimer) scheduler_.Cancel(id);
  id = sim::Scheduler::kNoTimer;
}

void Dmc16::CancelAllTimers() {
  CancelTimer(report_timer_);
  CancelTimer(frame_timer_);
  CancelTimer(phase_timer_);
  for (IoTimer& t : io_timers_) CancelTimer(t.id);
  io_timers_.clear();
}

// --- framing and dispatch ---------------------------------------------------------------

void Dmc16::OnHostBytes(wire::ByteView bytes) {
  if (!powered_) return;
  decoder_->Feed(bytes, [this](const dmc::FrameEvent& e) {
    if (const auto* f = std::get_if<dmc::FrameRef>(&e)) {
      OnFrame(*f);
    } else if (const auto* c = std::get_if<dmc::ChecksumError>(&e)) {
      // "If it is not [zero] the device should respond with response code
      // ACK_ERR_CHECKSUM" — with the ID and Type as received. An ACK from the
      // host is never answered, even a damaged one.
      if ((c->type & dmc::kFlagAck) == 0) {
        ++stats_.checksum_errors;
        ++stats_.requests;
        Ack(c->id, c->type, AckCode::kErrChecksum);
      }
    } else {
      // Noise, oversize Length (ERRATA 1.2) or a truncated candidate: nothing
      // trustworthy to answer (the reference parser drops them silently).
      ++stats_.framing_errors;
    }
  });
}

void Dmc16::OnFrame(const dmc::FrameRef& f) {
  if ((f.type & dmc::kFlagAck) != 0) {
    // ERRATA 1.9: the host's ACK of an unsolicited message; never waited for.
    ++stats_.host_acks;
    return;
  }
  ++stats_.requests;
  if (!Advertised(f.type)) {
    Ack(f.id, f.type, AckCode::kErrUnsupported);
    return;
  }
  dmc::Result<dmc::HostMessage> decoded = dmc::DecodeHostMessage(f.type, f.data);
  if (!decoded.ok()) {
    Ack(f.id, f.type, dmc::SuggestedAck(decoded.error()));
    return;
  }
  Handle(f.id, decoded.value());
}

bool Dmc16::Advertised(uint16_t type) const {
  const bool motors = profile_.motor_count > 0;
  const bool rt = profile_.Has(dmc::kCapRealTime);
  switch (static_cast<MsgType>(type)) {
    case MsgType::kHi:
    case MsgType::kGioOut:
    case MsgType::kGioIn:
    case MsgType::kGioCam:
      return true;
    case MsgType::kDmx:
      return profile_.dmx_channels > 0;
    case MsgType::kMotorStatus:
    case MsgType::kMotorMove:
    case MsgType::kMotorStop:
    case MsgType::kMotorStopAll:
    case MsgType::kMotorGetPosition:
    case MsgType::kMotorResetPosition:
    case MsgType::kMotorJog:
    case MsgType::kMotorConfigure:
    case MsgType::kMotorSetSpeed:
    case MsgType::kMotorSetLimits:
    case MsgType::kMotorHardStop:
      return motors;
    case MsgType::kRtUploadMoveBegin:
    case MsgType::kRtUploadMoveAxis:
    case MsgType::kRtUploadMoveEnd:
    case MsgType::kRtUploadMoveTriggers:
    case MsgType::kRtPositionFrame:
    case MsgType::kRtRunMove:
    case MsgType::kRtJogAll:
      return rt;
    case MsgType::kRtUploadMoveDmx:
      return rt && profile_.dmx_channels > 0;
    case MsgType::kRtShootFrame:
      return profile_.Has(dmc::kCapGoMotion);
    case MsgType::kRtShootFrame2:
      return profile_.Has(dmc::kCapGoMotion2);
    case MsgType::kRtGo:
      return rt || profile_.Has(dmc::kCapGoMotion) || profile_.Has(dmc::kCapGoMotion2);
    case MsgType::kRtStopLoop:
      return profile_.Has(dmc::kCapRtLooping);
    case MsgType::kVirtConfig:
    case MsgType::kVirtMove:
    case MsgType::kVirtStop:
    case MsgType::kVirtJog:
    case MsgType::kVirtJogOnLine:
    case MsgType::kVirtGetPosition:
      // "If the device advertises virtuals" (any of the four mode bits).
      return profile_.Has(dmc::kCapVirtBoomSwingTrack | dmc::kCapVirtSwingPan |
                          dmc::kCapVirtYSwingTrack | dmc::kCapVirtXyz);
    case MsgType::kVirtAimPoint:
      return profile_.Has(dmc::kCapAimPoint);
    case MsgType::kRtEnd:
      // A device-to-host message; a host sending it plainly is not a request
      // this device knows.
      return false;
  }
  return false;
}

void Dmc16::Handle(uint32_t id, const dmc::HostMessage& msg) {
  const uint16_t type = dmc::TypeOf(msg);
  std::visit(
      wire::Overloaded{
          [&](const dmc::HiRequest&) { Send(id, profile_.Hi()); },
          [&](const dmc::Dmx& m) { Ack(id, type, OnDmx(m)); },
          [&](const dmc::GioOut& m) { Ack(id, type, OnGioOut(m)); },
          [&](const dmc::GioInRequest&) {
            Send(id, dmc::GioInReport{gio_.inputs() & GioMask(profile_.gio_inputs)});
          },
          [&](const dmc::GioCam& m) {
            // Test of the camera outputs: shutter and meter lines follow the flags.
            camera_.SetFlags(m.flags & (dmc::kGioCamShutter | dmc::kGioCamMeter));
            Ack(id, type, AckCode::kOk);
          },
          [&](const dmc::MotorStatusRequest&) {
            Send(id, dmc::MotorStatusResponse{rig_.MovingMask(),
                                              static_cast<uint8_t>(dmx_.Adjusting() ? 1 : 0)});
          },
          [&](const dmc::MotorMove& m) { OnMotorMove(id, m); },
          [&](const dmc::MotorStop& m) { Ack(id, type, OnMotorStop(m)); },
          [&](const dmc::MotorStopAll& m) { Ack(id, type, OnStopAll(m)); },
          [&](const dmc::MotorGetPositionRequest&) { SendPositions(id); },
          [&](const dmc::MotorResetPosition& m) {
            const AckCode code = OnResetPosition(m);
            Ack(id, type, code);
            // "After changing the internal position and responding to this
            // message, the device should send a MSG_MOTOR_GET_POSITION".
            if (code == AckCode::kOk) SendPositionUpdate();
          },
          [&](const dmc::MotorJog& m) { Ack(id, type, OnJog(m)); },
          [&](const dmc::MotorConfigure& m) { Ack(id, type, OnConfigure(m)); },
          [&](const dmc::MotorSetSpeed& m) { Ack(id, type, OnSetSpeed(m)); },
          [&](const dmc::MotorSetLimits& m) { Ack(id, type, OnSetLimits(m)); },
          [&](const dmc::RtUploadMoveBegin& m) {
            if (Playing()) {
              Ack(id, type, AckCode::kErrMoving);
              return;
            }
            mode_ = Mode::kIdle;
            run_.reset();
            on_frame_.reset();
            Ack(id, type, upload_.Begin(m.start_frame, m.end_frame).code);
          },
          [&](const dmc::RtUploadMoveAxis& m) { Ack(id, type, upload_.Axis(m).code); },
          [&](const dmc::RtUploadMoveDmx& m) { Ack(id, type, upload_.Dmx(m).code); },
          [&](const dmc::RtUploadMoveTriggers& m) { Ack(id, type, upload_.Triggers(m).code); },
          [&](const dmc::RtUploadMoveEnd&) { Ack(id, type, upload_.End().code); },
          [&](const dmc::RtPositionFrame& m) { Ack(id, type, OnPositionFrame(m)); },
          [&](const dmc::RtRunMove& m) { Ack(id, type, OnRunMove(m)); },
          [&](const dmc::RtShootFrame& m) {
            // Blur percent of the frame's 360 degrees, centred on the frame
            // (docs/protocol-notes.md); DIRECTION 0 plays B towards A.
            if (m.blur_percent_x10 > 1000) {
              Ack(id, type, AckCode::kErrRange);
              return;
            }
            const double half = 180.0 * m.blur_percent_x10 / 1000.0;
            Ack(id, type,
                OnShootFrame(m.frame, m.direction == dmc::kDirectionBackward ? -1 : 1,
                             m.exposure_ms, 180.0 - half, 180.0 + half, m.motors));
          },
          [&](const dmc::RtShootFrame2& m) {
            if (m.open_angle_deg > 360 || m.close_angle_deg > 360 ||
                m.close_angle_deg < m.open_angle_deg) {
              Ack(id, type, AckCode::kErrRange);
              return;
            }
            Ack(id, type,
                OnShootFrame(m.frame, 1, m.exposure_ms, m.open_angle_deg, m.close_angle_deg,
                             m.motors));
          },
          [&](const dmc::RtGo&) { Ack(id, type, OnGo()); },
          [&](const dmc::RtStopLoop&) { Ack(id, type, OnStopLoop()); },
          [&](const dmc::RtJogAll& m) { Ack(id, type, OnJogAll(m)); },
          [&](const dmc::VirtConfig& m) {
            Ack(id, type, Playing() ? AckCode::kErrMoving : virtual_.Configure(m));
          },
          [&](const dmc::VirtMove& m) {
            Ack(id, type, Playing() ? AckCode::kErrMoving : AfterVirtualMotion(virtual_.Move(m)));
          },
          [&](const dmc::VirtJog& m) {
            Ack(id, type, Playing() ? AckCode::kErrMoving : AfterVirtualMotion(virtual_.Jog(m)));
          },
          [&](const dmc::VirtJogOnLine& m) {
            Ack(id, type,
                Playing() ? AckCode::kErrMoving : AfterVirtualMotion(virtual_.JogOnLine(m)));
          },
          [&](const dmc::VirtStop& m) {
            // Stopping during playback ends the run, as MOTOR_STOP does.
            if (Playing() && m.axis >= 1 && m.axis <= 6) {
              Abort(true);
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
            if (m.type == dmc::ToWire(MsgType::kMotorHardStop)) {
              // Listed among the motor commands a device must handle, with no
              // request data: read as "hard stop everything now".
              virtual_.CancelJog();
              Abort(true);
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

AckCode Dmc16::AfterVirtualMotion(AckCode code) {
  if (code != AckCode::kOk) return code;
  if (mode_ == Mode::kArmedRun || mode_ == Mode::kArmedShoot) mode_ = Mode::kIdle;
  on_frame_.reset();
  EnsurePositionReports();
  return code;
}

// --- output -----------------------------------------------------------------------------

void Dmc16::Send(uint32_t id, const dmc::DeviceMessage& m) {
  tx_.clear();
  dmc::Encode(id, m, tx_);
  out_.Write(tx_);
}

void Dmc16::SendUnsolicited(const dmc::DeviceMessage& m) {
  ++stats_.unsolicited;
  Send(next_id_++, m);
}

void Dmc16::Ack(uint32_t id, uint16_t type, AckCode code) {
  if (code != AckCode::kOk) ++stats_.error_replies;
  dmc::Ack a;
  a.type = static_cast<uint16_t>(type & ~dmc::kFlagAck);
  a.code = dmc::ToWire(code);
  a.width = profile_.ack_width;
  Send(id, a);
}

void Dmc16::SendPositions(uint32_t id) {
  dmc::MotorPositionReport r;
  r.move_time_x1000 = move_time_x1000_;
  r.positions_steps.reserve(static_cast<size_t>(rig_.motor_count()));
  for (int m = 1; m <= rig_.motor_count(); ++m) {
    // The wire carries int32; positions past it saturate rather than wrap.
    const int64_t p = rig_.motor(m).Position();
    r.positions_steps.push_back(static_cast<int32_t>(std::clamp<int64_t>(
        p, std::numeric_limits<int32_t>::min(), std::numeric_limits<int32_t>::max())));
  }
  Send(id, r);
}

void Dmc16::SendPositionUpdate() {
  ++stats_.unsolicited;
  SendPositions(next_id_++);
}

// "The device should send these out, about every 0.10 seconds, if any of the
// motors are moving" — and once when they stop (OnMotionFinished).
void Dmc16::EnsurePositionReports() {
  if (report_timer_ != sim::Scheduler::kNoTimer || !rig_.AnyMoving()) return;
  report_timer_ = scheduler_.After(TimeNs{profile_.position_report_interval_ms} * kNsPerMs,
                                   [this] { OnReportTimer(); });
}

void Dmc16::OnReportTimer() {
  report_timer_ = sim::Scheduler::kNoTimer;
  if (!rig_.AnyMoving()) return;
  // During playback the per-frame reports take the place of the cadence.
  if (mode_ != Mode::kPass && mode_ != Mode::kJogAll) SendPositionUpdate();
  EnsurePositionReports();
}

// --- simple commands ------------------------------------------------------------------------

AckCode Dmc16::FromMoveStatus(sim::MoveStatus s) {
  switch (s) {
    case sim::MoveStatus::kOk:
      return AckCode::kOk;
    case sim::MoveStatus::kMoving:
      return AckCode::kErrMoving;
    case sim::MoveStatus::kSoftLimitLower:
      return AckCode::kErrSoftLow;
    case sim::MoveStatus::kSoftLimitUpper:
      return AckCode::kErrSoftUp;
    case sim::MoveStatus::kHardLimitLower:
      return AckCode::kErrHardLow;
    case sim::MoveStatus::kHardLimitUpper:
      return AckCode::kErrHardUp;
    case sim::MoveStatus::kBadArgument:
      return AckCode::kErrRange;
    case sim::MoveStatus::kDisabled:
    case sim::MoveStatus::kEStop:
      return AckCode::kErrGeneral;
  }
  return AckCode::kErrGeneral;
}

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
  if (!MotorValid(m.motor)) {
    code = AckCode::kErrRange;
  } else if (Playing()) {
    code = AckCode::kErrMoving;
  } else {
    code = FromMoveStatus(rig_.motor(m.motor).MoveTo(m.position_steps));
  }
  if (code != AckCode::kOk) {
    Ack(id, type, code);
    return;
  }
  if (mode_ == Mode::kArmedRun || mode_ == Mode::kArmedShoot) mode_ = Mode::kIdle;
  on_frame_.reset();
  virtual_.CancelJog();  // a motor commanded directly leaves the line
  Send(id, dmc::MotorMoveResponse{static_cast<uint8_t>(rig_.motor(m.motor).IsMoving() ? 1 : 0)});
  EnsurePositionReports();
}

AckCode Dmc16::OnMotorStop(const dmc::MotorStop& m) {
  if (!MotorValid(m.motor)) return AckCode::kErrRange;
  virtual_.CancelJog();
  if (Playing()) {
    // Stopping one motor of a synchronised run ends the run.
    Abort(true);
    rig_.StopAll();
  } else {
    rig_.motor(m.motor).Stop();
  }
  return AckCode::kOk;
}

AckCode Dmc16::OnStopAll(const dmc::MotorStopAll& m) {
  const TimeNs now = scheduler_.Now();
  const bool second = last_stop_all_ns_ >= 0 &&
                      now - last_stop_all_ns_ <= TimeNs{profile_.hard_stop_window_ms} * kNsPerMs;
  last_stop_all_ns_ = now;
  virtual_.CancelJog();
  silent_stop_ = m.flags.has_value() && (*m.flags & dmc::kStopAllSilent) != 0;
  Abort(true);
  if (mode_ == Mode::kArmedRun || mode_ == Mode::kArmedShoot) mode_ = Mode::kIdle;
  run_.reset();
  // "If the device gets a second STOP_ALL soon after a first, it should HARD STOP."
  if (second) {
    rig_.HardStopAll();
  } else {
    rig_.StopAll();
  }
  return AckCode::kOk;
}

AckCode Dmc16::OnResetPosition(const dmc::MotorResetPosition& m) {
  if (!MotorValid(m.motor)) return AckCode::kErrRange;
  const AckCode code = FromMoveStatus(rig_.motor(m.motor).ResetPosition(m.position_steps));
  if (code == AckCode::kOk) {
    on_frame_.reset();
    // The count is renamed, nothing moves: the physical joint stays put.
    if (physical_) physical_->Rebase();
  }
  return code;
}

AckCode Dmc16::OnJog(const dmc::MotorJog& m) {
  if (!MotorValid(m.motor)) return AckCode::kErrRange;
  if (m.speed < dmc::kJogSpeedInch || m.speed > dmc::kJogSpeedMax) return AckCode::kErrRange;
  if (Playing()) {
    return AckCode::kErrMoving;
  }
  const AckCode code = FromMoveStatus(rig_.motor(m.motor).Jog(m.destination_steps, m.speed));
  if (code == AckCode::kOk) {
    if (mode_ == Mode::kArmedRun || mode_ == Mode::kArmedShoot) mode_ = Mode::kIdle;
    on_frame_.reset();
    virtual_.CancelJog();
    EnsurePositionReports();
  }
  return code;
}

AckCode Dmc16::OnConfigure(const dmc::MotorConfigure& m) {
  if (!MotorValid(m.motor)) return AckCode::kErrRange;
  // FACTS: flag bits beyond 0x01/0x02 (virtual axis, live control, coupling)
  // are accepted without error; they are kept in State().
  rig_.motor(m.motor).SetEnabled((m.flags & dmc::kMotorEnabled) != 0);
  rig_.motor(m.motor).SetBlur((m.flags & dmc::kMotorBlurEnabled) != 0);
  return AckCode::kOk;
}

AckCode Dmc16::OnSetSpeed(const dmc::MotorSetSpeed& m) {
  if (!MotorValid(m.motor)) return AckCode::kErrRange;
  if (m.max_velocity_steps_per_s == 0 || m.max_accel_steps_per_s2 == 0) return AckCode::kErrRange;
  sim::MotionProfile p = rig_.motor(m.motor).profile();
  p.max_velocity_steps_per_s = m.max_velocity_steps_per_s;
  p.max_accel_steps_per_s2 = m.max_accel_steps_per_s2;
  return FromMoveStatus(rig_.motor(m.motor).SetProfile(p));
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
  return FromMoveStatus(rig_.BindLimits(m.motor, binding));
}

// --- real-time moves -------------------------------------------------------------------------

std::vector<int> Dmc16::PlaybackMotors() const {
  std::vector<int> out;
  for (int m : upload_.Motors()) {
    if (MotorValid(m) && rig_.motor(m).enabled()) out.push_back(m);
  }
  return out;
}

bool Dmc16::OnFramePosition(uint32_t frame) const {
  if (!upload_.Contains(frame) || rig_.AnyMoving()) return false;
  for (int m : PlaybackMotors()) {
    if (rig_.motor(m).Position() != upload_.Position(m, frame)) return false;
  }
  return true;
}

void Dmc16::ApplyFrameOutputs(uint32_t frame) {
  for (int ch : upload_.Channels()) {
    if (ch <= profile_.dmx_channels) dmx_.Set(ch, upload_.Level(ch, frame));
  }
  if (upload_.trigger_mask() != 0) {
    const uint32_t mask = upload_.trigger_mask();
    gio_.SetOutputs((gio_.outputs() & ~mask) | (upload_.TriggersAt(frame) & mask));
  }
}

AckCode Dmc16::OnPositionFrame(const dmc::RtPositionFrame& m) {
  if (!upload_.complete()) return AckCode::kErrGeneral;
  if (!upload_.Contains(m.frame)) return AckCode::kErrRange;
  if (Playing()) {
    return AckCode::kErrMoving;
  }
  if (rig_.estop_engaged()) return AckCode::kErrGeneral;
  const std::vector<int> motors = PlaybackMotors();
  // Check every motor first so a refusal moves nothing.
  for (int m_id : motors) {
    const sim::SoftLimits& s = rig_.motor(m_id).soft_limits();
    const int64_t p = upload_.Position(m_id, m.frame);
    if (s.upper_enabled && p > s.upper_steps) return AckCode::kErrSoftUp;
    if (s.lower_enabled && p < s.lower_steps) return AckCode::kErrSoftLow;
  }
  for (int m_id : motors) {
    const AckCode code = FromMoveStatus(rig_.motor(m_id).MoveTo(upload_.Position(m_id, m.frame)));
    if (code != AckCode::kOk) {
      rig_.StopAll();
      return code;
    }
  }
  // "send all motors (and DMX if applicable) to the uploaded frame position".
  for (int ch : upload_.Channels()) {
    if (ch <= profile_.dmx_channels) dmx_.Set(ch, upload_.Level(ch, m.frame));
  }
  mode_ = Mode::kIdle;
  run_.reset();
  on_frame_ = m.frame;
  move_time_x1000_ = static_cast<uint32_t>(
      std::min<uint64_t>(uint64_t{m.frame} * dmc::kMoveTimeScale, UINT32_MAX));
  EnsurePositionReports();
  return AckCode::kOk;
}

Dmc16::Pass Dmc16::MakePass(uint32_t from, uint32_t to, double fps, double pre_s,
                            double post_s) const {
  Pass p;
  p.from_frame = from;
  p.to_frame = to;
  p.dir = to >= from ? 1 : -1;
  p.fps = fps;
  p.preroll_s = pre_s;
  p.postroll_s = post_s;
  return p;
}

int32_t Dmc16::PassPosition(int motor, const Pass& p, uint32_t k) const {
  const int64_t frame = int64_t{p.from_frame} + int64_t{p.dir} * k;
  return upload_.Position(motor, static_cast<uint32_t>(frame));
}

double Dmc16::PassVelocity(int motor, const Pass& p, uint32_t k) const {
  return (static_cast<double>(PassPosition(motor, p, k + 1)) - PassPosition(motor, p, k)) * p.fps;
}

namespace {
uint32_t Intervals(uint32_t a, uint32_t b) { return a > b ? a - b : b - a; }
}  // namespace

// Pre-roll (MSG_RT_RUN_MOVE): the rig starts at rest and accelerates uniformly
// over PRE-ROLL TIME to the speed of the first frame interval, reaching the
// start frame at full speed; it covers v*T/2, rounded down to whole steps so
// the acceleration never exceeds v/T.
int64_t Dmc16::PrerollStart(int motor, const Pass& p) const {
  const double v = Intervals(p.from_frame, p.to_frame) == 0 ? 0 : PassVelocity(motor, p, 0);
  const auto d = static_cast<int64_t>(std::floor(std::fabs(v) * p.preroll_s / 2));
  return PassPosition(motor, p, 0) - Sign(v) * d;
}

// Post-roll: decelerates uniformly from the last interval's speed to rest
// over POST-ROLL TIME, past the end frame.
int64_t Dmc16::PostrollEnd(int motor, const Pass& p) const {
  const uint32_t n = Intervals(p.from_frame, p.to_frame);
  const double v = n == 0 ? 0 : PassVelocity(motor, p, n - 1);
  const auto d = static_cast<int64_t>(std::floor(std::fabs(v) * p.postroll_s / 2));
  return PassPosition(motor, p, n) + Sign(v) * d;
}

AckCode Dmc16::CheckPass(const Pass& p) const {
  const uint32_t n = Intervals(p.from_frame, p.to_frame);
  for (int m : PlaybackMotors()) {
    const sim::SoftLimits& s = rig_.motor(m).soft_limits();
    for (uint32_t k = 0; k <= n; ++k) {
      const int32_t x = PassPosition(m, p, k);
      if (s.upper_enabled && x > s.upper_steps) return AckCode::kErrSoftUp;
      if (s.lower_enabled && x < s.lower_steps) return AckCode::kErrSoftLow;
    }
    const int64_t pre = PrerollStart(m, p);
    const int64_t post = PostrollEnd(m, p);
    if ((s.upper_enabled && pre > s.upper_steps) || (s.lower_enabled && pre < s.lower_steps)) {
      return AckCode::kErrPreroll;
    }
    if ((s.upper_enabled && post > s.upper_steps) || (s.lower_enabled && post < s.lower_steps)) {
      return AckCode::kErrPostroll;
    }
  }
  return AckCode::kOk;
}

AckCode Dmc16::OnRunMove(const dmc::RtRunMove& m) {
  if (Playing()) {
    return AckCode::kErrMoving;
  }
  if (!upload_.complete()) return AckCode::kErrGeneral;
  if (m.fps_x1000 == 0 || !upload_.Contains(m.start_frame) || !upload_.Contains(m.end_frame) ||
      m.start_frame == m.end_frame) {
    return AckCode::kErrRange;
  }
  const uint16_t flags = m.flags.value_or(0);
  const bool loops = (flags & (dmc::kPlayPingPong | dmc::kPlayLoop)) != 0;
  const bool camera = (flags & (dmc::kPlayCameraVideo | dmc::kPlayCameraStills)) != 0;
  // FLAGS: "Only set if capability 0x0200 ... or 0x0400 ... are set".
  if ((loops && !profile_.Has(dmc::kCapRtLooping)) ||
      (camera && !profile_.Has(dmc::kCapRtCameraTrigger))) {
    return AckCode::kErrRange;
  }
  if ((flags & dmc::kPlayCameraStills) != 0) {
    const uint16_t open = m.camera_open_angle_deg.value_or(0);
    const uint16_t close = m.camera_close_angle_deg.value_or(360);
    if (open > 360 || close > 360 || close <= open) return AckCode::kErrRange;
  }
  if (m.bloop_dmx_channel > profile_.dmx_channels ||
      (m.bloop_outputs & ~GioMask(profile_.gio_outputs)) != 0) {
    return AckCode::kErrRange;
  }
  if (rig_.estop_engaged()) return AckCode::kErrGeneral;
  const double fps = m.fps_x1000 / static_cast<double>(dmc::kFpsScale);
  const double pre_s = m.preroll_ms / 1000.0;
  const double post_s = m.postroll_ms / 1000.0;
  const Pass forward = MakePass(m.start_frame, m.end_frame, fps, pre_s, post_s);
  if (AckCode c = CheckPass(forward); c != AckCode::kOk) return c;
  if ((flags & dmc::kPlayPingPong) != 0) {
    if (AckCode c = CheckPass(MakePass(m.end_frame, m.start_frame, fps, pre_s, post_s));
        c != AckCode::kOk) {
      return c;
    }
  }
  // Move to the pre-roll position and wait for MSG_RT_GO.
  for (int motor : PlaybackMotors()) {
    const AckCode code = FromMoveStatus(rig_.motor(motor).MoveTo(PrerollStart(motor, forward)));
    if (code != AckCode::kOk) {
      rig_.StopAll();
      return code;
    }
  }
  run_ = RunSetup{m, PlaybackMotors()};
  pass_ = forward;
  stop_loop_ = false;
  passes_done_ = 0;
  mode_ = Mode::kArmedRun;
  on_frame_.reset();
  EnsurePositionReports();
  return AckCode::kOk;
}

AckCode Dmc16::OnShootFrame(uint32_t frame, int dir, uint32_t exposure_ms, double open_deg,
                            double close_deg, const std::vector<dmc::BlurMotor>& motors) {
  if (Playing()) {
    return AckCode::kErrMoving;
  }
  if (!upload_.complete()) return AckCode::kErrGeneral;
  if (!upload_.Contains(frame) || exposure_ms == 0) return AckCode::kErrRange;
  if (rig_.estop_engaged()) return AckCode::kErrGeneral;
  std::vector<BlurAxis> axes;
  const double exposure_s = exposure_ms / 1000.0;
  for (const dmc::BlurMotor& b : motors) {
    if (!MotorValid(b.motor)) return AckCode::kErrRange;
    for (const BlurAxis& a : axes) {
      if (a.motor == b.motor) return AckCode::kErrRange;  // a motor listed twice
    }
    const sim::StepperMotor& motor = rig_.motor(b.motor);
    if (!motor.enabled()) return AckCode::kErrGeneral;
    // POS A at angle 0, POS B at angle 360; backward runs B towards A.
    const double from = dir > 0 ? b.pos_a_steps : b.pos_b_steps;
    const double to = dir > 0 ? b.pos_b_steps : b.pos_a_steps;
    BlurAxis a;
    a.motor = b.motor;
    a.x_open_steps = from + (to - from) * open_deg / 360.0;
    a.x_close_steps = from + (to - from) * close_deg / 360.0;
    const double v = (a.x_close_steps - a.x_open_steps) / exposure_s;
    if (std::fabs(v) > motor.profile().max_velocity_steps_per_s) return AckCode::kErrRange;
    const double ramp = v * v / (2 * motor.profile().max_accel_steps_per_s2);
    if (v > 0) {
      a.pre_steps = static_cast<int64_t>(std::floor(a.x_open_steps - ramp));
      a.post_steps = static_cast<int64_t>(std::ceil(a.x_close_steps + ramp));
    } else if (v < 0) {
      a.pre_steps = static_cast<int64_t>(std::ceil(a.x_open_steps + ramp));
      a.post_steps = static_cast<int64_t>(std::floor(a.x_close_steps - ramp));
    } else {
      a.pre_steps = a.post_steps = std::llround(a.x_open_steps);
    }
    const sim::SoftLimits& s = motor.soft_limits();
    if ((s.upper_enabled && a.pre_steps > s.upper_steps) ||
        (s.lower_enabled && a.pre_steps < s.lower_steps)) {
      return AckCode::kErrPreroll;
    }
    if ((s.upper_enabled && a.post_steps > s.upper_steps) ||
        (s.lower_enabled && a.post_steps < s.lower_steps)) {
      return AckCode::kErrPostroll;
    }
    axes.push_back(a);
  }
  // Motors of the move that are not blurred go to the frame's position.
  std::vector<std::pair<int, int64_t>> targets;
  for (const BlurAxis& a : axes) targets.emplace_back(a.motor, a.pre_steps);
  for (int m : PlaybackMotors()) {
    const bool blurred =
        std::any_of(axes.begin(), axes.end(), [m](const BlurAxis& a) { return a.motor == m; });
    if (!blurred) targets.emplace_back(m, upload_.Position(m, frame));
  }
  for (const auto& [m, target] : targets) {
    const AckCode code = FromMoveStatus(rig_.motor(m).MoveTo(target));
    if (code != AckCode::kOk) {
      rig_.StopAll();
      return code;
    }
  }
  for (int ch : upload_.Channels()) {
    if (ch <= profile_.dmx_channels) dmx_.Set(ch, upload_.Level(ch, frame));
  }
  blur_ = std::move(axes);
  shoot_frame_ = frame;
  exposure_ms_ = exposure_ms;
  run_.reset();
  mode_ = Mode::kArmedShoot;
  on_frame_.reset();
  move_time_x1000_ =
      static_cast<uint32_t>(std::min<uint64_t>(uint64_t{frame} * dmc::kMoveTimeScale, UINT32_MAX));
  EnsurePositionReports();
  return AckCode::kOk;
}

AckCode Dmc16::OnGo() {
  if (mode_ != Mode::kArmedRun && mode_ != Mode::kArmedShoot) {
    return mode_ == Mode::kIdle ? AckCode::kErrGeneral : AckCode::kErrMoving;
  }
  // "When the device has stopped moving, a MSG_RT_GO command will perform the run".
  if (rig_.AnyMoving()) return AckCode::kErrMoving;
  if (rig_.estop_engaged()) return AckCode::kErrGeneral;
  if (mode_ == Mode::kArmedRun) {
    for (int m : run_->motors) {
      if (rig_.motor(m).Position() != PrerollStart(m, pass_)) return AckCode::kErrNotInPosition;
    }
    StartPass(pass_);
  } else {
    for (const BlurAxis& a : blur_) {
      if (rig_.motor(a.motor).Position() != a.pre_steps) return AckCode::kErrNotInPosition;
    }
    StartShoot();
  }
  return AckCode::kOk;
}

AckCode Dmc16::OnStopLoop() {
  // "The currently running loop/ping-pong must stop after it reaches the next end point."
  stop_loop_ = true;
  return AckCode::kOk;
}

AckCode Dmc16::OnJogAll(const dmc::RtJogAll& m) {
  if (Playing()) {
    return AckCode::kErrMoving;
  }
  if (!upload_.complete()) return AckCode::kErrGeneral;
  if (m.fps_x1000 == 0 || !upload_.Contains(m.destination_frame)) return AckCode::kErrRange;
  if (rig_.estop_engaged()) return AckCode::kErrGeneral;
  // "The rig must already be on a frame position that is uploaded to the device."
  if (!on_frame_ || !OnFramePosition(*on_frame_)) return AckCode::kErrNotInPosition;
  if (*on_frame_ == m.destination_frame) return AckCode::kOk;
  Pass p = MakePass(*on_frame_, m.destination_frame,
                    m.fps_x1000 / static_cast<double>(dmc::kFpsScale), 0, 0);
  if (AckCode c = CheckPass(p); c != AckCode::kOk) return c;
  run_.reset();
  mode_ = Mode::kIdle;
  StartPass(p);
  mode_ = Mode::kJogAll;
  return AckCode::kOk;
}

// --- playback ---------------------------------------------------------------------------------

void Dmc16::Script(int motor, std::vector<sim::Segment> segments, int64_t target_steps) {
  ScriptPlanner* planner = planners_[static_cast<size_t>(motor - 1)];
  planner->Load(std::move(segments));
  const sim::MoveStatus s = rig_.motor(motor).MoveTo(target_steps);
  if (s != sim::MoveStatus::kOk) planner->Drop();
}

void Dmc16::AppendPath(int motor, const Pass& p, uint32_t k0, uint32_t k1,
                       std::vector<sim::Segment>& out) const {
  const double now_s = static_cast<double>(scheduler_.Now() - p.t_first_frame_ns) / kNsPerSecondF;
  for (uint32_t k = k0; k < k1; ++k) {
    const double v = PassVelocity(motor, p, k);
    const double end_s = (k + 1) / p.fps;
    // The first interval of a window starts now (at or a few ns after the
    // frame time): it ends on the ideal frame time so windows never drift.
    const double start_s = k == k0 ? std::max(now_s, k / p.fps) : k / p.fps;
    if (end_s > start_s) out.push_back(Seg(end_s - start_s, v, 0));
  }
}

void Dmc16::StartPass(const Pass& p) {
  pass_ = p;
  pass_.t_first_frame_ns = scheduler_.Now() + CeilNs(p.preroll_s);
  pass_.frames_done = 0;
  const uint16_t flags = run_ ? run_->request.flags.value_or(0) : 0;
  pass_.live = run_.has_value();
  pass_.video = pass_.live && (flags & dmc::kPlayCameraVideo) != 0;
  pass_.stills = pass_.live && (flags & dmc::kPlayCameraStills) != 0;
  mode_ = run_ ? Mode::kPass : Mode::kJogAll;
  CancelTimer(report_timer_);
  PlanWindow(0);
  frame_timer_ = scheduler_.At(pass_.t_first_frame_ns, [this] { OnFrameTick(); });
}

// Plans frame intervals [k0, k0 + kWindowFrames) of every playback motor, with
// the pre-roll before the first window and the post-roll after the last; a
// window that is not the last ends in a brake to rest that the next window
// replaces before it begins (so a lost window can never run a motor away).
void Dmc16::PlanWindow(uint32_t k0) {
  const uint32_t n = Intervals(pass_.from_frame, pass_.to_frame);
  const uint32_t k1 = std::min(n, k0 + kWindowFrames);
  for (int m : (run_ ? run_->motors : PlaybackMotors())) {
    std::vector<sim::Segment> segs;
    if (k0 == 0) {
      // Idle, then accelerate uniformly to the first interval's speed so as
      // to pass the start frame at t_first_frame_ns.
      const double v = n == 0 ? 0 : PassVelocity(m, pass_, 0);
      const double d =
          std::fabs(static_cast<double>(PassPosition(m, pass_, 0) - rig_.motor(m).Position()));
      const double accel_s = (v != 0 && d > 0) ? 2 * d / std::fabs(v) : 0;
      const double lead_s =
          static_cast<double>(pass_.t_first_frame_ns - scheduler_.Now()) / kNsPerSecondF;
      if (lead_s > accel_s) segs.push_back(Seg(lead_s - accel_s, 0, 0));
      if (accel_s > 0) segs.push_back(Seg(accel_s, 0, v / accel_s));
    }
    AppendPath(m, pass_, k0, k1, segs);
    const double v_end = n == 0 ? 0 : PassVelocity(m, pass_, k1 - 1);
    int64_t target = PassPosition(m, pass_, k1);
    if (k1 == n) {
      target = PostrollEnd(m, pass_);
    } else if (v_end != 0) {
      const sim::StepperMotor& motor = rig_.motor(m);
      const double a = motor.profile().max_accel_steps_per_s2 * motor.profile().hard_stop_multiple;
      target += Sign(v_end) * static_cast<int64_t>(std::ceil(v_end * v_end / (2 * a)));
      const sim::SoftLimits& s = motor.soft_limits();
      if (s.upper_enabled)
        target =
            std::min<int64_t>(target, std::max<int64_t>(s.upper_steps, PassPosition(m, pass_, k1)));
      if (s.lower_enabled)
        target =
            std::max<int64_t>(target, std::min<int64_t>(s.lower_steps, PassPosition(m, pass_, k1)));
    }
    const double d = std::fabs(static_cast<double>(target - PassPosition(m, pass_, k1)));
    if (v_end != 0 && d > 0)
      segs.push_back(Seg(2 * d / std::fabs(v_end), v_end, -v_end * std::fabs(v_end) / (2 * d)));
    Script(m, std::move(segs), target);
  }
  if (k1 == n) {
    // The pass ends when the post-roll has run its course on every motor.
    TimeNs end = pass_.t_first_frame_ns + CeilNs(n / pass_.fps);
    for (int m : (run_ ? run_->motors : PlaybackMotors())) {
      end = std::max(end, rig_.motor(m).CurrentPlan().EndNs());
    }
    CancelTimer(phase_timer_);
    phase_timer_ = scheduler_.At(end, [this] {
      phase_timer_ = sim::Scheduler::kNoTimer;
      EndPass();
    });
  }
}

void Dmc16::OnFrameTick() {
  frame_timer_ = sim::Scheduler::kNoTimer;
  const uint32_t n = Intervals(pass_.from_frame, pass_.to_frame);
  const uint32_t k = pass_.frames_done;
  const auto frame =
      static_cast<uint32_t>(int64_t{pass_.from_frame} + int64_t{pass_.dir} * int64_t{k});
  move_time_x1000_ =
      static_cast<uint32_t>(std::min<uint64_t>(uint64_t{frame} * dmc::kMoveTimeScale, UINT32_MAX));
  if (pass_.live) {
    const dmc::RtRunMove& req = run_->request;
    if (req.sync_dmx == 1) ApplyFrameOutputs(frame);
    if (k == 0 && passes_done_ == 0 && (req.bloop_outputs != 0 || req.bloop_dmx_channel != 0)) {
      // Bloop: a sync mark on the GIO outputs and/or a DMX channel at the
      // start of the move, for about BLOOP TIME.
      const uint32_t outputs = req.bloop_outputs;
      const int channel = req.bloop_dmx_channel;
      const uint8_t before = channel != 0 ? dmx_.Value(channel) : 0;
      gio_.SetOutputs(gio_.outputs() | outputs);
      if (channel != 0) dmx_.Set(channel, 255);
      AddIoTimer(scheduler_.Now() + TimeNs{req.bloop_time_ms} * kNsPerMs,
                 [this, outputs, channel, before] {
                   gio_.SetOutputs(gio_.outputs() & ~outputs);
                   if (channel != 0) dmx_.Set(channel, before);
                 });
    }
    if (pass_.video && k == 0) camera_.Set(sim::CameraPort::kShutter, true);
    if (pass_.video && k == n) camera_.Set(sim::CameraPort::kShutter, false);
    if (pass_.stills && k < n) {
      const double open = req.camera_open_angle_deg.value_or(0) / 360.0;
      const double close = req.camera_close_angle_deg.value_or(360) / 360.0;
      const TimeNs t0 = pass_.t_first_frame_ns;
      const TimeNs t_open = t0 + CeilNs((k + open) / pass_.fps);
      const TimeNs t_close = t0 + CeilNs((k + close) / pass_.fps);
      AddIoTimer(t_open, [this] { camera_.Set(sim::CameraPort::kShutter, true); });
      AddIoTimer(t_close, [this] { camera_.Set(sim::CameraPort::kShutter, false); });
    }
  }
  // "it must send a MSG_MOTOR_GET_POSITION each time it reaches a new frame".
  SendPositionUpdate();
  if (k > 0 && k < n && k % kWindowFrames == 0) PlanWindow(k);
  // Forget I/O timers that already ran so the list stays short on long moves.
  const TimeNs now = scheduler_.Now();
  io_timers_.erase(std::remove_if(io_timers_.begin(), io_timers_.end(),
                                  [now](const IoTimer& t) { return t.at_ns < now; }),
                   io_timers_.end());
  if (k < n) {
    ++pass_.frames_done;
    frame_timer_ = scheduler_.At(pass_.t_first_frame_ns + CeilNs((k + 1) / pass_.fps),
                                 [this] { OnFrameTick(); });
  }
}

void Dmc16::AddIoTimer(TimeNs at_ns, sim::Callback cb) {
  io_timers_.push_back(IoTimer{scheduler_.At(at_ns, std::move(cb)), at_ns});
}

void Dmc16::EndPass() {
  ++passes_done_;
  if (mode_ == Mode::kJogAll) {
    // JOG_ALL ends on its destination frame, which is a frame position again.
    on_frame_ = pass_.to_frame;
    mode_ = Mode::kIdle;
    SendPositionUpdate();
    EnsurePositionReports();
    return;
  }
  StartNextPassOrEnd();
}

void Dmc16::StartNextPassOrEnd() {
  const uint16_t flags = run_ ? run_->request.flags.value_or(0) : 0;
  const bool ping_pong = (flags & dmc::kPlayPingPong) != 0;
  const bool loop = (flags & dmc::kPlayLoop) != 0;
  if (!run_ || stop_loop_ || !(ping_pong || loop)) {
    FinishRun(true);
    return;
  }
  // Loop: back to the start's pre-roll and play again; ping-pong: play the
  // range the other way. The rig repositions at full speed, then goes on by
  // itself (OnMotionFinished) without another GO.
  Pass next = pass_;
  if (ping_pong) std::swap(next.from_frame, next.to_frame);
  next = MakePass(next.from_frame, next.to_frame, pass_.fps, pass_.preroll_s, pass_.postroll_s);
  pass_ = next;
  mode_ = Mode::kArmedRun;
  bool any = false;
  for (int m : run_->motors) {
    const sim::MoveStatus st = rig_.motor(m).MoveTo(PrerollStart(m, pass_));
    if (st != sim::MoveStatus::kOk) {
      FinishRun(true);
      rig_.StopAll();
      return;
    }
    any = any || rig_.motor(m).IsMoving();
  }
  mode_ = Mode::kPass;  // still playing: no host command may interfere
  reposition_pending_ = true;
  if (!any) {
    reposition_pending_ = false;
    StartPass(pass_);
  } else {
    EnsurePositionReports();
  }
}

void Dmc16::StartShoot() {
  mode_ = Mode::kShooting;
  const double exposure_s = exposure_ms_ / 1000.0;
  double lead_s = 0;
  struct Ramp {
    double v, accel_s, decel_s;
  };
  std::vector<Ramp> ramps;
  for (const BlurAxis& a : blur_) {
    const double v = (a.x_close_steps - a.x_open_steps) / exposure_s;
    Ramp r{v, 0, 0};
    if (v != 0) {
      r.accel_s = 2 * std::fabs(a.x_open_steps - static_cast<double>(a.pre_steps)) / std::fabs(v);
      r.decel_s = 2 * std::fabs(static_cast<double>(a.post_steps) - a.x_close_steps) / std::fabs(v);
    }
    lead_s = std::max(lead_s, r.accel_s);
    ramps.push_back(r);
  }
  // All blurred motors reach speed together, as the shutter opens.
  TimeNs end = scheduler_.Now();
  for (size_t i = 0; i < blur_.size(); ++i) {
    const BlurAxis& a = blur_[i];
    const Ramp& r = ramps[i];
    if (r.v == 0) continue;
    std::vector<sim::Segment> segs;
    if (lead_s > r.accel_s) segs.push_back(Seg(lead_s - r.accel_s, 0, 0));
    if (r.accel_s > 0) segs.push_back(Seg(r.accel_s, 0, r.v / r.accel_s));
    segs.push_back(Seg(exposure_s, r.v, 0));
    if (r.decel_s > 0) segs.push_back(Seg(r.decel_s, r.v, -r.v / r.decel_s));
    Script(a.motor, std::move(segs), a.post_steps);
    end = std::max(end, rig_.motor(a.motor).CurrentPlan().EndNs());
  }
  const TimeNs t_open = scheduler_.Now() + CeilNs(lead_s);
  const TimeNs exposure_ns = TimeNs{exposure_ms_} * kNsPerMs;
  AddIoTimer(t_open, [this, exposure_ns] { camera_.Expose(exposure_ns); });
  end = std::max(end, t_open + exposure_ns);
  CancelTimer(phase_timer_);
  phase_timer_ = scheduler_.At(end, [this] {
    phase_timer_ = sim::Scheduler::kNoTimer;
    FinishRun(true);
  });
}

// The run or shot is over: back to idle, RT_END to the host ("After a
// MSG_RT_RUN_MOVE or MSG_RT_SHOOT_FRAME has finished shooting, the device
// sends MSG_RT_END").
void Dmc16::FinishRun(bool send_end) {
  CancelTimer(frame_timer_);
  CancelTimer(phase_timer_);
  reposition_pending_ = false;
  mode_ = Mode::kIdle;
  run_.reset();
  blur_.clear();
  SendPositionUpdate();
  if (send_end) SendUnsolicited(dmc::RtEnd{});
  EnsurePositionReports();
}

// Ends whatever playback is going on (a stop, a limit, the e-stop); an armed
// but not started run is simply disarmed.
void Dmc16::Abort(bool send_end) {
  const bool playing = Playing();
  const bool live = mode_ == Mode::kPass || mode_ == Mode::kShooting;
  if (mode_ == Mode::kArmedRun || mode_ == Mode::kArmedShoot) {
    mode_ = Mode::kIdle;
    run_.reset();
    blur_.clear();
  }
  if (!playing) return;
  for (IoTimer& t : io_timers_) CancelTimer(t.id);
  io_timers_.clear();
  for (ScriptPlanner* p : planners_) p->Drop();
  camera_.Set(sim::CameraPort::kShutter, false);
  rig_.StopAll();
  on_frame_.reset();
  FinishRun(send_end && live);
}

// --- what the rig and the inputs report --------------------------------------------------

void Dmc16::OnMotionFinished(int, TimeNs, int64_t) {
  if (rig_.AnyMoving()) return;
  if (reposition_pending_) {
    // A loop or ping-pong pass repositioned; it plays on by itself.
    reposition_pending_ = false;
    StartPass(pass_);
    return;
  }
  if (Playing()) return;
  // "... and once when it stops".
  CancelTimer(report_timer_);
  SendPositionUpdate();
}

void Dmc16::OnLimitTripped(int motor_id, sim::LimitEnd end, int, sim::SwitchInput, TimeNs,
                           int64_t) {
  // MSG_MOTOR_HARD_STOP: REASON 1 upper / 2 lower limit, with the motor.
  virtual_.CancelJog();
  Abort(true);
  const auto reason = end == sim::LimitEnd::kUpper ? dmc::HardStopReason::kUpperLimit
                                                   : dmc::HardStopReason::kLowerLimit;
  SendUnsolicited(dmc::MotorHardStop{static_cast<uint8_t>(reason), static_cast<uint8_t>(motor_id)});
}

void Dmc16::OnEStop(bool engaged, TimeNs) {
  if (!engaged) return;
  virtual_.CancelJog();
  Abort(true);
  // REASON 0 = E-Stop/General, without a MOTOR byte.
  SendUnsolicited(dmc::MotorHardStop{static_cast<uint8_t>(dmc::HardStopReason::kEStop), {}});
}

void Dmc16::OnGioInputs(uint32_t inputs) {
  // "The device should also send this message, unsolicited, any time the
  // inputs change" (debounced by the GIO port).
  const uint32_t visible = inputs & GioMask(profile_.gio_inputs);
  if (visible == reported_inputs_) return;
  reported_inputs_ = visible;
  SendUnsolicited(dmc::GioInReport{visible});
}

// --- state ---------------------------------------------------------------------------------

std::string_view Dmc16::ModeName() const {
  switch (mode_) {
    case Mode::kIdle:
      return "idle";
    case Mode::kArmedRun:
      return "armed-run";
    case Mode::kArmedShoot:
      return "armed-shoot";
    case Mode::kPass:
      return "running";
    case Mode::kShooting:
      return "shooting";
    case Mode::kJogAll:
      return "jogging-all";
  }
  return "idle";
}

nlohmann::json Dmc16::State() const {
  nlohmann::json motors = nlohmann::json::array();
  for (int m = 1; m <= rig_.motor_count(); ++m) {
    const sim::StepperMotor& motor = rig_.motor(m);
    const sim::SoftLimits& s = motor.soft_limits();
    nlohmann::json limits = nlohmann::json::object();
    if (s.lower_enabled) limits["lower_steps"] = s.lower_steps;
    if (s.upper_enabled) limits["upper_steps"] = s.upper_steps;
    motors.push_back({{"motor", m},
                      {"position_steps", motor.Position()},
                      {"target_steps", motor.Target()},
                      {"moving", motor.IsMoving()},
                      {"velocity_steps_per_s", motor.Velocity()},
                      {"enabled", motor.enabled()},
                      {"blur", motor.blur()},
                      {"max_velocity_steps_per_s", motor.profile().max_velocity_steps_per_s},
                      {"max_accel_steps_per_s2", motor.profile().max_accel_steps_per_s2},
                      {"soft_limits", limits},
                      {"hw_set", rig_.binding(m).ToWire()},
                      {"lower_switch", motor.SwitchTripped(sim::LimitEnd::kLower)},
                      {"upper_switch", motor.SwitchTripped(sim::LimitEnd::kUpper)}});
  }
  nlohmann::json dmx = nlohmann::json::object();
  for (int ch = 1; ch <= profile_.dmx_channels; ++ch) {
    if (dmx_.Value(ch) != 0) dmx[std::to_string(ch)] = dmx_.Value(ch);
  }
  nlohmann::json upload = {{"complete", upload_.complete()},
                           {"in_progress", upload_.in_progress()}};
  if (upload_.complete() || upload_.in_progress()) {
    upload["start_frame"] = upload_.start_frame();
    upload["end_frame"] = upload_.end_frame();
    upload["motors"] = upload_.Motors();
    upload["dmx_channels"] = upload_.Channels();
  }
  nlohmann::json physical = nullptr;
  if (physical_) {
    physical = physical_->StateJson();
    physical["collisions"] = stats_.collisions;
    physical["stalls"] = stats_.stalls;
    physical["last_collision"] = last_collision_;
  }
  return {
      {"model", "dmc16"},
      {"physical_rig", physical},
      {"powered", powered_},
      {"time_ns", scheduler_.Now()},
      {"mode", ModeName()},
      {"move_time_x1000", move_time_x1000_},
      {"on_frame", on_frame_ ? nlohmann::json(*on_frame_) : nlohmann::json(nullptr)},
      {"estop", rig_.estop_engaged()},
      {"motors", motors},
      {"gio", {{"outputs", gio_.outputs()}, {"inputs", gio_.inputs()}}},
      {"camera",
       {{"shutter", camera_.level(sim::CameraPort::kShutter)},
        {"meter", camera_.level(sim::CameraPort::kMeter)},
        {"exposures", camera_.exposures()}}},
      {"dmx", {{"adjusting", dmx_.Adjusting()}, {"nonzero", dmx}}},
      {"upload", upload},
      {"virtual", virtual_.State()},
      {"stats",
       {{"requests", stats_.requests},
        {"checksum_errors", stats_.checksum_errors},
        {"framing_errors", stats_.framing_errors},
        {"host_acks", stats_.host_acks},
        {"unsolicited", stats_.unsolicited},
        {"error_replies", stats_.error_replies}}},
  };
}

}  // namespace moco::devices
