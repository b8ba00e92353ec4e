// The motors of one device with their limit sets, the e-stop input and motor
// coupling (dmc-v2-protocol.txt MSG_MOTOR_STOP_ALL, MSG_MOTOR_SET_LIMITS,
// MSG_MOTOR_HARD_STOP reason 0 "E-Stop", 1 upper limit, 2 lower limit;
// capability 0x0100 "Couple motors").
#ifndef MOCO_SIM_RIG_H_
#define MOCO_SIM_RIG_H_

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "sim/limits.h"
#include "sim/scheduler.h"
#include "sim/stepper_motor.h"

namespace moco::sim {

// What a device hears from its rig. Default implementations ignore.
class RigObserver {
 public:
  virtual ~RigObserver() = default;
  // `motor_id` took a new motion plan (a move, a jog, a script, a stop ramp),
  // whoever commanded it: a host request or one of the device's own timers.
  virtual void OnMotionStarted(int /*motor_id*/, TimeNs /*time_ns*/) {}
  virtual void OnMotionFinished(int /*motor_id*/, TimeNs /*time_ns*/, int64_t /*steps*/) {}
  // A limit switch tripped while `motor_id` moved towards `end`; `set` and
  // `input` name the hardware input (set 0 for a switch without a set).
  virtual void OnLimitTripped(int /*motor_id*/, LimitEnd /*end*/, int /*set*/,
                              SwitchInput /*input*/, TimeNs /*time_ns*/, int64_t /*steps*/) {}
  // The e-stop input changed (engaged: every motor halted).
  virtual void OnEStop(bool /*engaged*/, TimeNs /*time_ns*/) {}
};

// Owns motors 1..motor_count and limit sets 1..limit_set_count.
class Rig final : private MotorObserver {
 public:
  // `scheduler` and `observer` (may be null) must outlive the rig. Every
  // motor gets `planner_factory()` (null: the trapezoid planner).
  using PlannerFactory = std::unique_ptr<Planner> (*)();
  Rig(Scheduler& scheduler, int motor_count, int limit_set_count, RigObserver* observer = nullptr,
      PlannerFactory planner_factory = nullptr);
  Rig(const Rig&) = delete;
  Rig& operator=(const Rig&) = delete;

  void SetObserver(RigObserver* observer) { observer_ = observer; }
  int motor_count() const { return static_cast<int>(motors_.size()); }
  int limit_set_count() const { return static_cast<int>(placements_.size()); }
  bool ValidMotor(int motor_id) const { return motor_id >= 1 && motor_id <= motor_count(); }
  // REQUIRES: ValidMotor(motor_id).
  StepperMotor& motor(int motor_id) { return *motors_[static_cast<size_t>(motor_id - 1)]; }
  const StepperMotor& motor(int motor_id) const {
    return *motors_[static_cast<size_t>(motor_id - 1)];
  }

  // Bit (n-1) set when motor n moves (MSG_MOTOR_STATUS, ERRATA dmc 5).
  uint32_t MovingMask() const;
  bool AnyMoving() const { return MovingMask() != 0; }
  // Every motor's Stop(stop_within_s).
  void StopAll(double stop_within_s = 0);
  // Every motor's StopAt(at_ns, stop_within_s): a stop on the controller's
  // next tick (StepperMotor::StopAt).
  void StopAllAt(TimeNs at_ns, double stop_within_s = 0);
  void HardStopAll();

  // --- limit sets ---
  // Places set `set`'s switches. Returns false for a set outside 1..count.
  bool SetLimitPlacement(int set, const LimitSetPlacement& placement);
  // Binds a motor to a set (set 0 unbinds). kBadArgument for an unknown
  // motor or set.
  MoveStatus BindLimits(int motor_id, HardLimitBinding binding);
  HardLimitBinding binding(int motor_id) const {
    return bindings_[static_cast<size_t>(motor_id - 1)];
  }
  // Level of an input: tripped by the position of a bound motor, or forced.
  bool InputActive(int set, SwitchInput input) const;
  // Forces an input on/off (wiring fault, a hand on the switch): every motor
  // bound to the set sees its corresponding end forced.
  void ForceInput(int set, SwitchInput input, bool active);

  // --- coupling ---
  // Couples `follower` to `leader`: every motion plan the leader takes from
  // now on (a move, a jog, a script, a stop ramp), the follower takes too,
  // step for step at the same times, mirrored when `reversed`; a halt of the
  // leader halts it. The follower refuses motion of its own (kCoupled) and
  // its Stop() is a no-op: stop its Root(). A limit switch tripping on any
  // motor of a coupled group halts the whole group. Leaders may themselves
  // follow (a chain). kBadArgument for unknown or equal motors or a cycle;
  // kMoving while either motor moves (nothing changes then). Re-coupling a
  // follower replaces its leader.
  MoveStatus Couple(int follower, int leader, bool reversed);
  // Lets `follower` go: it stays where it is and takes commands again.
  // kMoving while it moves; kOk for a motor that did not follow.
  MoveStatus Uncouple(int follower);
  // The motor `motor_id` follows, or 0.
  int leader(int motor_id) const { return leaders_[static_cast<size_t>(motor_id - 1)].motor; }
  bool coupled_reversed(int motor_id) const {
    return leaders_[static_cast<size_t>(motor_id - 1)].reversed;
  }
  // The head of `motor_id`'s chain of leaders (itself when it follows none).
  int Root(int motor_id) const;

  // --- e-stop ---
  // Halts every motor at once and refuses motion (kEStop) until released.
  void EngageEStop();
  void ReleaseEStop();
  bool estop_engaged() const { return estop_; }

  size_t HeapBytes() const;

 private:
  void OnMotionStarted(int motor_id, TimeNs time_ns) override;
  void OnMotionFinished(int motor_id, TimeNs time_ns, int64_t steps) override;
  void OnLimitTripped(int motor_id, LimitEnd end, TimeNs time_ns, int64_t steps) override;
  // The input of the motor's set that guards `end`.
  static SwitchInput InputFor(HardLimitBinding b, LimitEnd end);
  void ApplyPlacement(int motor_id);
  // Followers of `leader` take its current plan (a halt when it rests).
  void Propagate(int leader);

  struct Coupling {
    int motor = 0;  // the leader, 0 for none
    bool reversed = false;
  };
  struct Finished {
    int motor_id;
    TimeNs time_ns;
    int64_t steps;
  };

  Scheduler& scheduler_;
  RigObserver* observer_;
  std::vector<std::unique_ptr<StepperMotor>> motors_;
  std::vector<HardLimitBinding> bindings_;
  std::vector<LimitSetPlacement> placements_;
  std::vector<uint8_t> forced_;    // per set: bit 0 low, bit 1 high
  std::vector<Coupling> leaders_;  // per motor
  bool estop_ = false;
  // While a limit trip halts a coupled group, the group's OnMotionFinished
  // wait until the observer has heard of the trip.
  bool defer_finished_ = false;
  std::vector<Finished> deferred_;
};

}  // namespace moco::sim

#endif  // MOCO_SIM_RIG_H_
