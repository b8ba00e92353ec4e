// DMC-16 motion shaping (dmc-v2-protocol.txt MSG_MOTOR_MOVE, MSG_MOTOR_SET_SPEED):
// trapezoidal or triangular velocity profiles under max velocity and max
// acceleration, blending from the current velocity on a new target.
#ifndef MOCO_SIM_PLANNER_TRAPEZOID_H_
#define MOCO_SIM_PLANNER_TRAPEZOID_H_

#include <vector>

#include "sim/planner.h"

namespace moco::sim {

// Plans, from any start state, speeding up at `accel` and slowing down at
// `decel` (both the request's max_accel unless decel_steps_per_s2 > 0):
//   1. if moving away from the target, or too fast to stop before it:
//      decelerate to rest and go back;
//   2. if faster than max velocity: decelerate to it;
//   3. accelerate to the peak (max velocity, or less: triangular), cruise,
//      decelerate to rest on the target.
// At most 4 segments. Non-positive limits plan a stop.
class TrapezoidPlanner final : public Planner {
 public:
  std::vector<Segment> Plan(const PlanRequest& req) override;
};

// The same profile as a free function (used by other planners too).
std::vector<Segment> PlanTrapezoid(const KinematicState& start, double target_steps,
                                   double max_velocity_steps_per_s, double accel_steps_per_s2,
                                   double decel_steps_per_s2);

}  // namespace moco::sim

#endif  // MOCO_SIM_PLANNER_TRAPEZOID_H_
