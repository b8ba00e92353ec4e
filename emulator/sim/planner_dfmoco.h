// DFMoco Arduino step generation (FACTS.md "DFMoco ... Step generation",
// "Planner"): a 40 kHz timer raises step pins at most every other tick
// (20 kHz), and every 50 ms loads the next constant velocity chunk of a
// trapezoid profile; a direction change waits one chunk.
#ifndef MOCO_SIM_PLANNER_DFMOCO_H_
#define MOCO_SIM_PLANNER_DFMOCO_H_

#include <vector>

#include "sim/planner.h"

namespace moco::sim {

inline constexpr TimeNs kDfmocoTickNs = 25'000;        // 40 kHz interrupt
inline constexpr TimeNs kDfmocoChunkNs = 50'000'000;   // 1000 low ticks
inline constexpr double kDfmocoMaxStepsPerS = 20'000;  // one step per two ticks

// Plans like the sketch: the continuous trapezoid profile (velocity capped at
// 20 kHz; the device sets max accel = pulse rate / 2) is cut into 50 ms
// chunks on the firmware's free-running chunk clock (phase 0 at power-on,
// i.e. t = 0); each chunk moves at the constant velocity that reaches the
// profile's position at the chunk's end. A command takes effect at the next
// chunk boundary (the current chunk runs out first); a chunk whose velocity
// reverses the previous one's sign is preceded by one idle chunk. Step edges
// fall on 25 us ticks. Each stretch of one direction is returned as one
// chunked run (Segment::chunks) that the plan expands lazily, bit for bit as
// one Segment per chunk would move, so a plan's memory does not grow with
// the move's duration.
class DfmocoPlanner final : public Planner {
 public:
  std::vector<Segment> Plan(const PlanRequest& req) override;
  TimeNs StepQuantumNs() const override { return kDfmocoTickNs; }
};

}  // namespace moco::sim

#endif  // MOCO_SIM_PLANNER_DFMOCO_H_
