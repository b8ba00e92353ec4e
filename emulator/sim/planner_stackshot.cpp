// StackShot 3X ramp-time moves and CC_MOTION_CONFIG Bezier curves
// (stackshot-protocol.txt CC_RAIL_CONFIG_RAMP_TIME, CC_MOTION_CONFIG; ERRATA 3.5).
#include "sim/planner_stackshot.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "sim/planner_trapezoid.h"

namespace moco::sim {
namespace {

constexpr double kNoRampAccel = 1e12;
// Recursion depth limit of the adaptive fit (2^-40 of a curve's parameter).
constexpr int kMaxFitDepth = 40;
// Bisection steps for time(u) = t (well past double resolution on [0, 1]).
constexpr int kBisectSteps = 80;

// A cubic in power form: c0 + c1 u + c2 u^2 + c3 u^3.
struct Cubic {
  double c0 = 0, c1 = 0, c2 = 0, c3 = 0;

  static Cubic FromBezier(double p0, double p1, double p2, double p3) {
    return {p0, 3 * (p1 - p0), 3 * (p0 - 2 * p1 + p2), p3 - 3 * p2 + 3 * p1 - p0};
  }
  double At(double u) const { return c0 + u * (c1 + u * (c2 + u * c3)); }
  double D1(double u) const { return c1 + u * (2 * c2 + u * 3 * c3); }
  double D2(double u) const { return 2 * c2 + 6 * c3 * u; }
  double D3() const { return 6 * c3; }
  // Coefficients of s -> At(ua + w s) - At(ua) (no constant term).
  std::array<double, 4> Local(double ua, double w) const {
    return {0, D1(ua) * w, D2(ua) / 2 * w * w, c3 * w * w * w};
  }
};

struct CurveForm {
  Cubic time;
  Cubic pos;
};

CurveForm FormOf(const BezierCurve& c) {
  return {Cubic::FromBezier(c.p[0].t_s, c.p[1].t_s, c.p[2].t_s, c.p[3].t_s),
          Cubic::FromBezier(c.p[0].position, c.p[1].position, c.p[2].position, c.p[3].position)};
}

// Minimum over [0, 1] of b0 (1-u)^2 + 2 b1 u (1-u) + b2 u^2 (a quadratic
// in Bernstein form).
double BernsteinQuadMin(double b0, double b1, double b2) {
  double m = std::min(b0, b2);
  const double a = b0 - 2 * b1 + b2;
  if (a > 0) {
    const double u = (b0 - b1) / a;
    if (u > 0 && u < 1) m = std::min(m, (b0 * b2 - b1 * b1) / a);
  }
  return m;
}

bool AllFinite(const BezierCurve& c) {
  for (const BezierPoint& p : c.p) {
    if (!std::isfinite(p.t_s) || !std::isfinite(p.position)) return false;
  }
  return true;
}

// Number of curves in use: curve 0, then each next one until a P0.x of 0.
int UsedCurves(const MotionCurves& curves) {
  int n = 1;
  while (n < kMotionCurves && curves[static_cast<size_t>(n)].p[0].t_s != 0) ++n;
  return n;
}

// Checks the rules on curves already in the units the limit is in.
std::optional<SplineFault> Check(const MotionCurves& curves, int used, double vmax) {
  for (int ci = 0; ci < used; ++ci) {
    const BezierCurve& c = curves[static_cast<size_t>(ci)];
    auto fault = [ci](SplineError e) { return SplineFault{e, ci}; };
    if (!AllFinite(c)) return fault(SplineError::kNonFinite);
    const double t0 = c.p[0].t_s;
    const double t1 = c.p[1].t_s;
    const double t2 = c.p[2].t_s;
    const double t3 = c.p[3].t_s;
    if (ci == 0) {
      if (t0 != 0) return fault(SplineError::kFirstStartNotZero);
    } else {
      const BezierCurve& prev = curves[static_cast<size_t>(ci - 1)];
      if (t0 != prev.p[3].t_s) return fault(SplineError::kTimeDiscontinuity);
      if (c.p[0].position != prev.p[3].position) {
        return fault(SplineError::kPositionDiscontinuity);
      }
    }
    if (!(t3 > t0)) return fault(SplineError::kEmptyCurve);
    if (t1 < t0 || t1 > t3 || t2 < t0 || t2 > t3) {
      return fault(SplineError::kControlTimeOutOfBounds);
    }
    // dtime/du = 3 (b0 (1-u)^2 + 2 b1 u (1-u) + b2 u^2): with b0, b2 >= 0 and
    // the bounds above, b1^2 <= b0 b2 whenever b1 < 0, so time never turns
    // back ((p - q)^2 <= p (1 - q) for 0 <= q < p <= 1 on a unit interval).
    const double b0 = t1 - t0;
    const double b1 = t2 - t1;
    const double b2 = t3 - t2;
    // |dy/du| <= vmax dtime/du on [0, 1]: both vmax t' - y' and vmax t' + y'
    // are quadratics in Bernstein form, non-negative everywhere. A relative
    // slack lets a curve run exactly at the limit despite rounding.
    const double y0 = c.p[0].position;
    const double y1 = c.p[1].position;
    const double y2 = c.p[2].position;
    const double y3 = c.p[3].position;
    const double d0 = y1 - y0;
    const double d1 = y2 - y1;
    const double d2 = y3 - y2;
    if (!(vmax > 0) || !std::isfinite(vmax)) {
      if (d0 != 0 || d1 != 0 || d2 != 0) return fault(SplineError::kTooFast);
      continue;
    }
    const double slack = 1e-12 * (vmax * std::max({b0, std::abs(b1), b2}) +
                                  std::max({std::abs(d0), std::abs(d1), std::abs(d2)}));
    for (double sign : {-1.0, 1.0}) {
      const double m =
          BernsteinQuadMin(vmax * b0 + sign * d0, vmax * b1 + sign * d1, vmax * b2 + sign * d2);
      if (m < -slack) return fault(SplineError::kTooFast);
    }
  }
  return std::nullopt;
}

// u in [0, 1] with time(u) = t (time non-decreasing in u).
double SolveU(const Cubic& time, double t) {
  double lo = 0;
  double hi = 1;
  for (int i = 0; i < kBisectSteps && lo < hi; ++i) {
    const double mid = 0.5 * (lo + hi);
    if (time.At(mid) < t) {
      lo = mid;
    } else {
      hi = mid;
    }
  }
  return 0.5 * (lo + hi);
}

// dy/dt at parameter u, clamped to the validated limit. Where dtime/du
// vanishes the validated bound forces dy/du to vanish too: the limit of the
// ratio is then that of the next derivatives.
double SlopeAt(const CurveForm& f, double u, double vmax) {
  double v = 0;
  const double tu = f.time.D1(u);
  if (tu > 0) {
    v = f.pos.D1(u) / tu;
  } else if (f.time.D2(u) != 0) {
    v = f.pos.D2(u) / f.time.D2(u);
  } else if (f.time.D3() != 0) {
    v = f.pos.D3() / f.time.D3();
  }
  return std::clamp(v, -vmax, vmax);
}

// Bound on |e(s)| over s in [0, 1] for e a polynomial of degree <= 6 in
// power form: the largest Bernstein coefficient.
double BernsteinBound(const std::array<double, 7>& a) {
  constexpr std::array<std::array<double, 7>, 7> kBinom = {{{1, 0, 0, 0, 0, 0, 0},
                                                            {1, 1, 0, 0, 0, 0, 0},
                                                            {1, 2, 1, 0, 0, 0, 0},
                                                            {1, 3, 3, 1, 0, 0, 0},
                                                            {1, 4, 6, 4, 1, 0, 0},
                                                            {1, 5, 10, 10, 5, 1, 0},
                                                            {1, 6, 15, 20, 15, 6, 1}}};
  double bound = 0;
  for (size_t j = 0; j <= 6; ++j) {
    double b = 0;
    for (size_t i = 0; i <= j; ++i) b += kBinom[j][i] / kBinom[6][i] * a[i];
    bound = std::max(bound, std::abs(b));
  }
  return bound;
}

// Bound on |q(t(u)) - y(u)| for u in [ua, ub], where q is the parabola
// q(t) = x0 + v (t - t(ua)) + a/2 (t - t(ua))^2 and y(ua) = y_a.
double PieceErrorBound(const CurveForm& f, double ua, double ub, double x0, double v, double a) {
  const double w = ub - ua;
  const std::array<double, 4> tau = f.time.Local(ua, w);  // t(u) - t(ua)
  const std::array<double, 4> eta = f.pos.Local(ua, w);   // y(u) - y(ua)
  std::array<double, 7> e{};
  e[0] = x0 - f.pos.At(ua);
  for (size_t i = 0; i < 4; ++i) e[i] += v * tau[i] - eta[i];
  for (size_t i = 0; i < 4; ++i) {
    for (size_t j = 0; j < 4; ++j) e[i + j] += 0.5 * a * tau[i] * tau[j];
  }
  return BernsteinBound(e);
}

// Appends the fit of curve f over [ua, ub].
void Fit(const CurveForm& f, double vmax, double ua, double ub, int depth,
         std::vector<Segment>& out) {
  const double um = 0.5 * (ua + ub);
  const double ta = f.time.At(ua);
  const double tm = f.time.At(um);
  const double tb = f.time.At(ub);
  const double ya = f.pos.At(ua);
  const double yb = f.pos.At(ub);
  const double va = SlopeAt(f, ua, vmax);
  const double vb = SlopeAt(f, ub, vmax);
  const double h1 = tm - ta;
  const double h2 = tb - tm;
  auto add = [&out](double v0, double a, double dur) {
    Segment s;
    s.v0_steps_per_s = v0;
    s.a_steps_per_s2 = a;
    s.duration_s = dur;
    out.push_back(s);
  };
  if (!(h1 > 0) || !(h2 > 0)) {
    // Time stands (nearly) still across the interval: one straight piece.
    if (tb - ta > 0) add((yb - ya) / (tb - ta), 0, tb - ta);
    return;
  }
  // Two parabolas joined at tm: position and velocity match at both ends.
  const double dist = yb - ya - va * (h1 + h2);
  const double a1 = (2 * dist - (vb - va) * h2) / (h1 * (h1 + h2));
  const double a2 = (vb - va - a1 * h1) / h2;
  const double xm = ya + h1 * (va + 0.5 * a1 * h1);
  const double vm = va + a1 * h1;
  if (depth < kMaxFitDepth) {
    const double err =
        std::max(PieceErrorBound(f, ua, um, ya, va, a1), PieceErrorBound(f, um, ub, xm, vm, a2));
    if (!(err <= kSplineToleranceSteps)) {
      Fit(f, vmax, ua, um, depth + 1, out);
      Fit(f, vmax, um, ub, depth + 1, out);
      return;
    }
  }
  add(va, a1, h1);
  add(vm, a2, h2);
}

}  // namespace

double RampAccel(double max_velocity_steps_per_s, double ramp_time_s) {
  if (!(ramp_time_s > 0)) return std::numeric_limits<double>::infinity();
  return max_velocity_steps_per_s / ramp_time_s;
}

MotionProfile RampProfile(double max_velocity_steps_per_s, double ramp_time_s) {
  MotionProfile p;
  p.max_velocity_steps_per_s = max_velocity_steps_per_s;
  const double a = RampAccel(max_velocity_steps_per_s, ramp_time_s);
  p.max_accel_steps_per_s2 = std::isfinite(a) ? a : kNoRampAccel;
  return p;
}

std::string_view SplineErrorName(SplineError e) {
  switch (e) {
    case SplineError::kNonFinite:
      return "non-finite";
    case SplineError::kFirstStartNotZero:
      return "first-start-not-zero";
    case SplineError::kTimeDiscontinuity:
      return "time-discontinuity";
    case SplineError::kPositionDiscontinuity:
      return "position-discontinuity";
    case SplineError::kEmptyCurve:
      return "empty-curve";
    case SplineError::kControlTimeOutOfBounds:
      return "control-time-out-of-bounds";
    case SplineError::kTooFast:
      return "too-fast";
    case SplineError::kBadScale:
      return "bad-scale";
  }
  return "?";
}

std::optional<SplineFault> ValidateMotionCurves(const MotionCurves& curves,
                                                double max_velocity_units_per_s) {
  return Check(curves, UsedCurves(curves), max_velocity_units_per_s);
}

struct SplineBuilder {
  static SplineOrFault Build(const MotionCurves& curves, double steps_per_unit, double vmax) {
    SplineOrFault r;
    if (!std::isfinite(steps_per_unit) || steps_per_unit == 0) {
      r.fault = SplineFault{SplineError::kBadScale, 0};
      return r;
    }
    const int used = UsedCurves(curves);
    MotionCurves in_steps = curves;
    for (int ci = 0; ci < used; ++ci) {
      for (BezierPoint& p : in_steps[static_cast<size_t>(ci)].p) p.position *= steps_per_unit;
    }
    // Rules checked in steps: the same comparisons as in units (a scale
    // keeps equal values equal), and the velocity bound in steps/s.
    if (auto fault = Check(in_steps, used, vmax)) {
      r.fault = *fault;
      return r;
    }
    BezierSpline s;
    const double y0 = in_steps[0].p[0].position;
    const double anchor = y0 - std::round(y0);
    for (int ci = 0; ci < used; ++ci) {
      BezierCurve c = in_steps[static_cast<size_t>(ci)];
      for (BezierPoint& p : c.p) p.position -= anchor;
      s.curves_.push_back(c);
    }
    s.start_step_ = static_cast<int64_t>(std::llround(s.curves_.front().p[0].position));
    s.final_step_ = static_cast<int64_t>(std::llround(s.curves_.back().p[3].position));
    s.max_velocity_ = vmax;
    r.spline = std::move(s);
    return r;
  }
};

SplineOrFault MakeSpline(const MotionCurves& curves, double steps_per_unit,
                         double max_velocity_steps_per_s) {
  return SplineBuilder::Build(curves, steps_per_unit, max_velocity_steps_per_s);
}

double BezierSpline::PositionAt(double t_s) const {
  const double t = std::clamp(t_s, 0.0, DurationS());
  for (const BezierCurve& c : curves_) {
    if (t <= c.p[3].t_s) {
      const CurveForm f = FormOf(c);
      return f.pos.At(SolveU(f.time, t));
    }
  }
  return curves_.back().p[3].position;
}

double BezierSpline::VelocityAt(double t_s) const {
  const double t = std::clamp(t_s, 0.0, DurationS());
  for (const BezierCurve& c : curves_) {
    if (t <= c.p[3].t_s) {
      const CurveForm f = FormOf(c);
      return SlopeAt(f, SolveU(f.time, t), max_velocity_);
    }
  }
  return 0;
}

std::vector<Segment> SplineSegments(const BezierSpline& spline) {
  std::vector<Segment> out;
  const double base = static_cast<double>(spline.StartStep());
  for (const BezierCurve& c : spline.curves()) {
    BezierCurve rel = c;
    for (BezierPoint& p : rel.p) p.position -= base;
    Fit(FormOf(rel), spline.max_velocity_steps_per_s(), 0, 1, 0, out);
  }
  if (out.empty()) return out;
  // Lay the segments end to end as Plan::Build will, and keep the end
  // strictly inside FinalStep() +- 1/2 so that the thresholds land on it.
  double x = 0;
  for (const Segment& s : out)
    x += s.duration_s * (s.v0_steps_per_s + 0.5 * s.a_steps_per_s2 * s.duration_s);
  const double target = static_cast<double>(spline.FinalStep()) - base;
  constexpr double kInside = 0.5 - 1e-6;
  if (std::abs(x - target) > kInside) {
    Segment& last = out.back();
    const double x_last0 =
        x - last.duration_s * (last.v0_steps_per_s + 0.5 * last.a_steps_per_s2 * last.duration_s);
    const double want = target + std::clamp(x - target, -kInside, kInside);
    const double h = last.duration_s;
    last.a_steps_per_s2 = 2 * (want - x_last0 - last.v0_steps_per_s * h) / (h * h);
  }
  return out;
}

StackshotPlanner::StackshotPlanner(double ramp_time_s)
    : ramp_time_s_(std::isfinite(ramp_time_s) && ramp_time_s >= 0 ? ramp_time_s : 0) {}

bool StackshotPlanner::SetRampTime(double ramp_time_s) {
  if (!std::isfinite(ramp_time_s) || ramp_time_s < 0) return false;
  ramp_time_s_ = ramp_time_s;
  return true;
}

std::vector<Segment> StackshotPlanner::Plan(const PlanRequest& req) {
  if (req.kind == PlanRequest::Kind::kStop) {
    if (ramp_time_s_ == 0) return {};  // no ramp: stops on the spot
    return PlanDecelerateToRest(req.start, req.decel_steps_per_s2);
  }
  if (armed_) {
    const BezierSpline spline = std::move(*armed_);
    armed_.reset();
    return SplineSegments(spline);
  }
  const double vmax = req.max_velocity_steps_per_s;
  const double target = static_cast<double>(req.target_steps);
  if (!(vmax > 0)) return PlanDecelerateToRest(req.start, req.decel_steps_per_s2);
  if (ramp_time_s_ == 0) {
    // The velocity steps: straight to the target at max velocity.
    const double d = target - req.start.x_steps;
    if (d == 0) return {};
    Segment s;
    s.v0_steps_per_s = d > 0 ? vmax : -vmax;
    s.duration_s = std::abs(d) / vmax;
    return {s};
  }
  const double accel = RampAccel(vmax, ramp_time_s_);
  const double decel = std::max(accel, req.decel_steps_per_s2);
  return PlanTrapezoid(req.start, target, vmax, accel, decel);
}

MoveStatus PlaySpline(StepperMotor& motor, StackshotPlanner& planner, const BezierSpline& spline) {
  if (motor.IsMoving()) return MoveStatus::kMoving;
  if (motor.Position() != spline.StartStep()) return MoveStatus::kBadArgument;
  planner.Arm(spline);
  const MoveStatus status = motor.MoveTo(spline.FinalStep());
  planner.Disarm();  // consumed by the plan, or refused
  return status;
}

}  // namespace moco::sim
