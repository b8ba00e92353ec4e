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
#include <memory>
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

// The velocities of a chunked run (see Segment::chunks): a step generator
// that loads a new constant velocity every chunk (DFMoco, FACTS.md).
class ChunkVelocities {
 public:
  virtual ~ChunkVelocities() = default;
  // Velocity of piece j (0-based) of the run, the piece that starts at
  // x_steps (relative to the plan origin). Must be deterministic and finite.
  virtual double Velocity(int64_t j, double x_steps) const = 0;
  // Heap bytes held by the object itself (for memory reports).
  virtual size_t HeapBytes() const { return 0; }
};

// Constant-acceleration piece of motion. Times in seconds after the plan's
// origin; positions in steps relative to the plan's origin_steps.
//
// Chunked run: with chunks > 1 the segment stands for `chunks` consecutive
// constant-velocity pieces of duration_s each (a_steps_per_s2 is ignored).
// Piece j moves at chunk_velocities->Velocity(j, x_j), or at v0_steps_per_s
// for every piece when chunk_velocities is null. The pieces are laid end to
// end exactly as that many separate Segments would be (each one's start time
// and position chained from the previous one's EndTime()/EndPosition() in
// floating point), so a run has bit for bit the step edges of its expansion
// while a plan holds it in O(1) memory. REQUIRES: the nonzero piece
// velocities of one run share a sign (else Plan::Build expands the run).
struct Segment {
  double t0_s = 0;
  double duration_s = 0;
  double x0_steps = 0;
  double v0_steps_per_s = 0;
  double a_steps_per_s2 = 0;
  int64_t chunks = 1;
  std::shared_ptr<const ChunkVelocities> chunk_velocities;

  bool IsRun() const { return chunks > 1; }
  // Of one piece: for a run, of its first piece.
  double EndTime() const { return t0_s + duration_s; }
  // REQUIRES: 0 <= tau_s <= duration_s (not checked; the formula extends).
  double PositionAt(double tau_s) const {
    return x0_steps + tau_s * (v0_steps_per_s + 0.5 * a_steps_per_s2 * tau_s);
  }
  double VelocityAt(double tau_s) const { return v0_steps_per_s + a_steps_per_s2 * tau_s; }
  double EndPosition() const { return PositionAt(duration_s); }
  double EndVelocity() const { return VelocityAt(duration_s); }
  // +1, -1, or 0 for a segment that does not move (of one piece).
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
  // The step quantum the plan was built with (1 = analytic edge times).
  TimeNs step_quantum_ns() const { return quantum_ns_; }

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
    int32_t run = -1;  // index into runs_ for a chunked run
  };
  // Start state of one piece of a run.
  struct PieceMark {
    int64_t j;
    double t_s;
    double x_steps;
    int64_t edges_before;  // edges of the run's earlier pieces
  };
  struct RunInfo {
    double end_t_s;  // chained end of the last piece
    double end_x_steps;
    std::vector<PieceMark> marks;  // every kRunMarkStride pieces, from piece 0
  };
  // A piece of a run being walked: its start, velocity and edges.
  struct PieceCursor {
    PieceMark at;
    double v_steps_per_s;
    int64_t edges;
  };
  static constexpr int64_t kRunMarkStride = 128;

  // Run piece helpers (i: the run's segment index).
  Segment PieceSegment(size_t i, const PieceCursor& c) const;
  PieceCursor MakeCursor(size_t i, const PieceMark& m) const;
  void NextPiece(size_t i, PieceCursor& c) const;
  // The piece holding the run's edge k (0 <= k < edges).
  PieceCursor PieceOfEdge(size_t i, int64_t k) const;
  // The last piece starting at or before relative time rel_ns.
  PieceCursor PieceAt(size_t i, double rel_ns) const;
  // Time of edge k_local of the piece under the cursor.
  TimeNs PieceEdgeTime(size_t i, const PieceCursor& c, int64_t k_local) const;
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
  std::vector<RunInfo> runs_;
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
    if (info.run >= 0) {
      if (k >= info.edges) continue;
      PieceCursor c = PieceOfEdge(i, k);
      for (; k < info.edges; ++k) {
        while (k >= c.at.edges_before + c.edges) NextPiece(i, c);
        const TimeNs t = PieceEdgeTime(i, c, k - c.at.edges_before);
        if (t > to_ns) return emitted;
        const int64_t step = origin_steps_ + info.p_start + info.dir * (k + 1);
        sink(StepEdge{t, step, info.dir});
        ++emitted;
      }
      continue;
    }
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
