// Tests for limit sets and the e-stop (dmc-v2-protocol.txt MSG_MOTOR_SET_LIMITS
// HW SET with flag 0x80, MSG_MOTOR_STOP_ALL, MSG_MOTOR_HARD_STOP reasons).
#include "sim/rig.h"

#include <gtest/gtest.h>

#include <vector>

namespace moco::sim {
namespace {

struct Events : RigObserver {
  struct Trip {
    int motor;
    LimitEnd end;
    int set;
    SwitchInput input;
    int64_t steps;
  };
  std::vector<Trip> trips;
  std::vector<bool> estop;
  std::vector<int> finished;
  void OnMotionFinished(int motor_id, TimeNs, int64_t) override { finished.push_back(motor_id); }
  void OnLimitTripped(int motor_id, LimitEnd end, int set, SwitchInput input, TimeNs,
                      int64_t steps) override {
    trips.push_back({motor_id, end, set, input, steps});
  }
  void OnEStop(bool engaged, TimeNs) override { estop.push_back(engaged); }
};

class RigTest : public ::testing::Test {
 protected:
  Scheduler sched_;
  Events events_;
  Rig rig_{sched_, 3, 2, &events_};
};

TEST(HardLimitBindingTest, WireByteCarriesSetAndSwapFlag) {
  EXPECT_EQ(HardLimitBinding::FromWire(0x00), (HardLimitBinding{0, false}));
  EXPECT_EQ(HardLimitBinding::FromWire(0x02), (HardLimitBinding{2, false}));
  EXPECT_EQ(HardLimitBinding::FromWire(0x81), (HardLimitBinding{1, true}));
  EXPECT_EQ((HardLimitBinding{1, true}).ToWire(), 0x81);
}

TEST_F(RigTest, MovingMaskHasBitNMinus1ForMotorN) {
  EXPECT_EQ(rig_.MovingMask(), 0u);
  rig_.motor(3).MoveTo(100);
  EXPECT_EQ(rig_.MovingMask(), 0b100u);
  rig_.motor(1).MoveTo(100);
  EXPECT_EQ(rig_.MovingMask(), 0b101u);
  sched_.RunUntilIdle();
  EXPECT_FALSE(rig_.AnyMoving());
  EXPECT_EQ(events_.finished.size(), 2u);
}

TEST_F(RigTest, UnswappedSetTripsHighInputAtTheUpperEnd) {
  ASSERT_TRUE(rig_.SetLimitPlacement(1, {-100, 500}));
  ASSERT_EQ(rig_.BindLimits(2, HardLimitBinding::FromWire(0x01)), MoveStatus::kOk);
  rig_.motor(2).MoveTo(1000);
  sched_.RunUntilIdle();
  ASSERT_EQ(events_.trips.size(), 1u);
  EXPECT_EQ(events_.trips[0].motor, 2);
  EXPECT_EQ(events_.trips[0].end, LimitEnd::kUpper);
  EXPECT_EQ(events_.trips[0].set, 1);
  EXPECT_EQ(events_.trips[0].input, SwitchInput::kHigh);
  EXPECT_EQ(events_.trips[0].steps, 500);
  EXPECT_TRUE(rig_.InputActive(1, SwitchInput::kHigh));
  EXPECT_FALSE(rig_.InputActive(1, SwitchInput::kLow));
  EXPECT_EQ(rig_.motor(2).MoveTo(600), MoveStatus::kHardLimitUpper);
  EXPECT_EQ(rig_.motor(2).MoveTo(-1000), MoveStatus::kOk);
  sched_.RunUntilIdle();
  ASSERT_EQ(events_.trips.size(), 2u);
  EXPECT_EQ(events_.trips[1].input, SwitchInput::kLow);
  EXPECT_EQ(events_.trips[1].steps, -100);
}

TEST_F(RigTest, SwapFlagMakesTheLowInputGuardTheUpperEnd) {
  // A rig wired the other way round: the set's low input sits at +800.
  ASSERT_TRUE(rig_.SetLimitPlacement(2, {800, -300}));
  ASSERT_EQ(rig_.BindLimits(1, HardLimitBinding::FromWire(0x82)), MoveStatus::kOk);
  rig_.motor(1).MoveTo(5000);
  sched_.RunUntilIdle();
  ASSERT_EQ(events_.trips.size(), 1u);
  EXPECT_EQ(events_.trips[0].end, LimitEnd::kUpper);
  EXPECT_EQ(events_.trips[0].input, SwitchInput::kLow);
  EXPECT_EQ(events_.trips[0].steps, 800);
  rig_.motor(1).MoveTo(-5000);
  sched_.RunUntilIdle();
  ASSERT_EQ(events_.trips.size(), 2u);
  EXPECT_EQ(events_.trips[1].end, LimitEnd::kLower);
  EXPECT_EQ(events_.trips[1].input, SwitchInput::kHigh);
  EXPECT_EQ(events_.trips[1].steps, -300);
}

TEST_F(RigTest, BindingRejectsUnknownMotorOrSet) {
  EXPECT_EQ(rig_.BindLimits(0, {1, false}), MoveStatus::kBadArgument);
  EXPECT_EQ(rig_.BindLimits(4, {1, false}), MoveStatus::kBadArgument);
  EXPECT_EQ(rig_.BindLimits(1, {3, false}), MoveStatus::kBadArgument);
  EXPECT_FALSE(rig_.SetLimitPlacement(0, {}));
  EXPECT_FALSE(rig_.SetLimitPlacement(3, {}));
}

TEST_F(RigTest, ForcedInputHaltsTheBoundMotorMovingTowardsIt) {
  rig_.BindLimits(3, {1, false});
  rig_.motor(3).MoveTo(100000);
  rig_.motor(2).MoveTo(100000);  // unbound: unaffected
  sched_.RunUntil(1'000'000'000);
  rig_.ForceInput(1, SwitchInput::kHigh, true);
  EXPECT_FALSE(rig_.motor(3).IsMoving());
  EXPECT_TRUE(rig_.motor(2).IsMoving());
  ASSERT_EQ(events_.trips.size(), 1u);
  EXPECT_EQ(events_.trips[0].motor, 3);
  EXPECT_EQ(events_.trips[0].input, SwitchInput::kHigh);
  EXPECT_TRUE(rig_.InputActive(1, SwitchInput::kHigh));
  rig_.ForceInput(1, SwitchInput::kHigh, false);
  EXPECT_FALSE(rig_.InputActive(1, SwitchInput::kHigh));
  EXPECT_EQ(rig_.motor(3).MoveTo(200000), MoveStatus::kOk);
}

TEST_F(RigTest, EStopHaltsEveryMotorAndRefusesMovesUntilReleased) {
  for (int id = 1; id <= 3; ++id) rig_.motor(id).MoveTo(100000 * id);
  sched_.RunUntil(2'000'000'000);
  std::vector<int64_t> at;
  for (int id = 1; id <= 3; ++id) at.push_back(rig_.motor(id).Position());
  rig_.EngageEStop();
  EXPECT_EQ(events_.estop, std::vector<bool>{true});
  EXPECT_EQ(rig_.MovingMask(), 0u);
  EXPECT_EQ(events_.finished.size(), 3u);
  sched_.RunUntil(10'000'000'000);
  for (int id = 1; id <= 3; ++id) {
    EXPECT_EQ(rig_.motor(id).Position(), at[static_cast<size_t>(id - 1)]);
    EXPECT_EQ(rig_.motor(id).MoveTo(0), MoveStatus::kEStop);
    EXPECT_EQ(rig_.motor(id).Jog(0, 100), MoveStatus::kEStop);
  }
  rig_.ReleaseEStop();
  EXPECT_EQ(events_.estop, (std::vector<bool>{true, false}));
  EXPECT_EQ(rig_.motor(1).MoveTo(0), MoveStatus::kOk);
}

TEST_F(RigTest, StopAllDeceleratesAndHardStopAllIsShorter) {
  auto distance = [](bool hard) {
    Scheduler s;
    Rig rig(s, 2, 0);
    MotionProfile p;
    p.max_velocity_steps_per_s = 2000;
    p.max_accel_steps_per_s2 = 1000;
    p.hard_stop_multiple = 4;
    rig.motor(1).SetProfile(p);
    rig.motor(1).MoveTo(1'000'000);
    s.RunUntil(3'000'000'000);
    const int64_t at = rig.motor(1).Position();
    hard ? rig.HardStopAll() : rig.StopAll();
    s.RunUntilIdle();
    return rig.motor(1).Position() - at;
  };
  EXPECT_NEAR(static_cast<double>(distance(false)), 2000, 1);  // v^2/2a
  EXPECT_NEAR(static_cast<double>(distance(true)), 500, 1);
}

// Capability 0x0100 "Couple motors": followers take every plan of their
// leader (moves, stop ramps) step for step, mirrored when reversed.
TEST_F(RigTest, CoupledMotorsFollowTheirLeaderThroughMovesAndStops) {
  ASSERT_EQ(rig_.Couple(2, 1, false), MoveStatus::kOk);
  ASSERT_EQ(rig_.Couple(3, 2, true), MoveStatus::kOk);  // a chain: 3 follows 2 follows 1
  EXPECT_EQ(rig_.Root(3), 1);
  EXPECT_EQ(rig_.leader(3), 2);
  EXPECT_TRUE(rig_.coupled_reversed(3));
  EXPECT_EQ(rig_.motor(2).MoveTo(5), MoveStatus::kCoupled);
  ASSERT_EQ(rig_.motor(3).ResetPosition(1000), MoveStatus::kOk);
  ASSERT_EQ(rig_.motor(1).MoveTo(100000), MoveStatus::kOk);
  EXPECT_EQ(rig_.MovingMask(), 0b111u);
  sched_.RunUntil(2'000'000'000);
  EXPECT_EQ(rig_.motor(2).Position(), rig_.motor(1).Position());
  EXPECT_EQ(rig_.motor(3).Position(), 1000 - rig_.motor(1).Position());
  rig_.StopAll();
  sched_.RunUntilIdle();
  const int64_t p1 = rig_.motor(1).Position();
  EXPECT_LT(p1, 100000);
  EXPECT_EQ(rig_.motor(2).Position(), p1);
  EXPECT_EQ(rig_.motor(3).Position(), 1000 - p1);
  // The leader finished first; the last follower's rest is the last event.
  ASSERT_EQ(events_.finished.size(), 3u);
  EXPECT_EQ(events_.finished.front(), 1);
  // Changing the coupling while moving is refused; a cycle never forms.
  EXPECT_EQ(rig_.Couple(1, 3, false), MoveStatus::kBadArgument);
  EXPECT_EQ(rig_.Couple(1, 1, false), MoveStatus::kBadArgument);
  rig_.motor(1).MoveTo(0);
  EXPECT_EQ(rig_.Uncouple(2), MoveStatus::kMoving);
  sched_.RunUntilIdle();
  ASSERT_EQ(rig_.Uncouple(2), MoveStatus::kOk);
  EXPECT_EQ(rig_.Root(3), 2);
  EXPECT_EQ(rig_.motor(2).MoveTo(10), MoveStatus::kOk);
}

TEST_F(RigTest, ALimitSwitchOnAFollowerHaltsTheWholeGroupBeforeTheTripIsHeard) {
  struct Watch : RigObserver {
    Rig* rig = nullptr;
    uint32_t moving_at_trip = 0xffffffff;
    std::vector<int> order;  // motor ids: trips as -id, finishes as +id
    void OnMotionFinished(int motor_id, TimeNs, int64_t) override { order.push_back(motor_id); }
    void OnLimitTripped(int motor_id, LimitEnd, int, SwitchInput, TimeNs, int64_t) override {
      moving_at_trip = rig->MovingMask();
      order.push_back(-motor_id);
    }
  } watch;
  watch.rig = &rig_;
  rig_.SetObserver(&watch);
  ASSERT_TRUE(rig_.SetLimitPlacement(1, {-100, 300}));
  ASSERT_EQ(rig_.BindLimits(2, {1, false}), MoveStatus::kOk);
  ASSERT_EQ(rig_.Couple(2, 1, false), MoveStatus::kOk);
  ASSERT_EQ(rig_.motor(1).MoveTo(5000), MoveStatus::kOk);
  sched_.RunUntilIdle();
  EXPECT_EQ(watch.moving_at_trip, 0u) << "the leader halted with the follower";
  EXPECT_EQ(rig_.motor(1).Position(), 300);
  EXPECT_EQ(rig_.motor(2).Position(), 300);
  EXPECT_EQ(watch.order, (std::vector<int>{-2, 1, 2}));
  // Driving the leader on into the follower's tripped switch trips it at once.
  watch.order.clear();
  ASSERT_EQ(rig_.motor(1).MoveTo(400), MoveStatus::kOk);
  EXPECT_FALSE(rig_.AnyMoving());
  EXPECT_EQ(rig_.motor(1).Position(), 300);
  ASSERT_FALSE(watch.order.empty());
  EXPECT_EQ(watch.order.front(), -2);
  // Away from the switch the group moves again.
  ASSERT_EQ(rig_.motor(1).MoveTo(0), MoveStatus::kOk);
  sched_.RunUntilIdle();
  EXPECT_EQ(rig_.motor(2).Position(), 0);
}

}  // namespace
}  // namespace moco::sim
