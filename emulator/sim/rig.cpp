// The motors of one device, their limit sets, the e-stop and coupling
// (dmc-v2-protocol.txt MSG_MOTOR_STOP_ALL / SET_LIMITS / HARD_STOP,
// capability 0x0100 "Couple motors").
#include "sim/rig.h"

namespace moco::sim {
namespace {

uint8_t InputBit(SwitchInput input) { return input == SwitchInput::kLow ? 1 : 2; }

}  // namespace

Rig::Rig(Scheduler& scheduler, int motor_count, int limit_set_count, RigObserver* observer,
         PlannerFactory planner_factory)
    : scheduler_(scheduler), observer_(observer) {
  MotorObserver* self = this;  // the private base, converted where accessible
  for (int id = 1; id <= motor_count; ++id) {
    motors_.push_back(std::make_unique<StepperMotor>(
        scheduler_, id, planner_factory ? planner_factory() : nullptr, self));
  }
  bindings_.resize(motors_.size());
  leaders_.resize(motors_.size());
  placements_.resize(limit_set_count > 0 ? static_cast<size_t>(limit_set_count) : 0);
  forced_.resize(placements_.size());
}

uint32_t Rig::MovingMask() const {
  uint32_t mask = 0;
  for (size_t i = 0; i < motors_.size() && i < 32; ++i) {
    if (motors_[i]->IsMoving()) mask |= 1u << i;
  }
  return mask;
}

void Rig::StopAll(double stop_within_s) {
  for (auto& m : motors_) m->Stop(stop_within_s);
}

void Rig::StopAllAt(TimeNs at_ns, double stop_within_s) {
  for (auto& m : motors_) m->StopAt(at_ns, stop_within_s);
}

void Rig::HardStopAll() {
  for (auto& m : motors_) m->HardStop();
}

bool Rig::SetLimitPlacement(int set, const LimitSetPlacement& placement) {
  if (set < 1 || set > limit_set_count()) return false;
  placements_[static_cast<size_t>(set - 1)] = placement;
  for (int id = 1; id <= motor_count(); ++id) {
    if (binding(id).set == set) ApplyPlacement(id);
  }
  return true;
}

MoveStatus Rig::BindLimits(int motor_id, HardLimitBinding b) {
  if (!ValidMotor(motor_id) || b.set > limit_set_count()) return MoveStatus::kBadArgument;
  bindings_[static_cast<size_t>(motor_id - 1)] = b;
  ApplyPlacement(motor_id);
  return MoveStatus::kOk;
}

SwitchInput Rig::InputFor(HardLimitBinding b, LimitEnd end) {
  const bool upper = end == LimitEnd::kUpper;
  return upper != b.swapped ? SwitchInput::kHigh : SwitchInput::kLow;
}

void Rig::ApplyPlacement(int motor_id) {
  StepperMotor& m = motor(motor_id);
  const HardLimitBinding b = binding(motor_id);
  if (b.set == 0) {
    m.SetSwitchForced(LimitEnd::kUpper, false);
    m.SetSwitchForced(LimitEnd::kLower, false);
    m.SetSwitchPositions({});
    return;
  }
  const LimitSetPlacement& p = placements_[b.set - 1];
  auto where = [&](SwitchInput in) {
    return in == SwitchInput::kLow ? p.low_input_steps : p.high_input_steps;
  };
  const uint8_t forced = forced_[b.set - 1];
  const SwitchInput up = InputFor(b, LimitEnd::kUpper);
  const SwitchInput down = InputFor(b, LimitEnd::kLower);
  m.SetSwitchPositions({where(down), where(up)});
  m.SetSwitchForced(LimitEnd::kUpper, (forced & InputBit(up)) != 0);
  m.SetSwitchForced(LimitEnd::kLower, (forced & InputBit(down)) != 0);
}

bool Rig::InputActive(int set, SwitchInput input) const {
  if (set < 1 || set > limit_set_count()) return false;
  if ((forced_[static_cast<size_t>(set - 1)] & InputBit(input)) != 0) return true;
  for (int id = 1; id <= motor_count(); ++id) {
    const HardLimitBinding b = binding(id);
    if (b.set != set) continue;
    const LimitEnd end =
        InputFor(b, LimitEnd::kUpper) == input ? LimitEnd::kUpper : LimitEnd::kLower;
    if (motor(id).SwitchTripped(end)) return true;
  }
  return false;
}

void Rig::ForceInput(int set, SwitchInput input, bool active) {
  if (set < 1 || set > limit_set_count()) return;
  uint8_t& f = forced_[static_cast<size_t>(set - 1)];
  f = static_cast<uint8_t>(active ? (f | InputBit(input)) : (f & ~InputBit(input)));
  for (int id = 1; id <= motor_count(); ++id) {
    const HardLimitBinding b = binding(id);
    if (b.set != set) continue;
    const LimitEnd end =
        InputFor(b, LimitEnd::kUpper) == input ? LimitEnd::kUpper : LimitEnd::kLower;
    motor(id).SetSwitchForced(end, active);
  }
}

MoveStatus Rig::Couple(int follower, int leader_id, bool reversed) {
  if (!ValidMotor(follower) || !ValidMotor(leader_id) || follower == leader_id) {
    return MoveStatus::kBadArgument;
  }
  for (int m = leader_id; m != 0; m = leader(m)) {
    if (m == follower) return MoveStatus::kBadArgument;  // the leader follows it
  }
  if (motor(follower).IsMoving() || motor(leader_id).IsMoving()) return MoveStatus::kMoving;
  leaders_[static_cast<size_t>(follower - 1)] = Coupling{leader_id, reversed};
  motor(follower).SetFollowing(true);
  return MoveStatus::kOk;
}

MoveStatus Rig::Uncouple(int follower) {
  if (!ValidMotor(follower)) return MoveStatus::kBadArgument;
  if (leader(follower) == 0) return MoveStatus::kOk;
  if (motor(follower).IsMoving()) return MoveStatus::kMoving;
  leaders_[static_cast<size_t>(follower - 1)] = Coupling{};
  motor(follower).SetFollowing(false);
  return MoveStatus::kOk;
}

int Rig::Root(int motor_id) const {
  int m = motor_id;
  while (leader(m) != 0) m = leader(m);
  return m;
}

void Rig::Propagate(int leader_id) {
  for (int f = 1; f <= motor_count(); ++f) {
    if (leader(f) != leader_id) continue;
    // Fetched for each follower: a follower's trip may have halted the leader.
    const StepperMotor& l = motor(leader_id);
    if (l.IsMoving()) {
      motor(f).Follow(l.CurrentPlan(), coupled_reversed(f) ? -1 : 1);
    } else {
      motor(f).EmergencyHalt();
    }
  }
}

void Rig::EngageEStop() {
  if (estop_) return;
  estop_ = true;
  for (auto& m : motors_) {
    m->SetInhibited(true);
    m->EmergencyHalt();
  }
  if (observer_ != nullptr) observer_->OnEStop(true, scheduler_.Now());
}

void Rig::ReleaseEStop() {
  if (!estop_) return;
  estop_ = false;
  for (auto& m : motors_) m->SetInhibited(false);
  if (observer_ != nullptr) observer_->OnEStop(false, scheduler_.Now());
}

size_t Rig::HeapBytes() const {
  size_t n = motors_.capacity() * sizeof(motors_[0]) + bindings_.capacity() * sizeof(bindings_[0]) +
             placements_.capacity() * sizeof(placements_[0]) + forced_.capacity() +
             leaders_.capacity() * sizeof(leaders_[0]);
  for (const auto& m : motors_) n += sizeof(StepperMotor) + m->HeapBytes();
  return n;
}

void Rig::OnMotionStarted(int motor_id, TimeNs time_ns) {
  Propagate(motor_id);
  if (observer_ != nullptr) observer_->OnMotionStarted(motor_id, time_ns);
}

void Rig::OnMotionFinished(int motor_id, TimeNs time_ns, int64_t steps) {
  // The observer hears of the leader first, while its followers still move,
  // so that "every motor at rest" is seen once, on the last of them.
  if (defer_finished_) {
    deferred_.push_back({motor_id, time_ns, steps});
  } else if (observer_ != nullptr) {
    observer_->OnMotionFinished(motor_id, time_ns, steps);
  }
  if (!motor(motor_id).IsMoving()) Propagate(motor_id);
}

void Rig::OnLimitTripped(int motor_id, LimitEnd end, TimeNs time_ns, int64_t steps) {
  // A coupled group is one mechanism: a switch on any of its motors halts
  // all of them, before the observer hears of the trip (so that whatever it
  // does in answer finds the group at rest).
  const int root = Root(motor_id);
  const bool outer = !defer_finished_;
  defer_finished_ = true;
  for (int m = 1; m <= motor_count(); ++m) {
    if (m != motor_id && Root(m) == root) motor(m).EmergencyHalt();
  }
  defer_finished_ = !outer;
  if (observer_ != nullptr) {
    const HardLimitBinding b = binding(motor_id);
    observer_->OnLimitTripped(motor_id, end, b.set, InputFor(b, end), time_ns, steps);
  }
  if (!outer) return;
  std::vector<Finished> finished;
  finished.swap(deferred_);
  for (const Finished& f : finished) {
    if (observer_ != nullptr) observer_->OnMotionFinished(f.motor_id, f.time_ns, f.steps);
  }
}

}  // namespace moco::sim
