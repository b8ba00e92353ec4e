// DMC-16 trapezoid/triangle profiles (dmc-v2-protocol.txt MSG_MOTOR_MOVE),
// blending from the current velocity.
#include "sim/planner_trapezoid.h"

#include <cmath>

namespace moco::sim {

std::vector<Segment> PlanDecelerateToRest(const KinematicState& start, double decel_steps_per_s2) {
  std::vector<Segment> out;
  const double v = start.v_steps_per_s;
  if (v == 0 || !(decel_steps_per_s2 > 0)) return out;
  Segment s;
  s.v0_steps_per_s = v;
  s.a_steps_per_s2 = v > 0 ? -decel_steps_per_s2 : decel_steps_per_s2;
  s.duration_s = std::abs(v) / decel_steps_per_s2;
  out.push_back(s);
  return out;
}

std::vector<Segment> PlanTrapezoid(const KinematicState& start, double target_steps,
                                   double max_velocity_steps_per_s, double accel_steps_per_s2,
                                   double decel_steps_per_s2) {
  std::vector<Segment> out;
  const double vmax = max_velocity_steps_per_s;
  const double acc = accel_steps_per_s2;
  const double dec = decel_steps_per_s2;
  if (!(vmax > 0) || !(acc > 0) || !(dec > 0)) {
    return PlanDecelerateToRest(start, dec > 0 ? dec : 1);
  }
  double x = start.x_steps;
  double v = start.v_steps_per_s;
  auto add = [&](double v0, double a, double dur) {
    if (!(dur > 0)) return;
    Segment s;
    s.v0_steps_per_s = v0;
    s.a_steps_per_s2 = a;
    s.duration_s = dur;
    s.x0_steps = x;
    out.push_back(s);
    x = s.EndPosition();
    v = s.EndVelocity();
  };

  double d = target_steps - x;
  const double stop_dist = v * v / (2 * dec);
  const bool away = (v > 0 && d < 0) || (v < 0 && d > 0);
  if (away || stop_dist > std::abs(d)) {
    // Cannot arrive without passing zero velocity first: come to rest, then
    // plan again from rest (the reversal).
    add(v, v > 0 ? -dec : dec, std::abs(v) / dec);
    v = 0;
    d = target_steps - x;
  }
  if (d == 0) return out;
  const double dir = d > 0 ? 1 : -1;
  const double dist = std::abs(d);
  double u = dir * v;  // speed towards the target, >= 0 here
  if (u < 0) u = 0;

  if (u > vmax) {
    // Too fast (a lower jog speed, or a lowered limit): slow to vmax, cruise,
    // stop. dist >= u^2/2dec = slow-down + stop distances here.
    const double slow_d = (u * u - vmax * vmax) / (2 * dec);
    const double stop_d = vmax * vmax / (2 * dec);
    add(dir * u, -dir * dec, (u - vmax) / dec);
    add(dir * vmax, 0, (dist - slow_d - stop_d) / vmax);
    add(dir * vmax, -dir * dec, vmax / dec);
    return out;
  }
  const double full_d = (vmax * vmax - u * u) / (2 * acc) + vmax * vmax / (2 * dec);
  double peak = vmax;
  double cruise_d = dist - full_d;
  if (cruise_d < 0) {
    // Triangle: (peak^2 - u^2) / 2acc + peak^2 / 2dec = dist; peak >= u
    // because dist >= u^2 / 2dec.
    peak = std::sqrt((dist + u * u / (2 * acc)) / (1 / (2 * acc) + 1 / (2 * dec)));
    cruise_d = 0;
  }
  add(dir * u, dir * acc, (peak - u) / acc);
  add(dir * peak, 0, cruise_d / peak);
  add(dir * peak, -dir * dec, peak / dec);
  return out;
}

std::vector<Segment> TrapezoidPlanner::Plan(const PlanRequest& req) {
  if (req.kind == PlanRequest::Kind::kStop) {
    return PlanDecelerateToRest(req.start, req.decel_steps_per_s2);
  }
  return PlanTrapezoid(
      req.start, static_cast<double>(req.target_steps), req.max_velocity_steps_per_s,
      req.max_accel_steps_per_s2,
      req.decel_steps_per_s2 > 0 ? req.decel_steps_per_s2 : req.max_accel_steps_per_s2);
}

}  // namespace moco::sim
