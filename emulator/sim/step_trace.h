// Step trace probe (ARCHITECTURE "Motion"): the (time, step, direction) edges
// a step driver would see, computed from the analytic segments, with bounded
// memory.
#ifndef MOCO_SIM_STEP_TRACE_H_
#define MOCO_SIM_STEP_TRACE_H_

#include <cstddef>
#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include "sim/motion.h"
#include "sim/stepper_motor.h"

namespace moco::sim {

// Records the edges of one motor within [from_ns, to_ns] into a ring buffer
// of fixed capacity (the oldest edges are overwritten; dropped() counts
// them), and optionally streams every edge to a callback.
//
// The probe registers itself on the motor and unregisters on destruction;
// REQUIRES: the motor outlives the probe. Edges appear once committed (see
// StepSink); call Sync() to commit up to the scheduler's Now().
class StepTrace final : public StepSink {
 public:
  using Stream = std::function<void(const StepEdge&)>;

  StepTrace(StepperMotor& motor, size_t capacity, TimeNs from_ns = 0, TimeNs to_ns = kTimeNever,
            Stream stream = nullptr);
  ~StepTrace() override;
  StepTrace(const StepTrace&) = delete;
  StepTrace& operator=(const StepTrace&) = delete;

  // Commits the motor's edges up to Now().
  void Sync() { motor_.FlushSteps(); }
  // Recorded edges, oldest first.
  std::vector<StepEdge> Edges() const;
  size_t size() const { return size_; }
  size_t capacity() const { return ring_.size(); }
  // Edges seen in the interval (recorded or overwritten).
  uint64_t total() const { return total_; }
  uint64_t dropped() const { return total_ - size_; }
  void Clear();

  void OnStepEdges(int motor_id, std::span<const StepEdge> edges) override;

 private:
  StepperMotor& motor_;
  TimeNs from_ns_;
  TimeNs to_ns_;
  Stream stream_;
  std::vector<StepEdge> ring_;
  size_t head_ = 0;  // next write
  size_t size_ = 0;
  uint64_t total_ = 0;
};

}  // namespace moco::sim

#endif  // MOCO_SIM_STEP_TRACE_H_
