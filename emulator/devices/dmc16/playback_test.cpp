// The DMC-16's real-time playback engine on its own, in virtual time
// (dmc-v2-protocol.txt MSG_RT_RUN_MOVE, MSG_RT_GO, MSG_RT_END,
// MSG_RT_STOP_LOOP, MSG_RT_JOG_ALL, MSG_RT_SHOOT_FRAME2): pre-roll and
// post-roll positions, a position report at each frame, loop and ping-pong
// passes, aborts, jog-all, stills triggers and a go-motion exposure.
#include "devices/dmc16/playback.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <memory>
#include <optional>
#include <utility>
#include <vector>

#include "sim/scheduler.h"

namespace moco::devices {
namespace {

using dmc::AckCode;
using sim::kNsPerMs;
using sim::kNsPerSecond;
using sim::TimeNs;

constexpr AckCode kOk = AckCode::kOk;

// One position report playback asked for.
struct Report {
  TimeNs t_ns = 0;
  uint32_t move_time_x1000 = 0;
  int64_t motor1_steps = 0;
};

Dmc16Profile SmallProfile() {
  Dmc16Profile p;
  p.motor_count = 4;
  p.hw_limit_sets = 2;
  p.gio_outputs = 4;
  p.gio_inputs = 4;
  p.dmx_channels = 16;
  p.upload_frame_count = 5000;
  return p;
}

// The parts of a DMC-16 that playback drives, glued as the device glues them:
// a motor at rest hands the rig back to playback (Dmc16::OnMotionFinished).
class Bench final : public sim::RigObserver {
 public:
  explicit Bench(Dmc16Profile profile = SmallProfile())
      : profile_(std::move(profile)),
        rig(scheduler, profile_.motor_count, profile_.hw_limit_sets),
        gio(scheduler, TimeNs{profile_.gio_debounce_ms} * kNsPerMs),
        dmx(scheduler, profile_.dmx_ramp_rate_per_s),
        camera(scheduler),
        upload(profile_.upload_frame_count, profile_.motor_count, profile_.dmx_channels),
        playback(scheduler, rig, planners_, upload, profile_, dmx, gio, camera,
                 PlaybackHooks{
                     .send_position_update =
                         [this] {
                           reports.push_back(Report{scheduler.Now(), playback.MoveTimeX1000(),
                                                    rig.motor(1).Position()});
                         },
                     .send_rt_end = [this] { rt_ends.push_back(scheduler.Now()); },
                     .ensure_position_reports = [this] { ++cadence_starts; },
                     .stop_position_reports = [this] { ++cadence_stops; },
                 }) {
    for (int m = 1; m <= rig.motor_count(); ++m) {
      auto planner = std::make_unique<ScriptPlanner>();
      planners_.push_back(planner.get());
      sim::MotionProfile mp;
      mp.max_velocity_steps_per_s = profile_.max_velocity_steps_per_s;
      mp.max_accel_steps_per_s2 = profile_.max_accel_steps_per_s2;
      mp.hard_stop_multiple = profile_.hard_stop_multiple;
      rig.motor(m).SetPlanner(std::move(planner));
      rig.motor(m).SetProfile(mp);
      rig.motor(m).SetBlur(true);  // as the device's motors until MSG_MOTOR_CONFIGURE
    }
    rig.SetObserver(this);
  }
  ~Bench() override { rig.SetObserver(nullptr); }

  // Uploads frames start..start+n-1: motor 1 on a ramp of `step` steps per
  // frame from 0, motor 2 resting on 50.
  void UploadRamp(uint32_t start, uint32_t n, int32_t step) {
    ASSERT_TRUE(upload.Begin(start, start + n - 1).ok());
    std::vector<int32_t> pos;
    for (uint32_t i = 0; i < n; ++i) pos.push_back(static_cast<int32_t>(i) * step);
    ASSERT_TRUE(upload.Axis({1, 0, true, pos}).ok());
    ASSERT_TRUE(upload.Axis({2, 0, true, {50}}).ok());
    ASSERT_TRUE(upload.End().ok());
  }
  void Settle() { scheduler.RunUntilIdle(10'000'000); }
  void RunFor(TimeNs ns) { scheduler.RunUntil(scheduler.Now() + ns); }
  int64_t Pos(int motor) const { return rig.motor(motor).Position(); }
  // The move times of the reports from index `from` on.
  std::vector<uint32_t> MoveTimes(size_t from = 0) const {
    std::vector<uint32_t> v;
    for (size_t i = from; i < reports.size(); ++i) v.push_back(reports[i].move_time_x1000);
    return v;
  }

 private:
  void OnMotionFinished(int, TimeNs, int64_t) override {
    if (!rig.AnyMoving()) playback.OnRigAtRest();
  }

  Dmc16Profile profile_;
  std::vector<ScriptPlanner*> planners_;

 public:
  sim::Scheduler scheduler;
  sim::Rig rig;
  sim::GioPort gio;
  sim::DmxUniverse dmx;
  sim::CameraPort camera;
  RtMove upload;
  Playback playback;
  std::vector<Report> reports;
  std::vector<TimeNs> rt_ends;
  int cadence_starts = 0;
  int cadence_stops = 0;
};

dmc::RtRunMove RunMove(uint32_t start, uint32_t end, uint32_t fps_x1000, uint32_t pre_ms,
                       uint32_t post_ms, std::optional<uint16_t> flags = std::nullopt) {
  dmc::RtRunMove r;
  r.fps_x1000 = fps_x1000;
  r.start_frame = start;
  r.end_frame = end;
  r.preroll_ms = pre_ms;
  r.postroll_ms = post_ms;
  r.flags = flags;
  return r;
}

// Frame move times from `a` to `b` (either way), thousandths of a frame.
std::vector<uint32_t> Frames(uint32_t a, uint32_t b) {
  std::vector<uint32_t> v;
  for (int64_t f = a;; f += (b >= a ? 1 : -1)) {
    v.push_back(static_cast<uint32_t>(f) * 1000);
    if (f == b) break;
  }
  return v;
}

std::vector<uint32_t> Concat(std::vector<uint32_t> a, const std::vector<uint32_t>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

// Runs until at least `passes` passes are done (bounded).
void RunUntilPasses(Bench& b, uint32_t passes) {
  for (int i = 0; i < 10'000 && b.playback.passes_done() < passes; ++i) b.RunFor(10 * kNsPerMs);
  ASSERT_EQ(b.playback.passes_done(), passes);
}

TEST(Playback, RunMoveArmsOnThePrerollStartAndGoPlaysEveryFrameThenRtEnd) {
  Bench b;
  b.UploadRamp(10, 200, 10);  // 10 steps per frame: 240 steps/s at 24 fps
  // MSG_RT_RUN_MOVE: "The rig must move into a pre-roll position that it
  // calculates, so that it can accelerate into full speed after pre-roll time".
  ASSERT_EQ(b.playback.RunMove(RunMove(20, 60, 24000, 1000, 500)), kOk);
  EXPECT_EQ(b.playback.ModeName(), "armed-run");
  EXPECT_FALSE(b.playback.Playing());
  EXPECT_GE(b.cadence_starts, 1) << "the move to the pre-roll reports as any move";
  // MSG_RT_GO: "When the device has stopped moving".
  EXPECT_EQ(b.playback.Go(), AckCode::kErrMoving);
  b.Settle();
  // Start frame 20 is at 100; the pre-roll covers v*T/2 = 240 * 1 / 2 steps.
  EXPECT_EQ(b.Pos(1), 100 - 120);
  EXPECT_EQ(b.Pos(2), 50);
  EXPECT_TRUE(b.reports.empty());
  const TimeNs t_go = b.scheduler.Now();
  ASSERT_EQ(b.playback.Go(), kOk);
  EXPECT_EQ(b.playback.ModeName(), "running");
  EXPECT_TRUE(b.playback.Playing());
  EXPECT_EQ(b.cadence_stops, 1) << "per-frame reports replace the cadence";
  b.Settle();
  // "it must send a MSG_MOTOR_GET_POSITION each time it reaches a new frame",
  // then one more when the run has stopped.
  ASSERT_EQ(b.MoveTimes(), Concat(Frames(20, 60), {60000}));
  for (uint32_t k = 0; k <= 40; ++k) {
    const Report& r = b.reports[k];
    const TimeNs ideal = t_go + kNsPerSecond + (k * kNsPerSecond + 23) / 24;
    EXPECT_GE(r.t_ns, ideal - 1) << k;
    EXPECT_LE(r.t_ns, ideal + 1) << k;
    EXPECT_EQ(r.motor1_steps, (10 + k) * 10) << "on the uploaded position at frame " << 20 + k;
  }
  // Post-roll: from 240 steps/s to rest in 0.5 s covers 60 steps past frame 60.
  EXPECT_EQ(b.Pos(1), 500 + 60);
  // MSG_RT_END once, when the post-roll is over.
  ASSERT_EQ(b.rt_ends.size(), 1u);
  EXPECT_NEAR(static_cast<double>(b.rt_ends[0]),
              static_cast<double>(b.reports[40].t_ns + 500 * kNsPerMs), 2);
  EXPECT_EQ(b.reports.back().t_ns, b.rt_ends[0]);
  EXPECT_EQ(b.playback.ModeName(), "idle");
  EXPECT_EQ(b.playback.MoveTimeX1000(), 60000u);
  EXPECT_EQ(b.playback.passes_done(), 1u);
  EXPECT_EQ(b.playback.Go(), AckCode::kErrGeneral) << "nothing armed any more";
}

TEST(Playback, RunMoveRefusesAPrerollPastASoftLimitAndMovesNothing) {
  Bench b;
  b.UploadRamp(10, 200, 10);
  sim::SoftLimits s;
  s.lower_enabled = true;
  s.lower_steps = 0;
  b.rig.motor(1).SetSoftLimits(s);
  // Frame 10 is at 0: its pre-roll would start below the limit.
  EXPECT_EQ(b.playback.RunMove(RunMove(10, 100, 24000, 1000, 0)), AckCode::kErrPreroll);
  EXPECT_FALSE(b.rig.AnyMoving());
  EXPECT_EQ(b.playback.ModeName(), "idle");
  // Without a pre-roll the same run is fine.
  EXPECT_EQ(b.playback.RunMove(RunMove(10, 100, 24000, 0, 0)), kOk);
}

TEST(Playback, LoopPlaysAgainFromThePrerollUntilStopLoopEndsItAtTheNextEndPoint) {
  Bench b;
  b.UploadRamp(10, 60, 10);
  ASSERT_EQ(b.playback.RunMove(RunMove(20, 40, 24000, 500, 500, dmc::kPlayLoop)), kOk);
  b.Settle();
  ASSERT_EQ(b.playback.Go(), kOk);
  RunUntilPasses(b, 1);
  // The rig goes back to the pre-roll by itself, still playing (no GO).
  EXPECT_TRUE(b.playback.Playing());
  EXPECT_TRUE(b.rt_ends.empty());
  const size_t first_pass = b.reports.size();
  EXPECT_EQ(b.MoveTimes(), Frames(20, 40));
  RunUntilPasses(b, 2);
  EXPECT_TRUE(b.rt_ends.empty()) << "a loop runs until MSG_RT_STOP_LOOP";
  // MSG_RT_STOP_LOOP: "must stop after it reaches the next end point".
  EXPECT_EQ(b.playback.StopLoop(), kOk);
  b.Settle();
  EXPECT_EQ(b.playback.passes_done(), 3u);
  EXPECT_EQ(b.MoveTimes(first_pass), Concat(Concat(Frames(20, 40), Frames(20, 40)), {40000}));
  ASSERT_EQ(b.rt_ends.size(), 1u);
  EXPECT_EQ(b.Pos(1), 300 + 60);  // frame 40 and the post-roll
  EXPECT_EQ(b.playback.ModeName(), "idle");
}

TEST(Playback, PingPongPlaysTheRangeBackwardOnTheSecondPass) {
  Bench b;
  b.UploadRamp(10, 60, 10);
  ASSERT_EQ(b.playback.RunMove(RunMove(20, 40, 24000, 500, 500, dmc::kPlayPingPong)), kOk);
  b.Settle();
  ASSERT_EQ(b.playback.Go(), kOk);
  RunUntilPasses(b, 1);
  // The backward pass starts 60 steps past frame 40 (its pre-roll).
  ASSERT_EQ(b.playback.StopLoop(), kOk);
  b.Settle();
  EXPECT_EQ(b.playback.passes_done(), 2u);
  EXPECT_EQ(b.MoveTimes(), Concat(Concat(Frames(20, 40), Frames(40, 20)), {20000}));
  for (size_t i = 21; i < 42; ++i) {
    EXPECT_EQ(b.reports[i].motor1_steps, 100 + 10 * static_cast<int64_t>(41 - i)) << i;
  }
  ASSERT_EQ(b.rt_ends.size(), 1u);
  EXPECT_EQ(b.Pos(1), 100 - 60);  // frame 20 and the backward post-roll
}

TEST(Playback, AbortEndsAPassWithOneRtEndAndDisarmsAnArmedRunSilently) {
  Bench b;
  b.UploadRamp(10, 200, 10);
  ASSERT_EQ(b.playback.RunMove(RunMove(20, 150, 24000, 1000, 500)), kOk);
  b.Settle();
  b.playback.Abort(true);
  EXPECT_EQ(b.playback.ModeName(), "idle");
  EXPECT_TRUE(b.rt_ends.empty()) << "nothing was shot";
  EXPECT_EQ(b.playback.Go(), AckCode::kErrGeneral);

  ASSERT_EQ(b.playback.RunMove(RunMove(20, 150, 24000, 1000, 500)), kOk);
  b.Settle();
  ASSERT_EQ(b.playback.Go(), kOk);
  b.RunFor(2 * kNsPerSecond);
  const size_t before = b.reports.size();
  ASSERT_GT(before, 0u);
  b.playback.Abort(true);
  ASSERT_EQ(b.rt_ends.size(), 1u);
  EXPECT_FALSE(b.playback.Playing());
  b.Settle();
  EXPECT_FALSE(b.rig.AnyMoving());
  EXPECT_EQ(b.reports.size(), before + 1) << "the stop report, then no more frames";
  EXPECT_EQ(b.rt_ends.size(), 1u);
}

TEST(Playback, JogAllGoesFromTheFrameTheRigIsOnWithoutRtEnd) {
  Bench b;
  b.UploadRamp(10, 200, 10);
  // MSG_RT_JOG_ALL: "The rig must already be on a frame position".
  EXPECT_EQ(b.playback.JogAll({24000, 40}), AckCode::kErrNotInPosition);
  ASSERT_EQ(b.playback.PositionFrame(20), kOk);
  EXPECT_EQ(b.playback.MoveTimeX1000(), 20000u);
  b.Settle();
  EXPECT_EQ(b.playback.on_frame(), 20u);
  EXPECT_EQ(b.Pos(1), 100);
  ASSERT_EQ(b.playback.JogAll({24000, 40}), kOk);
  EXPECT_EQ(b.playback.ModeName(), "jogging-all");
  EXPECT_TRUE(b.playback.ReportsEachFrame());
  b.Settle();
  // A report at each frame and one when the jog has stopped (the stop and
  // the last frame fall on the same instant, in either order).
  std::vector<uint32_t> times = b.MoveTimes();
  ASSERT_EQ(times.size(), 21u + 1u);
  EXPECT_EQ(times.back(), 40000u);
  EXPECT_EQ(b.reports.back().motor1_steps, 300);
  times.erase(std::unique(times.begin(), times.end()), times.end());
  EXPECT_EQ(times, Frames(20, 40));
  EXPECT_TRUE(b.rt_ends.empty()) << "RT_END follows RUN_MOVE and SHOOT_FRAME only";
  EXPECT_EQ(b.Pos(1), 300) << "no pre-roll or post-roll";
  EXPECT_EQ(b.playback.on_frame(), 40u);
  EXPECT_EQ(b.playback.ModeName(), "idle");
  // A motor moved off the frame by another command leaves it...
  b.playback.OnDirectMotion();
  ASSERT_EQ(b.rig.motor(1).MoveTo(305), sim::MoveStatus::kOk);
  b.Settle();
  EXPECT_EQ(b.playback.JogAll({24000, 20}), AckCode::kErrNotInPosition);
  // ...and moved back onto an uploaded frame's position it is on that frame
  // again: "The rig must already be on a frame position that is uploaded".
  b.playback.OnDirectMotion();
  ASSERT_EQ(b.rig.motor(1).MoveTo(200), sim::MoveStatus::kOk);  // frame 30 of the ramp
  b.Settle();
  ASSERT_EQ(b.playback.JogAll({24000, 20}), kOk);
  b.Settle();
  EXPECT_EQ(b.Pos(1), 100);
  EXPECT_EQ(b.playback.on_frame(), 20u);
}

TEST(Playback, JogAllAfterAReuploadStartsFromTheFrameTheRigRestsOn) {
  Bench b;
  b.UploadRamp(10, 200, 10);
  ASSERT_EQ(b.playback.PositionFrame(20), kOk);
  b.Settle();
  ASSERT_EQ(b.playback.on_frame(), 20u);
  // The host uploads an edited move; the motors have not moved and still
  // rest on frame 20's position, which the new upload keeps.
  b.playback.OnUploadBegin();
  b.UploadRamp(10, 200, 10);
  EXPECT_EQ(b.playback.on_frame(), std::nullopt);
  ASSERT_EQ(b.playback.JogAll({24000, 30}), kOk);
  b.Settle();
  EXPECT_EQ(b.Pos(1), 200);
  EXPECT_EQ(b.playback.on_frame(), 30u);
  // An upload on which the rig's position is no frame: not in position.
  b.playback.OnUploadBegin();
  b.UploadRamp(10, 200, 7);
  EXPECT_EQ(b.playback.JogAll({24000, 40}), AckCode::kErrNotInPosition);
}

TEST(Playback, StillsTriggerOpensAndClosesTheShutterInEveryFrame) {
  Bench b;
  b.UploadRamp(10, 60, 10);
  dmc::RtRunMove r = RunMove(20, 25, 10000, 0, 0, dmc::kPlayCameraStills);
  r.camera_open_angle_deg = 0;
  r.camera_close_angle_deg = 180;
  ASSERT_EQ(b.playback.RunMove(r), kOk);
  b.Settle();
  const TimeNs t0 = b.scheduler.Now();
  ASSERT_EQ(b.playback.Go(), kOk);
  b.Settle();
  // Frames 20..24 are each exposed for the first half of the frame (10 fps).
  std::vector<sim::CameraPort::Edge> want;
  for (TimeNs k = 0; k < 5; ++k) {
    want.push_back({t0 + k * 100 * kNsPerMs, sim::CameraPort::kShutter, true});
    want.push_back({t0 + k * 100 * kNsPerMs + 50 * kNsPerMs, sim::CameraPort::kShutter, false});
  }
  const std::vector<sim::CameraPort::Edge> got = b.camera.Trace();
  ASSERT_EQ(got.size(), want.size());
  for (size_t i = 0; i < want.size(); ++i) {
    EXPECT_NEAR(static_cast<double>(got[i].time_ns), static_cast<double>(want[i].time_ns), 1) << i;
    EXPECT_EQ(got[i].line, want[i].line) << i;
    EXPECT_EQ(got[i].level, want[i].level) << i;
  }
  EXPECT_EQ(b.rt_ends.size(), 1u);
}

TEST(Playback, ShootFrameExposesWhileTheBlurredMotorCrossesTheShutterAngles) {
  Bench b;
  b.UploadRamp(10, 60, 10);
  // MSG_RT_SHOOT_FRAME2: POS A at angle 0, POS B at 360; the shutter opens
  // at 90 and closes at 270 degrees, 100 ms later: 200 steps in 0.1 s.
  ASSERT_EQ(b.playback.ShootFrame(20, 1, 100, 90, 270, std::vector<dmc::BlurMotor>{{1, 0, 400}}),
            kOk);
  EXPECT_EQ(b.playback.ModeName(), "armed-shoot");
  b.Settle();
  // Ramp to 2000 steps/s at 10000 steps/s^2 takes 200 steps before the opening.
  EXPECT_EQ(b.Pos(1), 100 - 200);
  EXPECT_EQ(b.Pos(2), 50) << "a motor not blurred goes to the frame's position";
  const TimeNs t_go = b.scheduler.Now();
  ASSERT_EQ(b.playback.Go(), kOk);
  EXPECT_EQ(b.playback.ModeName(), "shooting");
  b.scheduler.RunUntil(t_go + 200 * kNsPerMs + 1);
  EXPECT_TRUE(b.camera.level(sim::CameraPort::kShutter));
  EXPECT_NEAR(static_cast<double>(b.Pos(1)), 100, 1);
  b.scheduler.RunUntil(t_go + 300 * kNsPerMs + 1);
  EXPECT_FALSE(b.camera.level(sim::CameraPort::kShutter));
  EXPECT_NEAR(static_cast<double>(b.Pos(1)), 300, 1);
  b.Settle();
  EXPECT_EQ(b.camera.exposures(), 1u);
  EXPECT_EQ(b.Pos(1), 300 + 200);
  ASSERT_EQ(b.rt_ends.size(), 1u);
  EXPECT_EQ(b.playback.ModeName(), "idle");
}

// MSG_MOTOR_CONFIGURE "0x02 - blur enabled" decides which of the motors a
// SHOOT_FRAME lists blur: one without the flag is held on the frame's
// position through the exposure, as the motors not listed are.
TEST(Playback, AListedMotorWithoutTheBlurFlagIsHeldOnTheFrame) {
  Bench b;
  b.UploadRamp(10, 60, 10);
  b.rig.motor(1).SetBlur(false);
  ASSERT_EQ(b.playback.ShootFrame(20, 1, 100, 90, 270, std::vector<dmc::BlurMotor>{{1, 0, 400}}),
            kOk);
  b.Settle();
  EXPECT_EQ(b.Pos(1), 100) << "frame 20's uploaded position, not the ramp start";
  ASSERT_EQ(b.playback.Go(), kOk);
  b.Settle();
  EXPECT_EQ(b.camera.exposures(), 1u);
  EXPECT_EQ(b.Pos(1), 100);
  // Listed twice is still refused, blurred or not.
  EXPECT_EQ(b.playback.ShootFrame(20, 1, 100, 90, 270,
                                  std::vector<dmc::BlurMotor>{{1, 0, 400}, {1, 0, 400}}),
            AckCode::kErrRange);
}

TEST(Playback, ResetForgetsTheFrameAndTheRun) {
  Bench b;
  b.UploadRamp(10, 60, 10);
  ASSERT_EQ(b.playback.PositionFrame(30), kOk);
  b.Settle();
  EXPECT_EQ(b.playback.on_frame(), 30u);
  EXPECT_EQ(b.playback.MoveTimeX1000(), 30000u);
  b.playback.Reset();
  EXPECT_EQ(b.playback.on_frame(), std::nullopt);
  EXPECT_EQ(b.playback.MoveTimeX1000(), 0u);
  ASSERT_EQ(b.playback.RunMove(RunMove(20, 40, 24000, 0, 0)), kOk);
  b.Settle();
  b.playback.Reset();
  EXPECT_EQ(b.playback.ModeName(), "idle");
  EXPECT_EQ(b.playback.Go(), AckCode::kErrGeneral);
}

}  // namespace
}  // namespace moco::devices
