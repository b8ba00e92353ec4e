// A planner for devices that play precomputed motion (DMC v2 real-time
// playback: pre-roll, frame path, post-roll; go-motion blur ramps): the next
// move request returns the loaded segments, everything else is planned as a
// trapezoid, optionally under tighter limits for coordinated virtual-axis
// moves (dmc-v2-protocol.txt MSG_MOTOR_MOVE / STOP; ARCHITECTURE "Motion").
#ifndef MOCO_DEVICES_DMC16_SCRIPT_PLANNER_H_
#define MOCO_DEVICES_DMC16_SCRIPT_PLANNER_H_

#include <algorithm>
#include <optional>
#include <utility>
#include <vector>

#include "sim/planner.h"
#include "sim/planner_trapezoid.h"

namespace moco::devices {

class ScriptPlanner final : public sim::Planner {
 public:
  // The next kMoveTo request gets `segments` (once). REQUIRES: laid end to end
  // from the motor's state at that request they end on the requested target
  // (within 1/2 step), at rest unless another script follows at their end.
  void Load(std::vector<sim::Segment> segments) { script_ = std::move(segments); }
  // The next kMoveTo request is planned as a trapezoid under at most
  // `max_velocity_steps_per_s`, accelerating and braking at
  // `accel_steps_per_s2` (never above the request's own limits): moves of
  // several motors that start and end together. REQUIRES: both > 0.
  void Cap(double max_velocity_steps_per_s, double accel_steps_per_s2) {
    script_.reset();
    cap_ = {max_velocity_steps_per_s, accel_steps_per_s2};
  }
  void Drop() {
    script_.reset();
    cap_.reset();
  }
  bool loaded() const { return script_.has_value(); }

  std::vector<sim::Segment> Plan(const sim::PlanRequest& req) override {
    if (req.kind == sim::PlanRequest::Kind::kMoveTo && script_) {
      std::vector<sim::Segment> out = std::move(*script_);
      script_.reset();
      return out;
    }
    script_.reset();
    if (req.kind == sim::PlanRequest::Kind::kMoveTo && cap_) {
      const auto [v, a] = *cap_;
      cap_.reset();
      const double accel = std::min(a, req.max_accel_steps_per_s2);
      return sim::PlanTrapezoid(req.start, static_cast<double>(req.target_steps),
                                std::min(v, req.max_velocity_steps_per_s), accel, accel);
    }
    cap_.reset();
    return trapezoid_.Plan(req);
  }

 private:
  sim::TrapezoidPlanner trapezoid_;
  std::optional<std::vector<sim::Segment>> script_;
  std::optional<std::pair<double, double>> cap_;  // velocity, acceleration
};

}  // namespace moco::devices

#endif  // MOCO_DEVICES_DMC16_SCRIPT_PLANNER_H_
