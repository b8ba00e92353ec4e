// The DMC-16 playback engine on the 20 ms velocity tick (see playback.h,
// behaviour.playback_tick_ms; docs/devices/dmc16.md "The 20 ms velocity
// tick"). Section names in comments are those of dmc-v2-protocol.txt.

#include "devices/dmc16/playback.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "devices/dmc16/playback_internal.h"

namespace moco::devices {

// --- the velocity tick ------------------------------------------------------------------------
//
// With behaviour.playback_tick_ms the device runs as dmc-lite does
// (docs/devices/dmc16.md "The 20 ms velocity tick"; FACTS "DMC v2"): every
// tick it computes where each motor must be at the next one and steps it
// there at one speed. A live run (dmc-v2-protocol.txt MSG_RT_RUN_MOVE,
// MSG_RT_GO) is a state machine sampled on that tick: the pre-roll ramp, the
// frame clock from START FRAME to END FRAME + 1 (each frame the interval up
// to the next), the post-roll ramp, then the next loop pass or a move back
// onto the frame the clock ended on.

void Playback::Report() {
  if (TickMode()) {
    hooks_.flag_position_update();
  } else {
    hooks_.send_position_update();
  }
}

// The frame path as the tick engine reads it. The upload is held in slots:
// slot i (1..frames) holds upload frame START FRAME + i - 1, slot 0 the frame
// before it on the first interval's line. The clock's frame f reads slot f
// (behaviour.upload_index_from_start_frame, dmc-lite: START FRAME 0 plays one
// frame behind the upload, 1 on it, 5 four frames ahead) or slot
// f - START FRAME + 1 (upload frame f); between slots linearly, past the last
// slot its position, before slot 0 on the first interval's line.
float Playback::PathAt(int motor, float clock) const {
  const uint32_t n = upload_.frames();
  const uint32_t start = upload_.start_frame();
  const auto slot = [&](int64_t i) -> int32_t {
    if (i >= 1)
      return upload_.Position(motor, start + static_cast<uint32_t>(std::min<int64_t>(i, n)) - 1);
    const int64_t first = upload_.Position(motor, start);
    const int64_t second = n > 1 ? upload_.Position(motor, start + 1) : first;
    return static_cast<int32_t>(std::clamp<int64_t>(2 * first - second, INT32_MIN, INT32_MAX));
  };
  const float u = profile_.behaviour.upload_index_from_start_frame
                      ? clock
                      : static_cast<float>(static_cast<double>(clock) - start + 1.0);
  if (u < 0) {
    const auto dx = static_cast<float>(int64_t{slot(1)} - slot(0));
    return static_cast<float>(slot(0)) + dx * u;
  }
  const auto i = static_cast<int64_t>(u);
  if (i >= int64_t{n}) return static_cast<float>(slot(n));
  const auto dx = static_cast<float>(int64_t{slot(i + 1)} - slot(i));
  return static_cast<float>(slot(i)) + dx * (u - static_cast<float>(i));
}

// MSG_RT_RUN_MOVE on the tick: refused while anything moves and unless the
// rig is on a frame (POSITION_FRAME, or where the last run ended); the ramps
// are those of the reference firmware: a pre-roll from rest reaching the
// first interval's speed at the start frame over PRE-ROLL TIME, a post-roll
// from the speed at the clock's end to rest over POST-ROLL TIME (none in a
// loop or ping-pong), each checked against the soft limits for a motor that
// would move.
AckCode Playback::RunMoveTicked(const dmc::RtRunMove& m) {
  if (Playing() || rig_.AnyMoving()) return AckCode::kErrMoving;
  if (!on_frame_) return AckCode::kErrNotInPosition;
  if (const AckCode refused = CheckRunMove(m); refused != AckCode::kOk) return refused;
  const uint16_t flags = m.flags.value_or(0);
  const bool loops = (flags & (dmc::kPlayPingPong | dmc::kPlayLoop)) != 0;
  const float fps = static_cast<float>(m.fps_x1000) * 0.001f;
  const float pre = static_cast<float>(m.preroll_ms) * 0.001f;
  const float post = loops ? 0.0f : static_cast<float>(m.postroll_ms) * 0.001f;
  const float dir = m.end_frame > m.start_frame ? 1.0f : -1.0f;
  TickRun r;
  r.preroll_s = pre;
  r.postroll_s = post;
  r.clock_from = static_cast<float>(m.start_frame);
  r.clock_to = static_cast<float>(static_cast<double>(m.end_frame) + 1.0);
  r.move_s = std::fabs(r.clock_to - r.clock_from) / fps;
  r.rate = fps * dir;
  for (int motor : PlaybackMotors()) {
    TickAxis a;
    a.motor = motor;
    const float p1 = PathAt(motor, r.clock_from);
    const float v = fps * (PathAt(motor, r.clock_from + dir) - p1);
    if (pre > 0 || profile_.behaviour.zero_preroll_nan) {
      // Reaches v at the start frame from rest: a = v / PRE-ROLL TIME over
      // v T / 2 steps. With T = 0 that is not a number (behaviour.zero_preroll_nan).
      const float accel = v / pre;
      a.ramp_from = static_cast<float>(FirmwareInt(p1 - 0.5f * accel * pre * pre));
      a.ramp_half_accel = accel * 0.5f;
    } else {
      a.ramp_from = static_cast<float>(FirmwareInt(p1));
    }
    const float f1 = PathAt(motor, r.clock_to);
    a.post_v = fps * (f1 - PathAt(motor, r.clock_to - dir));
    a.post_from = static_cast<float>(FirmwareInt(f1));
    a.post_half_accel = post > 0 ? (-a.post_v / post) * 0.5f : 0.0f;
    r.axes.push_back(a);
  }
  // ERR_PREROLL / ERR_POSTROLL "usually because preroll would send motors
  // past limits", motor by motor, for the motors that would move.
  for (const TickAxis& a : r.axes) {
    const sim::StepperMotor& motor = rig_.motor(a.motor);
    if (static_cast<double>(a.ramp_from) == static_cast<double>(motor.Position())) continue;
    const sim::SoftLimits& s = motor.soft_limits();
    const auto outside = [&s](double x) {
      return (s.lower_enabled && x < static_cast<double>(s.lower_steps)) ||
             (s.upper_enabled && x > static_cast<double>(s.upper_steps));
    };
    if (outside(a.ramp_from)) return AckCode::kErrPreroll;
    if (outside(FirmwareInt(a.post_from + a.post_v * (post * 0.5f)))) return AckCode::kErrPostroll;
  }
  // To the pre-roll start from the next tick (until then a RUN_MOVE re-arms);
  // GO plays from there.
  r.to_preroll = true;
  run_ = RunSetup{m, PlaybackMotors()};
  tick_run_ = std::move(r);
  stop_loop_ = false;
  passes_done_ = 0;
  mode_ = Mode::kArmedRun;
  armed_ns_ = scheduler_.Now();
  // The frame clock stands on the frame the rig is on until the move phase.
  move_time_x1000_ = ClampMoveTime(int64_t{*on_frame_} * dmc::kMoveTimeScale);
  hooks_.ensure_position_reports();
  return AckCode::kOk;
}

// MSG_RT_GO on the tick: taken once the armed rig rests (else
// ERR_NOT_IN_POSITION, the firmware's one answer when it is not waiting for GO).
AckCode Playback::GoTicked() {
  if (mode_ != Mode::kArmedRun || !tick_run_ || tick_run_->to_preroll || rig_.AnyMoving()) {
    return AckCode::kErrNotInPosition;
  }
  if (rig_.estop_engaged()) return AckCode::kErrGeneral;
  if (profile_.behaviour.arming_ms > 0 &&
      scheduler_.Now() <
          std::max(armed_ns_, rest_ns_) + TimeNs{profile_.behaviour.arming_ms} * kNsPerMs) {
    return AckCode::kErrNotInPosition;
  }
  TickRun& r = *tick_run_;
  r.phase = TickRun::Phase::kPreroll;
  r.t = 0;
  for (TickAxis& a : r.axes) a.x = static_cast<float>(rig_.motor(a.motor).Position());
  rt_end_sent_ = false;
  mode_ = Mode::kPass;
  const uint16_t flags = run_->request.flags.value_or(0);
  pass_.live = true;
  pass_.video = (flags & dmc::kPlayCameraVideo) != 0;
  pass_.stills = (flags & dmc::kPlayCameraStills) != 0;
  // FLAGS 0x10: recording starts with the run.
  if (pass_.video) VideoTrigger(scheduler_.Now(), true);
  hooks_.ensure_position_reports();
  return AckCode::kOk;
}

std::optional<int64_t> Playback::ModelPosition(int motor) const {
  if (mode_ != Mode::kPass || !tick_run_) return std::nullopt;
  for (const TickAxis& a : tick_run_->axes) {
    if (a.motor != motor) continue;
    // behaviour.positions_truncate: the position truncated toward zero, as
    // the firmware reads its own; else the nearest step.
    if (profile_.behaviour.positions_truncate) return FirmwareInt(a.x);
    return std::llround(static_cast<double>(a.x));
  }
  return std::nullopt;
}

void Playback::Drive(TickAxis& a, float x, float tick_s) {
  sim::StepperMotor& motor = rig_.motor(a.motor);
  a.x = x;
  // Where the motor is now, between steps.
  double now_x = static_cast<double>(motor.Position());
  if (motor.IsMoving()) {
    now_x = static_cast<double>(motor.CurrentPlan().origin_steps()) +
            motor.CurrentPlan().StateAt(scheduler_.Now()).x_steps;
  }
  if (!motor.IsMoving() && std::fabs(static_cast<double>(x) - now_x) < 1e-6) return;
  // One speed for the tick, then held until the next tick replaces it (so a
  // motor stays in motion from tick to tick and comes to rest one tick
  // after its last step, as the firmware's moving flag does).
  const double v = (static_cast<double>(x) - now_x) / tick_s;
  Script(a.motor, {Seg(tick_s, v, 0), Seg(tick_s, 0, 0)}, std::llround(static_cast<double>(x)));
}

// A new frame of the clock during the move phase: its report, its outputs.
void Playback::FrameReached(int64_t frame) {
  Report();
  const dmc::RtRunMove& req = run_->request;
  const uint32_t f =
      static_cast<uint32_t>(std::clamp<int64_t>(frame, upload_.start_frame(), upload_.end_frame()));
  if (req.sync_dmx == 1) ApplyFrameOutputs(f);
  const TickRun& r = *tick_run_;
  if (passes_done_ == 0 && static_cast<float>(frame) == r.clock_from &&
      (req.bloop_outputs != 0 || req.bloop_dmx_channel != 0)) {
    Bloop(req);
  }
  if (pass_.stills) {
    // Open while the clock is within the frame's angles, whichever way it
    // runs. A window from 0 to 360 degrees or past them never closes between
    // frames: one exposure until the clock's end, as dmc-lite's shutter
    // follows the clock's fraction of a frame.
    const auto [open, close] = StillsExposure(req);
    if (open <= 0 && close >= 1) {
      camera_.Set(sim::CameraPort::kShutter, true);
      return;
    }
    const double rate = std::fabs(static_cast<double>(r.rate));
    const double from = r.clock_from;
    const double t_a = std::fabs(static_cast<double>(frame) + open - from) / rate;
    const double t_b = std::fabs(static_cast<double>(frame) + close - from) / rate;
    const TimeNs t_open = std::max(scheduler_.Now(), r.move_t0_ns + CeilNs(std::min(t_a, t_b)));
    const TimeNs t_close = std::max(t_open, r.move_t0_ns + CeilNs(std::max(t_a, t_b)));
    AddIoTimer(t_open, [this] { camera_.Set(sim::CameraPort::kShutter, true); });
    AddIoTimer(t_close, [this] { camera_.Set(sim::CameraPort::kShutter, false); });
  }
  const TimeNs now = scheduler_.Now();
  io_timers_.erase(std::remove_if(io_timers_.begin(), io_timers_.end(),
                                  [now](const IoTimer& t) { return t.at_ns < now; }),
                   io_timers_.end());
}

void Playback::OnTick() {
  if (!Ticking()) return;
  TickRun& r = *tick_run_;
  if (mode_ == Mode::kArmedRun) {
    // The armed run's motors leave for their pre-roll start.
    r.to_preroll = false;
    for (const TickAxis& a : r.axes) {
      if (rig_.motor(a.motor).MoveTo(static_cast<int64_t>(a.ramp_from)) != sim::MoveStatus::kOk) {
        rig_.StopAll();
        mode_ = Mode::kIdle;
        tick_run_.reset();
        run_.reset();
        break;
      }
    }
    hooks_.ensure_position_reports();
    return;
  }
  // The tick in seconds, single precision (0.02f at 20 ms).
  const auto tick_s = static_cast<float>(profile_.behaviour.playback_tick_ms / 1000.0);
  std::vector<float> x;
  x.reserve(r.axes.size());
  for (const TickAxis& a : r.axes) x.push_back(a.x);  // held unless a phase moves it
  r.t += tick_s;
  if (r.phase == TickRun::Phase::kPreroll) {
    if (r.t < r.preroll_s) {
      const float t2 = r.t * r.t;
      for (size_t i = 0; i < r.axes.size(); ++i) {
        x[i] = r.axes[i].ramp_from + r.axes[i].ramp_half_accel * t2;
      }
    } else {
      r.t -= r.preroll_s;
      r.phase = TickRun::Phase::kMove;
      r.move_t0_ns = scheduler_.Now() - CeilNs(r.t);
      on_frame_.reset();  // the next frame of the clock is new
    }
  }
  if (r.phase == TickRun::Phase::kMove) {
    if (r.t < r.move_s) {
      const float clock = r.clock_from + r.t * r.rate;
      move_time_x1000_ = ClockX1000(clock);
      const int64_t frame = std::max(0, FirmwareInt(clock));
      if (!on_frame_ || int64_t{*on_frame_} != frame) {
        on_frame_ = static_cast<uint32_t>(frame);
        FrameReached(frame);
      }
      for (size_t i = 0; i < r.axes.size(); ++i) x[i] = PathAt(r.axes[i].motor, clock);
    } else {
      // The clock's end: its update at once, with the positions of the last
      // tick (the motors pause for this one unless the post-roll moves them).
      move_time_x1000_ = ClockX1000(r.clock_from + r.move_s * r.rate);
      r.phase = TickRun::Phase::kPostroll;
      r.t -= r.move_s;
      if (pass_.stills) camera_.Set(sim::CameraPort::kShutter, false);
      hooks_.send_position_update();
      if (profile_.behaviour.rt_end_at_last_frame) {
        // dmc-lite: RT_END here, on every pass of a loop or ping-pong.
        rt_end_sent_ = true;
        hooks_.send_rt_end();
      }
    }
  }
  if (r.phase == TickRun::Phase::kPostroll) {
    if (r.t < r.postroll_s) {
      const float t2 = r.t * r.t;
      for (size_t i = 0; i < r.axes.size(); ++i) {
        const TickAxis& a = r.axes[i];
        x[i] = a.post_from + a.post_v * r.t + a.post_half_accel * t2;
      }
    } else {
      EndTickPass(x, tick_s);
      return;
    }
  }
  for (size_t i = 0; i < r.axes.size(); ++i) Drive(r.axes[i], x[i], tick_s);
}

// The pass is over: the next pass of a loop or ping-pong starts on the next
// tick (no pre-roll, no post-roll); else the run ends with a move onto the
// frame its clock ended on (END FRAME + 1 going forward).
void Playback::EndTickPass(const std::vector<float>& x, float tick_s) {
  TickRun& r = *tick_run_;
  ++passes_done_;
  hooks_.flag_position_update();
  if (pass_.video) VideoTrigger(scheduler_.Now(), false);
  const uint16_t flags = run_->request.flags.value_or(0);
  if (!stop_loop_ && (flags & (dmc::kPlayPingPong | dmc::kPlayLoop)) != 0) {
    if ((flags & dmc::kPlayPingPong) != 0) {
      std::swap(r.clock_from, r.clock_to);
      r.rate = -r.rate;
    }
    r.phase = TickRun::Phase::kPreroll;
    r.t = 0;
    r.preroll_s = 0;
    r.postroll_s = 0;
    if (pass_.video) VideoTrigger(scheduler_.Now(), true);
    // Held for this tick.
    for (size_t i = 0; i < r.axes.size(); ++i) Drive(r.axes[i], x[i], tick_s);
    return;
  }
  const auto frame = static_cast<int64_t>(std::lround(static_cast<double>(r.clock_to)));
  const bool end_message = !rt_end_sent_;
  const std::vector<int> motors = run_->motors;
  mode_ = Mode::kIdle;
  tick_run_.reset();
  run_.reset();
  rt_end_sent_ = false;
  const uint32_t f =
      static_cast<uint32_t>(std::clamp<int64_t>(frame, upload_.start_frame(), upload_.end_frame()));
  for (int m : motors) MoveToFrame(m, upload_.Position(m, f));
  on_frame_ = static_cast<uint32_t>(std::max<int64_t>(frame, 0));
  end_update_ns_ = scheduler_.Now();
  if (end_message) hooks_.send_rt_end();
  hooks_.ensure_position_reports();
}

// POSITION_FRAME's move with a tick (dmc-lite): from rest, a point-to-point
// move that takes at least 0.5 s to accelerate and as long to brake (a
// gentler acceleration for short moves), cruising at max velocity only when
// the distance needs more than twice the ramps' distance, and at rest a tick
// after it arrives; while the motor moves, a plain move.
sim::MoveStatus Playback::MoveToFrame(int motor_id, int64_t target_steps) {
  sim::StepperMotor& motor = rig_.motor(motor_id);
  const double dist = std::fabs(static_cast<double>(target_steps - motor.Position()));
  // (A motor the tick holds still is at rest for this.)
  if (motor.Velocity() != 0 || dist < 1) return motor.MoveTo(target_steps);
  constexpr double kMinRampS = 0.5;
  const double v_max = motor.profile().max_velocity_steps_per_s;
  double a = motor.profile().max_accel_steps_per_s2;
  if (std::sqrt(dist / a) < kMinRampS) a = dist / (kMinRampS * kMinRampS);
  double ramps = v_max * v_max / a;  // distance of both ramps at max velocity
  if (dist > ramps && dist < 2 * ramps) {
    a = v_max * v_max / dist;
    ramps = dist;
  }
  const double sign = target_steps > motor.Position() ? 1 : -1;
  std::vector<sim::Segment> segs;
  if (dist <= ramps) {
    const double t = std::sqrt(dist / a);
    segs = {Seg(t, 0, sign * a), Seg(t, sign * a * t, -sign * a)};
  } else {
    const double t = v_max / a;
    segs = {Seg(t, 0, sign * a), Seg((dist - ramps) / v_max, sign * v_max, 0),
            Seg(t, sign * v_max, -sign * a)};
  }
  // At rest one tick after it arrives, as the tick finds it there.
  segs.push_back(Seg(static_cast<double>(profile_.behaviour.playback_tick_ms) / 1000.0, 0, 0));
  ScriptPlanner* planner = planners_[static_cast<size_t>(motor_id - 1)];
  planner->Load(std::move(segs));
  const sim::MoveStatus s = motor.MoveTo(target_steps);
  if (s != sim::MoveStatus::kOk) planner->Drop();
  return s;
}

std::string_view Playback::ModeName() const {
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

}  // namespace moco::devices
