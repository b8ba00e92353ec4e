// The device-facing boom rig on the one clock (ARCHITECTURE "One clock",
// house style 15; model in docs/rig-dynamics.md "Stepping on the scheduler").
#include "physics/bullet/physical_rig.h"

#include <cmath>
#include <numbers>
#include <utility>

namespace moco::physics {

PhysicalRig::PhysicalRig(sim::Scheduler& scheduler, const RigProfile& profile, CommandSource source,
                         Callbacks callbacks)
    : scheduler_(scheduler),
      dynamics_(profile),
      source_(std::move(source)),
      callbacks_(std::move(callbacks)) {
  last_counts_ = source_();
  dynamics_.Reset(ToJoints(last_counts_));
  Wake();
}

PhysicalRig::~PhysicalRig() { scheduler_.Cancel(timer_); }

void PhysicalRig::Wake() {
  rest_ticks_ = 0;
  if (timer_ == sim::Scheduler::kNoTimer) {
    timer_ = scheduler_.After(kStepNs, [this] { Tick(); });
  }
}

void PhysicalRig::Rebase() {
  const StepCounts counts = source_();
  for (size_t j = 0; j < kJointCount; ++j) shift_[j] += last_counts_[j] - counts[j];
  last_counts_ = counts;
  Wake();
}

JointVector PhysicalRig::ToJoints(const StepCounts& counts) const {
  const RigProfile& p = dynamics_.profile();
  JointVector q{};
  for (size_t j = 0; j < kJointCount; ++j) {
    const bool prismatic = RigProfile::Prismatic(static_cast<Joint>(j));
    q[j] = p.joints[j].home +
           static_cast<double>(counts[j] + shift_[j]) / p.joints[j].StepsPerUnit(prismatic);
  }
  return q;
}

void PhysicalRig::Tick() {
  timer_ = sim::Scheduler::kNoTimer;
  const StepCounts counts = source_();
  const StepEvents& events = dynamics_.Step(ToJoints(counts));
  ++steps_taken_;
  // Dynamics time runs only while awake, one step per tick, and a stall
  // episode never spans a sleep: map its times onto the scheduler's clock.
  const sim::TimeNs offset_ns = scheduler_.Now() - dynamics_.time_ns();
  collision_count_ += static_cast<int64_t>(events.collisions.size());

  bool at_rest = counts == last_counts_ && dynamics_.MaxSpeed() < kRestSpeed &&
                 !(callbacks_.motion_planned && callbacks_.motion_planned());
  for (size_t j = 0; j < kJointCount; ++j) {
    if (dynamics_.Stalled(static_cast<Joint>(j))) at_rest = false;
  }
  last_counts_ = counts;
  rest_ticks_ = at_rest ? rest_ticks_ + 1 : 0;
  if (rest_ticks_ < kRestTicks) timer_ = scheduler_.After(kStepNs, [this] { Tick(); });

  // Only Tick steps the dynamics, so `events` stays valid through callbacks.
  for (StallEvent s : events.stalls) {
    s.time_ns += offset_ns;
    s.end_ns += offset_ns;
    if (callbacks_.on_stall) callbacks_.on_stall(s);
  }
  for (CollisionEvent c : events.collisions) {
    c.time_ns += offset_ns;
    if (callbacks_.on_collision) callbacks_.on_collision(c);
  }
}

nlohmann::json PhysicalRig::StateJson() const {
  using nlohmann::json;
  const JointVector commanded = dynamics_.CommandedJoints();
  const JointVector physical = dynamics_.PhysicalJoints();
  const JointVector error = dynamics_.FollowingError();
  const auto lost = dynamics_.LostSteps();
  const auto stalls = dynamics_.StallCounts();
  json joints = json::object();
  for (size_t j = 0; j < kJointCount; ++j) {
    const Joint joint = static_cast<Joint>(j);
    const bool prismatic = RigProfile::Prismatic(joint);
    const double scale = prismatic ? 1.0 : 180.0 / std::numbers::pi;
    joints[std::string(kJointNames[j])] = {
        {"unit", prismatic ? "m" : "deg"},
        {"commanded", commanded[j] * scale},
        {"physical", physical[j] * scale},
        {"following_error", error[j] * scale},
        {"lost_steps", lost[j]},
        {"stalls", stalls[j]},
        {"stalled", dynamics_.Stalled(joint)},
    };
  }
  const HeadPose pose = dynamics_.Pose();
  const std::optional<std::string> contact = dynamics_.Contact();
  return json{
      {"time_ns", scheduler_.Now()},
      {"awake", awake()},
      {"steps", steps_taken_},
      {"pose", {{"nodal_m", pose.nodal_m}, {"view", pose.view}, {"up", pose.up}}},
      {"joints", joints},
      {"contact", contact ? json(*contact) : json(nullptr)},
      {"collisions", collision_count_},
  };
}

}  // namespace moco::physics
