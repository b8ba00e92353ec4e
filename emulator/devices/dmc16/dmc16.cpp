// The emulated DMC-16 (see dmc16.h). Section names in comments are those of
// dmc-v2-protocol.txt; readings taken are listed in docs/protocol-notes.md.
// Its commands (MSG_DMX .. MSG_MOTOR_SET_LIMITS, the motion requests and
// the reference firmware's departures) are in dmc16_commands.cpp.
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
               &AckForMoveStatus),
      decoder_(NewDecoder()),
      playback_(scheduler, rig_, planners_, upload_, profile_, dmx_, gio_, camera_,
                PlaybackHooks{
                    .send_position_update =
                        [this] {
                          SendPositionUpdate();
                          // The cadence counts on from the update just sent.
                          CancelTimer(report_timer_);
                          EnsurePositionReports();
                        },
                    .send_rt_end = [this] { SendUnsolicited(dmc::RtEnd{}); },
                    .ensure_position_reports = [this] { EnsurePositionReports(); },
                    .flag_position_update =
                        [this] {
                          report_due_ = true;
                          EnsureTick();
                        },
                }) {
  upload_.SetTriggerFramesChecked(profile_.behaviour.trigger_frames_checked);
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
  CancelTimer(idle_timer_);
}

DeviceLine Dmc16::Line() const { return {{.baud = profile_.baud}, profile_.usb_bridge}; }

// --- lifecycle ------------------------------------------------------------------------

void Dmc16::ResetState() {
  CancelAllTimers();
  for (ScriptPlanner* p : planners_) p->Drop();
  for (int m = 1; m <= rig_.motor_count(); ++m) rig_.motor(m).EmergencyHalt();
  config_flags_.assign(static_cast<size_t>(rig_.motor_count()),
                       profile_.motors_enabled ? dmc::kMotorEnabled | dmc::kMotorBlurEnabled : 0);
  uncounted_.assign(static_cast<size_t>(rig_.motor_count()), 0);
  follow_origin_.assign(static_cast<size_t>(rig_.motor_count()), std::nullopt);
  engine_exception_sent_ = false;
  hard_stop_lock_ = false;
  for (int m = 1; m <= rig_.motor_count(); ++m) {
    sim::StepperMotor& motor = rig_.motor(m);
    rig_.Uncouple(m);
    motor.ResetPosition(0);
    sim::MotionProfile mp;
    mp.max_velocity_steps_per_s = profile_.max_velocity_steps_per_s;
    mp.max_accel_steps_per_s2 = profile_.max_accel_steps_per_s2;
    mp.hard_stop_multiple = profile_.hard_stop_multiple;
    motor.SetProfile(mp);
    // Until MSG_MOTOR_CONFIGURE, motors stand as if configured with
    // `motors_enabled`: enabled and blur-enabled (0x03), or neither.
    motor.SetEnabled(profile_.motors_enabled);
    motor.SetBlur(profile_.motors_enabled);
    motor.SetSoftLimits({});
    motor.SetSoftLimitsBoundMoves(profile_.behaviour.soft_limits_bound_moves);
    rig_.BindLimits(m, {});
  }
  gio_.SetOutputs(0);
  camera_.SetFlags(0);
  for (int ch = 1; ch <= sim::DmxUniverse::kChannels; ++ch) dmx_.Set(ch, 0);
  upload_.Clear();
  virtual_.Reset();
  ResetFraming();
  playback_.Reset();
  last_stop_all_ns_ = -1;
  last_report_ns_ = -1;
  silent_stop_ = false;
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
  ResetFraming();
  playback_.Halt();
}

void Dmc16::OnHostLink(bool open) {
  // A frame cut by the host closing the port is not completed by the next
  // session's bytes.
  if (!open) ResetFraming();
}

void Dmc16::CancelTimer(sim::Scheduler::TimerId& id) {
  if (id != sim::Scheduler::kNoTimer) scheduler_.Cancel(id);
  id = sim::Scheduler::kNoTimer;
}

void Dmc16::CancelAllTimers() {
  CancelTimer(report_timer_);
  CancelTimer(tick_timer_);
  report_due_ = false;
  playback_.Halt();
}

// --- framing and dispatch ---------------------------------------------------------------

std::unique_ptr<dmc::FrameDecoder> Dmc16::NewDecoder() const {
  dmc::FrameDecoderOptions options;
  // "The receiving buffer on the device must be at least 1048 bytes": a
  // larger one waits for a Length the spec's minimum would drop.
  options.max_frame_bytes = profile_.behaviour.receive_buffer_bytes;
  options.rescan_rejected = profile_.behaviour.rescan_after_bad_frame;
  return std::make_unique<dmc::FrameDecoder>(options);
}

void Dmc16::ResetFraming() {
  decoder_->Reset();
  CancelTimer(idle_timer_);
}

void Dmc16::OnHostBytes(wire::ByteView bytes) {
  if (!powered_ || bytes.empty()) return;
  last_host_bytes_ns_ = scheduler_.Now();
  decoder_->Feed(bytes, [this](const dmc::FrameEvent& e) { OnFrameEvent(e); });
  ArmIdleGap();
}

// Idle line (docs/protocol-notes.md): a candidate frame still incomplete
// kLineIdleGapNs after the last host bytes will not be completed (a corrupted
// Length, a false "DF" in noise, a cut frame): the decoder gives it up and
// rescans its bytes, so requests behind it are answered now rather than
// after up to a receive buffer's worth of later traffic.
void Dmc16::ArmIdleGap() {
  if (decoder_->pending_bytes() == 0) {
    CancelTimer(idle_timer_);
    return;
  }
  // A timer already set finds the later deadline when it fires.
  if (idle_timer_ != sim::Scheduler::kNoTimer) return;
  idle_timer_ = scheduler_.At(last_host_bytes_ns_ + kLineIdleGapNs, [this] { OnIdleGap(); });
}

void Dmc16::OnIdleGap() {
  idle_timer_ = sim::Scheduler::kNoTimer;
  if (scheduler_.Now() < last_host_bytes_ns_ + kLineIdleGapNs) {
    ArmIdleGap();
    return;
  }
  if (out_.HostBytesWaiting()) {
    // The host's bytes wait on the line, not yet handed over (a transport
    // behind in its reading): the line was not idle, the frame may go on.
    last_host_bytes_ns_ = scheduler_.Now();
    ArmIdleGap();
    return;
  }
  decoder_->Finish([this](const dmc::FrameEvent& e) { OnFrameEvent(e); });
}

void Dmc16::OnFrameEvent(const dmc::FrameEvent& e) {
  if (const auto* f = std::get_if<dmc::FrameRef>(&e)) {
    OnFrame(*f);
  } else if (const auto* c = std::get_if<dmc::ChecksumError>(&e);
             c != nullptr && dmc::PlausibleRequestHeader(c->type)) {
    // "For received messages, this checksum should be zero. If it is not the
    // device should respond with response code ACK_ERR_CHECKSUM", with the ID
    // and Type as received ("MSG_FLAG_ACK"). A received message is a
    // candidate whose header a request can have (no ACK flag: the host's
    // ACKs are never answered, even damaged; a Type within the reference
    // mask); any other false "DF" in noise is dropped unanswered, so no
    // answer ever carries an ID and Type made of noise.
    ++stats_.checksum_errors;
    ++stats_.requests;
    Ack(c->id, c->type, AckCode::kErrChecksum);
  } else {
    // Noise, an implausible candidate, an oversize Length (ERRATA 1.2) or a
    // frame given up at an idle gap: nothing trustworthy to answer (the
    // reference parser drops them silently).
    ++stats_.framing_errors;
  }
}

void Dmc16::OnFrame(const dmc::FrameRef& f) {
  if ((f.type & dmc::kFlagAck) != 0) {
    // ERRATA 1.9: the host's ACK of an unsolicited message; never waited for.
    ++stats_.host_acks;
    if (profile_.behaviour.host_acks_silent) return;
    // dmc-lite answers it like any message it does not take as a request
    // (in its hard-stop state, as any type from 0x0031 up).
    ++stats_.requests;
    Ack(f.id, f.type, HardStopLockout(f.type) ? AckCode::kErrHardLow : AckCode::kErrUnsupported);
    return;
  }
  ++stats_.requests;
  if (HardStopLockout(f.type)) {
    Ack(f.id, f.type, AckCode::kErrHardLow);
    return;
  }
  if (!Advertised(f.type)) {
    Ack(f.id, f.type, AckCode::kErrUnsupported);
    return;
  }
  // The protocol grows by appending fields ("Document Revision History"):
  // bytes after a message's known layout are ignored; shorter data is an
  // error (docs/protocol-notes.md "Trailing bytes"). behaviour.length_checks
  // kMoveAndResetOnly: MOVE and RESET_POSITION must be exactly 5 bytes, any
  // other request reads what its data lacks as zeros.
  const bool lengths_lax =
      profile_.behaviour.length_checks == Dmc16Behaviour::LengthChecks::kMoveAndResetOnly;
  if (lengths_lax && f.data.size() != 5 &&
      (f.type == dmc::ToWire(MsgType::kMotorMove) ||
       f.type == dmc::ToWire(MsgType::kMotorResetPosition))) {
    // RESET_POSITION answers ERR_MOVING first while anything moves.
    const bool moving_first = f.type == dmc::ToWire(MsgType::kMotorResetPosition) &&
                              (rig_.AnyMoving() || playback_.Playing());
    Ack(f.id, f.type, moving_first ? AckCode::kErrMoving : AckCode::kErrGeneral);
    return;
  }
  dmc::Result<dmc::HostMessage> decoded =
      dmc::DecodeHostMessage(f.type, f.data, dmc::TrailingBytes::kIgnore,
                             lengths_lax ? dmc::MissingFields::kZero : dmc::MissingFields::kError);
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
  std::visit(wire::Overloaded{
                 [&](const dmc::HiRequest&) { Send(id, profile_.Hi()); },
                 [&](const dmc::Dmx& m) { Ack(id, type, OnDmx(m)); },
                 [&](const dmc::GioOut& m) { Ack(id, type, OnGioOut(m)); },
                 [&](const dmc::GioInRequest&) {
                   // "Dragonframe may request the input state with this message";
                   // dmc-lite takes GIO_IN only as its own unsolicited message.
                   if (!profile_.behaviour.gio_in_request) {
                     Ack(id, type, AckCode::kErrUnsupported);
                     return;
                   }
                   Send(id, dmc::GioInReport{gio_.inputs() & GioMask(profile_.gio_inputs)});
                 },
                 [&](const dmc::GioCam& m) {
                   // Test of the camera outputs: shutter and meter lines follow the flags.
                   camera_.SetFlags(m.flags & (dmc::kGioCamShutter | dmc::kGioCamMeter));
                   Ack(id, type, AckCode::kOk);
                 },
                 [&](const dmc::MotorStatusRequest&) {
                   Send(id, dmc::MotorStatusResponse{
                                rig_.MovingMask(), static_cast<uint8_t>(dmx_.Adjusting() ? 1 : 0)});
                 },
                 [&](const dmc::MotorMove& m) { OnMotorMove(id, m); },
                 [&](const dmc::MotorStop& m) { Ack(id, type, OnMotorStop(m)); },
                 [&](const dmc::MotorStopAll& m) { Ack(id, type, OnStopAll(m)); },
                 [&](const dmc::MotorGetPositionRequest&) {
                   if (profile_.behaviour.position_response) {
                     SendPositions(id);
                     return;
                   }
                   // dmc-lite: the positions go out as a message with ID 0, and an
                   // ACK OK carries the request's ID.
                   SendPositions(0);
                   Ack(id, type, AckCode::kOk);
                 },
                 [&](const dmc::MotorResetPosition& m) {
                   const AckCode code = OnResetPosition(m);
                   // "After changing the internal position and responding to this
                   // message, the device should send a MSG_MOTOR_GET_POSITION";
                   // behaviour.position_confirm kBeforeAck sends it first.
                   const bool before = profile_.behaviour.position_confirm ==
                                       Dmc16Behaviour::PositionConfirm::kBeforeAck;
                   if (code == AckCode::kOk && before) SendPositionUpdate();
                   Ack(id, type, code);
                   if (code == AckCode::kOk && !before) SendPositionUpdate();
                 },
                 [&](const dmc::MotorJog& m) { Ack(id, type, OnJog(m)); },
                 [&](const dmc::MotorConfigure& m) { Ack(id, type, OnConfigure(m)); },
                 [&](const dmc::MotorSetSpeed& m) { Ack(id, type, OnSetSpeed(m)); },
                 [&](const dmc::MotorSetLimits& m) { Ack(id, type, OnSetLimits(m)); },
                 // The real-time and virtual-axis requests, and those it does not know.
                 [&](const auto&) { HandleRealTimeAndVirtual(id, msg); },
             },
             msg);
}

AckCode Dmc16::AfterVirtualMotion(AckCode code) {
  if (code != AckCode::kOk) return code;
  playback_.OnDirectMotion();
  EnsurePositionReports();
  return code;
}

// --- output -----------------------------------------------------------------------------

void Dmc16::Send(uint32_t id, const dmc::DeviceMessage& m) {
  tx_.clear();
  dmc::Encode(id, m, tx_);
  out_.Write(tx_);
}

// ERRATA 1.9: a device-side sequence ID; dmc-lite sends 0 (behaviour.unsolicited_id_zero).
uint32_t Dmc16::UnsolicitedId() { return profile_.behaviour.unsolicited_id_zero ? 0 : next_id_++; }

void Dmc16::SendUnsolicited(const dmc::DeviceMessage& m) {
  ++stats_.unsolicited;
  Send(UnsolicitedId(), m);
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
  last_report_ns_ = scheduler_.Now();
  dmc::MotorPositionReport r;
  r.move_time_x1000 = playback_.MoveTimeX1000();
  r.positions_steps.reserve(static_cast<size_t>(rig_.motor_count()));
  for (int m = 1; m <= rig_.motor_count(); ++m) {
    // The wire carries int32; positions past it saturate rather than wrap.
    const int64_t p = ReportedPosition(m);
    r.positions_steps.push_back(static_cast<int32_t>(std::clamp<int64_t>(
        p, std::numeric_limits<int32_t>::min(), std::numeric_limits<int32_t>::max())));
  }
  Send(id, r);
}

void Dmc16::SendPositionUpdate() {
  ++stats_.unsolicited;
  SendPositions(UnsolicitedId());
}

// "The device should send these out, about every 0.10 seconds, if any of the
// motors are moving" — and once when they stop (OnMotionFinished). The
// cadence (position_report_interval_ms) runs whatever moves the motors,
// every phase of playback included: a live pass's per-frame reports come
// besides it, each restarting its count, so updates are never further
// apart than the interval.
void Dmc16::EnsurePositionReports() {
  if (Tick() > 0) {
    if (rig_.AnyMoving() || playback_.Playing() || playback_.Ticking() || report_due_) {
      EnsureTick();
    }
    return;
  }
  if (report_timer_ != sim::Scheduler::kNoTimer || !rig_.AnyMoving()) return;
  report_timer_ = scheduler_.After(TimeNs{profile_.position_report_interval_ms} * kNsPerMs,
                                   [this] { OnReportTimer(); });
}

void Dmc16::OnReportTimer() {
  report_timer_ = sim::Scheduler::kNoTimer;
  if (!rig_.AnyMoving()) return;
  SendPositionUpdate();
  EnsurePositionReports();
}

// The velocity tick (behaviour.playback_tick_ms; docs/devices/dmc16.md "The
// 20 ms velocity tick"): on the device clock's multiples of the tick, while
// anything moves, a run plays or an update is due.
void Dmc16::EnsureTick() {
  if (Tick() == 0 || tick_timer_ != sim::Scheduler::kNoTimer) return;
  tick_timer_ = scheduler_.At((scheduler_.Now() / Tick() + 1) * Tick(), [this] { OnTick(); });
}

// One tick: playback moves first, then the updates are decided as dmc-lite
// decides them: one that is due (a new frame, a pass's end, a motor come to
// rest) goes at once in a real-time state and otherwise once 100 ms have
// passed since the last update; while anything moves, one goes once
// position_report_interval_ms have passed (so every 60 ms at 50 ms on a 20 ms
// tick: "about every 0.10 seconds, if any of the motors are moving").
void Dmc16::OnTick() {
  tick_timer_ = sim::Scheduler::kNoTimer;
  playback_.OnTick();
  const TimeNs now = scheduler_.Now();
  const bool moving = rig_.AnyMoving() || playback_.Playing();
  const TimeNs since =
      last_report_ns_ < 0 ? std::numeric_limits<TimeNs>::max() : now - last_report_ns_;
  constexpr TimeNs kAtRestUpdateNs = 100 * kNsPerMs;
  if ((report_due_ && (playback_.InRealTimeState() || since > kAtRestUpdateNs)) ||
      (moving && since > TimeNs{profile_.position_report_interval_ms} * kNsPerMs)) {
    report_due_ = false;
    SendPositionUpdate();
  }
  if (moving || report_due_ || playback_.Ticking()) EnsureTick();
}

// --- what the rig and the inputs report --------------------------------------------------

void Dmc16::OnMotionFinished(int motor_id, TimeNs, int64_t) {
  ResyncUncounted(motor_id);
  if (Tick() > 0) {
    // On the tick each motor that comes to rest makes an update due.
    report_due_ = true;
    EnsureTick();
    if (!rig_.AnyMoving()) playback_.OnRigAtRest();
    return;
  }
  if (rig_.AnyMoving()) return;
  // A loop or ping-pong pass that repositioned plays on by itself; during
  // playback the per-frame reports stand in for this one.
  if (playback_.OnRigAtRest()) return;
  // "... and once when it stops".
  CancelTimer(report_timer_);
  SendPositionUpdate();
}

void Dmc16::OnLimitTripped(int motor_id, sim::LimitEnd end, int, sim::SwitchInput, TimeNs,
                           int64_t) {
  // MSG_MOTOR_HARD_STOP: REASON 1 upper / 2 lower limit, with the motor.
  virtual_.CancelJog();
  playback_.Abort(true);
  const auto reason = end == sim::LimitEnd::kUpper ? dmc::HardStopReason::kUpperLimit
                                                   : dmc::HardStopReason::kLowerLimit;
  SendUnsolicited(dmc::MotorHardStop{static_cast<uint8_t>(reason), static_cast<uint8_t>(motor_id)});
}

void Dmc16::OnEStop(bool engaged, TimeNs) {
  if (!engaged) return;
  virtual_.CancelJog();
  playback_.Abort(true);
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
                      {"config_flags", config_flags_[static_cast<size_t>(m - 1)]},
                      {"coupled_to", rig_.leader(m) != 0 ? nlohmann::json(rig_.leader(m))
                                                         : nlohmann::json(nullptr)},
                      {"coupled_reversed", rig_.coupled_reversed(m)},
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
      {"move_time_x1000", playback_.MoveTimeX1000()},
      {"on_frame",
       playback_.on_frame() ? nlohmann::json(*playback_.on_frame()) : nlohmann::json(nullptr)},
      {"estop", rig_.estop_engaged()},
      {"hard_stop_lockout", LockoutActive()},
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
