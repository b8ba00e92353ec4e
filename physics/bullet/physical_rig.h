// The boom rig as a device sees it (ARCHITECTURE house style 15): motor step
// counts in, the physical rig stepped at 1 kHz on the one clock while it moves
// or settles, stall and collision events out, state as JSON. No Bullet types.
#ifndef MOCO_PHYSICS_BULLET_PHYSICAL_RIG_H_
#define MOCO_PHYSICS_BULLET_PHYSICAL_RIG_H_

#include <array>
#include <cstdint>
#include <functional>

#include <nlohmann/json.hpp>

#include "physics/bullet/rig_dynamics.h"
#include "sim/scheduler.h"

namespace moco::physics {

// Motor step counts of the six joints, in Joint order.
using StepCounts = std::array<int64_t, kJointCount>;

// Samples the commanded step counts every 1 ms of simulated time while
// awake, steps the dynamics, and goes to sleep (no pending timer, no cost)
// once the command has not changed, no motion is planned and every joint is
// at rest for kRestTicks steps. The device calls Wake() whenever a commanded
// count may start changing (a motor takes a motion plan); a sleeping rig does
// not poll.
class PhysicalRig {
 public:
  // Sampled once per step; must be cheap and must not call back into the rig.
  using CommandSource = std::function<StepCounts()>;
  struct Callbacks {
    // A stepper lost steps (reported when it is back in step). `time_ns` on
    // the scheduler's clock is when the episode began.
    std::function<void(const StallEvent&)> on_stall;
    // The head began to touch the floor or an obstacle (a device e-stops).
    std::function<void(const CollisionEvent&)> on_collision;
    // Optional, sampled once per step: whether the device still has motion
    // planned for a driving motor. The rig does not go to sleep while it has,
    // even if the counts hold still for a while (a planned pause in a move).
    std::function<bool()> motion_planned;
  };

  // Joint speeds (m/s or rad/s) below this count as rest.
  static constexpr double kRestSpeed = 1e-4;
  static constexpr int kRestTicks = 50;

  // `scheduler` must outlive the rig. The rig starts at the commanded
  // position sampled now and wakes to settle under gravity.
  // REQUIRES: a profile ParseRigProfile accepted; `source` non-empty.
  PhysicalRig(sim::Scheduler& scheduler, const RigProfile& profile, CommandSource source,
              Callbacks callbacks = {});
  ~PhysicalRig();
  PhysicalRig(const PhysicalRig&) = delete;
  PhysicalRig& operator=(const PhysicalRig&) = delete;

  // Resumes 1 ms stepping (no effect while awake, except restarting the rest count).
  void Wake();
  bool awake() const { return timer_ != sim::Scheduler::kNoTimer; }

  // The device relabelled its step counts without moving a motor (a
  // position reset, the counts restarting at 0 on power-on): the joints stay
  // where they are and the counts sampled now name the present command from
  // here on. A rig that followed the old counts does not lurch to the new ones.
  void Rebase();

  // Step counts -> SI joint positions (home + (steps + rebase shift) / steps
  // per unit; the shift is 0 until the first Rebase).
  JointVector ToJoints(const StepCounts& counts) const;

  const BoomRigDynamics& dynamics() const { return dynamics_; }
  // Dynamics steps taken so far.
  int64_t steps_taken() const { return steps_taken_; }
  int64_t collision_count() const { return collision_count_; }

  // State for the control channel: pose, per joint commanded / physical /
  // following error (m or deg), lost steps and stalls, contact.
  nlohmann::json StateJson() const;

 private:
  void Tick();

  sim::Scheduler& scheduler_;
  BoomRigDynamics dynamics_;
  CommandSource source_;
  Callbacks callbacks_;
  sim::Scheduler::TimerId timer_ = sim::Scheduler::kNoTimer;
  StepCounts last_counts_{};
  StepCounts shift_{};  // added to sampled counts (Rebase)
  int rest_ticks_ = 0;
  int64_t steps_taken_ = 0;
  int64_t collision_count_ = 0;
};

}  // namespace moco::physics

#endif  // MOCO_PHYSICS_BULLET_PHYSICAL_RIG_H_
