// The DMC-16's real-time playback engine (dmc-v2-protocol.txt "Real-time
// moves": MSG_RT_POSITION_FRAME, MSG_RT_RUN_MOVE, MSG_RT_SHOOT_FRAME /
// _FRAME_2, MSG_RT_GO, MSG_RT_STOP_LOOP, MSG_RT_JOG_ALL, MSG_RT_END): plays
// the uploaded move on the rig in virtual time. It arms a run (the rig goes
// to the pre-roll position) or a shot (the blurred motors go to their ramp
// start), and on GO plays the frame path window by window with pre-roll and
// post-roll, loop and ping-pong passes, per-frame DMX/GIO outputs, bloop,
// camera video/stills edges and go-motion exposures; it sends a position
// report at each frame and RT_END when a live run or shot ends.
//
// The device (dmc16.cpp) decodes and answers the requests; this class only
// decides the ACK codes of the real-time requests and moves the rig. Its
// output goes through the hooks, so it can be driven alone in tests.
#ifndef MOCO_DEVICES_DMC16_PLAYBACK_H_
#define MOCO_DEVICES_DMC16_PLAYBACK_H_

#include <cstdint>
#include <functional>
#include <optional>
#include <string_view>
#include <vector>

#include "devices/dmc16/dmc16_profile.h"
#include "devices/dmc16/rt_move.h"
#include "devices/dmc16/script_planner.h"
#include "sim/callback.h"
#include "sim/io.h"
#include "sim/rig.h"
#include "sim/scheduler.h"
#include "wire/dmc.h"

namespace moco::devices {

// The bits of `count` GIO lines (MSG_HI GIO OUT / INPUT COUNT, 0-32).
inline uint32_t GioMask(int count) { return count >= 32 ? 0xffffffffu : (1u << count) - 1u; }

// The device's mapping of a refused motor command to its ACK code.
dmc::AckCode AckForMoveStatus(sim::MoveStatus s);

// What playback tells the device to send; every hook must be set.
struct PlaybackHooks {
  // An unsolicited MSG_MOTOR_GET_POSITION now ("each time it reaches a new
  // frame", and when a run ends); the periodic cadence counts on from it.
  std::function<void()> send_position_update;
  // An unsolicited MSG_RT_END (a live run or a shot has finished).
  std::function<void()> send_rt_end;
  // The device's periodic position reports while anything moves ("about
  // every 0.10 seconds"): they run through every phase of playback, beside
  // the per-frame reports. With a velocity tick (behaviour.playback_tick_ms)
  // this also keeps the device's tick running (Dmc16 calls OnTick()).
  std::function<void()> ensure_position_reports;
  // With a velocity tick: an update is due, sent at the next tick (a new
  // frame, the end of a pass, a stop); without one playback sends at once.
  std::function<void()> flag_position_update;
};

// A video camera trigger (MSG_RT_RUN_MOVE FLAGS 0x10) is a press of the
// shutter line this long; two presses are at least this far apart.
inline constexpr sim::TimeNs kVideoTriggerPressNs = 100 * sim::kNsPerMs;

class Playback {
 public:
  enum class Mode : uint8_t { kIdle, kArmedRun, kArmedShoot, kPass, kShooting, kJogAll };

  // Every reference must outlive this; `planners` (index motor-1, owned by
  // the motors) may be filled after construction.
  Playback(sim::Scheduler& scheduler, sim::Rig& rig, const std::vector<ScriptPlanner*>& planners,
           const RtMove& upload, const Dmc16Profile& profile, sim::DmxUniverse& dmx,
           sim::GioPort& gio, sim::CameraPort& camera, PlaybackHooks hooks);
  ~Playback();
  Playback(const Playback&) = delete;
  Playback& operator=(const Playback&) = delete;

  // --- the real-time requests: each returns the ACK code ---
  // MSG_RT_POSITION_FRAME: every playback motor (and DMX) to the frame.
  dmc::AckCode PositionFrame(uint32_t frame);
  // MSG_RT_RUN_MOVE: checks the run and moves the rig to its pre-roll start.
  dmc::AckCode RunMove(const dmc::RtRunMove& m);
  // MSG_RT_SHOOT_FRAME / _2: `dir` +1 plays POS A towards POS B, -1 back;
  // the shutter is open from `open_deg` to `close_deg` of the frame's 360.
  dmc::AckCode ShootFrame(uint32_t frame, int dir, uint32_t exposure_ms, double open_deg,
                          double close_deg, const std::vector<dmc::BlurMotor>& motors);
  // MSG_RT_GO: plays the armed run or shot.
  dmc::AckCode Go();
  // MSG_RT_STOP_LOOP: the loop or ping-pong ends at its next end point.
  dmc::AckCode StopLoop();
  // MSG_RT_JOG_ALL: from the frame the rig is on to another, at an fps.
  dmc::AckCode JogAll(const dmc::RtJogAll& m);

  // --- what the rest of the device does to playback ---
  // Ends whatever playback is going on (a stop, a limit, the e-stop), with
  // RT_END when `send_end` and a live pass or shot was running; an armed
  // but not started run is simply disarmed.
  void Abort(bool send_end);
  // A new upload begins (MSG_RT_UPLOAD_MOVE_BEGIN, not while Playing()).
  void OnUploadBegin();
  // A motor moved by another command: an armed run or shot is disarmed and
  // the rig is no longer on a frame.
  void OnDirectMotion();
  // An armed run or shot is disarmed and the run forgotten (STOP_ALL).
  void Disarm();
  // A position was renamed (MSG_MOTOR_RESET_POSITION): not on a frame.
  void ForgetFrame() { on_frame_.reset(); }
  // Every motor came to rest. True when playback takes it (a repositioned
  // loop pass starts, or a pass is under way); false when the device
  // should report the stop.
  bool OnRigAtRest();
  // Power-on: everything forgotten, no timer.
  void Reset();
  // Power-off: timers cancelled, back to idle (the last frame is kept).
  void Halt();
  // With a velocity tick (behaviour.playback_tick_ms): one tick of a live
  // run; the device calls it on every tick while Ticking().
  void OnTick();

  // --- observation ---
  // A live pass, a shoot or a jog-all is under way (motion commands wait).
  bool Playing() const {
    return mode_ == Mode::kPass || mode_ == Mode::kShooting || mode_ == Mode::kJogAll;
  }
  // A pass (run or jog-all) reports positions at each frame (besides the cadence).
  bool ReportsEachFrame() const { return mode_ == Mode::kPass || mode_ == Mode::kJogAll; }
  Mode mode() const { return mode_; }
  // "idle", "armed-run", "armed-shoot", "running", "shooting", "jogging-all".
  std::string_view ModeName() const;
  // MOVE TIME the device reports now (thousandths of a frame;
  // docs/protocol-notes.md "MOVE TIME"): exactly frame x 1000 at each frame
  // of a pass, strictly between two frames' values in between, the pass's
  // frame clock run on before the start frame and after the end frame.
  uint32_t MoveTimeX1000() const;
  // The frame the rig was last sent to, if it is still there by playback's account.
  std::optional<uint32_t> on_frame() const { return on_frame_; }
  // Passes completed since the run started (loop and ping-pong count each).
  uint32_t passes_done() const { return passes_done_; }
  // A live run on the velocity tick needs OnTick(): one armed waiting for its
  // pre-roll to begin, or one playing.
  bool Ticking() const {
    return tick_run_.has_value() && (mode_ == Mode::kPass || tick_run_->to_preroll);
  }
  // A run is armed or playing, a shot or a jog-all under way: the device is
  // out of its plain jog state (the tick sends a due update at once).
  bool InRealTimeState() const { return mode_ != Mode::kIdle; }
  // While the tick drives `motor` through a run: the position the device
  // reports (the engine's position, truncated toward zero with
  // behaviour.positions_truncate, else the nearest step); nullopt otherwise.
  std::optional<int64_t> ModelPosition(int motor) const;

 private:
  struct RunSetup {
    dmc::RtRunMove request;
    std::vector<int> motors;  // uploaded, enabled motors taking part
  };
  struct BlurAxis {
    int motor = 0;
    double x_open_steps = 0;   // continuous position when the shutter opens
    double x_close_steps = 0;  // ... when it closes
    int64_t pre_steps = 0;     // rest position before the ramp up
    int64_t post_steps = 0;    // rest position after the ramp down
  };
  struct Pass {
    uint32_t from_frame = 0;
    uint32_t to_frame = 0;
    int dir = 1;     // +1 forward through the frames, -1 backward
    double fps = 0;  // the frame rate between the ramps
    double preroll_s = 0;
    double postroll_s = 0;
    // JOG_ALL's frame clock ramps from rest to `fps` and back to rest at
    // `accel_fps2` frames/s^2 (0: a live pass, which runs at `fps` from the
    // start frame to the end frame). With ramps, the clock accelerates for
    // `ramp_s`, runs at `fps` for `cruise_s`, then brakes for `ramp_s`.
    double accel_fps2 = 0;
    double ramp_s = 0;
    double cruise_s = 0;
    sim::TimeNs t_first_frame_ns = 0;  // when the rig passes from_frame
    uint32_t frames_done = 0;          // frame intervals completed
    int64_t ticked = -1;               // index of the last frame reached, -1 before the first
    sim::TimeNs tick_ns = 0;           // when it was reached
    bool video = false;
    bool stills = false;
    bool live = false;  // a RUN_MOVE pass (camera, DMX, triggers, bloop); false for JOG_ALL
  };
  struct IoTimer {
    sim::Scheduler::TimerId id;
    sim::TimeNs at_ns;
  };
  // A live run on the velocity tick (docs/devices/dmc16.md "The 20 ms velocity
  // tick"), in single precision as the reference firmware computes it.
  struct TickAxis {
    int motor = 0;
    float x = 0;                // where the engine has sent the motor (its position)
    float ramp_from = 0;        // pre-roll start, a whole step
    float ramp_half_accel = 0;  // steps/s^2, halved
    float post_from = 0;        // post-roll start: the path at the clock's end, a whole step
    float post_v = 0;           // steps/s at the post-roll start
    float post_half_accel = 0;
  };
  struct TickRun {
    enum class Phase : uint8_t { kPreroll, kMove, kPostroll };
    Phase phase = Phase::kPreroll;
    float t = 0;  // seconds into the phase, counted in ticks
    float preroll_s = 0;
    float postroll_s = 0;
    float clock_from = 0;  // the frame clock over the move phase
    float clock_to = 0;
    float move_s = 0;            // the move phase's length
    float rate = 0;              // frames per second along the clock (signed)
    sim::TimeNs move_t0_ns = 0;  // when the move phase began
    bool to_preroll = false;     // armed: the motors leave for the pre-roll at the next tick
    std::vector<TickAxis> axes;
  };

  bool MotorValid(int motor) const { return motor >= 1 && motor <= profile_.motor_count; }
  // Motors of the upload that are enabled (they take part in playback).
  std::vector<int> PlaybackMotors() const;
  // Whether every playback motor rests on its position at `frame`.
  bool OnFramePosition(uint32_t frame) const;
  // The uploaded frame whose positions the rig rests on (the one it last
  // reached if it still does, else the one nearest `toward`), or nullopt.
  std::optional<uint32_t> FrameTheRigIsOn(uint32_t toward) const;
  // Starts motor `motor` on `segments` (from rest), ending at rest on `target`.
  // The bloop of `req` at the start of the move, for about BLOOP TIME.
  void Bloop(const dmc::RtRunMove& req);
  void Script(int motor, std::vector<sim::Segment> segments, int64_t target_steps);
  // Frame-path segments of `motor` for frame intervals [k0, k1) of the pass.
  void AppendPath(int motor, const Pass& p, uint32_t k0, uint32_t k1,
                  std::vector<sim::Segment>& out) const;
  int32_t PassPosition(int motor, const Pass& p, uint32_t k) const;
  double PassVelocity(int motor, const Pass& p, uint32_t k) const;  // interval k at fps, steps/s
  // The pass's frame clock: frames from from_frame `t_s` after it (negative
  // before), the time it reaches frame index `s`, and its rate (frames/s).
  static double FramesAt(const Pass& p, double t_s);
  static double TimeOfFrames(const Pass& p, double s);
  static double RateAt(const Pass& p, double t_s);
  static double AccelAt(const Pass& p, double t_s);  // frames/s^2
  // JOG_ALL: the ramps of a pass from rest to rest, each motor within its max
  // velocity (the clock's rate is lowered) and its max acceleration.
  void FitJogRamps(Pass& p) const;
  // MOVE TIME of the pass now (MoveTimeX1000 while a pass runs).
  uint32_t PassMoveTime() const;
  // A press of the shutter line for a video trigger (`start`: recording
  // starts, else stops), at `due_ns` or as soon as the previous press and
  // its release have ended.
  void VideoTrigger(sim::TimeNs due_ns, bool start);
  // Pre-roll: rest position before the pass and the time to reach speed.
  int64_t PrerollStart(int motor, const Pass& p) const;
  int64_t PostrollEnd(int motor, const Pass& p) const;
  dmc::AckCode CheckPass(const Pass& p) const;
  static Pass MakePass(uint32_t from, uint32_t to, double fps, double pre_s, double post_s);
  void StartPass(const Pass& p);
  void PlanWindow(uint32_t k0);
  void OnFrameTick();
  void EndPass();
  void StartNextPassOrEnd();
  void StartShoot();
  // `stopped`: ended early (Abort), the update goes out whatever was sent this instant.
  void FinishRun(bool send_end, bool stopped = false);
  void ApplyFrameOutputs(uint32_t frame);
  // --- the velocity tick ---
  bool TickMode() const { return profile_.behaviour.playback_tick_ms > 0; }
  // A position update now (continuous playback) or at the next tick.
  void Report();
  // The frame path at frame clock `clock` (behaviour.upload_index_from_start_frame).
  float PathAt(int motor, float clock) const;
  dmc::AckCode RunMoveTicked(const dmc::RtRunMove& m);
  // RT_RUN_MOVE's checks of the request itself (kOk, or the refusal).
  dmc::AckCode CheckRunMove(const dmc::RtRunMove& m) const;
  dmc::AckCode GoTicked();
  // Sends the motor to `x` over the next tick.
  void Drive(TickAxis& a, float x, float tick_s);
  void FrameReached(int64_t frame);
  // `x`: where the motors are held if another pass follows.
  void EndTickPass(const std::vector<float>& x, float tick_s);
  // POSITION_FRAME's move with a tick: a point-to-point move of at least 2 x
  // 0.5 s from rest (a plain move while the motor moves).
  sim::MoveStatus MoveToFrame(int motor, int64_t target_steps);
  void CancelTimer(sim::Scheduler::TimerId& id);
  void AddIoTimer(sim::TimeNs at_ns, sim::Callback cb);
  void CancelTimers();

  sim::Scheduler& scheduler_;
  sim::Rig& rig_;
  const std::vector<ScriptPlanner*>& planners_;
  const RtMove& upload_;
  const Dmc16Profile& profile_;
  sim::DmxUniverse& dmx_;
  sim::GioPort& gio_;
  sim::CameraPort& camera_;
  PlaybackHooks hooks_;

  Mode mode_ = Mode::kIdle;
  std::optional<RunSetup> run_;
  std::vector<BlurAxis> blur_;
  uint32_t shoot_frame_ = 0;
  uint32_t exposure_ms_ = 0;
  Pass pass_;
  bool stop_loop_ = false;
  bool reposition_pending_ = false;  // a loop pass waits for the rig to reach its pre-roll
  uint32_t passes_done_ = 0;
  std::optional<uint32_t> on_frame_;  // last frame the rig was sent to
  uint32_t move_time_x1000_ = 0;      // MOVE TIME outside a running pass
  bool rt_end_sent_ = false;          // this run's RT_END went out at its last frame
  bool video_recording_ = false;      // a video start trigger awaits its stop trigger
  sim::TimeNs video_free_ns_ = 0;     // the next video press may begin from here
  sim::TimeNs armed_ns_ = 0;          // when the run or shot was last armed
  sim::TimeNs rest_ns_ = 0;           // when every motor last came to rest
  sim::TimeNs end_update_ns_ = -1;    // when the last pass or shot ended, with its update

  sim::Scheduler::TimerId frame_timer_ = sim::Scheduler::kNoTimer;
  sim::Scheduler::TimerId phase_timer_ = sim::Scheduler::kNoTimer;
  std::vector<IoTimer> io_timers_;  // camera and bloop edges of the running pass
  // The run on the velocity tick, from RUN_MOVE (armed) through its passes.
  std::optional<TickRun> tick_run_;
};

}  // namespace moco::devices

#endif  // MOCO_DEVICES_DMC16_PLAYBACK_H_
