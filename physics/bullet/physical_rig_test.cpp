// Tests of the device-facing boom rig on the one clock (ARCHITECTURE "One
// clock"; docs/rig-dynamics.md "Stepping on the scheduler"): 1 ms sampling
// while moving, no events while idle, stall and collision callbacks on the
// scheduler's time, state JSON.
#include "physics/bullet/physical_rig.h"

#include <gtest/gtest.h>

#include <cmath>
#include <optional>
#include <vector>

#include "physics/bullet/rig_test_support.h"

namespace moco::physics {
namespace {

using sim::kNsPerMs;
using sim::kNsPerSecond;
using sim::TimeNs;
using test_support::BoomJib;
using test_support::kDeg;
using test_support::Trapezoid;

// A stand-in for a device's motors: each joint's step count follows a
// trapezoid in steps started at a scheduler time, or holds.
class FakeMotors {
 public:
  FakeMotors(sim::Scheduler& scheduler, const RigProfile& profile)
      : scheduler_(scheduler), profile_(profile) {}

  StepCounts Counts() const {
    StepCounts c = held_;
    for (size_t j = 0; j < kJointCount; ++j) {
      if (!moves_[j]) continue;
      const double t_s = static_cast<double>(scheduler_.Now() - starts_[j]) * 1e-9;
      c[j] = std::llround(moves_[j]->At(t_s));
    }
    return c;
  }

  // Starts joint j moving to `target` (SI) at speed and acceleration in SI.
  void Move(Joint j, double target, double v, double a) {
    const size_t i = Index(j);
    const double spu = profile_.joints[i].StepsPerUnit(RigProfile::Prismatic(j));
    held_ = Counts();
    moves_[i] = Trapezoid{static_cast<double>(held_[i]), (target - profile_.joints[i].home) * spu,
                          v * spu, a * spu};
    starts_[i] = scheduler_.Now();
  }
  // Jumps joint j's count at once (as a host writing a position would).
  void Jump(Joint j, double target) {
    const size_t i = Index(j);
    held_ = Counts();
    moves_[i].reset();
    held_[i] = std::llround((target - profile_.joints[i].home) *
                            profile_.joints[i].StepsPerUnit(RigProfile::Prismatic(j)));
  }
  // Holds every count where it is now (a hard stop).
  void Freeze() {
    held_ = Counts();
    for (auto& m : moves_) m.reset();
  }

 private:
  sim::Scheduler& scheduler_;
  const RigProfile& profile_;
  StepCounts held_{};
  std::array<std::optional<Trapezoid>, kJointCount> moves_;
  std::array<TimeNs, kJointCount> starts_{};
};

class PhysicalRigTest : public ::testing::Test {
 protected:
  PhysicalRig MakeRig(PhysicalRig::Callbacks callbacks = {}) {
    return PhysicalRig(
        scheduler_, profile_, [this] { return motors_.Counts(); }, std::move(callbacks));
  }

  sim::Scheduler scheduler_;
  RigProfile profile_ = BoomJib();
  FakeMotors motors_{scheduler_, profile_};
};

TEST_F(PhysicalRigTest, AnIdleRigSettlesThenSchedulesNothing) {
  PhysicalRig rig = MakeRig();
  EXPECT_TRUE(rig.awake());  // settling under gravity
  scheduler_.RunUntilIdle(100'000);
  EXPECT_FALSE(rig.awake());
  EXPECT_EQ(scheduler_.PendingCount(), 0u);
  const int64_t settled_after = rig.steps_taken();
  EXPECT_LT(settled_after, 5000);
  // One step per millisecond while awake.
  EXPECT_EQ(scheduler_.Now(), settled_after * kNsPerMs);
  scheduler_.RunUntil(scheduler_.Now() + 60 * kNsPerSecond);
  EXPECT_EQ(rig.steps_taken(), settled_after);
  EXPECT_EQ(scheduler_.PendingCount(), 0u);
}

TEST_F(PhysicalRigTest, APlannedPauseKeepsTheRigAwakeSoTheMoveAfterItIsFollowed) {
  bool planned = false;
  PhysicalRig rig = MakeRig(
      {.on_stall = nullptr, .on_collision = nullptr, .motion_planned = [&] { return planned; }});
  scheduler_.RunUntilIdle(100'000);
  ASSERT_FALSE(rig.awake());
  // A move whose first second holds still (the counts do not change).
  planned = true;
  rig.Wake();
  scheduler_.RunUntil(scheduler_.Now() + 1 * kNsPerSecond);
  EXPECT_TRUE(rig.awake());
  motors_.Move(Joint::kTrack, 0.3, 0.2, 0.5);  // no Wake: the rig is still sampling
  scheduler_.RunUntil(scheduler_.Now() + 3 * kNsPerSecond);
  planned = false;
  scheduler_.RunUntilIdle(100'000);
  EXPECT_FALSE(rig.awake());
  EXPECT_NEAR(rig.dynamics().PhysicalJoints()[0], 0.3, 1e-3);
}

TEST_F(PhysicalRigTest, FollowsAMoveWithLagAndSleepsWhenItIsOver) {
  PhysicalRig rig = MakeRig();
  scheduler_.RunUntilIdle(100'000);
  const TimeNs start = scheduler_.Now();
  motors_.Move(Joint::kTrack, 1.0, 0.2, 0.5);
  rig.Wake();
  scheduler_.RunUntil(start + 300 * kNsPerMs);  // accelerating
  EXPECT_TRUE(rig.awake());
  const nlohmann::json mid = rig.StateJson();
  EXPECT_GT(mid["joints"]["track"]["following_error"].get<double>(), 0);
  EXPECT_EQ(mid["joints"]["track"]["unit"], "m");
  scheduler_.RunUntilIdle(100'000);
  EXPECT_FALSE(rig.awake());
  const double duration_s = Trapezoid{0, 1.0, 0.2, 0.5}.Duration();
  // It slept within a second after the counts stopped changing.
  EXPECT_GT(scheduler_.Now(), start + static_cast<TimeNs>(duration_s * 1e9));
  EXPECT_LT(scheduler_.Now(), start + static_cast<TimeNs>((duration_s + 1.0) * 1e9));
  const double spu = profile_.joint(Joint::kTrack).StepsPerUnit(true);
  EXPECT_NEAR(rig.dynamics().PhysicalJoints()[0], 1.0, 1.0 / spu);
  EXPECT_EQ(rig.StateJson()["joints"]["track"]["lost_steps"], 0);
}

TEST_F(PhysicalRigTest, AHeadCollisionCallsBackOnTheSchedulersTimeAndAStopHolds) {
  std::vector<CollisionEvent> hits;
  std::vector<TimeNs> when;
  PhysicalRig rig = MakeRig({.on_stall = nullptr,
                             .on_collision =
                                 [&](const CollisionEvent& c) {
                                   hits.push_back(c);
                                   when.push_back(scheduler_.Now());
                                   motors_.Freeze();  // the device's e-stop
                                 },
                             .motion_planned = nullptr});
  scheduler_.RunUntilIdle(100'000);
  const TimeNs start = scheduler_.Now();
  motors_.Move(Joint::kBoom, -60 * kDeg, 10 * kDeg, 20 * kDeg);
  rig.Wake();
  scheduler_.RunUntilIdle(100'000);
  ASSERT_EQ(hits.size(), 1u);
  EXPECT_EQ(hits[0].what, "floor");
  EXPECT_EQ(hits[0].time_ns, when[0]);
  EXPECT_GT(hits[0].time_ns, start);
  // Stopped near the touching angle (about -53 deg), not at -60.
  const double boom = rig.dynamics().PhysicalJoints()[Index(Joint::kBoom)];
  EXPECT_GT(boom, -56 * kDeg);
  EXPECT_FALSE(rig.awake());
  const nlohmann::json state = rig.StateJson();
  EXPECT_EQ(state["collisions"], 1);
  EXPECT_EQ(state["contact"], "floor");
}

TEST_F(PhysicalRigTest, AStallCallsBackWithTheEpisodeOnTheSchedulersClock) {
  std::vector<StallEvent> stalls;
  PhysicalRig rig = MakeRig({.on_stall = [&](const StallEvent& s) { stalls.push_back(s); },
                             .on_collision = nullptr,
                             .motion_planned = nullptr});
  scheduler_.RunUntilIdle(100'000);
  scheduler_.RunUntil(scheduler_.Now() + 5 * kNsPerSecond);  // idle for a while
  const TimeNs jump_at = scheduler_.Now();
  motors_.Jump(Joint::kTrack, 0.4);
  rig.Wake();
  scheduler_.RunUntilIdle(100'000);
  ASSERT_FALSE(stalls.empty());
  EXPECT_EQ(stalls[0].joint, Joint::kTrack);
  EXPECT_GE(stalls[0].time_ns, jump_at);
  EXPECT_LE(stalls[0].time_ns, jump_at + 3 * kNsPerMs);
  EXPECT_GE(stalls[0].end_ns, stalls[0].time_ns);
  int64_t lost = 0;
  for (const StallEvent& s : stalls) lost += s.lost_steps;
  EXPECT_GT(lost, 0);
  const nlohmann::json state = rig.StateJson();
  EXPECT_EQ(state["joints"]["track"]["lost_steps"], lost);
  EXPECT_EQ(state["joints"]["track"]["stalls"], static_cast<int64_t>(stalls.size()));
  EXPECT_FALSE(state["joints"]["track"]["stalled"].get<bool>());
}

TEST_F(PhysicalRigTest, ARebasedCountJumpMovesNothingAndLaterMovesAreRelativeToIt) {
  std::vector<StallEvent> stalls;
  PhysicalRig rig = MakeRig({.on_stall = [&](const StallEvent& s) { stalls.push_back(s); },
                             .on_collision = nullptr,
                             .motion_planned = nullptr});
  motors_.Move(Joint::kTrack, 0.5, 0.2, 0.5);
  rig.Wake();
  scheduler_.RunUntilIdle(100'000);
  const double before = rig.dynamics().PhysicalJoints()[0];
  ASSERT_NEAR(before, 0.5, 1e-3);
  // The host zeroes the track's count where it stands (MOTOR_RESET_POSITION).
  motors_.Jump(Joint::kTrack, profile_.joint(Joint::kTrack).home);
  rig.Rebase();
  scheduler_.RunUntilIdle(100'000);
  EXPECT_TRUE(stalls.empty());
  EXPECT_NEAR(rig.dynamics().PhysicalJoints()[0], before, 1e-6);
  EXPECT_NEAR(rig.dynamics().CommandedJoints()[0], 0.5, 1e-9);
  // Counts from the new zero: +0.3 m of count is 0.8 m of track.
  motors_.Move(Joint::kTrack, profile_.joint(Joint::kTrack).home + 0.3, 0.2, 0.5);
  rig.Wake();
  scheduler_.RunUntilIdle(100'000);
  EXPECT_NEAR(rig.dynamics().PhysicalJoints()[0], 0.8, 1e-3);
  EXPECT_TRUE(stalls.empty());
  // Without Rebase the same jump is a lurch the stepper cannot follow.
  motors_.Jump(Joint::kTrack, profile_.joint(Joint::kTrack).home);
  rig.Wake();
  scheduler_.RunUntilIdle(100'000);
  EXPECT_FALSE(stalls.empty());
}

TEST_F(PhysicalRigTest, StateReportsPoseAndRevoluteJointsInDegrees) {
  motors_.Jump(Joint::kBoom, 20 * kDeg);  // where the rig starts
  PhysicalRig rig = MakeRig();
  scheduler_.RunUntilIdle(100'000);
  const nlohmann::json state = rig.StateJson();
  const nlohmann::json& boom = state["joints"]["boom"];
  EXPECT_EQ(boom["unit"], "deg");
  EXPECT_NEAR(boom["commanded"].get<double>(), 20.0, 1e-3);
  // Sagging: physical below commanded, error = commanded - physical.
  EXPECT_LT(boom["physical"].get<double>(), 20.0);
  EXPECT_NEAR(boom["following_error"].get<double>(),
              boom["commanded"].get<double>() - boom["physical"].get<double>(), 1e-9);
  ASSERT_EQ(state["pose"]["nodal_m"].size(), 3u);
  const Point3 nodal = rig.dynamics().Pose().nodal_m;
  EXPECT_EQ(state["pose"]["nodal_m"][2].get<double>(), nodal[2]);
  EXPECT_TRUE(state["contact"].is_null());
  EXPECT_EQ(state["awake"], false);
  for (std::string_view name : kJointNames) EXPECT_TRUE(state["joints"].contains(name));
}

}  // namespace
}  // namespace moco::physics
