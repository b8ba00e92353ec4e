// A step-accurate stepper motor (dmc-v2-protocol.txt MSG_MOTOR_* sections):
// commands become plans; events only at plan ends and switch crossings.
#include "sim/stepper_motor.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "sim/planner_trapezoid.h"

namespace moco::sim {
namespace {

constexpr size_t kEdgeBatch = 256;

bool Positive(double v) { return std::isfinite(v) && v > 0; }

// The velocities of a chunked run, mirrored: piece j moves at minus the
// original's velocity at the mirrored position.
class MirroredChunks final : public ChunkVelocities {
 public:
  explicit MirroredChunks(std::shared_ptr<const ChunkVelocities> inner)
      : inner_(std::move(inner)) {}
  double Velocity(int64_t j, double x_steps) const override {
    return -inner_->Velocity(j, -x_steps);
  }
  size_t HeapBytes() const override { return inner_->HeapBytes(); }

 private:
  std::shared_ptr<const ChunkVelocities> inner_;
};

}  // namespace

std::string_view MoveStatusName(MoveStatus s) {
  switch (s) {
    case MoveStatus::kOk:
      return "ok";
    case MoveStatus::kDisabled:
      return "disabled";
    case MoveStatus::kMoving:
      return "moving";
    case MoveStatus::kSoftLimitLower:
      return "soft-limit-lower";
    case MoveStatus::kSoftLimitUpper:
      return "soft-limit-upper";
    case MoveStatus::kHardLimitLower:
      return "hard-limit-lower";
    case MoveStatus::kHardLimitUpper:
      return "hard-limit-upper";
    case MoveStatus::kEStop:
      return "e-stop";
    case MoveStatus::kBadArgument:
      return "bad-argument";
    case MoveStatus::kCoupled:
      return "coupled";
  }
  return "?";
}

StepperMotor::StepperMotor(Scheduler& scheduler, int motor_id, std::unique_ptr<Planner> planner,
                           MotorObserver* observer)
    : scheduler_(scheduler),
      id_(motor_id),
      planner_(planner ? std::move(planner) : std::make_unique<TrapezoidPlanner>()),
      observer_(observer),
      plan_(Plan::Build(scheduler.Now(), 0, 0, {})),
      committed_ns_(scheduler.Now()) {}

StepperMotor::~StepperMotor() {
  CancelTimers();
  CancelPending();
}

void StepperMotor::SetPlanner(std::unique_ptr<Planner> planner) {
  if (planner) planner_ = std::move(planner);
}

int64_t StepperMotor::Position() const { return plan_.StepsAt(scheduler_.Now()); }

int64_t StepperMotor::PositionAt(TimeNs t) const { return plan_.StepsAt(t); }

double StepperMotor::Velocity() const {
  if (!moving_) return 0;
  return plan_.StateAt(scheduler_.Now()).v_steps_per_s;
}

MoveStatus StepperMotor::CheckCanMove(int64_t target_steps) const {
  if (following_) return MoveStatus::kCoupled;
  if (!enabled_) return MoveStatus::kDisabled;
  if (inhibited_) return MoveStatus::kEStop;
  if (soft_bounds_moves_) {
    if (soft_.upper_enabled && target_steps > soft_.upper_steps) return MoveStatus::kSoftLimitUpper;
    if (soft_.lower_enabled && target_steps < soft_.lower_steps) return MoveStatus::kSoftLimitLower;
  }
  const int64_t p = Position();
  if (target_steps > p && SwitchTripped(LimitEnd::kUpper)) return MoveStatus::kHardLimitUpper;
  if (target_steps < p && SwitchTripped(LimitEnd::kLower)) return MoveStatus::kHardLimitLower;
  return MoveStatus::kOk;
}

PlanRequest StepperMotor::MoveRequest(int64_t target_steps) const {
  PlanRequest req;
  req.kind = PlanRequest::Kind::kMoveTo;
  req.target_steps = target_steps;
  req.max_velocity_steps_per_s = profile_.max_velocity_steps_per_s;
  req.max_accel_steps_per_s2 = profile_.max_accel_steps_per_s2;
  return req;
}

MoveStatus StepperMotor::MoveTo(int64_t target_steps) {
  const MoveStatus status = CheckCanMove(target_steps);
  if (status != MoveStatus::kOk) return status;
  Replan(MoveRequest(target_steps));
  return MoveStatus::kOk;
}

MoveStatus StepperMotor::Jog(int64_t destination_steps, int speed) {
  if (following_) return MoveStatus::kCoupled;
  if (speed < kJogSpeedMin || speed > kJogSpeedMax) return MoveStatus::kBadArgument;
  const double scale = JogSpeedFraction(speed);
  return JogAt(destination_steps, profile_.max_velocity_steps_per_s * scale,
               profile_.max_accel_steps_per_s2 * scale);
}

MoveStatus StepperMotor::JogAt(int64_t destination_steps, double velocity_steps_per_s,
                               double accel_steps_per_s2) {
  if (following_) return MoveStatus::kCoupled;
  if (!(velocity_steps_per_s > 0) || !(accel_steps_per_s2 > 0) ||
      !std::isfinite(velocity_steps_per_s) || !std::isfinite(accel_steps_per_s2)) {
    return MoveStatus::kBadArgument;
  }
  const int64_t p = Position();
  int64_t dest = destination_steps;
  if (soft_bounds_moves_ && soft_.upper_enabled && dest > soft_.upper_steps) {
    if (p >= soft_.upper_steps) return MoveStatus::kSoftLimitUpper;
    dest = soft_.upper_steps;
  }
  if (soft_bounds_moves_ && soft_.lower_enabled && dest < soft_.lower_steps) {
    if (p <= soft_.lower_steps) return MoveStatus::kSoftLimitLower;
    dest = soft_.lower_steps;
  }
  const MoveStatus status = CheckCanMove(dest);
  if (status != MoveStatus::kOk) return status;
  PlanRequest req;
  req.kind = PlanRequest::Kind::kMoveTo;
  req.target_steps = dest;
  req.max_velocity_steps_per_s = velocity_steps_per_s;
  req.max_accel_steps_per_s2 = accel_steps_per_s2;
  // Braking (to reverse, to slow to the jog speed, to arrive) uses the full
  // deceleration: a slow jog must not coast for minutes after a fast move.
  req.decel_steps_per_s2 = std::max(profile_.max_accel_steps_per_s2, accel_steps_per_s2);
  Replan(req);
  return MoveStatus::kOk;
}

void StepperMotor::Stop(double stop_within_s) {
  if (!moving_ || following_) return;
  StopWith(StopDecel(stop_within_s));
}

double StepperMotor::StopDecel(double stop_within_s) const {
  const double decel = profile_.max_accel_steps_per_s2;
  if (!(stop_within_s > 0)) return decel;
  return std::max(decel, std::fabs(plan_.StateAt(scheduler_.Now()).v_steps_per_s) / stop_within_s);
}

void StepperMotor::HardStop() {
  if (!moving_ || following_) return;
  StopWith(profile_.max_accel_steps_per_s2 * profile_.hard_stop_multiple);
}

MoveStatus StepperMotor::MoveToAt(TimeNs at_ns, int64_t target_steps) {
  const MoveStatus status = CheckCanMove(target_steps);
  if (status != MoveStatus::kOk) return status;
  pending_ = Pending{.stop = false, .target_steps = target_steps, .stop_within_s = 0};
  ArmPending(at_ns);
  return MoveStatus::kOk;
}

void StepperMotor::StopAt(TimeNs at_ns, double stop_within_s) {
  if (!moving_ || following_) return;
  pending_ = Pending{.stop = true, .target_steps = 0, .stop_within_s = stop_within_s};
  ArmPending(at_ns);
}

void StepperMotor::ArmPending(TimeNs at_ns) {
  if (pending_timer_ != Scheduler::kNoTimer) scheduler_.Cancel(pending_timer_);
  moving_ = true;
  pending_timer_ = scheduler_.At(at_ns, [this] { ApplyPending(); });
}

void StepperMotor::CancelPending() {
  if (pending_timer_ != Scheduler::kNoTimer) scheduler_.Cancel(pending_timer_);
  pending_timer_ = Scheduler::kNoTimer;
}

void StepperMotor::ApplyPending() {
  pending_timer_ = Scheduler::kNoTimer;
  const TimeNs now = scheduler_.Now();
  if (!pending_.stop) {
    Replan(MoveRequest(pending_.target_steps));
    return;
  }
  if (plan_.empty() || now >= plan_.EndNs()) {
    // A stop for a move that had not started, or that ended meanwhile.
    const int64_t steps = Position();
    Halt();
    if (observer_ != nullptr) observer_->OnMotionFinished(id_, now, steps);
    return;
  }
  StopWith(StopDecel(pending_.stop_within_s));
}

void StepperMotor::StopWith(double decel_steps_per_s2) {
  const KinematicState s = plan_.StateAt(scheduler_.Now());
  const double x = static_cast<double>(plan_.origin_steps()) + s.x_steps;
  const double v = s.v_steps_per_s;
  // A stop never carries a motor past a soft limit it is still inside of:
  // it brakes as hard as needed to come to rest on the limit.
  std::optional<double> room;
  const double reach = v * v / (2 * decel_steps_per_s2);
  if (v > 0 && soft_.upper_enabled) {
    const auto limit = static_cast<double>(soft_.upper_steps);
    if (x <= limit && x + reach > limit) room = limit - x;
  } else if (v < 0 && soft_.lower_enabled) {
    const auto limit = static_cast<double>(soft_.lower_steps);
    if (x >= limit && x - reach < limit) room = x - limit;
  }
  if (room) {
    if (!(*room > 0)) {
      EmergencyHalt();
      return;
    }
    decel_steps_per_s2 = v * v / (2 * *room);
  }
  PlanRequest req;
  req.kind = PlanRequest::Kind::kStop;
  req.decel_steps_per_s2 = decel_steps_per_s2;
  Replan(req);
}

void StepperMotor::Follow(const Plan& leader, int sign) {
  if (leader.empty() || leader.origin_ns() != scheduler_.Now()) {
    EmergencyHalt();
    return;
  }
  if (!enabled_ || inhibited_) return;
  std::vector<Segment> segments = leader.segments();
  const double start_x = segments.front().x0_steps * (sign < 0 ? -1 : 1);
  if (sign < 0) {
    // Negation is exact in floating point, and the step thresholds sit
    // symmetrically at +-1/2: the mirrored plan's edges fall at the very
    // same nanoseconds as the leader's.
    for (Segment& seg : segments) {
      seg.x0_steps = -seg.x0_steps;
      seg.v0_steps_per_s = -seg.v0_steps_per_s;
      seg.a_steps_per_s2 = -seg.a_steps_per_s2;
      if (seg.chunk_velocities) {
        seg.chunk_velocities = std::make_shared<MirroredChunks>(seg.chunk_velocities);
      }
    }
  }
  const TimeNs now = scheduler_.Now();
  CommitEdges(now);
  const int64_t p = plan_.StepsAt(now);
  InstallPlan(Plan::Build(now, p, start_x, segments, leader.step_quantum_ns()));
  if (!moving_) return;
  // Heading into a switch that is already tripped: it trips at once, as a
  // motor placed past a switch does (SetSwitchPositions).
  const int dir = CurrentDirection();
  if (dir > 0 && SwitchTripped(LimitEnd::kUpper)) return OnSwitchTrip(LimitEnd::kUpper);
  if (dir < 0 && SwitchTripped(LimitEnd::kLower)) return OnSwitchTrip(LimitEnd::kLower);
}

void StepperMotor::EmergencyHalt() {
  if (!moving_) return;
  const int64_t steps = Position();
  Halt();
  if (observer_ != nullptr) observer_->OnMotionFinished(id_, scheduler_.Now(), steps);
}

MoveStatus StepperMotor::ResetPosition(int64_t steps) {
  if (moving_) return MoveStatus::kMoving;
  const TimeNs now = scheduler_.Now();
  CommitEdges(now);
  plan_ = Plan::Build(now, steps, 0, {});
  return MoveStatus::kOk;
}

MoveStatus StepperMotor::SetProfile(const MotionProfile& profile) {
  if (!Positive(profile.max_velocity_steps_per_s) || !Positive(profile.max_accel_steps_per_s2) ||
      !Positive(profile.hard_stop_multiple)) {
    return MoveStatus::kBadArgument;
  }
  profile_ = profile;
  return MoveStatus::kOk;
}

void StepperMotor::SetEnabled(bool enabled) {
  enabled_ = enabled;
  if (!enabled_) EmergencyHalt();
}

void StepperMotor::SetSwitchPositions(const SwitchPositions& switches) {
  switches_ = switches;
  if (!moving_) return;
  const int dir = CurrentDirection();
  if (dir > 0 && SwitchTripped(LimitEnd::kUpper)) return OnSwitchTrip(LimitEnd::kUpper);
  if (dir < 0 && SwitchTripped(LimitEnd::kLower)) return OnSwitchTrip(LimitEnd::kLower);
  ScheduleSwitchCheck();
}

void StepperMotor::SetSwitchForced(LimitEnd end, bool forced) {
  (end == LimitEnd::kUpper ? forced_upper_ : forced_lower_) = forced;
  if (!forced || !moving_) return;
  const int dir = CurrentDirection();
  if ((end == LimitEnd::kUpper && dir > 0) || (end == LimitEnd::kLower && dir < 0)) {
    OnSwitchTrip(end);
  }
}

bool StepperMotor::SwitchTripped(LimitEnd end) const {
  if (end == LimitEnd::kUpper) {
    return forced_upper_ || (switches_.upper_steps && Position() >= *switches_.upper_steps);
  }
  return forced_lower_ || (switches_.lower_steps && Position() <= *switches_.lower_steps);
}

void StepperMotor::AddStepSink(StepSink* sink) {
  if (sink == nullptr || std::find(sinks_.begin(), sinks_.end(), sink) != sinks_.end()) return;
  CommitEdges(scheduler_.Now());  // the new sink sees edges from now on
  sinks_.push_back(sink);
  batch_.reserve(kEdgeBatch);
}

void StepperMotor::RemoveStepSink(StepSink* sink) { std::erase(sinks_, sink); }

void StepperMotor::FlushSteps() { CommitEdges(scheduler_.Now()); }

size_t StepperMotor::HeapBytes() const {
  return plan_.HeapBytes() + sinks_.capacity() * sizeof(StepSink*) +
         batch_.capacity() * sizeof(StepEdge);
}

void StepperMotor::Replan(PlanRequest req) {
  const TimeNs now = scheduler_.Now();
  CommitEdges(now);
  const int64_t p = plan_.StepsAt(now);
  KinematicState start;
  if (moving_ && now < plan_.EndNs()) {
    const KinematicState s = plan_.StateAt(now);
    start.x_steps = s.x_steps - static_cast<double>(p - plan_.origin_steps());
    start.v_steps_per_s = s.v_steps_per_s;
  }
  req.now_ns = now;
  req.start = start;
  req.target_steps -= p;
  InstallPlan(Plan::Build(now, p, start.x_steps, planner_->Plan(req), planner_->StepQuantumNs()));
}

void StepperMotor::InstallPlan(Plan plan) {
  CancelTimers();
  CancelPending();
  const bool was_moving = moving_;
  plan_ = std::move(plan);
  if (plan_.empty()) {
    moving_ = false;
    if (was_moving && observer_ != nullptr) {
      observer_->OnMotionFinished(id_, scheduler_.Now(), plan_.origin_steps());
    }
    return;
  }
  moving_ = true;
  end_timer_ = scheduler_.At(plan_.EndNs(), [this] { OnPlanEnd(); });
  ScheduleSwitchCheck();
  if (observer_ != nullptr) observer_->OnMotionStarted(id_, scheduler_.Now());
}

void StepperMotor::CommitEdges(TimeNs up_to_ns) {
  if (up_to_ns <= committed_ns_) return;
  if (!sinks_.empty()) {
    auto deliver = [this] {
      for (StepSink* sink : sinks_) sink->OnStepEdges(id_, batch_);
      batch_.clear();
    };
    plan_.ForEachEdge(committed_ns_, up_to_ns, [&](const StepEdge& e) {
      batch_.push_back(e);
      if (batch_.size() == kEdgeBatch) deliver();
    });
    if (!batch_.empty()) deliver();
  }
  committed_ns_ = up_to_ns;
}

void StepperMotor::CancelTimers() {
  if (end_timer_ != Scheduler::kNoTimer) scheduler_.Cancel(end_timer_);
  if (switch_timer_ != Scheduler::kNoTimer) scheduler_.Cancel(switch_timer_);
  end_timer_ = Scheduler::kNoTimer;
  switch_timer_ = Scheduler::kNoTimer;
}

void StepperMotor::ScheduleSwitchCheck() {
  if (switch_timer_ != Scheduler::kNoTimer) scheduler_.Cancel(switch_timer_);
  switch_timer_ = Scheduler::kNoTimer;
  if (!moving_) return;
  const TimeNs now = scheduler_.Now();
  std::optional<TimeNs> upper;
  std::optional<TimeNs> lower;
  if (switches_.upper_steps) upper = plan_.TimeOfStep(*switches_.upper_steps, +1, now);
  if (switches_.lower_steps) lower = plan_.TimeOfStep(*switches_.lower_steps, -1, now);
  if (!upper && !lower) return;
  const bool upper_first = upper && (!lower || *upper <= *lower);
  const LimitEnd end = upper_first ? LimitEnd::kUpper : LimitEnd::kLower;
  const TimeNs when = upper_first ? *upper : *lower;
  switch_timer_ = scheduler_.At(when, [this, end] {
    switch_timer_ = Scheduler::kNoTimer;
    OnSwitchTrip(end);
  });
}

void StepperMotor::OnPlanEnd() {
  end_timer_ = Scheduler::kNoTimer;
  const TimeNs now = scheduler_.Now();
  CommitEdges(now);
  const int64_t steps = plan_.EndSteps();
  CancelTimers();
  plan_ = Plan::Build(now, steps, 0, {});
  // Still moving for its owner: a command starts at the next tick.
  if (CommandPending()) return;
  moving_ = false;
  if (observer_ != nullptr) observer_->OnMotionFinished(id_, now, steps);
}

void StepperMotor::OnSwitchTrip(LimitEnd end) {
  const TimeNs now = scheduler_.Now();
  const int64_t steps = Position();
  Halt();
  if (observer_ != nullptr) {
    observer_->OnLimitTripped(id_, end, now, steps);
    observer_->OnMotionFinished(id_, now, steps);
  }
}

void StepperMotor::Halt() {
  const TimeNs now = scheduler_.Now();
  CommitEdges(now);
  const int64_t steps = plan_.StepsAt(now);
  CancelTimers();
  CancelPending();
  plan_ = Plan::Build(now, steps, 0, {});
  moving_ = false;
}

int StepperMotor::CurrentDirection() const {
  const double v = Velocity();
  if (v > 0) return 1;
  if (v < 0) return -1;
  if (!moving_) return 0;
  const int64_t delta = plan_.EndSteps() - Position();
  return delta > 0 ? 1 : (delta < 0 ? -1 : 0);
}

}  // namespace moco::sim
