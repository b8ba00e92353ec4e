// A planner for devices that play precomputed motion (DMC v2 real-time
// playback: pre-roll, frame path, post-roll; go-motion blur ramps): the next
// move request returns the loaded segments, everything else is planned as a
// trapezoid (dmc-v2-protocol.txt MSG_MOTOR_MOVE / STOP; ARCHITECTURE "Motion").
#ifndef MOCO_DEVICES_DMC16_SCRIPT_PLANNER_H_
#define MOCO_DEVICES_DMC16_SCRIPT_PLANNER_H_

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
  void Drop() { script_.reset(); }
  bool loaded() const { return script_.has_value(); }

  std::vector<sim::Segment> Plan(const sim::PlanRequest& req) override {
    if (req.kind == sim::PlanRequest::Kind::kMoveTo && script_) {
      std::vector<sim::Segment> out = std::move(*script_);
      script_.reset();
      return out;
    }
    script_.reset();
    return trapezoid_.Plan(req);
  }

 private:
  sim::TrapezoidPlanner trapezoid_;
  std::optional<std::vector<sim::Segment>> script_;
};

}  // namespace moco::devices

#endif  // MOCO_DEVICES_DMC16_SCRIPT_PLANNER_H_
