// The motors of one device, their limit sets and the e-stop
// (dmc-v2-protocol.txt MSG_MOTOR_STOP_ALL / SET_LIMITS / HARD_STOP).
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

void Rig::StopAll() {
  for (auto& m : motors_) m->Stop();
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
             placements_.capacity() * sizeof(placements_[0]) + forced_.capacity();
  for (const auto& m : motors_) n += sizeof(StepperMotor) + m->HeapBytes();
  return n;
}

void Rig::OnMotionStarted(int motor_id, TimeNs time_ns) {
  if (observer_ != nullptr) observer_->OnMotionStarted(motor_id, time_ns);
}

void Rig::OnMotionFinished(int motor_id, TimeNs time_ns, int64_t steps) {
  if (observer_ != nullptr) observer_->OnMotionFinished(motor_id, time_ns, steps);
}

void Rig::OnLimitTripped(int motor_id, LimitEnd end, TimeNs time_ns, int64_t steps) {
  if (observer_ == nullptr) return;
  const HardLimitBinding b = binding(motor_id);
  observer_->OnLimitTripped(motor_id, end, b.set, InputFor(b, end), time_ns, steps);
}

}  // namespace moco::sim
