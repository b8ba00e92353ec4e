// The DMC-16's real-time playback engine (see playback.h). Section names in
// comments are those of dmc-v2-protocol.txt; readings taken are listed in
// docs/protocol-notes.md.
#include "devices/dmc16/playback.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace moco::devices {

using dmc::AckCode;
using sim::kNsPerMs;
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

TimeNs CeilNs(double seconds) { return static_cast<TimeNs>(std::ceil(seconds * kNsPerSecondF)); }

uint32_t Intervals(uint32_t a, uint32_t b) { return a > b ? a - b : b - a; }

// MOVE TIME is a DWORD: before frame 0 it stays 0.
uint32_t ClampMoveTime(int64_t x1000) {
  return static_cast<uint32_t>(std::clamp<int64_t>(x1000, 0, int64_t{UINT32_MAX}));
}

// The velocity tick's conversion of a single-precision value to a whole
// number: truncation toward zero; not a number, and a value outside int32,
// give INT32_MIN, as on the reference firmware's measured (x86-64) build.
int32_t FirmwareInt(float v) {
  if (!(v > -2147483648.0f && v < 2147483648.0f)) return INT32_MIN;
  return static_cast<int32_t>(v);
}

// MOVE TIME of the tick's frame clock: the clock kept in 1/100000 frame
// (a whole number), reported in thousandths, each step in single precision.
uint32_t ClockX1000(float clock) {
  const float scaled = clock * 100000.0f;
  if (!(std::fabs(scaled) < 2147483648.0f)) return ClampMoveTime(std::llround(clock * 1000.0));
  const float x1000 = static_cast<float>(static_cast<int32_t>(scaled)) / 100.0f;
  return x1000 <= 0 ? 0 : static_cast<uint32_t>(x1000);
}

// The stills exposure of RUN_MOVE FLAGS 0x20, in fractions of a frame: from
// CAMERA OPEN ANGLE to CAMERA CLOSE ANGLE of its 360 degrees. Angles the
// device takes unchecked (behaviour.camera_angles_checked false) are read as
// dmc-lite reads them: CLOSE not above OPEN exposes 90 to 180 degrees, and
// the shutter stays open to the frame's end past 360.
std::pair<double, double> StillsExposure(const dmc::RtRunMove& m) {
  double open = m.camera_open_angle_deg.value_or(0);
  double close = m.camera_close_angle_deg.value_or(360);
  if (close <= open) {
    open = 90;
    close = 180;
  }
  return {std::min(open, 360.0) / 360.0, std::min(close, 360.0) / 360.0};
}

}  // namespace

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

// --- playback ---------------------------------------------------------------------------------

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
