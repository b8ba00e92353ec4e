// A step-accurate stepper motor (ARCHITECTURE "Motion"; dmc-v2-protocol.txt
// MSG_MOTOR_MOVE / STOP / JOG / CONFIGURE / RESET_POSITION / SET_LIMITS):
// integer step position, analytic motion from a pluggable Planner, soft
// limits, limit switches, stop / hard stop / emergency halt.
#ifndef MOCO_SIM_STEPPER_MOTOR_H_
#define MOCO_SIM_STEPPER_MOTOR_H_

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

#include "sim/motion.h"
#include "sim/planner.h"
#include "sim/scheduler.h"

namespace moco::sim {

// Outcome of a motion command. kOk means accepted (the motor may already be
// on the target: then IsMoving() stays false); everything else is a refusal
// that left the motor untouched.
enum class MoveStatus : uint8_t {
  kOk,
  kDisabled,        // motor not enabled (MSG_MOTOR_CONFIGURE flag 0x01 clear)
  kMoving,          // ResetPosition while moving
  kSoftLimitLower,  // target below the enabled lower soft limit
  kSoftLimitUpper,  // target above the enabled upper soft limit
  kHardLimitLower,  // lower switch tripped and the target is further down
  kHardLimitUpper,  // upper switch tripped and the target is further up
  kEStop,           // e-stop engaged
  kBadArgument,     // jog speed outside 1..10000, non-positive speed limits
  kCoupled,         // the motor follows another (Rig::Couple): it takes no motion of its own
};
std::string_view MoveStatusName(MoveStatus s);

enum class LimitEnd : uint8_t { kLower, kUpper };

// Software step limits (MSG_MOTOR_SET_LIMITS LOWER/UPPER ENABLE and LIMIT).
struct SoftLimits {
  bool lower_enabled = false;
  int64_t lower_steps = 0;
  bool upper_enabled = false;
  int64_t upper_steps = 0;
};

// Where this motor's limit switches sit along its travel, in its steps. The
// upper switch trips on the edge that brings the position to upper_steps
// while moving up (and stays tripped while position >= upper_steps); the
// lower one likewise downwards.
struct SwitchPositions {
  std::optional<int64_t> lower_steps;
  std::optional<int64_t> upper_steps;
};

// Receives a motor's notifications. Called from scheduler callbacks (or from
// the command that caused them, for halts). Must outlive the motor.
class MotorObserver {
 public:
  virtual ~MotorObserver() = default;
  // The motor took a new, non-empty motion plan (also when re-planned while
  // moving). Called after the plan is in place.
  virtual void OnMotionStarted(int /*motor_id*/, TimeNs /*time_ns*/) {}
  // The motor came to rest (end of a move or stop, or a halt) at `steps`.
  virtual void OnMotionFinished(int motor_id, TimeNs time_ns, int64_t steps) = 0;
  // A limit switch tripped during motion; the motor halted on `steps`
  // (OnMotionFinished follows).
  virtual void OnLimitTripped(int motor_id, LimitEnd end, TimeNs time_ns, int64_t steps) = 0;
};

// Receives committed step edges in time order, in batches. Edges are
// committed when motion can no longer change them: at each new command,
// at the end of motion, and on FlushSteps(). Must outlive its registration.
class StepSink {
 public:
  virtual ~StepSink() = default;
  virtual void OnStepEdges(int motor_id, std::span<const StepEdge> edges) = 0;
};

// The jog speed range of MSG_MOTOR_JOG: 1 = inching, 10000 = full speed.
inline constexpr int kJogSpeedMin = 1;
inline constexpr int kJogSpeedMax = 10000;

// The share of the maximum velocity and acceleration a jog at `speed`
// (kJogSpeedMin..kJogSpeedMax) runs at. dmc-v2-protocol.txt MSG_MOTOR_JOG: "A
// value in between 1 and 10,000 should provide an appropriate speed between
// 1% and 100% of the jog speed": 1 (inching) is 1%, 10000 is 100%, linear
// between.
constexpr double JogSpeedFraction(int speed) {
  return 0.01 + 0.99 * static_cast<double>(speed - kJogSpeedMin) / (kJogSpeedMax - kJogSpeedMin);
}

class StepperMotor {
 public:
  // `scheduler` and `observer` (may be null) must outlive the motor. A null
  // planner selects the TrapezoidPlanner. The motor starts enabled, at rest
  // on step 0, with the default MotionProfile and no limits.
  StepperMotor(Scheduler& scheduler, int motor_id, std::unique_ptr<Planner> planner = nullptr,
               MotorObserver* observer = nullptr);
  ~StepperMotor();
  StepperMotor(const StepperMotor&) = delete;
  StepperMotor& operator=(const StepperMotor&) = delete;

  int id() const { return id_; }
  void SetObserver(MotorObserver* observer) { observer_ = observer; }
  // Replaces the planner; takes effect at the next command. REQUIRES: planner.
  void SetPlanner(std::unique_ptr<Planner> planner);

  // --- state at the scheduler's Now() ---
  int64_t Position() const;
  // Step position at time t >= the start of the current motion; earlier
  // times give the position at that start. Future times follow the plan as
  // it stands (a later command may change them).
  int64_t PositionAt(TimeNs t) const;
  double Velocity() const;  // steps/s, signed
  bool IsMoving() const { return moving_; }
  // The step the motor is heading for (its position when at rest).
  int64_t Target() const { return plan_.EndSteps(); }
  // The motion in effect (empty at rest).
  const Plan& CurrentPlan() const { return plan_; }

  // --- commands ---
  // Moves to `target_steps` under the profile's limits, blending from the
  // current velocity. Ends exactly on target unless a switch trips first.
  MoveStatus MoveTo(int64_t target_steps);
  // MSG_MOTOR_JOG: moves to `destination_steps` with velocity and
  // acceleration scaled by speed/10000 (10000 = the profile's maxima);
  // braking uses the full max acceleration. A destination beyond an enabled
  // soft limit stops at the limit instead (refused if already there), unless
  // soft limits do not bound moves (SetSoftLimitsBoundMoves).
  MoveStatus Jog(int64_t destination_steps, int speed);
  // Jog() at the given velocity and acceleration (REQUIRES: both positive
  // and finite) instead of a share of the profile's; braking uses the larger
  // of the acceleration and the profile's max acceleration.
  MoveStatus JogAt(int64_t destination_steps, double velocity_steps_per_s,
                   double accel_steps_per_s2);
  // Decelerates to rest at max acceleration, or at |velocity| / stop_within_s
  // where that is larger (so the stop lasts at most stop_within_s; 0: the
  // max acceleration alone). No-op at rest, and for a following motor (its
  // leader's stop carries it). Soft limits bound the stop: a motor inside an
  // enabled soft limit whose ramp would carry it past the limit brakes
  // harder, to rest on the limit.
  void Stop(double stop_within_s = 0);
  // Decelerates at hard_stop_multiple x max acceleration, bounded by the
  // soft limits as Stop(). No-op at rest and for a following motor.
  void HardStop();
  // Halts at once on the current step (infinite deceleration).
  void EmergencyHalt();
  // Sets the position without moving. Refused (kMoving) while moving.
  MoveStatus ResetPosition(int64_t steps);

  // --- commands on a controller's tick ---
  // A controller that samples its motion plans on a fixed tick (dmc-lite's
  // 20 ms velocity update) starts a move or a stop at its next tick, not on
  // arrival. These take effect at `at_ns` (REQUIRES: at_ns > Now()): the
  // motor counts as moving from now, the plan in force runs on until then,
  // and a later command (these or the ones above) replaces one still
  // waiting. MoveToAt() checks the move now, as MoveTo() does.
  MoveStatus MoveToAt(TimeNs at_ns, int64_t target_steps);
  // Stop(stop_within_s) at `at_ns`, from the motion then.
  void StopAt(TimeNs at_ns, double stop_within_s = 0);
  // A command is waiting for its tick.
  bool CommandPending() const { return pending_timer_ != Scheduler::kNoTimer; }

  // --- configuration ---
  // REQUIRES nothing; non-positive or non-finite values are refused with
  // kBadArgument. A moving motor keeps its current plan until the next command.
  MoveStatus SetProfile(const MotionProfile& profile);
  const MotionProfile& profile() const { return profile_; }
  // Disabling a moving motor halts it at once.
  void SetEnabled(bool enabled);
  bool enabled() const { return enabled_; }
  void SetBlur(bool blur) { blur_ = blur; }
  bool blur() const { return blur_; }
  void SetSoftLimits(const SoftLimits& limits) { soft_ = limits; }
  const SoftLimits& soft_limits() const { return soft_; }
  // Whether the soft limits refuse MoveTo targets beyond them and clamp Jog
  // destinations (default). When false, moves and jogs beyond them complete;
  // the limits still bound Stop() and HardStop().
  void SetSoftLimitsBoundMoves(bool bound) { soft_bounds_moves_ = bound; }
  bool soft_limits_bound_moves() const { return soft_bounds_moves_; }
  // Places the switches; a moving motor already past a switch in its
  // direction of travel trips at once.
  void SetSwitchPositions(const SwitchPositions& switches);
  const SwitchPositions& switch_positions() const { return switches_; }
  // Forces a switch input on or off regardless of position (a wiring fault,
  // an external trip). Forcing on while moving towards that end trips it.
  void SetSwitchForced(LimitEnd end, bool forced);
  bool SwitchTripped(LimitEnd end) const;
  // While inhibited (e-stop) every motion command is refused with kEStop.
  void SetInhibited(bool inhibited) { inhibited_ = inhibited; }
  bool inhibited() const { return inhibited_; }

  // --- coupling (driven by Rig::Couple) ---
  // A following motor refuses MoveTo and Jog (kCoupled) and ignores Stop and
  // HardStop: it moves only by Follow(). EmergencyHalt, ResetPosition,
  // switches and configuration work as for any motor.
  void SetFollowing(bool following) { following_ = following; }
  bool following() const { return following_; }
  // Takes `leader`'s motion from now on: the same segments from this motor's
  // own step, negated when `sign` < 0, so it makes the leader's step edges at
  // the same times (mirrored). An empty leader plan halts the motor where it
  // is. A disabled or inhibited motor does not follow. A plan heading into a
  // tripped limit switch trips it at once (OnLimitTripped). REQUIRES: a
  // non-empty `leader` starts now (origin_ns() == the scheduler's Now()).
  void Follow(const Plan& leader, int sign);

  // --- observation ---
  // REQUIRES: sink outlives the registration. Edges committed from now on.
  void AddStepSink(StepSink* sink);
  void RemoveStepSink(StepSink* sink);
  // Commits (delivers to the sinks) every edge with time <= Now().
  void FlushSteps();
  // Heap bytes held by the motor (plan and buffers), for memory reports.
  size_t HeapBytes() const;

 private:
  MoveStatus CheckCanMove(int64_t target_steps) const;
  // MoveTo()'s plan request under the profile's limits.
  PlanRequest MoveRequest(int64_t target_steps) const;
  // Stop() and HardStop() at `decel_steps_per_s2`, bounded by the soft limits.
  void StopWith(double decel_steps_per_s2);
  // Stop()'s deceleration now.
  double StopDecel(double stop_within_s) const;
  // Replaces the plan with the planner's answer to `req` from Now().
  void Replan(PlanRequest req);
  void InstallPlan(Plan plan);
  void CommitEdges(TimeNs up_to_ns);
  void CancelTimers();
  // Drops a command waiting for its tick (a new command replaces it).
  void CancelPending();
  void ArmPending(TimeNs at_ns);
  void ApplyPending();
  void ScheduleSwitchCheck();
  void OnPlanEnd();
  void OnSwitchTrip(LimitEnd end);
  void Halt();
  int CurrentDirection() const;

  Scheduler& scheduler_;
  const int id_;
  std::unique_ptr<Planner> planner_;
  MotorObserver* observer_;
  MotionProfile profile_;
  SoftLimits soft_;
  SwitchPositions switches_;
  bool forced_lower_ = false;
  bool forced_upper_ = false;
  bool enabled_ = true;
  bool blur_ = false;
  bool inhibited_ = false;
  bool soft_bounds_moves_ = true;
  bool following_ = false;

  Plan plan_;
  bool moving_ = false;
  Scheduler::TimerId end_timer_ = Scheduler::kNoTimer;
  Scheduler::TimerId switch_timer_ = Scheduler::kNoTimer;
  // The command waiting for its tick (MoveToAt, StopAt).
  struct Pending {
    bool stop = false;
    int64_t target_steps = 0;
    double stop_within_s = 0;
  };
  Pending pending_;
  Scheduler::TimerId pending_timer_ = Scheduler::kNoTimer;
  std::vector<StepSink*> sinks_;
  TimeNs committed_ns_ = 0;  // edges with time <= this were delivered
  std::vector<StepEdge> batch_;
};

}  // namespace moco::sim

#endif  // MOCO_SIM_STEPPER_MOTOR_H_
