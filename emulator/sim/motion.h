// The step model of a stepper motor (ARCHITECTURE "Motion"): analytic
// constant-acceleration segments, step edges as exact roots, integer steps.
// The model is defined in full in docs/sim-model.md; in short:
//
//   * A Plan starts at an integer time `origin_ns` with the motor on the
//     integer step `origin_steps`. Its continuous position x(t), in steps
//     relative to origin_steps, is piecewise quadratic: each Segment holds
//     (t0, duration, x0, v0, a) and x(t0 + tau) = x0 + v0 tau + a tau^2 / 2.
//     Segments are contiguous in time and in x, and monotonic: the velocity
//     never changes sign inside one (Normalize splits where it would).
//   * The step position p is an integer state that changes only by step
//     edges of +-1. Moving up from p, the next edge happens when x reaches
//     p + 1/2; moving down, when x reaches p - 1/2 (nearest-step rounding
//     with the thresholds half-way between steps, so a motor at rest on an
//     integer x sits as far as possible from any threshold).
//   * An edge's time is the exact root of the segment equation, in
//     nanoseconds after origin_ns, rounded UP to the next integer ns (and to
//     the plan's step quantum, 1 ns unless a planner models a step timer)
//     and at least 1 ns after origin_ns: p(T) counts the edges with time <= T.
//   * Floating point is used only to place edges in time; positions are
//     integers and are never rounded from x.
#ifndef MOCO_SIM_MOTION_H_
#define MOCO_SIM_MOTION_H_

#include <cstddef>
#include <cstdint>
#include <optional>
#include <tuple>
#include <utility>
#include <vector>

#include "sim/scheduler.h"

namespace moco::sim {

// One step edge as a step driver would see it.
struct StepEdge {
  TimeNs time_ns = 0;
  int64_t step = 0;      // the position after the edge
  int8_t direction = 0;  // +1 or -1

  bool operator==(const StepEdge&) const = default;
};

// Constant-acceleration piece of motion. Times in seconds after the plan's
// origin; positions in steps relative to the plan's origin_steps.
struct Segment {
  double t0_s = 0;
  double duration_s = 0;
  double x0_steps = 0;
  double v0_steps_per_s = 0;
  double a_steps_per_s2 = 0;

  double EndTime() const { return t0_s + duration_s; }
  // REQUIRES: 0 <= tau_s <= duration_s (not checked; the formula extends).
  double PositionAt(double tau_s) const {
    return x0_steps + tau_s * (v0_steps_per_s + 0.5 * a_steps_per_s2 * tau_s);
  }
  double VelocityAt(double tau_s) const { return v0_steps_per_s + a_steps_per_s2 * tau_s; }
  double EndPosition() const { return PositionAt(duration_s); }
  double EndVelocity() const { return VelocityAt(duration_s); }
  // +1, -1, or 0 for a segment that does not move.
  int Direction() const;
};

// Continuous kinematic state relative to a plan origin.
struct KinematicState {
  double x_steps = 0;
  double v_steps_per_s = 0;
};

// A committed motion: segments plus the per-segment integer bookkeeping that
// makes step counting exact. Immutable once built.
class Plan {
 public:
  Plan() = default;

  // Builds a plan from a planner's segments. Makes the segments contiguous
  // (each starts where the previous ended, in time and position; the first
  // at t = 0 and x = start_x_steps), drops empty ones, and splits any
  // segment whose velocity changes sign. start_x_steps is the motor's
  // continuous offset from origin_steps (|start_x_steps| <= 1/2 in practice).
  // step_quantum_ns > 1 models a step generator clocked by a timer: each
  // edge time is further rounded up to a multiple of it (absolute time), as
  // is the plan's end. REQUIRES: the segments never ask for more than one
  // edge per quantum.
  static Plan Build(TimeNs origin_ns, int64_t origin_steps, double start_x_steps,
                    const std::vector<Segment>& segments, TimeNs step_quantum_ns = 1);

  bool empty() const { return segs_.empty(); }
  TimeNs origin_ns() const { return origin_ns_; }
  int64_t origin_steps() const { return origin_steps_; }
  const std::vector<Segment>& segments() const { return segs_; }

  // Time the motion ends (the last segment's end, rounded up to an integer
  // ns); origin_ns for an empty plan. Every edge has time <= EndNs().
  TimeNs EndNs() const { return end_ns_; }
  // Step position after the last edge.
  int64_t EndSteps() const;
  // Total number of edges.
  int64_t EdgeCount() const;

  // Step position at time T (edges with time <= T counted). T before the
  // origin gives origin_steps.
  int64_t StepsAt(TimeNs t) const;
  // Continuous state at time T relative to origin_steps (clamped to the plan).
  KinematicState StateAt(TimeNs t) const;

  // Calls sink(edge) for every edge with from_ns < time <= to_ns, in order.
  // Returns the number of edges emitted.
  template <typename Sink>
  int64_t ForEachEdge(TimeNs from_ns, TimeNs to_ns, Sink&& sink) const;

  // Time of the edge after which the position equals `steps`, reached while
  // moving in `direction`, the first such edge with time > after_ns; nullopt
  // if the plan has none.
  std::optional<TimeNs> TimeOfStep(int64_t steps, int direction, TimeNs after_ns) const;

  // Bytes of heap memory held by the plan.
  size_t HeapBytes() const;

 private:
  struct SegInfo {
    int64_t p_start;  // step position (relative) at the segment's start
    int64_t edges;    // edges inside the segment
    int8_t dir;
  };
  // Time of the k-th edge (0-based) of segment i.
  TimeNs EdgeTime(size_t i, int64_t k) const;
  // Index of the segment in effect at time T (the last with t0 <= T).
  size_t SegmentAt(TimeNs t) const;
  // The segment holding the last edge with time <= T (or the one in effect
  // at T), and the number of its edges up to T.
  std::pair<size_t, int64_t> Locate(TimeNs t) const;
  // Edges of segment i with time <= T.
  int64_t EdgesUpTo(size_t i, TimeNs t) const;

  TimeNs origin_ns_ = 0;
  int64_t origin_steps_ = 0;
  TimeNs end_ns_ = 0;
  TimeNs quantum_ns_ = 1;
  std::vector<Segment> segs_;
  std::vector<SegInfo> info_;
};

// Seconds from the segment start until x reaches `threshold_steps`, for a
// monotonic segment moving in direction `dir`; 0 if already there, and at
// most duration_s.
double CrossingTime(const Segment& s, int dir, double threshold_steps);

// --- template implementation ---

template <typename Sink>
int64_t Plan::ForEachEdge(TimeNs from_ns, TimeNs to_ns, Sink&& sink) const {
  int64_t emitted = 0;
  if (segs_.empty() || to_ns <= from_ns || to_ns <= origin_ns_) return 0;
  size_t i = 0;
  int64_t k = 0;
  if (from_ns >= origin_ns_) std::tie(i, k) = Locate(from_ns);
  for (; i < segs_.size(); ++i, k = 0) {
    const SegInfo& info = info_[i];
    for (; k < info.edges; ++k) {
      const TimeNs t = EdgeTime(i, k);
      if (t > to_ns) return emitted;
      const int64_t step = origin_steps_ + info.p_start + info.dir * (k + 1);
      sink(StepEdge{t, step, info.dir});
      ++emitted;
    }
  }
  return emitted;
}

}  // namespace moco::sim

#endif  // MOCO_SIM_MOTION_H_
