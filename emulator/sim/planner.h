// The planner interface: how a device family shapes motion (ARCHITECTURE
// "Motion": DMC-16 trapezoid, DFMoco chunked, StackShot ramp/Bezier) onto the
// same StepperMotor, which executes whatever segments a planner returns.
#ifndef MOCO_SIM_PLANNER_H_
#define MOCO_SIM_PLANNER_H_

#include <cstdint>
#include <vector>

#include "sim/motion.h"
#include "sim/scheduler.h"

namespace moco::sim {

// Speed limits of a motor (MSG_MOTOR_SET_SPEED; DFMoco `pr`).
struct MotionProfile {
  double max_velocity_steps_per_s = 5000;
  double max_accel_steps_per_s2 = 2500;
  // Hard stop decelerates at this multiple of max_accel (MSG_MOTOR_STOP_ALL
  // twice, MSG_MOTOR_HARD_STOP handling).
  double hard_stop_multiple = 4;
};

// What the motor asks of a planner. Positions are relative to the plan
// origin (the motor's step position when the request is made); `start` is
// the motor's continuous state there (x within +-1/2 of 0).
struct PlanRequest {
  enum class Kind {
    kMoveTo,  // come to rest exactly on target_steps
    kStop,    // come to rest as soon as possible at decel_steps_per_s2
  };
  // kMoveTo: speed up at max_accel; slow down at decel_steps_per_s2 when it
  // is > 0 (a jog slower than the motor's maxima still brakes at full
  // deceleration), else at max_accel.
  Kind kind = Kind::kMoveTo;
  TimeNs now_ns = 0;  // absolute time of the origin (for planners with a phase)
  KinematicState start;
  int64_t target_steps = 0;  // kMoveTo: relative target
  double max_velocity_steps_per_s = 0;
  double max_accel_steps_per_s2 = 0;
  double decel_steps_per_s2 = 0;
};

// Shapes motion into segments. A planner may keep state between requests
// (e.g. a chunk phase) but must be deterministic.
//
// Contract for Plan(): the returned segments, laid end to end from
// req.start, must end at rest, and for kMoveTo end within 1/2 step of
// target_steps (the motor lands on the integer target). Velocity should be
// continuous unless the modelled device really steps it (DFMoco chunks).
// Each segment's t0_s and x0_steps are ignored (the motor recomputes them).
class Planner {
 public:
  virtual ~Planner() = default;
  virtual std::vector<Segment> Plan(const PlanRequest& req) = 0;
  // Step edges are rounded up to multiples of this (a step generator run by
  // a timer interrupt); 1 = analytic edge times.
  virtual TimeNs StepQuantumNs() const { return 1; }
};

// Segments bringing `start` to rest at constant deceleration `decel`
// (REQUIRES: decel > 0). Empty when already at rest.
std::vector<Segment> PlanDecelerateToRest(const KinematicState& start, double decel_steps_per_s2);

}  // namespace moco::sim

#endif  // MOCO_SIM_PLANNER_H_
