// DFMoco's chunked step generation (FACTS.md, DFMoco "Step generation" and
// "Planner"): 50 ms constant-velocity chunks of a trapezoid, 20 kHz cap.
#include "sim/planner_dfmoco.h"

#include <algorithm>
#include <cmath>

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
  std::vector<Segment> profile;
  double target = at_boundary.x_steps;
  if (req.kind == PlanRequest::Kind::kStop) {
    profile = PlanDecelerateToRest(at_boundary, req.decel_steps_per_s2);
    target = PositionAt(profile, at_boundary.x_steps, 1e300);
    // The sketch stops on a whole step.
    target = std::round(target);
  } else {
    target = static_cast<double>(req.target_steps);
    profile = PlanTrapezoid(at_boundary, target, vmax, accel,
                            req.decel_steps_per_s2 > 0 ? req.decel_steps_per_s2 : accel);
  }
  double total_s = 0;
  for (const Segment& s : profile) total_s += s.duration_s;
  const auto chunks = static_cast<int64_t>(std::ceil(total_s / kChunkS));

  double x = at_boundary.x_steps;
  double prev_v = v_now;
  for (int64_t j = 0; j < chunks; ++j) {
    const double t_end = static_cast<double>(j + 1) * kChunkS;
    const double x_end = j + 1 == chunks ? target : PositionAt(profile, at_boundary.x_steps, t_end);
    double v = (x_end - x) / kChunkS;
    v = std::clamp(v, -kDfmocoMaxStepsPerS, kDfmocoMaxStepsPerS);
    if (v != 0 && prev_v != 0 && (v > 0) != (prev_v > 0)) {
      Segment idle;  // direction pins change: one chunk without steps
      idle.duration_s = kChunkS;
      out.push_back(idle);
    }
    Segment s;
    s.v0_steps_per_s = v;
    s.duration_s = kChunkS;
    out.push_back(s);
    x += v * kChunkS;
    prev_v = v;
  }
  return out;
}

}  // namespace moco::sim
