// The DMC-16 driving the Bullet-modelled boom rig (profile `physical_rig`,
// fixtures/profiles/dmc16-boom.json; docs/rig-dynamics.md): the rig follows
// the motors, reports its pose through State(), and a collision of the camera
// head with the floor stops every motor with MOTOR_HARD_STOP REASON 0, as an
// e-stop does (dmc-v2-protocol.txt MSG_MOTOR_HARD_STOP).
#include <gtest/gtest.h>

#include <cstdlib>
#include <string>
#include <vector>

#include "devices/dmc16/dmc16_profile.h"
#include "devices/dmc16/dmc16_test_support.h"
#include "devices/profile.h"

namespace moco::devices {
namespace {

using testing::Host;

// MOTOR_MOVE is answered with its specific response (not an ACK) when accepted.
bool Moves(Host& h, uint8_t motor, int32_t steps) {
  const uint32_t id = h.Send(dmc::MotorMove{motor, steps});
  return std::holds_alternative<dmc::MotorMoveResponse>(h.Reply(id).msg);
}

std::string ProfilesDir() {
  const char* root = std::getenv("MOCO_SOURCE_DIR");
  return std::string(root ? root : ".") + "/fixtures/profiles";
}

Dmc16Profile BoomProfile() { return LoadDmc16Profile(ProfilesDir() + "/dmc16-boom.json"); }

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

TEST(Dmc16PhysicalRig, ACollisionIsReportedAsADeviceEvent) {
  Host h(BoomProfile());
  std::vector<nlohmann::json> events;
  h.device().SetEventListener([&](const nlohmann::json& e) { events.push_back(e); });
  ASSERT_TRUE(Moves(h, 3, static_cast<int32_t>(-59 * kBoomStepsPerDeg)));
  h.RunMs(15000);
  ASSERT_FALSE(events.empty());
  EXPECT_EQ(events[0]["event"], "collision");
  EXPECT_EQ(events[0]["with"], "floor");
  EXPECT_EQ(events[0]["halted_motors"], true);
  EXPECT_GT(events[0]["began_ns"].get<int64_t>(), 0);
  for (const auto& e : events) EXPECT_NE(e["event"], "stall") << e.dump();
}

TEST(Dmc16PhysicalRig, RaisingTheBoomFasterThanItsMotorCarriesReportsAStall) {
  Host h(BoomProfile());
  std::vector<nlohmann::json> events;
  h.device().SetEventListener([&](const nlohmann::json& e) { events.push_back(e); });
  // 40 deg/s: the boom motor turns at 11 rev/s, where its pull-out torque
  // (0.5 N m, boom-jib.json) is far below what the boom's weight needs.
  ASSERT_EQ(h.Request(dmc::MotorSetSpeed{3, static_cast<uint32_t>(40 * kBoomStepsPerDeg),
                                         static_cast<uint32_t>(400 * kBoomStepsPerDeg)}),
            dmc::AckCode::kOk);
  const int32_t target = static_cast<int32_t>(40 * kBoomStepsPerDeg);
  ASSERT_TRUE(Moves(h, 3, target));
  h.RunMs(5000);
  ASSERT_EQ(h.Pos(3), target);  // the device counted every step
  int64_t lost = 0;
  size_t stalls = 0;
  for (const auto& e : events) {
    if (e["event"] != "stall") continue;
    ++stalls;
    EXPECT_EQ(e["joint"], "boom");
    EXPECT_EQ(e["motor"], 3);
    EXPECT_GE(e["ended_ns"].get<int64_t>(), e["began_ns"].get<int64_t>());
    lost += e["lost_steps"].get<int64_t>();
  }
  ASSERT_GT(stalls, 0u);
  EXPECT_GT(lost, 0);  // fell behind going up
  const nlohmann::json s = h.device().State()["physical_rig"];
  EXPECT_EQ(s["stalls"], stalls);
  EXPECT_EQ(s["joints"]["boom"]["lost_steps"], lost);
  // ... and the joint is that many steps short of where the count says.
  const auto& dyn = h.device().physical_rig()->dynamics();
  const double boom_deg =
      dyn.PhysicalJoints()[static_cast<size_t>(physics::Joint::kBoom)] * 180.0 / 3.14159265358979;
  EXPECT_LT(boom_deg, 40.0 - static_cast<double>(lost) / kBoomStepsPerDeg + 1.0);
}

TEST(Dmc16PhysicalRig, ResettingAPositionOrPowerCyclingDoesNotMoveTheRig) {
  Host h(BoomProfile());
  std::vector<nlohmann::json> events;
  h.device().SetEventListener([&](const nlohmann::json& e) { events.push_back(e); });
  ASSERT_TRUE(Moves(h, 1, 16000));  // 0.1 m of track (3200 x 50 steps per metre)
  h.RunMs(6000);
  const auto& dyn = h.device().physical_rig()->dynamics();
  const double track_m = dyn.PhysicalJoints()[0];
  ASSERT_NEAR(track_m, 0.1, 1e-3);
  // Zero the track where it stands: the count changes, the cart does not.
  ASSERT_EQ(h.Request(dmc::MotorResetPosition{1, 0}), dmc::AckCode::kOk);
  h.RunMs(2000);
  EXPECT_EQ(h.Pos(1), 0);
  EXPECT_NEAR(h.device().physical_rig()->dynamics().PhysicalJoints()[0], track_m, 1e-6);
  // A power cycle restarts every count at 0; the rig stays where it stood.
  h.device().PowerOff();
  h.RunMs(500);
  h.device().PowerOn();
  h.RunMs(2000);
  EXPECT_NEAR(h.device().physical_rig()->dynamics().PhysicalJoints()[0], track_m, 1e-6);
  EXPECT_TRUE(events.empty()) << events.front().dump();
  // Moves now count from the new zero.
  ASSERT_TRUE(Moves(h, 1, 16000));
  h.RunMs(6000);
  EXPECT_NEAR(h.device().physical_rig()->dynamics().PhysicalJoints()[0], 0.2, 1e-3);
}

TEST(Dmc16PhysicalRig, APlaybackIsFollowedFromASleepingRigToItsLastFrame) {
  // The rig sleeps once the pre-roll position is reached; RT_GO and then the
  // device's own frame timers plan the motion, and every new plan wakes it.
  Host h(BoomProfile());
  constexpr uint32_t kFrames = 48;
  ASSERT_EQ(h.Request(dmc::RtUploadMoveBegin{0, kFrames - 1}), dmc::AckCode::kOk);
  dmc::RtUploadMoveAxis track;
  track.motor = 1;
  track.last_set = true;
  for (uint32_t i = 0; i < kFrames; ++i)
    track.positions_steps.push_back(static_cast<int32_t>(i) * 300);
  ASSERT_EQ(h.Request(track), dmc::AckCode::kOk);
  ASSERT_EQ(h.Request(dmc::RtUploadMoveEnd{}), dmc::AckCode::kOk);
  dmc::RtRunMove run;
  run.fps_x1000 = 24000;
  run.start_frame = 0;
  run.end_frame = kFrames - 1;
  run.preroll_ms = 500;
  run.postroll_ms = 500;
  ASSERT_EQ(h.Request(run), dmc::AckCode::kOk);
  h.RunMs(5000);  // pre-roll reached, the rig settles and sleeps
  ASSERT_FALSE(h.device().physical_rig()->awake());
  const int64_t steps_before = h.device().physical_rig()->steps_taken();
  ASSERT_EQ(h.Request(dmc::RtGo{}), dmc::AckCode::kOk);
  EXPECT_TRUE(h.device().physical_rig()->awake());
  h.RunMs(10000);
  // It stepped through the whole pass (about 2.5 s), not just a moment.
  EXPECT_GT(h.device().physical_rig()->steps_taken() - steps_before, 2000);
  ASSERT_FALSE(h.All<dmc::RtEnd>().empty());
  // 0.1 m of track per 16000 steps (3200 steps/rev x 50:1 per metre).
  const double track_m = h.device().physical_rig()->dynamics().PhysicalJoints()[0];
  EXPECT_NEAR(track_m, static_cast<double>(h.Pos(1)) / 160000.0, 1e-3);
  EXPECT_GT(h.Pos(1), (kFrames - 1) * 300);
}

// A profile whose physical_rig maps the joints badly is refused at load,
// naming the field and the fix (docs/profiles.md).
TEST(Dmc16PhysicalRig, AProfileMappingTheJointsBadlyIsRefusedNamingTheField) {
  const std::string profiles = ProfilesDir();
  const nlohmann::json good = nlohmann::json::parse(
      R"({"model":"dmc16","motor_count":16,"physical_rig":{"rig":"../rigs/boom-jib.json"}})");
  ASSERT_EQ(Dmc16ProfileFromJson(good, "p", profiles).physical_rig.rig.name,
            "studio boom jib on 2.5 m track");
  auto error = [&](const nlohmann::json& j) -> std::string {
    try {
      Dmc16ProfileFromJson(j, "p", profiles);
    } catch (const ProfileError& e) {
      return e.what();
    }
    return "(accepted)";
  };
  nlohmann::json shared = good;
  shared["physical_rig"]["motors"] = {{"swing", 2}, {"pan", 2}};
  const std::string e1 = error(shared);
  EXPECT_NE(e1.find("physical_rig.motors.pan"), std::string::npos) << e1;
  EXPECT_NE(e1.find("already drives the swing"), std::string::npos) << e1;
  EXPECT_NE(e1.find("give each joint its own motor"), std::string::npos) << e1;
  // Two fixed joints (motor 0) share nothing.
  nlohmann::json fixed = good;
  fixed["physical_rig"]["motors"] = {{"pan", 0}, {"roll", 0}};
  EXPECT_EQ(error(fixed), "(accepted)");
  nlohmann::json beyond = good;
  beyond["motor_count"] = 4;
  const std::string e2 = error(beyond);  // the default mapping uses motors 5 and 6
  EXPECT_NE(e2.find("beyond motor_count"), std::string::npos) << e2;
  nlohmann::json missing = good;
  missing["physical_rig"].erase("rig");
  EXPECT_NE(error(missing).find("physical_rig.rig"), std::string::npos);
}

}  // namespace
}  // namespace moco::devices
