// The DMC-16 driving the Bullet-modelled boom rig (profile `physical_rig`,
// fixtures/profiles/dmc16-boom.json; docs/rig-dynamics.md): the rig follows
// the motors, reports its pose through State(), and a collision of the camera
// head with the floor stops every motor with MOTOR_HARD_STOP REASON 0, as an
// e-stop does (dmc-v2-protocol.txt MSG_MOTOR_HARD_STOP).
#include <gtest/gtest.h>

#include <cstdlib>

#include "devices/dmc16/dmc16_test_support.h"

namespace moco::devices {
namespace {

using testing::Host;

// MOTOR_MOVE is answered with its specific response (not an ACK) when accepted.
bool Moves(Host& h, uint8_t motor, int32_t steps) {
  const uint32_t id = h.Send(dmc::MotorMove{motor, steps});
  return std::holds_alternative<dmc::MotorMoveResponse>(h.Reply(id).msg);
}

Dmc16Profile BoomProfile() {
  const char* root = std::getenv("MOCO_SOURCE_DIR");
  return LoadDmc16Profile(std::string(root ? root : ".") + "/fixtures/profiles/dmc16-boom.json");
}

// Boom motor 3: 3200 steps/rev x 100:1 gear = 888.9 steps per degree (boom-jib.json).
constexpr double kBoomStepsPerDeg = 3200.0 * 100.0 / 360.0;

TEST(Dmc16PhysicalRig, TheProfileLoadsTheRigAndTheStateShowsItsPose) {
  Host h(BoomProfile());
  ASSERT_NE(h.device().physical_rig(), nullptr);
  h.RunMs(600);  // settles under gravity
  const nlohmann::json s = h.device().State();
  ASSERT_TRUE(s["physical_rig"].is_object()) << s.dump();
  EXPECT_TRUE(s["physical_rig"].contains("pose"));
  EXPECT_EQ(s["physical_rig"]["collisions"], 0);
  // Without the profile entry there is no physical rig.
  Host plain;
  EXPECT_EQ(plain.device().physical_rig(), nullptr);
  EXPECT_TRUE(plain.device().State()["physical_rig"].is_null());
}

TEST(Dmc16PhysicalRig, ABoomMoveIsFollowedByThePhysicalJoint) {
  Host h(BoomProfile());
  const int32_t target = static_cast<int32_t>(20 * kBoomStepsPerDeg);
  ASSERT_TRUE(Moves(h, 3, target));
  h.RunMs(8000);
  ASSERT_EQ(h.Pos(3), target);
  const auto& dyn = h.device().physical_rig()->dynamics();
  const double boom_deg =
      dyn.PhysicalJoints()[static_cast<size_t>(physics::Joint::kBoom)] * 180.0 / 3.14159265358979;
  // It follows to within the sag under gravity (well under a degree).
  EXPECT_NEAR(boom_deg, 20.0, 1.0);
  EXPECT_EQ(h.All<dmc::MotorHardStop>().size(), 0u);
}

TEST(Dmc16PhysicalRig, DrivingTheHeadIntoTheFloorHardStopsEveryMotor) {
  Host h(BoomProfile());
  const int32_t floor_target = static_cast<int32_t>(-59 * kBoomStepsPerDeg);
  ASSERT_TRUE(Moves(h, 3, floor_target));
  ASSERT_TRUE(Moves(h, 1, 80000));  // the track moves too (16 s)
  h.RunMs(20000);
  const auto stops = h.All<dmc::MotorHardStop>();
  ASSERT_EQ(stops.size(), 1u);
  EXPECT_EQ(stops[0].second.reason, static_cast<uint8_t>(dmc::HardStopReason::kEStop));
  // Every motor halted short of its target, and nothing moves any more.
  EXPECT_GT(h.Pos(3), floor_target);
  EXPECT_LT(h.Pos(1), 80000);
  EXPECT_FALSE(h.device().rig_ref().motor(3).IsMoving());
  EXPECT_FALSE(h.device().rig_ref().motor(1).IsMoving());
  const nlohmann::json s = h.device().State();
  // The head may touch again while it settles at rest: counted, nothing to stop.
  EXPECT_GE(s["physical_rig"]["collisions"].get<int>(), 1);
  EXPECT_EQ(s["physical_rig"]["last_collision"], "floor");
  // The e-stop chain re-armed: the device accepts a move away again.
  EXPECT_FALSE(s["estop"].get<bool>());
  EXPECT_TRUE(Moves(h, 3, 0));
}

}  // namespace
}  // namespace moco::devices
