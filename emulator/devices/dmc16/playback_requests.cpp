// The DMC-16 playback engine's real-time requests (see playback.h): the
// upload's checks, RT_RUN_MOVE, RT_GO, POSITION_FRAME, the shot and jog-all
// requests. Section names in comments are those of dmc-v2-protocol.txt.

#include "devices/dmc16/playback.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "devices/dmc16/playback_internal.h"

namespace moco::devices {

// --- real-time requests ---------------------------------------------------------------------

std::vector<int> Playback::PlaybackMotors() const {
  std::vector<int> out;
  for (int m : upload_.Motors()) {
    // A coupled motor follows the motor that drives it instead of its own data.
    if (MotorValid(m) && rig_.motor(m).enabled() && rig_.leader(m) == 0) out.push_back(m);
  }
  return out;
}

bool Playback::OnFramePosition(uint32_t frame) const {
  if (!upload_.Contains(frame) || rig_.AnyMoving()) return false;
  for (int m : PlaybackMotors()) {
    if (rig_.motor(m).Position() != upload_.Position(m, frame)) return false;
  }
  return true;
}

std::optional<uint32_t> Playback::FrameTheRigIsOn(uint32_t toward) const {
  if (on_frame_ && OnFramePosition(*on_frame_)) return on_frame_;
  // The frame the rig last reached is gone (a new upload, a motor moved by
  // another command): the rig is still on a frame when every motor of the
  // move rests on that frame's uploaded position. Of several such frames (a
  // hold), the one nearest `toward`.
  if (!upload_.complete() || rig_.AnyMoving()) return std::nullopt;
  std::optional<uint32_t> best;
  uint64_t best_distance = 0;
  for (uint32_t f = upload_.start_frame(); f <= upload_.end_frame(); ++f) {
    if (!OnFramePosition(f)) continue;
    const uint64_t d = f > toward ? f - toward : toward - f;
    if (!best || d < best_distance) {
      best = f;
      best_distance = d;
    }
    if (f == upload_.end_frame()) break;  // end_frame may be the largest uint32_t
  }
  return best;
}

void Playback::ApplyFrameOutputs(uint32_t frame) {
  for (int ch : upload_.Channels()) {
    if (ch <= profile_.dmx_channels) dmx_.Set(ch, upload_.Level(ch, frame));
  }
  if (upload_.trigger_mask() != 0) {
    const uint32_t mask = upload_.trigger_mask();
    gio_.SetOutputs((gio_.outputs() & ~mask) | (upload_.TriggersAt(frame) & mask));
  }
}

AckCode Playback::PositionFrame(uint32_t frame) {
  if (!upload_.complete()) return AckCode::kErrGeneral;
  if (!upload_.Contains(frame)) {
    // dmc-lite (behaviour.position_frame_clamped) goes to the nearest
    // uploaded frame; the spec names no answer (DMC-RT-010 is a NOTE).
    if (!profile_.behaviour.position_frame_clamped) return AckCode::kErrRange;
    frame = std::clamp(frame, upload_.start_frame(), upload_.end_frame());
  }
  if (Playing()) {
    return AckCode::kErrMoving;
  }
  if (rig_.estop_engaged()) return AckCode::kErrGeneral;
  const std::vector<int> motors = PlaybackMotors();
  // Check every motor first so a refusal moves nothing.
  for (int m_id : motors) {
    // Soft limits that do not bound moves (behaviour.soft_limits_bound_moves) let it pass them.
    if (!profile_.behaviour.soft_limits_bound_moves) break;
    const sim::SoftLimits& s = rig_.motor(m_id).soft_limits();
    const int64_t p = upload_.Position(m_id, frame);
    if (s.upper_enabled && p > s.upper_steps) return AckCode::kErrSoftUp;
    if (s.lower_enabled && p < s.lower_steps) return AckCode::kErrSoftLow;
  }
  for (int m_id : motors) {
    const int64_t target = upload_.Position(m_id, frame);
    const AckCode code =
        AckForMoveStatus(TickMode() ? MoveToFrame(m_id, target) : rig_.motor(m_id).MoveTo(target));
    if (code != AckCode::kOk) {
      rig_.StopAll();
      return code;
    }
  }
  // "send all motors (and DMX if applicable) to the uploaded frame position".
  for (int ch : upload_.Channels()) {
    if (ch <= profile_.dmx_channels) dmx_.Set(ch, upload_.Level(ch, frame));
  }
  mode_ = Mode::kIdle;
  run_.reset();
  tick_run_.reset();
  on_frame_ = frame;
  // With a tick, MOVE TIME is the frame clock, which only runs and jogs move.
  if (!TickMode()) {
    move_time_x1000_ = static_cast<uint32_t>(
        std::min<uint64_t>(uint64_t{frame} * dmc::kMoveTimeScale, UINT32_MAX));
  }
  hooks_.ensure_position_reports();
  return AckCode::kOk;
}

Playback::Pass Playback::MakePass(uint32_t from, uint32_t to, double fps, double pre_s,
                                  double post_s) {
  Pass p;
  p.from_frame = from;
  p.to_frame = to;
  p.dir = to >= from ? 1 : -1;
  p.fps = fps;
  p.preroll_s = pre_s;
  p.postroll_s = post_s;
  return p;
}

int32_t Playback::PassPosition(int motor, const Pass& p, uint32_t k) const {
  const int64_t frame = int64_t{p.from_frame} + int64_t{p.dir} * k;
  return upload_.Position(motor, static_cast<uint32_t>(frame));
}

double Playback::PassVelocity(int motor, const Pass& p, uint32_t k) const {
  return (static_cast<double>(PassPosition(motor, p, k + 1)) - PassPosition(motor, p, k)) * p.fps;
}

// The frame clock. A live pass (no ramps) runs at FPS throughout, so the
// clock extends before the start frame (pre-roll) and after the end frame
// (post-roll). JOG_ALL's clock is a trapezoid from rest to rest over the
// pass's n frame intervals: accelerate for ramp_s, run at fps for cruise_s,
// brake for ramp_s.
double Playback::FramesAt(const Pass& p, double t_s) {
  if (p.accel_fps2 <= 0) return p.fps * t_s;
  const double n = Intervals(p.from_frame, p.to_frame);
  const double a = p.accel_fps2;
  const double ta = p.ramp_s;
  const double total_s = 2 * ta + p.cruise_s;
  if (t_s <= 0) return 0;
  if (t_s < ta) return 0.5 * a * t_s * t_s;
  if (t_s < ta + p.cruise_s) return 0.5 * a * ta * ta + p.fps * (t_s - ta);
  if (t_s < total_s) return n - 0.5 * a * (total_s - t_s) * (total_s - t_s);
  return n;
}

double Playback::TimeOfFrames(const Pass& p, double s) {
  if (p.accel_fps2 <= 0) return s / p.fps;
  const double n = Intervals(p.from_frame, p.to_frame);
  const double a = p.accel_fps2;
  const double ta = p.ramp_s;
  const double total_s = 2 * ta + p.cruise_s;
  const double ramp_frames = 0.5 * a * ta * ta;
  if (s <= 0) return 0;
  if (s < ramp_frames) return std::sqrt(2 * s / a);
  if (s < n - ramp_frames) return ta + (s - ramp_frames) / p.fps;
  if (s < n) return total_s - std::sqrt(2 * (n - s) / a);
  return total_s;
}

double Playback::RateAt(const Pass& p, double t_s) {
  if (p.accel_fps2 <= 0) return p.fps;
  const double ta = p.ramp_s;
  const double total_s = 2 * ta + p.cruise_s;
  if (t_s <= 0 || t_s >= total_s) return 0;
  if (t_s < ta) return p.accel_fps2 * t_s;
  if (t_s < ta + p.cruise_s) return p.fps;
  return p.accel_fps2 * (total_s - t_s);
}

double Playback::AccelAt(const Pass& p, double t_s) {
  if (p.accel_fps2 <= 0) return 0;
  const double ta = p.ramp_s;
  const double total_s = 2 * ta + p.cruise_s;
  if (t_s <= 0 || t_s >= total_s) return 0;
  if (t_s < ta) return p.accel_fps2;
  if (t_s < ta + p.cruise_s) return 0;
  return -p.accel_fps2;
}

// MSG_RT_JOG_ALL "Jog all motors towards the destination frame": a jog, like
// MSG_MOTOR_JOG's, moves within each motor's max velocity and acceleration
// (MSG_MOTOR_SET_SPEED). The motors follow the uploaded path together, so
// the frame clock is what is limited: its rate to what the motor with the
// steepest frame interval can follow at its max velocity (a faster FPS is
// lowered, not refused), its ramps to what every motor can follow at its max
// acceleration. The path's own bends at the frames are the upload's.
void Playback::FitJogRamps(Pass& p) const {
  const uint32_t n = Intervals(p.from_frame, p.to_frame);
  double max_fps = p.fps;
  double accel = std::numeric_limits<double>::infinity();
  for (int m : PlaybackMotors()) {
    double steepest = 0;  // steps per frame
    for (uint32_t k = 0; k < n; ++k) {
      steepest = std::max(steepest, std::fabs(static_cast<double>(PassPosition(m, p, k + 1)) -
                                              PassPosition(m, p, k)));
    }
    if (steepest == 0) continue;
    const sim::MotionProfile& mp = rig_.motor(m).profile();
    max_fps = std::min(max_fps, mp.max_velocity_steps_per_s / steepest);
    accel = std::min(accel, mp.max_accel_steps_per_s2 / steepest);
  }
  p.fps = max_fps;
  if (!std::isfinite(accel) || n == 0) {
    p.accel_fps2 = 0;  // nothing moves: no ramps to make
    return;
  }
  p.accel_fps2 = accel;
  const double ramp_frames = p.fps * p.fps / (2 * accel);
  if (2 * ramp_frames >= n) {
    // Too short to reach the rate: accelerate half-way, brake the rest.
    p.fps = std::sqrt(accel * n);
    p.ramp_s = p.fps / accel;
    p.cruise_s = 0;
  } else {
    p.ramp_s = p.fps / accel;
    p.cruise_s = (n - 2 * ramp_frames) / p.fps;
  }
}

uint32_t Playback::MoveTimeX1000() const {
  // With a tick a live run keeps its frame clock in move_time_x1000_.
  if (TickMode() && mode_ != Mode::kJogAll) return move_time_x1000_;
  if ((mode_ == Mode::kPass && !reposition_pending_) || mode_ == Mode::kJogAll) {
    return PassMoveTime();
  }
  return move_time_x1000_;
}

// MOVE TIME of a running pass (docs/protocol-notes.md "MOVE TIME"), in
// thousandths of a frame from its from_frame along its direction: exactly
// k x 1000 when frame k is reached (its report), strictly between two frames'
// values in between (the cadence's updates), the clock run on before the
// start frame (pre-roll) and after the end frame (post-roll).
uint32_t Playback::PassMoveTime() const {
  const Pass& p = pass_;
  const int64_t n = Intervals(p.from_frame, p.to_frame);
  const TimeNs now = scheduler_.Now();
  const double t_s = static_cast<double>(now - p.t_first_frame_ns) / kNsPerSecondF;
  int64_t off = 0;
  if (p.ticked < 0) {
    // Pre-roll: before the start frame, unless the profile reads it as the
    // start frame's (dmc-lite).
    if (p.live && !profile_.behaviour.preroll_move_time_is_start_frame) {
      off = std::min<int64_t>(-1, std::llround(FramesAt(p, t_s) * 1000));
    }
  } else {
    const int64_t k = p.ticked;
    const int64_t lo = now == p.tick_ns ? 0 : 1;
    // Rounded to the nearest thousandth, but never onto a frame's own value.
    const int64_t frac = std::llround((FramesAt(p, t_s) - static_cast<double>(k)) * 1000);
    off = k * 1000 + (k < n ? std::clamp<int64_t>(frac, lo, 999) : std::max(frac, lo));
    if (!p.live) off = std::min(off, n * 1000);  // JOG_ALL ends at rest on its frame
  }
  return ClampMoveTime(int64_t{p.from_frame} * 1000 + p.dir * off);
}

// Pre-roll (MSG_RT_RUN_MOVE): the rig starts at rest and accelerates uniformly
// over PRE-ROLL TIME to the speed of the first frame interval, reaching the
// start frame at full speed; it covers v*T/2, rounded down to whole steps so
// the acceleration never exceeds v/T.
int64_t Playback::PrerollStart(int motor, const Pass& p) const {
  const double v = Intervals(p.from_frame, p.to_frame) == 0 ? 0 : PassVelocity(motor, p, 0);
  const auto d = static_cast<int64_t>(std::floor(std::fabs(v) * p.preroll_s / 2));
  return PassPosition(motor, p, 0) - Sign(v) * d;
}

// Post-roll: decelerates uniformly from the last interval's speed to rest
// over POST-ROLL TIME, past the end frame.
int64_t Playback::PostrollEnd(int motor, const Pass& p) const {
  const uint32_t n = Intervals(p.from_frame, p.to_frame);
  const double v = n == 0 ? 0 : PassVelocity(motor, p, n - 1);
  const auto d = static_cast<int64_t>(std::floor(std::fabs(v) * p.postroll_s / 2));
  return PassPosition(motor, p, n) + Sign(v) * d;
}

AckCode Playback::CheckPass(const Pass& p) const {
  const uint32_t n = Intervals(p.from_frame, p.to_frame);
  for (int m : PlaybackMotors()) {
    const sim::SoftLimits& s = rig_.motor(m).soft_limits();
    // behaviour.soft_limits_bound_moves false: only pre- and post-roll are bounded.
    for (uint32_t k = 0; profile_.behaviour.soft_limits_bound_moves && k <= n; ++k) {
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

// The checks RT_RUN_MOVE makes of its request in either engine, after the
// engine's own state: the upload, the frames, the FLAGS against the
// capabilities (0x0200, 0x0400), the stills angles, the bloop and the e-stop.
AckCode Playback::CheckRunMove(const dmc::RtRunMove& m) const {
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
  // "0-360 degrees" (behaviour.camera_angles_checked; dmc-lite takes any).
  if ((flags & dmc::kPlayCameraStills) != 0 && profile_.behaviour.camera_angles_checked) {
    const uint16_t open = m.camera_open_angle_deg.value_or(0);
    const uint16_t close = m.camera_close_angle_deg.value_or(360);
    if (open > 360 || close > 360 || close <= open) return AckCode::kErrRange;
  }
  if (m.bloop_dmx_channel > profile_.dmx_channels ||
      (m.bloop_outputs & ~GioMask(profile_.gio_outputs)) != 0) {
    return AckCode::kErrRange;
  }
  if (rig_.estop_engaged()) return AckCode::kErrGeneral;
  return AckCode::kOk;
}

AckCode Playback::RunMove(const dmc::RtRunMove& m) {
  if (TickMode()) return RunMoveTicked(m);
  if (Playing()) {
    return AckCode::kErrMoving;
  }
  if (const AckCode refused = CheckRunMove(m); refused != AckCode::kOk) return refused;
  const uint16_t flags = m.flags.value_or(0);
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
    const AckCode code = AckForMoveStatus(rig_.motor(motor).MoveTo(PrerollStart(motor, forward)));
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
  armed_ns_ = scheduler_.Now();
  // While the rig goes to its pre-roll, MOVE TIME is where the pass's frame
  // clock will begin at GO: PRE-ROLL TIME before the start frame (or the
  // start frame itself, as dmc-lite reports it).
  const int64_t lead_x1000 =
      profile_.behaviour.preroll_move_time_is_start_frame
          ? 0
          : static_cast<int64_t>(std::ceil(pre_s * fps * dmc::kMoveTimeScale));
  move_time_x1000_ =
      ClampMoveTime(int64_t{m.start_frame} * dmc::kMoveTimeScale - forward.dir * lead_x1000);
  hooks_.ensure_position_reports();
  return AckCode::kOk;
}

AckCode Playback::ShootFrame(uint32_t frame, int dir, uint32_t exposure_ms, double open_deg,
                             double close_deg, const std::vector<dmc::BlurMotor>& motors) {
  if (Playing()) {
    return AckCode::kErrMoving;
  }
  if (!upload_.complete()) return AckCode::kErrGeneral;
  if (!upload_.Contains(frame) || exposure_ms == 0) return AckCode::kErrRange;
  if (rig_.estop_engaged()) return AckCode::kErrGeneral;
  std::vector<BlurAxis> axes;
  std::vector<int> listed;
  const double exposure_s = exposure_ms / 1000.0;
  for (const dmc::BlurMotor& b : motors) {
    if (!MotorValid(b.motor)) return AckCode::kErrRange;
    if (std::find(listed.begin(), listed.end(), b.motor) != listed.end()) {
      return AckCode::kErrRange;  // a motor listed twice
    }
    listed.push_back(b.motor);
    const sim::StepperMotor& motor = rig_.motor(b.motor);
    // Which motors blur: those listed whose blur flag is set
    // (MSG_MOTOR_CONFIGURE 0x02 "blur enabled"); a listed motor without it
    // is held as the unlisted ones are (docs/protocol-notes.md). A coupled
    // motor blurs with the motor that drives it.
    if (!motor.blur() || rig_.leader(b.motor) != 0) continue;
    if (!motor.enabled()) {
      if (profile_.behaviour.disabled_motors_ignore_motion) continue;
      return AckCode::kErrGeneral;
    }
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
    const AckCode code = AckForMoveStatus(rig_.motor(m).MoveTo(target));
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
  armed_ns_ = scheduler_.Now();
  move_time_x1000_ =
      static_cast<uint32_t>(std::min<uint64_t>(uint64_t{frame} * dmc::kMoveTimeScale, UINT32_MAX));
  hooks_.ensure_position_reports();
  return AckCode::kOk;
}

AckCode Playback::Go() {
  if (TickMode() && mode_ != Mode::kArmedShoot) return GoTicked();
  if (mode_ != Mode::kArmedRun && mode_ != Mode::kArmedShoot) {
    return mode_ == Mode::kIdle ? AckCode::kErrGeneral : AckCode::kErrMoving;
  }
  // "When the device has stopped moving, a MSG_RT_GO command will perform the run".
  if (rig_.AnyMoving()) return AckCode::kErrMoving;
  if (rig_.estop_engaged()) return AckCode::kErrGeneral;
  // A device that arms after the rig came to rest (dmc-lite, profile
  // behaviour.arming_ms) is not in position until it has.
  if (profile_.behaviour.arming_ms > 0 &&
      scheduler_.Now() <
          std::max(armed_ns_, rest_ns_) + TimeNs{profile_.behaviour.arming_ms} * kNsPerMs) {
    return AckCode::kErrNotInPosition;
  }
  rt_end_sent_ = false;
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

AckCode Playback::StopLoop() {
  // "The currently running loop/ping-pong must stop after it reaches the next end point."
  stop_loop_ = true;
  return AckCode::kOk;
}

AckCode Playback::JogAll(const dmc::RtJogAll& m) {
  if (Playing()) {
    return AckCode::kErrMoving;
  }
  if (!upload_.complete()) return AckCode::kErrGeneral;
  if (m.fps_x1000 == 0 || !upload_.Contains(m.destination_frame)) return AckCode::kErrRange;
  if (rig_.estop_engaged()) return AckCode::kErrGeneral;
  // "The rig must already be on a frame position that is uploaded to the device."
  const std::optional<uint32_t> from = FrameTheRigIsOn(m.destination_frame);
  if (!from) return AckCode::kErrNotInPosition;
  on_frame_ = from;
  if (*from == m.destination_frame) return AckCode::kOk;
  Pass p =
      MakePass(*from, m.destination_frame, m.fps_x1000 / static_cast<double>(dmc::kFpsScale), 0, 0);
  if (AckCode c = CheckPass(p); c != AckCode::kOk) return c;
  FitJogRamps(p);
  run_.reset();
  mode_ = Mode::kIdle;
  StartPass(p);
  mode_ = Mode::kJogAll;
  return AckCode::kOk;
}

}  // namespace moco::devices
