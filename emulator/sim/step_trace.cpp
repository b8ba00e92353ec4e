// Step trace probe: a bounded ring of step edges per motor (ARCHITECTURE "Motion").
#include "sim/step_trace.h"

#include <utility>

namespace moco::sim {

StepTrace::StepTrace(StepperMotor& motor, size_t capacity, TimeNs from_ns, TimeNs to_ns,
                     Stream stream)
    : motor_(motor), from_ns_(from_ns), to_ns_(to_ns), stream_(std::move(stream)), ring_(capacity) {
  motor_.AddStepSink(this);
}

StepTrace::~StepTrace() { motor_.RemoveStepSink(this); }

std::vector<StepEdge> StepTrace::Edges() const {
  std::vector<StepEdge> out;
  out.reserve(size_);
  const size_t start = (head_ + ring_.size() - size_) % (ring_.empty() ? 1 : ring_.size());
  for (size_t i = 0; i < size_; ++i) out.push_back(ring_[(start + i) % ring_.size()]);
  return out;
}

void StepTrace::Clear() {
  head_ = 0;
  size_ = 0;
  total_ = 0;
}

void StepTrace::OnStepEdges(int /*motor_id*/, std::span<const StepEdge> edges) {
  for (const StepEdge& e : edges) {
    if (e.time_ns < from_ns_ || e.time_ns > to_ns_) continue;
    ++total_;
    if (stream_) stream_(e);
    if (ring_.empty()) continue;
    ring_[head_] = e;
    head_ = head_ + 1 == ring_.size() ? 0 : head_ + 1;
    if (size_ < ring_.size()) ++size_;
  }
}

}  // namespace moco::sim
