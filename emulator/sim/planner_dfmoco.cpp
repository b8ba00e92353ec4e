// DFMoco's chunked step generation (FACTS.md, DFMoco "Step generation" and
// "Planner"): 50 ms constant-velocity chunks of a trapezoid, 20 kHz cap.
#include "sim/planner_dfmoco.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <utility>

#include "sim/planner_trapezoid.h"

namespace moco::sim {
namespace {

constexpr double kChunkS = static_cast<double>(kDfmocoChunkNs) / 1e9;

// Position of a laid-out segment list at time t (seconds from its start).
double PositionAt(const std::vector<Segment>& segs, double x_start, double t) {
  double x = x_start;
  double t0 = 0;
  for (const Segment& s : segs) {
    if (t <= t0 + s.duration_s) {
      return x + (t - t0) * (s.v0_steps_per_s + 0.5 * s.a_steps_per_s2 * (t - t0));
    }
    x += s.duration_s * (s.v0_steps_per_s + 0.5 * s.a_steps_per_s2 * s.duration_s);
    t0 += s.duration_s;
  }
  return x;
}

// The chunk schedule of one move: chunk j (0-based from the first boundary)
// moves at the velocity that takes the chunk's start position to the
// profile's position at the chunk's end (the last chunk to the target).
struct ChunkSchedule {
  std::vector<Segment> profile;
  double x_boundary_steps = 0;  // profile start (the first chunk boundary)
  double target_steps = 0;
  int64_t chunks = 0;

  double Velocity(int64_t j, double x_steps) const {
    const double t_end = static_cast<double>(j + 1) * kChunkS;
    const double x_end =
        j + 1 == chunks ? target_steps : PositionAt(profile, x_boundary_steps, t_end);
    const double v = (x_end - x_steps) / kChunkS;
    return std::clamp(v, -kDfmocoMaxStepsPerS, kDfmocoMaxStepsPerS);
  }
};

// The velocities of a run of chunks [first, first + n) of a schedule.
class ChunkRun final : public ChunkVelocities {
 public:
  ChunkRun(std::shared_ptr<const ChunkSchedule> schedule, int64_t first)
      : schedule_(std::move(schedule)), first_(first) {}
  double Velocity(int64_t j, double x_steps) const override {
    return schedule_->Velocity(first_ + j, x_steps);
  }
  size_t HeapBytes() const override {
    // Counts the shared schedule with every run (an upper bound).
    return sizeof(*this) + sizeof(ChunkSchedule) + schedule_->profile.capacity() * sizeof(Segment);
  }

 private:
  std::shared_ptr<const ChunkSchedule> schedule_;
  int64_t first_;
};

}  // namespace

std::vector<Segment> DfmocoPlanner::Plan(const PlanRequest& req) {
  std::vector<Segment> out;
  if (req.kind == PlanRequest::Kind::kMoveTo && req.start.v_steps_per_s == 0 &&
      static_cast<double>(req.target_steps) == req.start.x_steps) {
    return out;  // already there
  }
  // The chunk in progress runs out at its current velocity.
  const TimeNs next_boundary = (req.now_ns + kDfmocoChunkNs - 1) / kDfmocoChunkNs * kDfmocoChunkNs;
  const double wait_s = static_cast<double>(next_boundary - req.now_ns) / 1e9;
  const double v_now = req.start.v_steps_per_s;
  if (wait_s > 0) {
    Segment s;
    s.v0_steps_per_s = v_now;
    s.duration_s = wait_s;
    out.push_back(s);
  }
  const KinematicState at_boundary{req.start.x_steps + v_now * wait_s, v_now};

  const double vmax = std::min(req.max_velocity_steps_per_s, kDfmocoMaxStepsPerS);
  const double accel = req.max_accel_steps_per_s2;
  auto schedule = std::make_shared<ChunkSchedule>();
  schedule->x_boundary_steps = at_boundary.x_steps;
  if (req.kind == PlanRequest::Kind::kStop) {
    schedule->profile = PlanDecelerateToRest(at_boundary, req.decel_steps_per_s2);
    // The sketch stops on a whole step.
    schedule->target_steps = std::round(PositionAt(schedule->profile, at_boundary.x_steps, 1e300));
  } else {
    schedule->target_steps = static_cast<double>(req.target_steps);
    schedule->profile = PlanTrapezoid(at_boundary, schedule->target_steps, vmax, accel,
                                      req.decel_steps_per_s2 > 0 ? req.decel_steps_per_s2 : accel);
  }
  double total_s = 0;
  for (const Segment& s : schedule->profile) total_s += s.duration_s;
  schedule->chunks = static_cast<int64_t>(std::ceil(total_s / kChunkS));

  // Walks the chunks once to find where runs must break: a stepping chunk
  // whose direction reverses the previous one's is preceded by an idle
  // chunk (direction pins change), and a run never holds both directions.
  // Each run is emitted as one chunked Segment whose velocities the plan
  // recomputes from the same schedule and the same chained positions, so
  // the motion is that of one Segment per chunk, bit for bit.
  auto emit_run = [&](int64_t first, int64_t n, double v_first) {
    if (n <= 0) return;
    Segment s;
    s.v0_steps_per_s = v_first;
    s.duration_s = kChunkS;
    if (n > 1) {
      s.chunks = n;
      s.chunk_velocities = std::make_shared<ChunkRun>(schedule, first);
    }
    out.push_back(std::move(s));
  };
  double x = at_boundary.x_steps;
  double prev_v = v_now;
  int64_t run_first = 0;
  double run_v_first = 0;
  int run_dir = 0;
  for (int64_t j = 0; j < schedule->chunks; ++j) {
    const double v = schedule->Velocity(j, x);
    const int dir = v > 0 ? 1 : (v < 0 ? -1 : 0);
    const bool idle = v != 0 && prev_v != 0 && (v > 0) != (prev_v > 0);
    if (idle || (dir != 0 && run_dir != 0 && dir != run_dir)) {
      emit_run(run_first, j - run_first, run_v_first);
      if (idle) {
        Segment pause;  // direction pins change: one chunk without steps
        pause.duration_s = kChunkS;
        out.push_back(pause);
      }
      run_first = j;
      run_dir = 0;
    }
    if (j == run_first) run_v_first = v;
    if (dir != 0) run_dir = dir;
    x += v * kChunkS;
    prev_v = v;
  }
  emit_run(run_first, schedule->chunks - run_first, run_v_first);
  return out;
}

}  // namespace moco::sim
