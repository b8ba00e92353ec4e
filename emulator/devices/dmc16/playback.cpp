// The DMC-16's real-time playback engine (see playback.h). Section names in
// comments are those of dmc-v2-protocol.txt; readings taken are listed in
// docs/protocol-notes.md.
// The real-time requests are in playback_requests.cpp, the 20 ms velocity
// tick in playback_tick.cpp.

#include "devices/dmc16/playback.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "devices/dmc16/playback_internal.h"

namespace moco::devices {

AckCode AckForMoveStatus(sim::MoveStatus s) {
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
    case sim::MoveStatus::kCoupled:  // driven by the motor before it, not on its own
      return AckCode::kErrGeneral;
  }
  return AckCode::kErrGeneral;
}

Playback::Playback(sim::Scheduler& scheduler, sim::Rig& rig,
                   const std::vector<ScriptPlanner*>& planners, const RtMove& upload,
                   const Dmc16Profile& profile, sim::DmxUniverse& dmx, sim::GioPort& gio,
                   sim::CameraPort& camera, PlaybackHooks hooks)
    : scheduler_(scheduler),
      rig_(rig),
      planners_(planners),
      upload_(upload),
      profile_(profile),
      dmx_(dmx),
      gio_(gio),
      camera_(camera),
      hooks_(std::move(hooks)) {}

Playback::~Playback() { CancelTimers(); }

// --- lifecycle ------------------------------------------------------------------------

void Playback::Reset() {
  CancelTimers();
  mode_ = Mode::kIdle;
  run_.reset();
  tick_run_.reset();
  blur_.clear();
  stop_loop_ = false;
  passes_done_ = 0;
  on_frame_.reset();
  move_time_x1000_ = 0;
  reposition_pending_ = false;
  rt_end_sent_ = false;
  video_recording_ = false;
  video_free_ns_ = 0;
  armed_ns_ = 0;
  rest_ns_ = 0;
  end_update_ns_ = -1;
}

void Playback::Halt() {
  CancelTimers();
  mode_ = Mode::kIdle;
  run_.reset();
  tick_run_.reset();
  video_recording_ = false;
}

void Playback::CancelTimer(sim::Scheduler::TimerId& id) {
  if (id != sim::Scheduler::kNoTimer) scheduler_.Cancel(id);
  id = sim::Scheduler::kNoTimer;
}

void Playback::CancelTimers() {
  CancelTimer(frame_timer_);
  CancelTimer(phase_timer_);
  for (IoTimer& t : io_timers_) CancelTimer(t.id);
  io_timers_.clear();
}

// --- what the rest of the device does to playback ----------------------------------------

void Playback::OnUploadBegin() {
  mode_ = Mode::kIdle;
  run_.reset();
  tick_run_.reset();
  on_frame_.reset();
}

void Playback::OnDirectMotion() {
  if (mode_ == Mode::kArmedRun || mode_ == Mode::kArmedShoot) {
    mode_ = Mode::kIdle;
    tick_run_.reset();
  }
  on_frame_.reset();
}

void Playback::Disarm() {
  if (mode_ == Mode::kArmedRun || mode_ == Mode::kArmedShoot) {
    mode_ = Mode::kIdle;
    tick_run_.reset();
  }
  run_.reset();
}

bool Playback::OnRigAtRest() {
  rest_ns_ = scheduler_.Now();
  if (reposition_pending_) {
    // A loop or ping-pong pass repositioned; it plays on by itself.
    reposition_pending_ = false;
    StartPass(pass_);
    return true;
  }
  // The update that ended a pass or shot this instant is the one at rest.
  return Playing() || end_update_ns_ == scheduler_.Now();
}

// --- playback ---------------------------------------------------------------------------------

// Bloop: a sync mark on the GIO outputs and/or a DMX channel at the start of
// the move, for about BLOOP TIME (MSG_RT_RUN_MOVE BLOOP LOCATION, BLOOP DMX,
// BLOOP TIME).
void Playback::Bloop(const dmc::RtRunMove& req) {
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

void Playback::Script(int motor, std::vector<sim::Segment> segments, int64_t target_steps) {
  ScriptPlanner* planner = planners_[static_cast<size_t>(motor - 1)];
  planner->Load(std::move(segments));
  const sim::MoveStatus s = rig_.motor(motor).MoveTo(target_steps);
  if (s != sim::MoveStatus::kOk) planner->Drop();
}

void Playback::AppendPath(int motor, const Pass& p, uint32_t k0, uint32_t k1,
                          std::vector<sim::Segment>& out) const {
  const double now_s = static_cast<double>(scheduler_.Now() - p.t_first_frame_ns) / kNsPerSecondF;
  // Where a jog's clock changes from ramp to cruise to brake, within an interval.
  const double ramp_end_s = p.ramp_s;
  const double brake_s = p.ramp_s + p.cruise_s;
  constexpr double kMinPieceS = 1e-9;
  for (uint32_t k = k0; k < k1; ++k) {
    const double dx =
        static_cast<double>(PassPosition(motor, p, k + 1)) - PassPosition(motor, p, k);
    const double end_s = TimeOfFrames(p, k + 1.0);
    // The first interval of a window starts now (at or a few ns after the
    // frame time): it ends on the ideal frame time so windows never drift.
    const double frame_s = TimeOfFrames(p, static_cast<double>(k));
    double t = k == k0 ? std::max(now_s, frame_s) : frame_s;
    while (end_s > t) {
      double next = end_s;
      if (p.accel_fps2 > 0) {
        for (const double cut : {ramp_end_s, brake_s}) {
          if (cut > t + kMinPieceS && cut < next - kMinPieceS) {
            next = cut;
            break;
          }
        }
      }
      // The motor's speed is the clock's rate times the interval's steps.
      out.push_back(Seg(next - t, RateAt(p, t) * dx, AccelAt(p, 0.5 * (t + next)) * dx));
      t = next;
    }
  }
}

void Playback::StartPass(const Pass& p) {
  pass_ = p;
  pass_.t_first_frame_ns = scheduler_.Now() + CeilNs(p.preroll_s);
  pass_.frames_done = 0;
  pass_.ticked = -1;
  const uint16_t flags = run_ ? run_->request.flags.value_or(0) : 0;
  pass_.live = run_.has_value();
  pass_.video = pass_.live && (flags & dmc::kPlayCameraVideo) != 0;
  pass_.stills = pass_.live && (flags & dmc::kPlayCameraStills) != 0;
  mode_ = run_ ? Mode::kPass : Mode::kJogAll;
  PlanWindow(0);
  frame_timer_ = scheduler_.At(pass_.t_first_frame_ns, [this] { OnFrameTick(); });
  // "about every 0.10 seconds, if any of the motors are moving" holds in
  // the pre-roll, between frames and in the post-roll too.
  hooks_.ensure_position_reports();
}

// Plans frame intervals [k0, k0 + kWindowFrames) of every playback motor, with
// the pre-roll before the first window and the post-roll after the last; a
// window that is not the last ends in a brake to rest that the next window
// replaces before it begins (so a lost window can never run a motor away).
void Playback::PlanWindow(uint32_t k0) {
  const uint32_t n = Intervals(pass_.from_frame, pass_.to_frame);
  const uint32_t k1 = std::min(n, k0 + kWindowFrames);
  for (int m : (run_ ? run_->motors : PlaybackMotors())) {
    std::vector<sim::Segment> segs;
    if (k0 == 0) {
      // Idle, then accelerate uniformly to the first interval's speed so as
      // to pass the start frame at t_first_frame_ns (a jog starts from rest).
      const double v = n == 0 || pass_.accel_fps2 > 0 ? 0 : PassVelocity(m, pass_, 0);
      const double d =
          std::fabs(static_cast<double>(PassPosition(m, pass_, 0) - rig_.motor(m).Position()));
      const double accel_s = (v != 0 && d > 0) ? 2 * d / std::fabs(v) : 0;
      const double lead_s =
          static_cast<double>(pass_.t_first_frame_ns - scheduler_.Now()) / kNsPerSecondF;
      if (lead_s > accel_s) segs.push_back(Seg(lead_s - accel_s, 0, 0));
      if (accel_s > 0) segs.push_back(Seg(accel_s, 0, v / accel_s));
    }
    AppendPath(m, pass_, k0, k1, segs);
    double v_end = 0;  // at frame k1
    if (n != 0 && pass_.accel_fps2 > 0) {
      v_end = (static_cast<double>(PassPosition(m, pass_, k1)) - PassPosition(m, pass_, k1 - 1)) *
              RateAt(pass_, TimeOfFrames(pass_, static_cast<double>(k1)));
    } else if (n != 0) {
      v_end = PassVelocity(m, pass_, k1 - 1);
    }
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
    // The pass ends when the post-roll has run its course on every motor
    // and the end frame's still exposure has closed.
    TimeNs end = pass_.t_first_frame_ns + CeilNs(TimeOfFrames(pass_, static_cast<double>(n)));
    for (int m : (run_ ? run_->motors : PlaybackMotors())) {
      end = std::max(end, rig_.motor(m).CurrentPlan().EndNs());
    }
    if (pass_.stills) {
      const double close = StillsExposure(run_->request).second;
      end = std::max(end, pass_.t_first_frame_ns + CeilNs((n + close) / pass_.fps));
    }
    CancelTimer(phase_timer_);
    phase_timer_ = scheduler_.At(end, [this] {
      phase_timer_ = sim::Scheduler::kNoTimer;
      // The end frame is reached by now (its tick may share this instant):
      // its report and outputs come before the pass ends.
      if (pass_.ticked < int64_t{Intervals(pass_.from_frame, pass_.to_frame)}) {
        CancelTimer(frame_timer_);
        OnFrameTick();
      }
      EndPass();
    });
  }
}

void Playback::OnFrameTick() {
  frame_timer_ = sim::Scheduler::kNoTimer;
  const uint32_t n = Intervals(pass_.from_frame, pass_.to_frame);
  const uint32_t k = pass_.frames_done;
  const auto frame =
      static_cast<uint32_t>(int64_t{pass_.from_frame} + int64_t{pass_.dir} * int64_t{k});
  // The frame is reached: MOVE TIME is frame x 1000 now (PassMoveTime).
  pass_.ticked = k;
  pass_.tick_ns = scheduler_.Now();
  if (pass_.live) {
    const dmc::RtRunMove& req = run_->request;
    if (req.sync_dmx == 1) ApplyFrameOutputs(frame);
    if (k == 0 && passes_done_ == 0 && (req.bloop_outputs != 0 || req.bloop_dmx_channel != 0)) {
      Bloop(req);
    }
    // FLAGS 0x10 "camera trigger at start/stop of move (video)": one press
    // of the shutter line when the pass reaches its start frame (recording
    // starts) and one at its end frame (recording stops).
    if (pass_.video && (k == 0 || k == n)) VideoTrigger(scheduler_.Now(), k == 0);
    // FLAGS 0x20 "camera trigger for every frame (stills)": every frame of
    // the pass, end frame included, is exposed from OPEN ANGLE to CLOSE
    // ANGLE of its 360 degrees, which run from the frame to the next one.
    if (pass_.stills) {
      const auto [open, close] = StillsExposure(req);
      const TimeNs t0 = pass_.t_first_frame_ns;
      const TimeNs t_open = t0 + CeilNs((k + open) / pass_.fps);
      const TimeNs t_close = t0 + CeilNs((k + close) / pass_.fps);
      AddIoTimer(t_open, [this] { camera_.Set(sim::CameraPort::kShutter, true); });
      AddIoTimer(t_close, [this] { camera_.Set(sim::CameraPort::kShutter, false); });
    }
  }
  // "it must send a MSG_MOTOR_GET_POSITION each time it reaches a new frame".
  Report();
  if (k == n && pass_.live && profile_.behaviour.rt_end_at_last_frame && !rt_end_sent_) {
    // dmc-lite: RT_END as the last frame of the run is reached, without
    // waiting for the post-roll.
    const uint16_t flags = run_->request.flags.value_or(0);
    if (stop_loop_ || (flags & (dmc::kPlayPingPong | dmc::kPlayLoop)) == 0) {
      rt_end_sent_ = true;
      hooks_.send_rt_end();
    }
  }
  if (k > 0 && k < n && k % kWindowFrames == 0) PlanWindow(k);
  // Forget I/O timers that already ran so the list stays short on long moves.
  const TimeNs now = scheduler_.Now();
  io_timers_.erase(std::remove_if(io_timers_.begin(), io_timers_.end(),
                                  [now](const IoTimer& t) { return t.at_ns < now; }),
                   io_timers_.end());
  if (k < n) {
    ++pass_.frames_done;
    frame_timer_ = scheduler_.At(pass_.t_first_frame_ns + CeilNs(TimeOfFrames(pass_, k + 1.0)),
                                 [this] { OnFrameTick(); });
  }
}

void Playback::AddIoTimer(TimeNs at_ns, sim::Callback cb) {
  io_timers_.push_back(IoTimer{scheduler_.At(at_ns, std::move(cb)), at_ns});
}

void Playback::VideoTrigger(TimeNs due_ns, bool start) {
  // Presses never merge: one that falls within the previous press or the
  // release after it waits, so a camera that toggles recording on each press
  // sees every start and stop.
  const TimeNs at = std::max(due_ns, video_free_ns_);
  video_free_ns_ = at + 2 * kVideoTriggerPressNs;
  auto press = [this, start] {
    camera_.Set(sim::CameraPort::kShutter, true);
    video_recording_ = start;
  };
  if (at <= scheduler_.Now()) {
    press();
  } else {
    AddIoTimer(at, std::move(press));
  }
  AddIoTimer(at + kVideoTriggerPressNs, [this] { camera_.Set(sim::CameraPort::kShutter, false); });
}

void Playback::EndPass() {
  ++passes_done_;
  if (mode_ == Mode::kJogAll) {
    // JOG_ALL ends on its destination frame, which is a frame position again.
    on_frame_ = pass_.to_frame;
    move_time_x1000_ = ClampMoveTime(int64_t{pass_.to_frame} * dmc::kMoveTimeScale);
    mode_ = Mode::kIdle;
    // The destination's frame report, sent this instant, is the one at rest.
    if (pass_.tick_ns != scheduler_.Now()) Report();
    end_update_ns_ = scheduler_.Now();
    hooks_.ensure_position_reports();
    return;
  }
  // Between passes MOVE TIME holds where this one's post-roll ended.
  move_time_x1000_ = PassMoveTime();
  StartNextPassOrEnd();
}

void Playback::StartNextPassOrEnd() {
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
    hooks_.ensure_position_reports();
  }
}

void Playback::StartShoot() {
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
  // The blurred motors move: the periodic updates run through the shot.
  hooks_.ensure_position_reports();
}

// The run or shot is over: back to idle, RT_END to the host ("After a
// MSG_RT_RUN_MOVE or MSG_RT_SHOOT_FRAME has finished shooting, the device
// sends MSG_RT_END").
void Playback::FinishRun(bool send_end, bool stopped) {
  // The last update carries the MOVE TIME reached (after a post-roll, the
  // frame clock run on past the end frame; a shot, its frame). A run on the
  // tick holds its frame clock in move_time_x1000_.
  const bool ticked = tick_run_.has_value();
  const bool was_pass =
      !ticked && ((mode_ == Mode::kPass && !reposition_pending_) || mode_ == Mode::kJogAll);
  if (was_pass) move_time_x1000_ = PassMoveTime();
  tick_run_.reset();
  // dmc-lite sends no RT_END after a go-motion shot (behaviour.rt_end_after_shot).
  const bool end_message = send_end && !rt_end_sent_ &&
                           (mode_ != Mode::kShooting || profile_.behaviour.rt_end_after_shot);
  CancelTimer(frame_timer_);
  CancelTimer(phase_timer_);
  reposition_pending_ = false;
  rt_end_sent_ = false;
  mode_ = Mode::kIdle;
  run_.reset();
  blur_.clear();
  // The update at the end, unless the end frame's report (a run without
  // post-roll) went out this instant with the same MOVE TIME. On the tick
  // the stopping motors flag theirs as they come to rest.
  if (ticked) {
    hooks_.flag_position_update();
  } else if (stopped || !(was_pass && pass_.ticked >= 0 && pass_.tick_ns == scheduler_.Now())) {
    Report();
  }
  end_update_ns_ = scheduler_.Now();
  if (end_message) hooks_.send_rt_end();
  hooks_.ensure_position_reports();
}

// Ends whatever playback is going on (a stop, a limit, the e-stop); an armed
// but not started run is simply disarmed.
void Playback::Abort(bool send_end) {
  const bool playing = Playing();
  const bool live = mode_ == Mode::kPass || mode_ == Mode::kShooting;
  if (mode_ == Mode::kArmedRun || mode_ == Mode::kArmedShoot) {
    mode_ = Mode::kIdle;
    run_.reset();
    tick_run_.reset();
    blur_.clear();
  }
  if (!playing) return;
  for (IoTimer& t : io_timers_) CancelTimer(t.id);
  io_timers_.clear();
  for (ScriptPlanner* p : planners_) p->Drop();
  camera_.Set(sim::CameraPort::kShutter, false);
  // A video recording that was started is stopped: the move has stopped.
  if (video_recording_) VideoTrigger(scheduler_.Now(), false);
  rig_.StopAll();
  on_frame_.reset();
  // dmc-lite sends no RT_END for a run or shot a stop ended (behaviour.rt_end_after_stop).
  FinishRun(send_end && live && profile_.behaviour.rt_end_after_stop, /*stopped=*/true);
}

}  // namespace moco::devices
