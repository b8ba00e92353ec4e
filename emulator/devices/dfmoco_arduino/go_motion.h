// DFMoco go-motion (blur) moves (dfmoco-protocol.txt "Go-Motion (Blur)",
// ERRATA 2.5, FACTS.md "DFMoco ... Go-motion"): the exposure maths for one
// motor and the planner that runs it in the sketch's 50 ms chunks.
//
// The move of one channel, with b = blur / 1000 and e = exposure / 1000 s:
//   exposure start  s = p1 - (p1 - p0) * b,   exposure end  f = p1 + (p2 - p1) * b;
//   v1 = (p1 - s) / (e/2),  v2 = (f - p1) / (e/2);
//   a 1 s ramp from rest to v1 ends at s, so it starts at s - v1/2 (the pre-position);
//   s -> p1 at v1 for e/2, p1 -> f at v2 for e/2;
//   a 1 s ramp from v2 to rest ends at f + v2/2.
// The exposure therefore opens exactly 1 s after the move starts.
#ifndef MOCO_DEVICES_DFMOCO_ARDUINO_GO_MOTION_H_
#define MOCO_DEVICES_DFMOCO_ARDUINO_GO_MOTION_H_

#include <cstdint>
#include <vector>

#include "sim/planner.h"
#include "sim/planner_dfmoco.h"
#include "sim/scheduler.h"
#include "wire/dfmoco_timing.h"

namespace moco::devices {

// "exactly 1 second" before and after (dfmoco::kGoMotionRampNs), in seconds.
inline constexpr double kGoMotionRampS = static_cast<double>(dfmoco::kGoMotionRampNs) / 1e9;

// One motor's go-motion move in absolute steps (continuous; the motor lands on
// whole steps).
struct BlurMove {
  double exposure_s = 0;
  double start_steps = 0;           // where the ramp up starts (the pre-position)
  double exposure_start_steps = 0;  // p1 - (p1 - p0) * b
  double p1_steps = 0;
  double exposure_end_steps = 0;  // p1 + (p2 - p1) * b
  double end_steps = 0;           // where the ramp down ends
  double v1_steps_per_s = 0;      // first half of the exposure
  double v2_steps_per_s = 0;      // second half

  double DurationS() const { return 2 * kGoMotionRampS + exposure_s; }
  // Position `t_s` seconds after the move starts (clamped to the move).
  double PositionAt(double t_s) const;
  // The larger of |v1| and |v2|: the top speed of the move.
  double MaxSpeed() const;
};

// REQUIRES: exposure_ms > 0. Any blur is accepted (1000 = the whole of
// p0 -> p1 -> p2; values beyond 0..1000 extrapolate).
BlurMove PlanBlur(int32_t exposure_ms, int32_t blur, int32_t p0_steps, int32_t p1_steps,
                  int32_t p2_steps);

// Runs one BlurMove like the sketch does after `go`: 50 ms chunks starting at
// `start_ns` (the sketch restarts its chunk clock at `go`), each at the
// constant velocity (capped at 20000 steps/s) that reaches the move's
// position at the chunk's end; a chunk that would reverse direction is spent
// setting the direction pin instead and the move resumes one chunk later. A
// motor held back by the speed cap catches up at the cap after the move's
// time is over. Use with StepperMotor::MoveTo(end_target_steps); kStop
// requests are planned as the ordinary DFMoco planner does.
class GoMotionPlanner final : public sim::Planner {
 public:
  // REQUIRES: start_ns >= the time of the MoveTo that uses the planner.
  GoMotionPlanner(const BlurMove& move, sim::TimeNs start_ns, int64_t end_target_steps)
      : move_(move), start_ns_(start_ns), end_target_steps_(end_target_steps) {}

  std::vector<sim::Segment> Plan(const sim::PlanRequest& req) override;
  sim::TimeNs StepQuantumNs() const override { return sim::kDfmocoTickNs; }

 private:
  BlurMove move_;
  sim::TimeNs start_ns_;
  int64_t end_target_steps_;
  sim::DfmocoPlanner fallback_;
};

}  // namespace moco::devices

#endif  // MOCO_DEVICES_DFMOCO_ARDUINO_GO_MOTION_H_
