// The DMC-16's real-time playback engine on its own, in virtual time
// (dmc-v2-protocol.txt MSG_RT_RUN_MOVE, MSG_RT_GO, MSG_RT_END,
// MSG_RT_STOP_LOOP, MSG_RT_JOG_ALL, MSG_RT_SHOOT_FRAME2): pre-roll and
// post-roll positions, a position report at each frame, loop and ping-pong
// passes, aborts, jog-all, stills triggers and a go-motion exposure.
#include "devices/dmc16/playback.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "devices/dmc16/dmc16_test_support.h"
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
                     .flag_position_update = [this] { ++flagged; },
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
  int flagged = 0;
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
  const int cadence_before_go = b.cadence_starts;
  ASSERT_EQ(b.playback.Go(), kOk);
  EXPECT_EQ(b.playback.ModeName(), "running");
  EXPECT_TRUE(b.playback.Playing());
  EXPECT_GT(b.cadence_starts, cadence_before_go) << "the cadence runs beside the frame reports";
  b.Settle();
  // "it must send a MSG_MOTOR_GET_POSITION each time it reaches a new frame",
  // then one more when the run has stopped, its MOVE TIME the frame clock
  // run on through the post-roll: 0.5 s at 24 fps past frame 60.
  ASSERT_EQ(b.MoveTimes(), Concat(Frames(20, 60), {72000}));
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
  EXPECT_EQ(b.playback.MoveTimeX1000(), 72000u);
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
  EXPECT_EQ(b.MoveTimes(first_pass), Concat(Concat(Frames(20, 40), Frames(20, 40)), {52000}));
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
  // The last update: 0.5 s of post-roll at 24 fps below frame 20.
  EXPECT_EQ(b.MoveTimes(), Concat(Concat(Frames(20, 40), Frames(40, 20)), {8000}));
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
  // A report at each frame, once: the destination's, as the jog comes to
  // rest there, is also the report of the stop.
  EXPECT_EQ(b.MoveTimes(), Frames(20, 40));
  EXPECT_EQ(b.reports.back().motor1_steps, 300);
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

// The motion of `motor` as planned now: checks every segment against the
// motor's limits and returns the largest speed reached.
struct PlanCheck {
  double first_v0 = 0;
  double last_v_end = 0;
  double max_abs_v = 0;
  double max_abs_a = 0;
  double duration_s = 0;
};
PlanCheck CheckPlan(const sim::Plan& plan) {
  PlanCheck c;
  const std::vector<sim::Segment>& segs = plan.segments();
  if (segs.empty()) return c;
  c.first_v0 = segs.front().v0_steps_per_s;
  for (const sim::Segment& s : segs) {
    const double v_end = s.v0_steps_per_s + s.a_steps_per_s2 * s.duration_s;
    c.max_abs_v = std::max({c.max_abs_v, std::fabs(s.v0_steps_per_s), std::fabs(v_end)});
    c.max_abs_a = std::max(c.max_abs_a, std::fabs(s.a_steps_per_s2));
    c.duration_s += s.duration_s;
    c.last_v_end = v_end;
  }
  return c;
}

TEST(Playback, JogAllRampsInAndOutWithinTheMotorsMaxAcceleration) {
  Bench b;
  b.UploadRamp(10, 200, 10);  // motor 1: 10 steps per frame
  sim::MotionProfile mp = b.rig.motor(1).profile();
  mp.max_accel_steps_per_s2 = 200;  // 20 frames/s^2 along the path
  ASSERT_EQ(b.rig.motor(1).SetProfile(mp), sim::MoveStatus::kOk);
  ASSERT_EQ(b.playback.PositionFrame(20), kOk);
  b.Settle();
  const TimeNs t0 = b.scheduler.Now();
  const size_t mark = b.reports.size();
  // MSG_RT_JOG_ALL "Jog all motors towards the destination frame": the rig
  // rests on frame 20, so it must start from rest and end at rest on frame 40.
  ASSERT_EQ(b.playback.JogAll({10000, 40}), kOk);
  const PlanCheck c = CheckPlan(b.rig.motor(1).CurrentPlan());
  EXPECT_EQ(c.first_v0, 0) << "starts at rest";
  EXPECT_NEAR(c.last_v_end, 0, 1e-6) << "ends at rest";
  EXPECT_LE(c.max_abs_a, 200 + 1e-6) << "within MAX ACCEL";
  EXPECT_NEAR(c.max_abs_v, 100, 1e-6) << "10 fps x 10 steps per frame between the ramps";
  // Ramps of 0.5 s (2.5 frames each), 15 frames at 10 fps: 2.5 s.
  EXPECT_NEAR(c.duration_s, 2.5, 1e-6);
  b.Settle();
  EXPECT_EQ(b.Pos(1), 300);
  EXPECT_EQ(b.playback.on_frame(), 40u);
  // Each frame is reported when the rig reaches it on the ramped clock:
  // frame 21 after sqrt(2 / 20) s, frame 30 in the cruise, 39 in the brake.
  std::vector<TimeNs> at(41, -1);
  for (size_t i = mark; i < b.reports.size(); ++i) {
    const Report& r = b.reports[i];
    if (r.move_time_x1000 % 1000 == 0 && at[r.move_time_x1000 / 1000] < 0) {
      at[r.move_time_x1000 / 1000] = r.t_ns - t0;
      EXPECT_EQ(r.motor1_steps, (r.move_time_x1000 / 1000 - 10) * 10) << "on the frame's position";
    }
  }
  EXPECT_NEAR(static_cast<double>(at[21]), std::sqrt(0.1) * 1e9, 2);
  EXPECT_NEAR(static_cast<double>(at[30]), (0.5 + 0.75) * 1e9, 2);
  EXPECT_NEAR(static_cast<double>(at[39]), (2.5 - std::sqrt(0.1)) * 1e9, 2);
  EXPECT_NEAR(static_cast<double>(at[40]), 2.5e9, 2);
}

TEST(Playback, JogAllFasterThanAMotorsMaxVelocityPlaysAtTheFastestFpsItCanFollow) {
  Bench b;
  b.UploadRamp(10, 200, 10);
  sim::MotionProfile mp = b.rig.motor(1).profile();
  mp.max_velocity_steps_per_s = 100;  // 10 fps at 10 steps per frame
  ASSERT_EQ(b.rig.motor(1).SetProfile(mp), sim::MoveStatus::kOk);
  ASSERT_EQ(b.playback.PositionFrame(20), kOk);
  b.Settle();
  const TimeNs t0 = b.scheduler.Now();
  // 24 fps would need 240 steps/s: the jog is taken (a jog moves within the
  // motor's speed, as MOTOR_JOG's SPEED 10000 "jog using the max velocity")
  // and runs the frame clock at 10 fps.
  ASSERT_EQ(b.playback.JogAll({24000, 40}), kOk);
  const PlanCheck c = CheckPlan(b.rig.motor(1).CurrentPlan());
  EXPECT_LE(c.max_abs_v, 100 + 1e-6);
  EXPECT_NEAR(c.max_abs_v, 100, 1e-6);
  EXPECT_LE(c.max_abs_a, b.rig.motor(1).profile().max_accel_steps_per_s2 + 1e-6);
  b.Settle();
  EXPECT_EQ(b.Pos(1), 300);
  // 20 frames at 10 fps plus a ramp (1000 frames/s^2: 10 ms each way).
  EXPECT_NEAR(static_cast<double>(b.reports.back().t_ns - t0), 2.01e9, 1e3);
  // Motor 2 holds still on the path: it limits nothing.
  EXPECT_EQ(b.Pos(2), 50);
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
  // Frames 20..25 are each exposed for the first half of the frame (10 fps),
  // the end frame too: "camera trigger for every frame".
  std::vector<sim::CameraPort::Edge> want;
  for (TimeNs k = 0; k <= 5; ++k) {
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

// --- the whole device: position updates, camera, triggers, errors, switches --------------

using testing::Host;

constexpr std::optional<AckCode> kAckOk = AckCode::kOk;
constexpr TimeNs kInterval = 100 * kNsPerMs;  // position_report_interval_ms of the default

// Uploads frames start..start+n-1 to the device: motor 1 climbs `step` steps
// a frame from 0, motor 2 holds 50, DMX channel 3 counts the frames; GIO
// trigger 0x1 is on at frame index 5 and 0x3 at index 6. Without `dmx` (a
// device with no DMX channels, as dmc-lite) no DMX track.
void UploadRamp(Host& h, uint32_t start, uint32_t n, int32_t step, bool dmx = true) {
  ASSERT_EQ(h.Request(dmc::RtUploadMoveBegin{start, start + n - 1}), kAckOk);
  std::vector<int32_t> pos;
  std::vector<uint8_t> levels;
  for (uint32_t i = 0; i < n; ++i) {
    pos.push_back(static_cast<int32_t>(i) * step);
    levels.push_back(static_cast<uint8_t>(i));
  }
  ASSERT_EQ(h.Request(dmc::RtUploadMoveAxis{1, 0, true, pos}), kAckOk);
  ASSERT_EQ(h.Request(dmc::RtUploadMoveAxis{2, 0, true, {50}}), kAckOk);
  if (dmx) {
    ASSERT_EQ(h.Request(dmc::RtUploadMoveDmx{3, 0, true, levels}), kAckOk);
  }
  ASSERT_EQ(h.Request(dmc::RtUploadMoveTriggers{0x3, {{5, 0x1}, {6, 0x3}}}), kAckOk);
  ASSERT_EQ(h.Request(dmc::RtUploadMoveEnd{}), kAckOk);
}

// The unsolicited position updates sent at or after `from_ns` (the device
// numbers its own messages from 1, the host's requests from 0x10000).
std::vector<std::pair<TimeNs, dmc::MotorPositionReport>> Updates(Host& h, TimeNs from_ns) {
  std::vector<std::pair<TimeNs, dmc::MotorPositionReport>> v;
  for (const testing::Out& o : h.out()) {
    const auto* r = std::get_if<dmc::MotorPositionReport>(&o.msg);
    if (r != nullptr && o.id < 0x10000 && o.t_ns >= from_ns) v.emplace_back(o.t_ns, *r);
  }
  return v;
}

// The longest wait for an update from `from_ns` up to the last update.
TimeNs LongestGap(const std::vector<std::pair<TimeNs, dmc::MotorPositionReport>>& ups,
                  TimeNs from_ns) {
  TimeNs gap = 0;
  TimeNs prev = from_ns;
  for (const auto& [t, r] : ups) {
    gap = std::max(gap, t - prev);
    prev = t;
  }
  return gap;
}

// When every motor of the rig will be at rest, as planned now.
TimeNs RestTime(Host& h) {
  TimeNs end = h.now();
  for (int m = 1; m <= h.device().rig_ref().motor_count(); ++m) {
    const sim::StepperMotor& motor = h.device().rig_ref().motor(m);
    if (motor.IsMoving()) end = std::max(end, motor.CurrentPlan().EndNs());
  }
  return end;
}

TEST(Dmc16PlaybackReports, UpdatesComeEveryIntervalThroughPrerollFramesAndPostrollAt2Fps) {
  Host h(SmallProfile());
  UploadRamp(h, 10, 100, 10);  // 20 steps/s at 2 fps
  ASSERT_EQ(h.Request(RunMove(20, 26, 2000, 1000, 1000)), kAckOk);
  h.Settle();
  const TimeNs t_go = h.now();
  ASSERT_EQ(h.Request(dmc::RtGo{}), kAckOk);
  h.Settle();
  const auto ups = Updates(h, t_go);
  ASSERT_FALSE(ups.empty());
  // MSG_MOTOR_GET_POSITION: "The device should send these out, about every
  // 0.10 seconds, if any of the motors are moving": in the pre-roll, between
  // the frames (0.5 s apart at 2 fps) and in the post-roll, until the stop.
  EXPECT_LE(LongestGap(ups, t_go), kInterval);
  EXPECT_EQ(ups.back().first, t_go + 5 * kNsPerSecond) << "1 s + 6 intervals at 2 fps + 1 s";
  EXPECT_FALSE(h.device().rig_ref().AnyMoving());
  // MSG_RT_GO: "it must send a MSG_MOTOR_GET_POSITION each time it reaches a
  // new frame": each frame once, at its time, with MOVE TIME = frame x 1000.
  const TimeNs t_first = t_go + kNsPerSecond;
  for (uint32_t f = 20; f <= 26; ++f) {
    int n = 0;
    for (const auto& [t, r] : ups) {
      if (r.move_time_x1000 != f * 1000) continue;
      ++n;
      EXPECT_EQ(t, t_first + (f - 20) * kNsPerSecond / 2) << f;
      EXPECT_EQ(r.positions_steps[0], static_cast<int32_t>((f - 10) * 10)) << f;
    }
    EXPECT_EQ(n, 1) << "frame " << f;
  }
  // The updates between carry MOVE TIME as the frame clock reads: before the
  // start frame in the pre-roll (2 frames of clock in 1 s), strictly between
  // two frames in the pass, past the end frame in the post-roll.
  uint32_t prev = 0;
  for (const auto& [t, r] : ups) {
    const uint32_t mt = r.move_time_x1000;
    EXPECT_GT(mt, prev) << "MOVE TIME runs forward, at " << t - t_go;
    prev = mt;
    const double clock_x1000 = 20000 + static_cast<double>(t - t_first) * 2e-6;
    EXPECT_NEAR(mt, clock_x1000, 1) << "at " << t - t_go;
    const bool frame_time = t >= t_first && (t - t_first) % (kNsPerSecond / 2) == 0;
    if (t < t_first) {
      EXPECT_LT(mt, 20000u);
    }
    if (t > t_first && t < t_first + 3 * kNsPerSecond && !frame_time) {
      EXPECT_NE(mt % 1000, 0u);
    }
    if (t > t_first + 3 * kNsPerSecond) {
      EXPECT_GT(mt, 26000u);
    }
  }
  EXPECT_EQ(ups.back().second.move_time_x1000, 28000u) << "the stop, 1 s past frame 26";
  EXPECT_EQ(h.All<dmc::RtEnd>().size(), 1u);
}

TEST(Dmc16PlaybackReports, UpdatesGoOnBetweenPingPongPassesHoldingWhereThePassEnded) {
  Host h(SmallProfile());
  UploadRamp(h, 10, 100, 10);
  // A post-roll longer than the pre-roll: between passes the rig travels
  // from the forward post-roll's end back to the backward pass's pre-roll,
  // 5 steps at 100 steps/s^2 (0.45 s).
  ASSERT_EQ(h.Request(dmc::MotorSetSpeed{1, 5000, 100}), kAckOk);
  ASSERT_EQ(h.Request(RunMove(20, 24, 2000, 500, 1000, dmc::kPlayPingPong)), kAckOk);
  h.Settle();
  const TimeNs t_go = h.now();
  ASSERT_EQ(h.Request(dmc::RtGo{}), kAckOk);
  // Forward pass: 0.5 s pre-roll, 2 s of frames, 1 s post-roll; then the
  // reposition and the backward pass; STOP_LOOP during the second.
  h.RunMs(4500);
  ASSERT_EQ(h.Request(dmc::RtStopLoop{}), kAckOk);
  h.Settle();
  ASSERT_EQ(h.device().playback().passes_done(), 2u);
  const auto ups = Updates(h, t_go);
  EXPECT_LE(LongestGap(ups, t_go), kInterval);
  // After the forward post-roll (1 s at 2 fps past frame 24) MOVE TIME holds
  // 26000 while the rig repositions; the backward pre-roll then counts down
  // from 25000 (0.5 s above frame 24) to the frames 24..20.
  const TimeNs t_pass_end = t_go + 3500 * kNsPerMs;
  std::vector<uint32_t> between;
  std::vector<uint32_t> frames;
  for (const auto& [t, r] : ups) {
    if (t > t_pass_end && r.move_time_x1000 >= 25000) between.push_back(r.move_time_x1000);
    if (r.move_time_x1000 % 1000 == 0 && r.move_time_x1000 >= 20000 && r.move_time_x1000 <= 24000) {
      frames.push_back(r.move_time_x1000);
    }
  }
  ASSERT_FALSE(between.empty()) << "updates while the rig repositions";
  EXPECT_EQ(between.front(), 26000u);
  for (uint32_t mt : between) EXPECT_TRUE(mt == 26000u || mt < 25000u + 1) << mt;
  EXPECT_EQ(frames, (std::vector<uint32_t>{20000, 21000, 22000, 23000, 24000, 24000, 23000, 22000,
                                           21000, 20000}));
  EXPECT_EQ(h.All<dmc::RtEnd>().size(), 1u);
}

TEST(Dmc16PlaybackReports, UpdatesGoOnThroughAGoMotionExposureWithTheShotFramesMoveTime) {
  Host h(SmallProfile());
  UploadRamp(h, 10, 100, 10);
  dmc::RtShootFrame2 shot;
  shot.frame = 30;
  shot.exposure_ms = 1000;
  shot.open_angle_deg = 0;
  shot.close_angle_deg = 360;
  shot.motors = {{1, 150, 250}};  // 100 steps/s while the shutter is open
  ASSERT_EQ(h.Request(shot), kAckOk);
  h.Settle();
  const TimeNs t_go = h.now();
  ASSERT_EQ(h.Request(dmc::RtGo{}), kAckOk);
  h.Settle();
  EXPECT_EQ(h.device().camera().exposures(), 1u);
  const auto ups = Updates(h, t_go);
  ASSERT_GE(ups.size(), 10u);
  EXPECT_LE(LongestGap(ups, t_go), kInterval);
  for (const auto& [t, r] : ups) EXPECT_EQ(r.move_time_x1000, 30000u) << "at " << t - t_go;
}

TEST(Dmc16PlaybackReports, UpdatesGoOnBetweenTheFramesOfASlowJogAll) {
  Host h(SmallProfile());
  UploadRamp(h, 10, 100, 10);
  ASSERT_EQ(h.Request(dmc::RtPositionFrame{20}), kAckOk);
  h.Settle();
  const TimeNs t0 = h.now();
  ASSERT_EQ(h.Request(dmc::RtJogAll{2000, 24}), kAckOk);
  h.Settle();
  const auto ups = Updates(h, t0);
  EXPECT_LE(LongestGap(ups, t0), kInterval);
  // Each frame once: the destination's report is also the one at rest.
  for (uint32_t f = 21; f <= 24; ++f) {
    int n = 0;
    for (const auto& [t, r] : ups) n += r.move_time_x1000 == f * 1000;
    EXPECT_EQ(n, 1) << "frame " << f;
  }
  EXPECT_EQ(ups.back().second.move_time_x1000, 24000u) << "at rest on the destination";
  EXPECT_FALSE(h.device().rig_ref().AnyMoving());
}

TEST(Dmc16PlaybackReports, TheProfilesIntervalSetsTheCadenceInEveryPhase) {
  // The spec's "about every 0.10 seconds" (the default 100 ms) and dmc-lite's
  // 50 ms (FACTS "DMC v2") from the profile's position_report_interval_ms.
  for (const uint32_t interval_ms : {100u, 50u}) {
    Dmc16Profile p = SmallProfile();
    p.position_report_interval_ms = interval_ms;
    Host h(p);
    UploadRamp(h, 10, 100, 10);
    ASSERT_EQ(h.Request(RunMove(20, 24, 2000, 1000, 1000)), kAckOk);
    h.Settle();
    const TimeNs t_go = h.now();
    ASSERT_EQ(h.Request(dmc::RtGo{}), kAckOk);
    h.Settle();
    const TimeNs interval = TimeNs{interval_ms} * kNsPerMs;
    const auto ups = Updates(h, t_go + 1);
    EXPECT_LE(LongestGap(ups, t_go), interval);
    // The 1 s pre-roll: an update every interval after GO, up to frame 20's.
    std::vector<TimeNs> preroll;
    for (const auto& [t, r] : ups) {
      if (t < t_go + kNsPerSecond) preroll.push_back(t - t_go);
    }
    ASSERT_EQ(preroll.size(), 1000u / interval_ms - 1);
    for (size_t i = 0; i < preroll.size(); ++i) {
      EXPECT_EQ(preroll[i], static_cast<TimeNs>(i + 1) * interval) << i;
    }
  }
}

// --- camera triggers and upload triggers -----------------------------------------------------

TEST(Dmc16PlaybackCamera, VideoPressesTheShutterOnceAtTheStartFrameAndOnceAtTheEndFrame) {
  Host h(SmallProfile());
  UploadRamp(h, 10, 100, 10);
  ASSERT_EQ(h.Request(RunMove(20, 30, 10000, 500, 500, dmc::kPlayCameraVideo)), kAckOk);
  h.Settle();
  const TimeNs t_first = h.now() + 500 * kNsPerMs;
  ASSERT_EQ(h.Request(dmc::RtGo{}), kAckOk);
  h.Settle();
  // FLAGS 0x10 "camera trigger at start/stop of move (video)": a press when
  // the start frame is reached, a press when the end frame is; nothing in
  // between, nothing per frame.
  const TimeNs t_last = t_first + kNsPerSecond;
  const std::vector<sim::CameraPort::Edge> want = {
      {t_first, sim::CameraPort::kShutter, true},
      {t_first + kVideoTriggerPressNs, sim::CameraPort::kShutter, false},
      {t_last, sim::CameraPort::kShutter, true},
      {t_last + kVideoTriggerPressNs, sim::CameraPort::kShutter, false},
  };
  EXPECT_EQ(h.device().camera().Trace(), want);
}

TEST(Dmc16PlaybackCamera, VideoPressesNeverMergeAndAStoppedRunStopsTheRecording) {
  Host h(SmallProfile());
  UploadRamp(h, 10, 100, 10);
  // One frame interval at 24 fps: the stop press waits until the start
  // press has been released for as long as it was held.
  ASSERT_EQ(h.Request(RunMove(20, 21, 24000, 0, 0, dmc::kPlayCameraVideo)), kAckOk);
  h.Settle();
  const TimeNs t0 = h.now();
  ASSERT_EQ(h.Request(dmc::RtGo{}), kAckOk);
  h.Settle();
  const std::vector<sim::CameraPort::Edge> want = {
      {t0, sim::CameraPort::kShutter, true},
      {t0 + kVideoTriggerPressNs, sim::CameraPort::kShutter, false},
      {t0 + 2 * kVideoTriggerPressNs, sim::CameraPort::kShutter, true},
      {t0 + 3 * kVideoTriggerPressNs, sim::CameraPort::kShutter, false},
  };
  EXPECT_EQ(h.device().camera().Trace(), want);

  // A run stopped after its start frame stops the camera it started.
  Host s(SmallProfile());
  UploadRamp(s, 10, 100, 10);
  ASSERT_EQ(s.Request(RunMove(20, 60, 10000, 0, 0, dmc::kPlayCameraVideo)), kAckOk);
  s.Settle();
  const TimeNs t1 = s.now();
  ASSERT_EQ(s.Request(dmc::RtGo{}), kAckOk);
  s.RunMs(1000);
  ASSERT_EQ(s.Request(dmc::MotorStopAll{}), kAckOk);
  s.Settle();
  const std::vector<sim::CameraPort::Edge> stopped = {
      {t1, sim::CameraPort::kShutter, true},
      {t1 + kVideoTriggerPressNs, sim::CameraPort::kShutter, false},
      {t1 + kNsPerSecond, sim::CameraPort::kShutter, true},
      {t1 + kNsPerSecond + kVideoTriggerPressNs, sim::CameraPort::kShutter, false},
  };
  EXPECT_EQ(s.device().camera().Trace(), stopped);
}

TEST(Dmc16PlaybackCamera, StillsExposeEveryFrameFromOpenToCloseAngleEndFrameIncluded) {
  Host h(SmallProfile());
  UploadRamp(h, 10, 100, 10);
  dmc::RtRunMove r = RunMove(20, 23, 10000, 0, 0, dmc::kPlayCameraStills);
  r.camera_open_angle_deg = 0;
  r.camera_close_angle_deg = 270;
  ASSERT_EQ(h.Request(r), kAckOk);
  h.Settle();
  const TimeNs t0 = h.now();
  ASSERT_EQ(h.Request(dmc::RtGo{}), kAckOk);
  h.Settle();
  // FLAGS 0x20 "camera trigger for every frame (stills)": frames 20..23,
  // each open from its frame time for 270 of the frame's 360 degrees.
  std::vector<sim::CameraPort::Edge> want;
  for (TimeNs k = 0; k <= 3; ++k) {
    want.push_back({t0 + k * 100 * kNsPerMs, sim::CameraPort::kShutter, true});
    want.push_back({t0 + k * 100 * kNsPerMs + 75 * kNsPerMs, sim::CameraPort::kShutter, false});
  }
  EXPECT_EQ(h.device().camera().Trace(), want);
  // The run has finished shooting when the last exposure has closed.
  const auto ends = h.All<dmc::RtEnd>();
  ASSERT_EQ(ends.size(), 1u);
  EXPECT_EQ(ends[0].first, t0 + 375 * kNsPerMs);
}

TEST(Dmc16PlaybackTriggers, UploadedTriggersAndDmxPlayOnlyWithSyncDmx) {
  for (const uint8_t sync : {uint8_t{0}, uint8_t{1}}) {
    Host h(SmallProfile());
    UploadRamp(h, 10, 100, 10);
    ASSERT_EQ(h.Request(dmc::GioOut{0x4}), kAckOk);
    ASSERT_EQ(h.Request(dmc::Dmx{0, 3, {200}}), kAckOk);
    // Frames 10..30 at 10 fps; trigger 0x1 at frame 15, 0x3 at frame 16.
    dmc::RtRunMove r = RunMove(10, 30, 10000, 0, 0);
    r.sync_dmx = sync;
    ASSERT_EQ(h.Request(r), kAckOk);
    h.Settle();
    const TimeNs t0 = h.now();
    ASSERT_EQ(h.Request(dmc::RtGo{}), kAckOk);
    h.scheduler().RunUntil(t0 + 500 * kNsPerMs + 1);  // frame 15
    const uint32_t at15 = h.device().gio_ref().outputs();
    const uint8_t dmx15 = h.device().dmx().Value(3);
    h.scheduler().RunUntil(t0 + 600 * kNsPerMs + 1);  // frame 16
    const uint32_t at16 = h.device().gio_ref().outputs();
    h.scheduler().RunUntil(t0 + 700 * kNsPerMs + 1);  // frame 17: no entry
    const uint32_t at17 = h.device().gio_ref().outputs();
    h.Settle();
    if (sync == 1) {
      // SYNC DMX "1=Play back upload DMX"; MSG_RT_UPLOAD_MOVE_TRIGGERS is
      // "Only sent if the DMX program has triggers": they play with the DMX.
      // The triggers own the masked outputs (0x3); output 0x4 stays as set.
      EXPECT_EQ(at15, 0x5u);
      EXPECT_EQ(at16, 0x7u);
      EXPECT_EQ(at17, 0x4u);
      EXPECT_EQ(dmx15, 5);
    } else {
      // "0=don't play DMX": neither the levels nor the triggers.
      EXPECT_EQ(at15, 0x4u);
      EXPECT_EQ(at16, 0x4u);
      EXPECT_EQ(at17, 0x4u);
      EXPECT_EQ(dmx15, 200);
      EXPECT_EQ(h.device().dmx().Value(3), 200);
    }
  }
}

// --- ERR_MOVING during a live run ---------------------------------------------------------

TEST(Dmc16PlaybackErrors, DuringALiveRunUploadsAndResetPositionAnswerErrMoving) {
  Host h(SmallProfile());
  UploadRamp(h, 10, 100, 10);
  ASSERT_EQ(h.Request(RunMove(20, 60, 10000, 500, 500)), kAckOk);
  h.Settle();
  ASSERT_EQ(h.Request(dmc::RtGo{}), kAckOk);
  h.RunMs(1000);
  ASSERT_EQ(h.device().ModeName(), "running");
  // ERR_MOVING "Can't handle this command while the rig is moving": the rig
  // plays the uploaded move, so no upload message may touch it (BEGIN would
  // clear it: "Any previously loaded move will be cleared") and no position
  // may be renamed under it, a motor at rest (motor 3) included.
  constexpr auto kMoving = std::optional<AckCode>(AckCode::kErrMoving);
  EXPECT_EQ(h.Request(dmc::RtUploadMoveBegin{0, 10}), kMoving);
  EXPECT_EQ(h.Request(dmc::RtUploadMoveAxis{1, 0, true, {0}}), kMoving);
  EXPECT_EQ(h.Request(dmc::RtUploadMoveDmx{3, 0, true, {1}}), kMoving);
  EXPECT_EQ(h.Request(dmc::RtUploadMoveTriggers{0x1, {{1, 0x1}}}), kMoving);
  EXPECT_EQ(h.Request(dmc::RtUploadMoveEnd{}), kMoving);
  EXPECT_EQ(h.Request(dmc::MotorResetPosition{3, 77}), kMoving);
  EXPECT_EQ(h.Request(dmc::MotorResetPosition{2, 77}), kMoving);
  EXPECT_EQ(h.Pos(3), 0);
  h.Settle();
  EXPECT_EQ(h.device().upload().end_frame(), 109u) << "the move played is still there";
  EXPECT_EQ(h.Pos(1), 500 + 25);
  // Once the run is over both are taken again.
  EXPECT_EQ(h.Request(dmc::MotorResetPosition{3, 77}), kAckOk);
  EXPECT_EQ(h.Pos(3), 77);
  EXPECT_EQ(h.Request(dmc::RtUploadMoveBegin{0, 10}), kAckOk);
}

// --- dmc-lite's playback switches (Dmc16Behaviour) ---------------------------------------

TEST(Dmc16PlaybackSwitches, PrerollMoveTimeRunsUpToTheStartFrameOrIsTheStartFrameWithTheSwitch) {
  for (const bool lite : {false, true}) {
    Dmc16Profile p = SmallProfile();
    p.behaviour.preroll_move_time_is_start_frame = lite;
    Host h(p);
    UploadRamp(h, 10, 100, 10);
    const TimeNs t_arm = h.now();
    ASSERT_EQ(h.Request(RunMove(20, 24, 2000, 1000, 0)), kAckOk);
    h.Settle();
    const TimeNs t_go = h.now();
    ASSERT_EQ(h.Request(dmc::RtGo{}), kAckOk);
    h.Settle();
    std::vector<uint32_t> arming;
    std::vector<uint32_t> preroll;
    for (const auto& [t, r] : Updates(h, t_arm)) {
      // The arming move's last update comes as the rig rests, at t_go.
      if (t <= t_go) arming.push_back(r.move_time_x1000);
      if (t > t_go && t < t_go + kNsPerSecond) preroll.push_back(r.move_time_x1000);
    }
    ASSERT_FALSE(arming.empty()) << "the rig moves to its pre-roll";
    ASSERT_EQ(preroll.size(), 9u) << "every 100 ms of the 1 s pre-roll";
    if (lite) {
      // FACTS "DMC v2": "during pre-roll MOVE TIME is the start frame's".
      for (uint32_t mt : arming) EXPECT_EQ(mt, 20000u);
      for (uint32_t mt : preroll) EXPECT_EQ(mt, 20000u);
    } else {
      // The frame clock at 2 fps, 1 s (2 frames) before frame 20 at GO.
      for (uint32_t mt : arming) EXPECT_EQ(mt, 18000u);
      for (size_t i = 0; i < preroll.size(); ++i) {
        EXPECT_EQ(preroll[i], 18000u + 200u * (i + 1)) << i;
      }
    }
  }
}

TEST(Dmc16PlaybackSwitches, RtEndComesAfterThePostrollOrAtTheLastFrameWithTheSwitch) {
  for (const bool lite : {false, true}) {
    Dmc16Profile p = SmallProfile();
    p.behaviour.rt_end_at_last_frame = lite;
    Host h(p);
    UploadRamp(h, 10, 100, 10);
    ASSERT_EQ(h.Request(RunMove(20, 30, 10000, 500, 800)), kAckOk);
    h.Settle();
    const TimeNs t_last = h.now() + 1500 * kNsPerMs;  // 0.5 s pre-roll, 10 frames at 10 fps
    ASSERT_EQ(h.Request(dmc::RtGo{}), kAckOk);
    h.Settle();
    const auto ends = h.All<dmc::RtEnd>();
    ASSERT_EQ(ends.size(), 1u) << "one RT_END per run either way";
    // MSG_RT_END: "After a MSG_RT_RUN_MOVE ... has finished shooting": after
    // the post-roll; dmc-lite sends it as the last frame is reached.
    EXPECT_EQ(ends[0].first, lite ? t_last : t_last + 800 * kNsPerMs);
    EXPECT_EQ(h.Pos(1), 200 + 40) << "the post-roll runs its course either way";
  }
}

TEST(Dmc16PlaybackSwitches, ShotsEndWithRtEndUnlessTheSwitchSaysNone) {
  for (const bool end_after_shot : {true, false}) {
    Dmc16Profile p = SmallProfile();
    p.behaviour.rt_end_after_shot = end_after_shot;
    Host h(p);
    UploadRamp(h, 10, 100, 10);
    ASSERT_EQ(h.Request(dmc::RtShootFrame2{30, 200, 90, 270, {{1, 150, 250}}}), kAckOk);
    h.Settle();
    ASSERT_EQ(h.Request(dmc::RtGo{}), kAckOk);
    h.Settle();
    ASSERT_EQ(h.Request(dmc::RtShootFrame{30, dmc::kDirectionForward, 200, 500, {{1, 150, 250}}}),
              kAckOk);
    h.Settle();
    ASSERT_EQ(h.Request(dmc::RtGo{}), kAckOk);
    h.Settle();
    EXPECT_EQ(h.device().camera().exposures(), 2u);
    // MSG_RT_END after "a MSG_RT_RUN_MOVE or MSG_RT_SHOOT_FRAME has finished
    // shooting"; dmc-lite sends none after SHOOT_FRAME / SHOOT_FRAME2.
    EXPECT_EQ(h.All<dmc::RtEnd>().size(), end_after_shot ? 2u : 0u);
    // A live run still ends with RT_END.
    ASSERT_EQ(h.Request(RunMove(20, 25, 10000, 0, 0)), kAckOk);
    h.Settle();
    ASSERT_EQ(h.Request(dmc::RtGo{}), kAckOk);
    h.Settle();
    EXPECT_EQ(h.All<dmc::RtEnd>().size(), end_after_shot ? 3u : 1u);
  }
}

TEST(Dmc16PlaybackSwitches, GoRightAfterTheRigRestsIsTakenOrNotInPositionWhileArming) {
  for (const uint32_t arming_ms : {0u, 50u}) {
    Dmc16Profile p = SmallProfile();
    p.behaviour.arming_ms = arming_ms;
    Host h(p);
    UploadRamp(h, 10, 100, 10);
    ASSERT_EQ(h.Request(RunMove(20, 30, 10000, 500, 0)), kAckOk);
    const TimeNs rest = RestTime(h);
    h.scheduler().RunUntil(rest);
    ASSERT_FALSE(h.device().rig_ref().AnyMoving());
    if (arming_ms == 0) {
      // MSG_RT_GO: "When the device has stopped moving, a MSG_RT_GO command
      // will perform the run".
      EXPECT_EQ(h.Request(dmc::RtGo{}), kAckOk);
    } else {
      // dmc-lite arms for 40-60 ms after the motors stop (FACTS).
      EXPECT_EQ(h.Request(dmc::RtGo{}), AckCode::kErrNotInPosition);
      h.scheduler().RunUntil(rest + 50 * kNsPerMs - 1);
      EXPECT_EQ(h.Request(dmc::RtGo{}), AckCode::kErrNotInPosition);
      h.scheduler().RunUntil(rest + 50 * kNsPerMs);
      EXPECT_EQ(h.Request(dmc::RtGo{}), kAckOk);
    }
    EXPECT_EQ(h.device().ModeName(), "running");
    h.Settle();
    // A shot arms the same way.
    ASSERT_EQ(h.Request(dmc::RtShootFrame2{30, 200, 90, 270, {{1, 150, 250}}}), kAckOk);
    const TimeNs shot_rest = RestTime(h);
    h.scheduler().RunUntil(shot_rest);
    EXPECT_EQ(h.Request(dmc::RtGo{}),
              arming_ms == 0 ? kAckOk : std::optional<AckCode>(AckCode::kErrNotInPosition));
  }
}

// --- the velocity tick (behaviour.playback_tick_ms and its engine's switches) ---------------

constexpr TimeNs kTick = 20 * kNsPerMs;

Dmc16Profile DmcLite() {
  const char* dir = std::getenv("MOCO_SOURCE_DIR");
  return LoadDmc16Profile(std::string(dir != nullptr ? dir : ".") +
                          "/fixtures/profiles/dmc-lite.json");
}

// A SmallProfile on a 20 ms tick with updates every 50 ms (dmc-lite's engine,
// the other departures left at the spec's reading).
Dmc16Profile Ticked() {
  Dmc16Profile p = SmallProfile();
  p.behaviour.playback_tick_ms = 20;
  p.position_report_interval_ms = 50;
  return p;
}

// Motors 1 and 2 enabled (dmc-lite's start disabled), at p1 and p2.
void Ready(Host& h, int32_t p1, int32_t p2) {
  for (uint8_t m = 1; m <= 2; ++m) {
    ASSERT_EQ(h.Request(dmc::MotorConfigure{m, dmc::kMotorEnabled | dmc::kMotorBlurEnabled}),
              kAckOk);
  }
  h.Send(dmc::MotorMove{1, p1});
  h.Send(dmc::MotorMove{2, p2});
  h.Settle();
  ASSERT_EQ(h.Pos(1), p1);
  ASSERT_EQ(h.Pos(2), p2);
}

// The upload of mococheck's live-run cases (conformance dmc_cases_rt.cpp):
// frames start..start+20, motor 1 climbing 40 steps a frame from p1 and
// motor 2 falling 25 from p2 over the first 10 frames, then both holding.
void UploadClimb(Host& h, uint32_t start, int32_t p1, int32_t p2) {
  ASSERT_EQ(h.Request(dmc::RtUploadMoveBegin{start, start + 20}), kAckOk);
  std::vector<int32_t> a;
  std::vector<int32_t> b;
  for (int32_t k = 0; k <= 10; ++k) {
    a.push_back(p1 + 40 * k);
    b.push_back(p2 - 25 * k);
  }
  ASSERT_EQ(h.Request(dmc::RtUploadMoveAxis{1, 0, true, a}), kAckOk);
  ASSERT_EQ(h.Request(dmc::RtUploadMoveAxis{2, 0, true, b}), kAckOk);
  ASSERT_EQ(h.Request(dmc::RtUploadMoveEnd{}), kAckOk);
}

// Motor 1 of UploadClimb at frame f (any real f): the upload between frames,
// the first interval's line before START FRAME, frame start+10's beyond.
double Climb(uint32_t start, int32_t p1, double f) { return p1 + 40 * std::min(f - start, 10.0); }

// Runs in ticks until `done` holds (at most `max_ms`).
template <typename Done>
void RunUntil(Host& h, Done done, int64_t max_ms = 20'000) {
  for (int64_t ms = 0; ms < max_ms && !done(); ms += 20) h.RunMs(20);
  ASSERT_TRUE(done());
}

struct Seen {
  TimeNs t_ns;
  uint32_t move_time;
  int32_t p1;
  int32_t p2;
};

std::vector<Seen> Seens(Host& h, TimeNs from_ns) {
  std::vector<Seen> v;
  for (const auto& [t, r] : Updates(h, from_ns)) {
    v.push_back({t, r.move_time_x1000, r.positions_steps[0], r.positions_steps[1]});
  }
  return v;
}

// The ping-pong run measured on dmc-lite (mococheck's stop-loop case against
// the firmware natively, FACTS "DMC v2"): START FRAME 0 plays one frame behind
// the upload, the frame reports carry the tick's fractional MOVE TIMEs 40 or
// 60 ms apart, every pass ends with RT_END, and STOP_LOOP on the way back
// ends the run on frame 0 with no post-roll. Every MOVE TIME and position of
// the move phases below is the one the firmware sent.
TEST(Dmc16PlaybackTick, DmcLiteReplaysTheMeasuredPingPongStoppedOnTheWayBack) {
  Host h(DmcLite());
  Ready(h, 3321, -478);
  UploadClimb(h, 0, 3321, -478);
  ASSERT_EQ(h.Request(dmc::RtPositionFrame{0}), kAckOk);
  h.Settle();
  ASSERT_EQ(h.Request(RunMove(0, 10, 24000, 500, 500, dmc::kPlayPingPong)), kAckOk);
  h.Settle();
  // The pre-roll starts 240 steps before slot 0 (frame -1 on the first interval's line).
  EXPECT_EQ(h.Pos(1), 3041);
  EXPECT_EQ(h.Pos(2), -303);
  h.RunMs(100);
  const TimeNs t_go = h.now();
  ASSERT_EQ(h.Request(dmc::RtGo{}), kAckOk);
  RunUntil(h, [&] { return !h.All<dmc::RtEnd>().empty(); });
  RunUntil(h, [&] {
    const auto ups = Updates(h, t_go);
    return !ups.empty() && ups.back().second.move_time_x1000 == 8600;
  });
  ASSERT_EQ(h.Request(dmc::RtStopLoop{}), kAckOk);
  h.Settle();
  const std::vector<Seen> seen = Seens(h, t_go);
  const std::vector<std::array<int32_t, 4>> measured = {
      // {ms after the frame 1 report, MOVE TIME, motor 1, motor 2}
      {-60, 0, 3281, -453},     {0, 1440, 3338, -489},    {40, 2400, 3377, -513},
      {80, 3360, 3415, -537},   {120, 4320, 3453, -561},  {160, 5280, 3492, -585},
      {200, 6240, 3530, -609},  {240, 7200, 3569, -633},  {280, 8160, 3607, -657},
      {320, 9120, 3645, -681},  {360, 10080, 3684, -705}, {400, 11000, 3703, -717},
      {400, 11000, 3703, -717}, {420, 10520, 3701, -716}, {460, 9559, 3663, -692},
      {500, 8600, 3625, -668},  {540, 7640, 3586, -644},  {580, 6680, 3548, -620},
      {620, 5720, 3509, -596},  {660, 4760, 3471, -572},  {700, 3799, 3433, -548},
      {740, 2839, 3394, -524},  {780, 1879, 3356, -499},  {820, 919, 3317, -475},
      {860, 0, 3298, -463}};
  size_t first = 0;
  while (first < seen.size() && seen[first].move_time != 1440) ++first;
  ASSERT_GE(first, 1u);
  ASSERT_LE(first - 1 + measured.size(), seen.size());
  const TimeNs t1 = seen[first].t_ns;
  for (size_t i = 0; i < measured.size(); ++i) {
    const Seen& s = seen[first - 1 + i];
    SCOPED_TRACE("update " + std::to_string(i));
    EXPECT_EQ(s.t_ns - t1, measured[i][0] * kNsPerMs);
    EXPECT_EQ(s.move_time, static_cast<uint32_t>(measured[i][1]));
    EXPECT_EQ(s.p1, measured[i][2]);
    EXPECT_EQ(s.p2, measured[i][3]);
  }
  // One RT_END at the end of each pass, as its last update goes out.
  const auto ends = h.All<dmc::RtEnd>();
  ASSERT_EQ(ends.size(), 2u);
  EXPECT_EQ(ends[0].first, t1 + 400 * kNsPerMs);
  EXPECT_EQ(ends[1].first, t1 + 860 * kNsPerMs);
  // No post-roll: from there the rig moves back onto frame 0 (upload frame
  // 0's positions) and rests.
  for (const Seen& s : seen) {
    if (s.t_ns > t1 + 860 * kNsPerMs) {
      EXPECT_GE(s.p1, 3298);
    }
  }
  EXPECT_EQ(h.Pos(1), 3321);
  EXPECT_EQ(h.Pos(2), -478);
  EXPECT_EQ(h.device().playback().on_frame(), 0u);
  // Every update on the tick and with ID 0; 40 or 60 ms apart while moving.
  for (const testing::Out& o : h.out()) {
    if (o.t_ns >= t_go && std::get_if<dmc::MotorPositionReport>(&o.msg) != nullptr) {
      EXPECT_EQ(o.t_ns % kTick, 0) << o.t_ns;
      EXPECT_EQ(o.id, 0u);
    }
  }
}

// The same ping-pong from START FRAME 1, measured on dmc-lite: on the upload,
// MOVE TIME from 1000 to 12000 and back; STOP_LOOP after the first RT_END
// ends the run on frame 1 (MOVE TIME 1000, no post-roll) and the rig moves
// onto frame 1's positions. (dmc-lite then read 1199 for 1200: its step
// accumulator's rounding, which the model reads exact.)
TEST(Dmc16PlaybackTick, DmcLiteReplaysTheMeasuredPingPongFromStartFrame1) {
  Host h(DmcLite());
  Ready(h, 1200, 0);
  UploadClimb(h, 1, 1200, 0);
  ASSERT_EQ(h.Request(dmc::RtPositionFrame{1}), kAckOk);
  h.Settle();
  ASSERT_EQ(h.Request(RunMove(1, 11, 24000, 500, 500, dmc::kPlayPingPong)), kAckOk);
  h.Settle();
  EXPECT_EQ(h.Pos(1), 960);
  EXPECT_EQ(h.Pos(2), 150);
  h.RunMs(100);
  const TimeNs t_go = h.now();
  ASSERT_EQ(h.Request(dmc::RtGo{}), kAckOk);
  RunUntil(h, [&] { return !h.All<dmc::RtEnd>().empty(); });
  h.RunMs(80);
  ASSERT_EQ(h.Request(dmc::RtStopLoop{}), kAckOk);
  h.Settle();
  std::map<uint32_t, std::pair<int32_t, int32_t>> at;  // the first update of each MOVE TIME
  for (const Seen& s : Seens(h, t_go)) at.emplace(s.move_time, std::pair{s.p1, s.p2});
  const std::vector<std::array<int32_t, 3>> measured = {
      {2440, 1257, -36},   {3400, 1296, -60},   {11080, 1600, -250},
      {12000, 1600, -250}, {11520, 1600, -250}, {10560, 1582, -238},
      {9600, 1544, -215},  {4799, 1352, -94},   {1919, 1236, -22}};
  for (const auto& [mt, p1, p2] : measured) {
    SCOPED_TRACE("MOVE TIME " + std::to_string(mt));
    ASSERT_EQ(at.count(static_cast<uint32_t>(mt)), 1u);
    EXPECT_EQ(at[static_cast<uint32_t>(mt)].first, p1);
    EXPECT_EQ(at[static_cast<uint32_t>(mt)].second, p2);
  }
  // The way back ends at MOVE TIME 1000 with the positions of the tick
  // before, with its RT_END; then the rig rests on frame 1.
  const auto ups = Updates(h, t_go);
  const auto ends = h.All<dmc::RtEnd>();
  ASSERT_EQ(ends.size(), 2u);
  for (const auto& [t, r] : ups) {
    if (t != ends[1].first) continue;
    EXPECT_EQ(r.move_time_x1000, 1000u);
    EXPECT_EQ(r.positions_steps[0], 1217);
    EXPECT_EQ(r.positions_steps[1], -10);
  }
  EXPECT_EQ(ups.back().second.move_time_x1000, 1000u);
  EXPECT_EQ(h.Pos(1), 1200);
  EXPECT_EQ(h.Pos(2), 0);
}

// START FRAME 0 runs one frame behind the upload, 1 on it, 5 four frames
// ahead, clamped at the last uploaded position (upload_index_from_start_frame);
// without the switch the run is on the upload whatever START FRAME. Either
// way the run plays frames START..END + 1 and rests on END + 1's position.
TEST(Dmc16PlaybackTick, TheClockReadsTheUploadFromStartFrameOrOnIt) {
  struct Case {
    uint32_t start;
    bool index;
    double ahead;  // frames the run plays ahead of the upload
  };
  for (const Case c : {Case{0, true, -1}, Case{1, true, 0}, Case{5, true, 4}, Case{0, false, 0},
                       Case{5, false, 0}}) {
    SCOPED_TRACE("START FRAME " + std::to_string(c.start) + (c.index ? " indexed" : " on it"));
    Dmc16Profile p = DmcLite();
    p.behaviour.upload_index_from_start_frame = c.index;
    Host h(p);
    Ready(h, 1200, 0);
    UploadClimb(h, c.start, 1200, 0);
    ASSERT_EQ(h.Request(dmc::RtPositionFrame{c.start}), kAckOk);
    h.Settle();
    ASSERT_EQ(h.Request(RunMove(c.start, c.start + 10, 24000, 500, 500)), kAckOk);
    h.Settle();
    h.RunMs(100);
    const TimeNs t_go = h.now();
    ASSERT_EQ(h.Request(dmc::RtGo{}), kAckOk);
    h.Settle();
    int checked = 0;
    bool fractional = false;
    for (const Seen& s : Seens(h, t_go)) {
      if (s.move_time <= c.start * 1000 || s.move_time >= (c.start + 11) * 1000) continue;
      const double clock = s.move_time / 1000.0;
      EXPECT_NEAR(s.p1, Climb(c.start, 1200, clock + c.ahead), 1.0) << "MOVE TIME " << s.move_time;
      fractional = fractional || s.move_time % 1000 != 0;
      ++checked;
    }
    EXPECT_GE(checked, 10);
    EXPECT_TRUE(fractional) << "MOVE TIME sampled on the tick";
    EXPECT_EQ(h.All<dmc::RtEnd>().size(), 1u);
    EXPECT_EQ(Updates(h, t_go).back().second.move_time_x1000, (c.start + 11) * 1000);
    EXPECT_EQ(h.Pos(1), 1600) << "on END FRAME + 1";
  }
}

// Without a tick the same run reports each frame at its time with MOVE TIME =
// frame x 1000, on the upload (spec reading).
TEST(Dmc16PlaybackTick, WithoutATickFramesAreReportedAtTheirTimesOnTheUpload) {
  Dmc16Profile p = DmcLite();
  p.behaviour.playback_tick_ms = 0;
  p.behaviour.upload_index_from_start_frame = false;
  p.behaviour.zero_preroll_nan = false;
  Host h(p);
  Ready(h, 1200, 0);
  UploadClimb(h, 0, 1200, 0);
  ASSERT_EQ(h.Request(dmc::RtPositionFrame{0}), kAckOk);
  h.Settle();
  ASSERT_EQ(h.Request(RunMove(0, 10, 24000, 500, 500)), kAckOk);
  h.Settle();
  h.RunMs(100);
  const TimeNs t_go = h.now();
  ASSERT_EQ(h.Request(dmc::RtGo{}), kAckOk);
  h.Settle();
  // (From frame 1: dmc-lite's profile gives the pre-roll's updates frame 0's MOVE TIME.)
  for (uint32_t f = 1; f <= 10; ++f) {
    bool seen = false;
    for (const Seen& s : Seens(h, t_go)) {
      if (s.move_time != f * 1000) continue;
      seen = true;
      // (positions_truncate reads the motor's position between steps toward zero)
      EXPECT_NEAR(s.p1, 1200 + 40 * static_cast<int32_t>(f), 1) << f;
      break;
    }
    EXPECT_TRUE(seen) << "frame " << f;
  }
}

// Position updates on the tick: every 60 ms while a motor moves (the first
// tick past 50 ms), the one for the stop at the first tick 100 ms past the
// last update; with the switch all carry ID 0. Without a tick: every 50 ms,
// the stop's at once, device-side sequence IDs (ERRATA 1.9).
TEST(Dmc16PlaybackTick, UpdatesAreDecidedOnTheTick) {
  for (const bool tick : {false, true}) {
    SCOPED_TRACE(tick ? "tick" : "continuous");
    Dmc16Profile p = SmallProfile();
    p.position_report_interval_ms = 50;
    p.behaviour.playback_tick_ms = tick ? 20 : 0;
    p.behaviour.unsolicited_id_zero = tick;
    Host h(p);
    h.RunMs(7);
    const TimeNs t0 = h.now();
    ASSERT_TRUE(h.Request(dmc::MotorMove{1, 3000}) == std::nullopt);
    const TimeNs rest = RestTime(h);
    h.Settle();
    const auto ups = Updates(h, t0);
    ASSERT_GE(ups.size(), 5u);
    for (size_t i = 1; i + 1 < ups.size(); ++i) {
      EXPECT_EQ(ups[i].first - ups[i - 1].first, (tick ? 60 : 50) * kNsPerMs) << i;
    }
    if (tick) {
      EXPECT_EQ(ups.back().first % kTick, 0);
      EXPECT_GT(ups.back().first - ups[ups.size() - 2].first, 100 * kNsPerMs);
      EXPECT_LE(ups.back().first - ups[ups.size() - 2].first, 120 * kNsPerMs);
      for (const testing::Out& o : h.out()) {
        if (std::get_if<dmc::MotorPositionReport>(&o.msg) != nullptr) {
          EXPECT_EQ(o.id, 0u);
        }
      }
    } else {
      EXPECT_EQ(ups.back().first, rest);
      EXPECT_GT(h.out().back().id, 1u);
    }
    EXPECT_EQ(ups.back().second.positions_steps[0], 3000);
  }
}

// POSITION_FRAME on the tick: a move of at least 0.5 s up and 0.5 s down
// (200 steps take 1 s), MOVE TIME left to the frame clock; without a tick
// a move at the motor's acceleration with MOVE TIME the frame's.
TEST(Dmc16PlaybackTick, PositionFrameMovesTakeAtLeastTwoHalfSeconds) {
  for (const bool tick : {false, true}) {
    SCOPED_TRACE(tick ? "tick" : "continuous");
    Dmc16Profile p = SmallProfile();
    p.behaviour.playback_tick_ms = tick ? 20 : 0;
    Host h(p);
    UploadRamp(h, 10, 100, 10);
    ASSERT_EQ(h.Request(dmc::RtPositionFrame{30}), kAckOk);
    const TimeNs took = RestTime(h) - h.now();
    h.Settle();
    EXPECT_EQ(h.Pos(1), 200);
    if (tick) {
      EXPECT_NEAR(static_cast<double>(took), 1e9 + kTick, 1e3) << "at rest a tick after";
      EXPECT_EQ(h.device().playback().MoveTimeX1000(), 0u);
    } else {
      EXPECT_NEAR(static_cast<double>(took), 2 * std::sqrt(200.0 / 10000) * 1e9, 1e3);
      EXPECT_EQ(h.device().playback().MoveTimeX1000(), 30000u);
    }
  }
}

// RUN_MOVE on the tick (dmc-lite): refused while the rig moves (a second
// RUN_MOVE during the first one's pre-roll) and unless the rig is on a frame;
// GO while not armed, or before the rig rests, is ERR_NOT_IN_POSITION.
TEST(Dmc16PlaybackTick, RunMoveNeedsAFrameAndRestAndGoAnswersNotInPosition) {
  Host h(Ticked());
  UploadRamp(h, 10, 100, 10);
  EXPECT_EQ(h.Request(RunMove(20, 30, 24000, 500, 500)), AckCode::kErrNotInPosition);
  EXPECT_EQ(h.Request(dmc::RtGo{}), AckCode::kErrNotInPosition);
  ASSERT_EQ(h.Request(dmc::RtPositionFrame{20}), kAckOk);
  EXPECT_EQ(h.Request(RunMove(20, 30, 24000, 500, 500)), AckCode::kErrMoving);
  h.Settle();
  ASSERT_EQ(h.Request(RunMove(20, 30, 24000, 500, 500)), kAckOk);
  // Its motors leave for the pre-roll at the next tick: until then RUN_MOVE
  // re-arms, after it the rig moves.
  EXPECT_EQ(h.Request(RunMove(20, 30, 24000, 500, 500)), kAckOk);
  EXPECT_EQ(h.Request(dmc::RtGo{}), AckCode::kErrNotInPosition);
  h.RunMs(20);
  ASSERT_TRUE(h.device().rig_ref().AnyMoving());
  EXPECT_EQ(h.Request(dmc::RtGo{}), AckCode::kErrNotInPosition) << "still going to its pre-roll";
  EXPECT_EQ(h.Request(RunMove(20, 30, 24000, 500, 500)), AckCode::kErrMoving);
  h.Settle();
  EXPECT_EQ(h.Request(RunMove(20, 30, 24000, 500, 500)), kAckOk) << "armed at rest: re-armed";
  h.Settle();
  EXPECT_EQ(h.Request(dmc::RtGo{}), kAckOk);
  h.Settle();
  EXPECT_EQ(h.Pos(1), 210) << "END FRAME + 1";
  EXPECT_EQ(h.device().playback().on_frame(), 31u);
  EXPECT_EQ(h.Request(RunMove(20, 30, 24000, 500, 500)), kAckOk) << "on the frame the run ended on";
}

// position_frame_clamped (dmc-lite): a frame outside the upload goes to the
// nearest uploaded one, OK; the spec reading refuses it (ERR_RANGE).
TEST(Dmc16PlaybackSwitches, PositionFrameOutsideTheUploadIsRefusedOrClamped) {
  for (const bool clamped : {false, true}) {
    Dmc16Profile p = SmallProfile();
    p.behaviour.position_frame_clamped = clamped;
    Host h(p);
    UploadRamp(h, 10, 100, 10);
    EXPECT_EQ(h.Request(dmc::RtPositionFrame{110}),
              clamped ? kAckOk : std::optional<AckCode>(AckCode::kErrRange));
    h.Settle();
    EXPECT_EQ(h.Pos(1), clamped ? 990 : 0);
    EXPECT_EQ(h.Request(dmc::RtPositionFrame{3}),
              clamped ? kAckOk : std::optional<AckCode>(AckCode::kErrRange));
    h.Settle();
    EXPECT_EQ(h.Pos(1), 0);
  }
}

// rt_end_after_stop false (dmc-lite): STOP_ALL ends a live run without RT_END.
TEST(Dmc16PlaybackSwitches, StopAllEndsARunWithRtEndOrWithout) {
  for (const bool tick : {false, true}) {
    for (const bool end : {true, false}) {
      SCOPED_TRACE(std::string(tick ? "tick" : "continuous") + (end ? " RT_END" : " none"));
      Dmc16Profile p = tick ? Ticked() : SmallProfile();
      p.behaviour.rt_end_after_stop = end;
      Host h(p);
      UploadRamp(h, 10, 100, 10);
      ASSERT_EQ(h.Request(dmc::RtPositionFrame{20}), kAckOk);
      h.Settle();
      ASSERT_EQ(h.Request(RunMove(20, 60, 24000, 500, 500)), kAckOk);
      h.Settle();
      h.RunMs(100);
      ASSERT_EQ(h.Request(dmc::RtGo{}), kAckOk);
      h.RunMs(1000);
      ASSERT_EQ(h.device().ModeName(), "running");
      ASSERT_EQ(h.Request(dmc::MotorStopAll{}), kAckOk);
      h.Settle();
      EXPECT_EQ(h.All<dmc::RtEnd>().size(), end ? 1u : 0u);
      EXPECT_EQ(h.device().ModeName(), "idle");
      EXPECT_FALSE(h.device().rig_ref().AnyMoving());
    }
  }
}

// camera_angles_checked false (dmc-lite): a stills angle past 360, or CLOSE
// not above OPEN, is taken; the spec reading refuses them with ERR_RANGE.
TEST(Dmc16PlaybackSwitches, StillsAnglesPast360AreRefusedOrTaken) {
  for (const bool checked : {true, false}) {
    Dmc16Profile p = SmallProfile();
    p.behaviour.camera_angles_checked = checked;
    Host h(p);
    UploadRamp(h, 10, 100, 10);
    for (const auto& [open, close] : {std::pair{0, 400}, std::pair{361, 360}}) {
      dmc::RtRunMove r = RunMove(20, 24, 10000, 0, 0, dmc::kPlayCameraStills);
      r.camera_open_angle_deg = static_cast<uint16_t>(open);
      r.camera_close_angle_deg = static_cast<uint16_t>(close);
      EXPECT_EQ(h.Request(r), checked ? std::optional<AckCode>(AckCode::kErrRange) : kAckOk);
      h.Settle();
    }
    if (checked) continue;
    // 361..360 exposes each frame from 90 to 180 degrees, as dmc-lite does.
    const TimeNs t_go = h.now();
    ASSERT_EQ(h.Request(dmc::RtGo{}), kAckOk);
    h.Settle();
    std::vector<TimeNs> opens;
    for (const sim::CameraPort::Edge& e : h.device().camera().Trace()) {
      if (e.line == sim::CameraPort::kShutter && e.level && e.time_ns >= t_go) {
        opens.push_back(e.time_ns);
      }
    }
    ASSERT_EQ(opens.size(), 5u);
    EXPECT_EQ(opens[1] - opens[0], 100 * kNsPerMs);
    EXPECT_EQ((opens[0] - t_go) % (100 * kNsPerMs), 25 * kNsPerMs) << "a quarter frame in";
  }
}

// zero_preroll_nan (dmc-lite, on the tick): a 0 ms pre-roll has no pre-roll
// position, so with motor 1's lower soft limit enabled RUN_MOVE answers
// ERR_PREROLL though only its post-roll would cross the upper one. Without the
// switch there is no ramp: the rig is already where the run starts, and the
// roll limits are checked only for a motor that the pre-roll moves.
TEST(Dmc16PlaybackSwitches, AZeroPrerollIsNotANumberOrNoRamp) {
  for (const bool nan : {false, true}) {
    SCOPED_TRACE(nan ? "NaN" : "no ramp");
    Dmc16Profile p = Ticked();
    p.behaviour.zero_preroll_nan = nan;
    Host h(p);
    UploadRamp(h, 10, 100, 10);
    ASSERT_EQ(h.Request(dmc::RtPositionFrame{20}), kAckOk);
    h.Settle();
    ASSERT_EQ(h.Request(dmc::MotorSetLimits{1, 1, 0, 1, 300, 0}), kAckOk);
    // 20 fps, 200 steps/s: a 1 s post-roll goes 100 past frame 31 (210).
    EXPECT_EQ(h.Request(RunMove(20, 30, 20000, 0, 1000)),
              nan ? std::optional<AckCode>(AckCode::kErrPreroll) : kAckOk);
    h.Settle();
    EXPECT_EQ(h.Pos(1), 100) << "nothing moved";
    if (nan) continue;
    ASSERT_EQ(h.Request(dmc::RtGo{}), kAckOk);
    h.Settle();
    EXPECT_EQ(h.Pos(1), 210) << "from frame 20 at full speed, back onto frame 31";
  }
}

}  // namespace
}  // namespace moco::devices
