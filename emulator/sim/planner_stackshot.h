// Cognisys StackShot 3X motion shaping (stackshot-protocol.txt
// CC_RAIL_CONFIG_RAMP_TIME / STACK_SPEED / MOVE_SPEED, CC_MOTION_CONFIG and
// CC_MOTION_START; ERRATA.md 3.5): ramp-time trapezoids and cubic Bezier
// position curves, played on a StepperMotor as constant-acceleration segments.
#ifndef MOCO_SIM_PLANNER_STACKSHOT_H_
#define MOCO_SIM_PLANNER_STACKSHOT_H_

#include <array>
#include <cstdint>
#include <optional>
#include <string_view>
#include <vector>

#include "sim/planner.h"
#include "sim/stepper_motor.h"

namespace moco::sim {

// ---------------------------------------------------------------------------
// Ramp-time moves.
//
// The rail is configured with a speed and a ramp TIME, not an acceleration:
//   CC_RAIL_CONFIG_STACK_SPEED (0x108B, F32 units/s, "maximum stacking
//   speed") and CC_RAIL_CONFIG_MOVE_SPEED (0x1097, F32 units/s, speed of the
//   FWD/BACK buttons)  -> the request's max velocity (the device converts
//                         units to steps and sets MotionProfile::
//                         max_velocity_steps_per_s; CC_RAIL_MOVE_AT_SPEED's
//                         percent scales it like a jog);
//   CC_RAIL_CONFIG_RAMP_TIME (0x108C, F32 s, "time in seconds the rail will
//   ramp from start to final speed") -> StackshotPlanner's ramp_time_s;
//   acceleration = max velocity / ramp time, so a move from rest reaches its
//   speed after exactly the ramp time, whatever the speed.

// max_velocity / ramp_time (+infinity for ramp_time == 0: no ramp).
// REQUIRES: max_velocity_steps_per_s > 0, ramp_time_s >= 0.
double RampAccel(double max_velocity_steps_per_s, double ramp_time_s);

// The profile a device sets on the motor for a ramp-time rail: max velocity
// as given and max acceleration = RampAccel(), so that Stop() (the soft
// ramp of CC_RAIL_STOP_RAMP) comes down from full speed in the ramp time
// too. With ramp_time_s == 0 the acceleration is set to a finite stand-in
// (1e12 steps/s^2); the planner itself then steps the velocity.
MotionProfile RampProfile(double max_velocity_steps_per_s, double ramp_time_s);

// ---------------------------------------------------------------------------
// Bezier position curves (CC_MOTION_CONFIG, 0x1600).
//
// Each curve is a cubic Bezier in the (time, position) plane: point p has
// x = time and y = position (ERRATA 3.5: point p of curve c has x at byte
// 4 + 32c + 8p and y 4 bytes after it, both F32). Readings taken where the
// spec is silent or ambiguous:
//   * x is time in seconds from CC_MOTION_START (the spec gives no unit);
//     y is the position in mm (linear) or degrees (rotary) from the axis's
//     zero, converted to steps by the device (steps_per_unit).
//   * Curve 0 is always in use; curve c >= 1 with P0.x == 0 ends the spline
//     and the curves after it are ignored ("this will terminate the motion").
//   * Continuity: the spec demands P0.x == previous P3.x; the position must
//     join too (P0.y == previous P3.y), since the rail cannot jump. Both are
//     compared exactly (the same F32 keyframe value on the wire).
//   * "Limits should be applied to prevent sudden velocity changes": a curve
//     asking, anywhere, for a speed above the axis's max velocity is refused
//     (this also refuses vertical tangents: infinite speed).

struct BezierPoint {
  double t_s = 0;       // x: time, seconds
  double position = 0;  // y: mm or degrees (steps once in a BezierSpline)
};

struct BezierCurve {
  std::array<BezierPoint, 4> p;  // P0..P3
};

inline constexpr int kMotionCurves = 4;
// The four curves of one axis as CC_MOTION_CONFIG carries them.
using MotionCurves = std::array<BezierCurve, kMotionCurves>;

// The rule a curve set breaks (the first found, curves in order).
enum class SplineError : uint8_t {
  kNonFinite,              // a coordinate of a used curve is NaN or infinite
  kFirstStartNotZero,      // curve 0's P0.x != 0
  kTimeDiscontinuity,      // a used curve's P0.x != the previous curve's P3.x
  kPositionDiscontinuity,  // a used curve's P0.y != the previous curve's P3.y
  kEmptyCurve,             // a used curve with P3.x <= P0.x (no duration)
  // P1.x or P2.x outside [P0.x, P3.x]. This also keeps every curve from
  // turning back in time (the spec's "back upon itself" rule): with the
  // control times in bounds, dtime/du >= 0 on [0, 1].
  kControlTimeOutOfBounds,
  kTooFast,   // |dposition/dtime| above the max velocity somewhere
  kBadScale,  // steps_per_unit not finite and nonzero
};
std::string_view SplineErrorName(SplineError e);

struct SplineFault {
  SplineError error = SplineError::kNonFinite;
  int curve = 0;  // index of the offending curve (0..3)

  bool operator==(const SplineFault&) const = default;
};

// A validated spline in steps: 1..4 curves, y converted to steps and
// anchored so that curve 0 starts on a whole step (a shift of less than
// 1/2 step: the motor rests on whole steps). Built only by MakeSpline.
class BezierSpline {
 public:
  const std::vector<BezierCurve>& curves() const { return curves_; }
  // The step the motor must rest on to start (curve 0's P0.y).
  int64_t StartStep() const { return start_step_; }
  // The step the motor rests on at the end: the last curve's P3.y rounded
  // to the nearest step (halves away from zero).
  int64_t FinalStep() const { return final_step_; }
  double DurationS() const { return curves_.back().p[3].t_s; }
  double max_velocity_steps_per_s() const { return max_velocity_; }

  // The analytic curve at time t (clamped to [0, DurationS()]): position in
  // steps and velocity in steps/s. Solves time(u) = t by bisection.
  double PositionAt(double t_s) const;
  double VelocityAt(double t_s) const;

 private:
  friend struct SplineBuilder;
  std::vector<BezierCurve> curves_;
  int64_t start_step_ = 0;
  int64_t final_step_ = 0;
  double max_velocity_ = 0;
};

// Checks `curves` (spec units) against the CC_MOTION_CONFIG rules; nullopt
// when valid. max_velocity_units_per_s bounds |dy/dt| (REQUIRES > 0; a
// non-positive or non-finite bound refuses every curve that moves).
std::optional<SplineFault> ValidateMotionCurves(const MotionCurves& curves,
                                                double max_velocity_units_per_s);

// Either a spline or the first rule broken.
struct SplineOrFault {
  std::optional<BezierSpline> spline;
  SplineFault fault;  // meaningful when !spline

  bool ok() const { return spline.has_value(); }
};

// Validates and converts: y in steps = y * steps_per_unit (negative for a
// reversed axis), limits |velocity| to max_velocity_steps_per_s.
SplineOrFault MakeSpline(const MotionCurves& curves, double steps_per_unit,
                         double max_velocity_steps_per_s);

// The bound on |x(t) - y(t)| (continuous plan position against the analytic
// curve, in steps) that SplineSegments guarantees at every instant. The
// motor's step position then stays within 1/2 + this of the curve, and each
// edge happens while the curve is within this of the edge's half-way
// threshold.
inline constexpr double kSplineToleranceSteps = 0.25;

// Constant-acceleration segments following `spline` from rest on
// StartStep() (positions relative to it): each Bezier is cut adaptively in
// its parameter into intervals fitted by two parabolas that match the
// curve's position and velocity at both ends (velocity is continuous), an
// interval being split until a Bernstein bound on the error polynomial is
// within kSplineToleranceSteps. The last segment ends on the last curve's
// final position (moved inside FinalStep() +- 1/2 when it sits exactly half
// way) at the curve's final velocity; the plan then ends and the motor rests
// on FinalStep() (the spline terminates the motion; a host keeps the final
// velocity zero, as the spec asks limits against sudden velocity changes).
std::vector<Segment> SplineSegments(const BezierSpline& spline);

// ---------------------------------------------------------------------------
// The planner of a StackShot axis: ramp-time moves, and a spline armed to be
// played by the next move.
class StackshotPlanner final : public Planner {
 public:
  // REQUIRES: ramp_time_s finite and >= 0 (else 0).
  explicit StackshotPlanner(double ramp_time_s = 0.5);

  // Refuses (false, unchanged) a negative or non-finite ramp time.
  bool SetRampTime(double ramp_time_s);
  double ramp_time_s() const { return ramp_time_s_; }

  // kMoveTo: trapezoid/triangle under the request's max velocity, speeding
  // up at RampAccel(max velocity, ramp time) and braking at the larger of
  // that and req.decel_steps_per_s2 (a jog brakes at full deceleration);
  // from any state (a new target mid-move decelerates and reverses as
  // needed). Ramp time 0: the velocity steps to +-max velocity and back to
  // rest on the target. kStop: decelerates at req.decel_steps_per_s2 (at
  // once with ramp time 0). An armed spline is played instead by the next
  // kMoveTo (see PlaySpline), then disarmed.
  std::vector<Segment> Plan(const PlanRequest& req) override;

  void Arm(const BezierSpline& spline) { armed_ = spline; }
  void Disarm() { armed_.reset(); }
  bool armed() const { return armed_.has_value(); }

 private:
  double ramp_time_s_;
  std::optional<BezierSpline> armed_;
};

// CC_MOTION_START for one axis: plays `spline` on `motor`. REQUIRES:
// `planner` is the motor's planner (owned by it). Refuses with kMoving while
// the motor moves and kBadArgument unless it rests on spline.StartStep()
// (the device positions the rail first); otherwise the motor's MoveTo
// checks apply to FinalStep() (soft limits, switches, e-stop). On kOk the
// motor follows the curve and rests on FinalStep() at DurationS().
MoveStatus PlaySpline(StepperMotor& motor, StackshotPlanner& planner, const BezierSpline& spline);

}  // namespace moco::sim

#endif  // MOCO_SIM_PLANNER_STACKSHOT_H_
