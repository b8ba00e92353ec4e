// The DMC-16's virtual axes against dmc-v2-protocol.txt MSG_VIRT_* and FACTS
// "Boom rig virtual axes", in virtual time: every VIRT message's answers and
// errors, moves landing on the inverse-kinematics targets, aim point, jogs.
#include "devices/dmc16/virtual_axes.h"

#include <gtest/gtest.h>

#include <cmath>

#include "devices/dmc16/dmc16_test_support.h"

namespace moco::devices {
namespace {

using dmc::AckCode;
using testing::Host;

constexpr std::optional<AckCode> kOk = AckCode::kOk;
// Motors of the test rig and their scales: angles in steps per degree,
// lengths in steps per unit.
constexpr int kBoom = 1, kSwing = 2, kTrack = 3, kPan = 4, kTilt = 5, kRoll = 6;
constexpr int32_t kAngleSpu = 1000;
constexpr int32_t kTrackSpu = 10000;

Dmc16Profile VirtualProfile(uint32_t virtual_caps = 0x007c) {
  Dmc16Profile p;
  p.motor_count = 8;
  p.hw_limit_sets = 0;
  p.max_velocity_steps_per_s = 20000;
  p.max_accel_steps_per_s2 = 40000;
  p.virtual_axes.enabled = true;
  p.virtual_axes.capabilities = virtual_caps;
  return p;
}

// Boom 2.0 + level extension 0.5, no nodal offset. POSITION fields: the
// virtual values FK gives at step 0 (vTrack 2.5), so reports are pure FK.
dmc::VirtRigBoomSwingTrack BoomRig() {
  dmc::VirtRigBoomSwingTrack b;
  b.boom = {kBoom, kAngleSpu, 0};
  b.swing = {kSwing, kAngleSpu, 0};
  b.track = {kTrack, kTrackSpu, 250000};
  b.pan = {kPan, kAngleSpu, 0};
  b.tilt = {kTilt, kAngleSpu, 0};
  b.roll = {kRoll, kAngleSpu, 0};
  b.boom_length_x1000 = 2000;
  b.boom_ext_x1000 = 500;
  return b;
}

dmc::VirtConfig Config(dmc::VirtRigBoomSwingTrack b) { return dmc::VirtConfig{std::move(b)}; }

// The same layout under another TYPE byte (3, 4 or 8 carry no layout of their own).
dmc::VirtConfig RawConfig(uint8_t type, const dmc::VirtRigBoomSwingTrack& b) {
  wire::Bytes data;
  dmc::EncodeData(dmc::HostMessage{Config(b)}, data);
  dmc::VirtRigRaw raw;
  raw.type = type;
  raw.data.assign(data.begin() + 1, data.end());
  return dmc::VirtConfig{raw};
}

dmc::VirtPositionReport Positions(Host& h) {
  const uint32_t id = h.Send(dmc::VirtGetPositionRequest{});
  const auto* r = std::get_if<dmc::VirtPositionReport>(&h.Reply(id).msg);
  EXPECT_NE(r, nullptr) << "VIRT_GET_POSITION answered with an ACK";
  return r != nullptr ? *r : dmc::VirtPositionReport{};
}

// --- advertising ------------------------------------------------------------------------------

TEST(Dmc16Virtual, ProfileAdvertisesAllFourModesAndTheAimPoint) {
  Host h(VirtualProfile());
  const auto& hi = std::get<dmc::HiResponse>(h.out()[0].msg);
  EXPECT_EQ(hi.capabilities, 0x0783u | 0x007cu);
}

TEST(Dmc16Virtual, WithoutTheAimBitAimPointIsUnsupportedAndPositionsAre24Bytes) {
  Host h(VirtualProfile(0x003c));
  EXPECT_EQ(h.Request(dmc::VirtAimPoint{1, 0, 0, 0}), AckCode::kErrUnsupported);
  ASSERT_EQ(h.Request(Config(BoomRig())), kOk);
  EXPECT_FALSE(Positions(h).aim.has_value());
}

// --- VIRT_CONFIG ----------------------------------------------------------------------------

TEST(Dmc16VirtConfig, MotionNeedsAConfigurationAndTypeZeroDropsIt) {
  Host h(VirtualProfile());
  // Before VIRT_CONFIG every axis reads 0 and nothing can move.
  EXPECT_EQ(Positions(h), (dmc::VirtPositionReport{0, 0, 0, 0, 0, 0, dmc::VirtAim{}}));
  EXPECT_EQ(h.Request(dmc::VirtMove{1, 0}), AckCode::kErrGeneral);
  EXPECT_EQ(h.Request(dmc::VirtJogOnLine{2, 100}), AckCode::kErrGeneral);
  ASSERT_EQ(h.Request(Config(BoomRig())), kOk);
  EXPECT_EQ(Positions(h).track_x100000, 250000);
  ASSERT_EQ(h.Request(dmc::VirtConfig{dmc::VirtRigNone{}}), kOk);
  EXPECT_EQ(Positions(h).track_x100000, 0);
  EXPECT_EQ(h.Request(dmc::VirtMove{1, 0}), AckCode::kErrGeneral);
}

TEST(Dmc16VirtConfig, BadMotorsScalesGeometryAndTablesAreOutOfRange) {
  Host h(VirtualProfile());
  auto b = BoomRig();
  b.roll.motor = 9;  // MOTOR COUNT is 8
  EXPECT_EQ(h.Request(Config(b)), AckCode::kErrRange);
  b = BoomRig();
  b.pan.motor = kTilt;  // one motor on two joints
  EXPECT_EQ(h.Request(Config(b)), AckCode::kErrRange);
  b = BoomRig();
  b.track.steps_per_unit = 0;
  EXPECT_EQ(h.Request(Config(b)), AckCode::kErrRange);
  b = BoomRig();
  b.boom_length_x1000 = 0;
  EXPECT_EQ(h.Request(Config(b)), AckCode::kErrRange);
  b = BoomRig();
  b.safe_distance_x1000 = -1;
  EXPECT_EQ(h.Request(Config(b)), AckCode::kErrRange);
  b = BoomRig();
  b.compensation.emplace();
  for (size_t i = 0; i < b.compensation->size(); ++i) {
    (*b.compensation)[i] = static_cast<int32_t>(i) * 100000;
  }
  (*b.compensation)[50] = (*b.compensation)[49];  // not strictly monotonic
  EXPECT_EQ(h.Request(Config(b)), AckCode::kErrRange);
  // TYPE 5..7 name no rig.
  dmc::VirtRigRaw raw;
  raw.type = 5;
  EXPECT_EQ(h.Request(dmc::VirtConfig{raw}), AckCode::kErrRange);
  // TYPE 3 with data that fits no layout.
  raw.type = 3;
  raw.data = {1, 2, 3};
  EXPECT_EQ(h.Request(dmc::VirtConfig{raw}), AckCode::kErrGeneral);
}

TEST(Dmc16VirtConfig, AModeNotAdvertisedIsOutOfRange) {
  Host h(VirtualProfile(dmc::kCapVirtBoomSwingTrack));
  EXPECT_EQ(h.Request(dmc::VirtConfig{dmc::VirtRigSwingPan{{kSwing, 1000}, {kPan, 1000}}}),
            AckCode::kErrRange);
  EXPECT_EQ(h.Request(RawConfig(4, BoomRig())), AckCode::kErrRange);
  EXPECT_EQ(h.Request(Config(BoomRig())), kOk);
}

TEST(Dmc16VirtConfig, PositionFieldIsTheVirtualValueAtConfiguration) {
  // FACTS: report = config value + (FK(now) - FK(at config)). FK at step 0
  // gives vTrack 2.5; TRACK POSITION says 1.0, PAN POSITION 5 degrees.
  Host h(VirtualProfile());
  auto b = BoomRig();
  b.track.position_x100000 = 100000;
  b.pan.position_x100000 = 500000;
  b.boom.position_x100000 = -20000;  // vNS -0.2
  ASSERT_EQ(h.Request(Config(b)), kOk);
  auto r = Positions(h);
  EXPECT_EQ(r.track_x100000, 100000);
  EXPECT_EQ(r.pan_x100000, 500000);
  EXPECT_EQ(r.ns_x100000, -20000);
  EXPECT_EQ(r.ew_x100000, 0);
  // One unit of track (10000 steps) later: 1.0 + 1.0.
  ASSERT_EQ(h.Request(dmc::MotorMove{kTrack, 10000}), std::nullopt);
  h.Settle();
  r = Positions(h);
  EXPECT_EQ(r.track_x100000, 200000);
  EXPECT_EQ(r.ns_x100000, -20000);
}

TEST(Dmc16VirtConfig, TypeEightIsXyzAsTypeFour) {
  // x-y-z: BOOM triple = vertical (vNS), SWING = east/west, TRACK = track.
  for (uint8_t type : {uint8_t{4}, uint8_t{8}}) {
    Host h(VirtualProfile());
    auto b = BoomRig();
    b.track.position_x100000 = 0;
    ASSERT_EQ(h.Request(RawConfig(type, b)), kOk) << int{type};
    ASSERT_EQ(h.Request(dmc::VirtMove{2, 50000}), kOk);   // vEW 0.5 units
    ASSERT_EQ(h.Request(dmc::VirtMove{3, -25000}), kOk);  // vNS -0.25 units
    h.Settle();
    // SWING spu is 1000 steps per unit here (a length on this rig).
    EXPECT_EQ(h.Pos(kSwing), 500);
    EXPECT_EQ(h.Pos(kBoom), -250);
    EXPECT_EQ(h.Pos(kTrack), 0);
  }
}

// --- VIRT_MOVE ------------------------------------------------------------------------------

TEST(Dmc16VirtMove, RaisingTheNodalPointSolvesBoomAndTrackTogether) {
  Host h(VirtualProfile());
  ASSERT_EQ(h.Request(Config(BoomRig())), kOk);
  // vNS 1.0 on L = 2, E = 0.5: b = asin(1/2) = 30 deg -> 30000 boom steps;
  // h = 2 cos 30 + 0.5 = 2.2320508; T = 2.5 - 2.2320508 = 0.2679492 -> 2679 steps.
  ASSERT_EQ(h.Request(dmc::VirtMove{3, 100000}), kOk);
  EXPECT_TRUE(h.device().rig_ref().motor(kBoom).IsMoving());
  EXPECT_TRUE(h.device().rig_ref().motor(kTrack).IsMoving());
  // Coordinated: the boom and the track come to rest together.
  sim::TimeNs boom_end = -1, track_end = -1;
  while (h.device().rig_ref().AnyMoving()) {
    h.RunMs(1);
    if (boom_end < 0 && !h.device().rig_ref().motor(kBoom).IsMoving()) boom_end = h.now();
    if (track_end < 0 && !h.device().rig_ref().motor(kTrack).IsMoving()) track_end = h.now();
  }
  EXPECT_NEAR(static_cast<double>(boom_end - track_end), 0, 2.0 * sim::kNsPerMs);
  EXPECT_EQ(h.Pos(kBoom), 30000);
  EXPECT_EQ(h.Pos(kTrack), 2679);
  EXPECT_EQ(h.Pos(kSwing), 0);
  const auto r = Positions(h);
  EXPECT_EQ(r.ns_x100000, 100000);
  // 2679 steps for 2679.49: within half a track step (0.5e-4 units = 5 here).
  EXPECT_NEAR(r.track_x100000, 250000, 5);
  EXPECT_EQ(r.ew_x100000, 0);
}

TEST(Dmc16VirtMove, SwingingSidewaysKeepsTheHeadingWithThePan) {
  Host h(VirtualProfile());
  ASSERT_EQ(h.Request(Config(BoomRig())), kOk);
  // vEW 1.25 with the boom level: h = 2.5, s = asin(1.25 / 2.5) = 30 deg;
  // T = 2.5 - 2.5 cos 30 = 0.3349365 -> 3349 steps; pan = vPan - s = -30 deg.
  ASSERT_EQ(h.Request(dmc::VirtMove{2, 125000}), kOk);
  h.Settle();
  EXPECT_EQ(h.Pos(kSwing), 30000);
  EXPECT_EQ(h.Pos(kTrack), 3349);
  EXPECT_EQ(h.Pos(kPan), -30000);
  const auto r = Positions(h);
  EXPECT_EQ(r.pan_x100000, 0);
  EXPECT_EQ(r.ew_x100000, 125000);
}

TEST(Dmc16VirtMove, UnreachableOrUnknownAxisIsOutOfRangeAndMovesNothing) {
  Host h(VirtualProfile());
  ASSERT_EQ(h.Request(Config(BoomRig())), kOk);
  EXPECT_EQ(h.Request(dmc::VirtMove{3, 300000}), AckCode::kErrRange);  // vNS 3 > L = 2
  EXPECT_EQ(h.Request(dmc::VirtMove{2, 260000}), AckCode::kErrRange);  // vEW 2.6 > L + E
  EXPECT_EQ(h.Request(dmc::VirtMove{0, 0}), AckCode::kErrRange);
  EXPECT_EQ(h.Request(dmc::VirtMove{7, 0}), AckCode::kErrRange);
  EXPECT_FALSE(h.device().rig_ref().AnyMoving());
}

TEST(Dmc16VirtMove, AnUndrivenJointThatWouldHaveToMoveIsOutOfRange) {
  Host h(VirtualProfile());
  auto b = BoomRig();
  b.roll.motor = 0;  // no roll motor
  ASSERT_EQ(h.Request(Config(b)), kOk);
  EXPECT_EQ(h.Request(dmc::VirtMove{6, 100000}), AckCode::kErrRange);
  EXPECT_EQ(h.Request(dmc::VirtMove{5, 100000}), kOk);  // tilt is driven
}

TEST(Dmc16VirtMove, SoftLimitOfAJointIsReported) {
  Host h(VirtualProfile());
  ASSERT_EQ(h.Request(Config(BoomRig())), kOk);
  ASSERT_EQ(h.Request(dmc::MotorSetLimits{kBoom, 0, 0, 1, 10000, 0}), kOk);
  EXPECT_EQ(h.Request(dmc::VirtMove{3, 100000}), AckCode::kErrSoftUp);  // boom to 30000
  EXPECT_FALSE(h.device().rig_ref().AnyMoving());
}

// --- VIRT_STOP / VIRT_JOG -------------------------------------------------------------------

TEST(Dmc16VirtStop, StopsEveryMappedMotorShortOfTheTarget) {
  Host h(VirtualProfile());
  ASSERT_EQ(h.Request(Config(BoomRig())), kOk);
  ASSERT_EQ(h.Request(dmc::VirtMove{1, 1250000}), kOk);  // vTrack 12.5: 100000 steps
  h.RunMs(200);
  ASSERT_TRUE(h.device().rig_ref().motor(kTrack).IsMoving());
  EXPECT_EQ(h.Request(dmc::VirtStop{0}), AckCode::kErrRange);
  EXPECT_EQ(h.Request(dmc::VirtStop{1}), kOk);
  h.Settle();
  EXPECT_LT(h.Pos(kTrack), 100000);
  EXPECT_GT(h.Pos(kTrack), 0);
}

TEST(Dmc16VirtJog, SpeedOutsideOneToTenThousandIsOutOfRange) {
  Host h(VirtualProfile());
  ASSERT_EQ(h.Request(Config(BoomRig())), kOk);
  EXPECT_EQ(h.Request(dmc::VirtJog{1, 0, 300000}), AckCode::kErrRange);
  EXPECT_EQ(h.Request(dmc::VirtJog{1, 10001, 300000}), AckCode::kErrRange);
  EXPECT_EQ(h.Request(dmc::VirtJog{9, 100, 300000}), AckCode::kErrRange);
}

TEST(Dmc16VirtJog, InchingReachesTheDestinationSlowerThanFullSpeed) {
  sim::TimeNs took[2] = {0, 0};
  for (int i = 0; i < 2; ++i) {
    Host h(VirtualProfile());
    ASSERT_EQ(h.Request(Config(BoomRig())), kOk);
    const sim::TimeNs t0 = h.now();
    ASSERT_EQ(h.Request(dmc::VirtJog{1, static_cast<uint16_t>(i == 0 ? 10000 : 1000), 300000}),
              kOk);
    h.Settle();
    took[i] = h.now() - t0;
    EXPECT_EQ(h.Pos(kTrack), 5000);  // vTrack 3.0 = 2.5 + 0.5 units
  }
  EXPECT_GT(took[1], 2 * took[0]);
}

// --- VIRT_JOG_ON_LINE -----------------------------------------------------------------------

TEST(Dmc16VirtJogOnLine, CameraLineAtPanZeroRunsDownTheTrackUntilStopped) {
  Host h(VirtualProfile());
  ASSERT_EQ(h.Request(Config(BoomRig())), kOk);
  EXPECT_EQ(h.Request(dmc::VirtJogOnLine{5, 100}), AckCode::kErrRange);
  EXPECT_EQ(h.Request(dmc::VirtJogOnLine{2, 10001}), AckCode::kErrRange);
  // Z is the camera line, +Z out of the back of the camera: at pan 0 the lens
  // looks down +track, so a positive speed moves the nodal point to -track.
  // Full speed is 1 unit/s (jog_line_units_per_s).
  ASSERT_EQ(h.Request(dmc::VirtJogOnLine{2, 10000}), kOk);
  h.RunMs(1000);
  EXPECT_TRUE(h.device().virtual_axes().jogging());
  auto r = Positions(h);
  EXPECT_LT(r.track_x100000, 250000 - 50000);
  EXPECT_GT(r.track_x100000, 250000 - 105000);
  EXPECT_NEAR(r.ew_x100000, 0, 1);
  EXPECT_NEAR(r.ns_x100000, 0, 1);
  ASSERT_EQ(h.Request(dmc::VirtJogOnLine{2, 0}), kOk);  // speed 0 ends the jog
  EXPECT_FALSE(h.device().virtual_axes().jogging());
  h.Settle();
  EXPECT_FALSE(h.device().rig_ref().AnyMoving());
}

TEST(Dmc16VirtJogOnLine, PanJogTurnsThePanAndStopAllEndsIt) {
  Host h(VirtualProfile());
  ASSERT_EQ(h.Request(Config(BoomRig())), kOk);
  ASSERT_EQ(h.Request(dmc::VirtJogOnLine{3, -5000}), kOk);  // 15 deg/s towards -pan
  h.RunMs(1000);
  EXPECT_LT(h.Pos(kPan), -5000);
  EXPECT_EQ(h.Pos(kTrack), 0);
  ASSERT_EQ(h.Request(dmc::MotorStopAll{}), kOk);
  EXPECT_FALSE(h.device().virtual_axes().jogging());
  h.Settle();
  EXPECT_FALSE(h.device().rig_ref().AnyMoving());
}

// --- VIRT_AIM_POINT -------------------------------------------------------------------------

TEST(Dmc16VirtAim, AnswerEchoesTheConfigurationAndPositionsCarryIt) {
  Host h(VirtualProfile());
  EXPECT_EQ(h.Request(dmc::VirtAimPoint{2, 0, 0, 0}), AckCode::kErrRange);
  const dmc::VirtAimPoint aim{1, 1500, -250, 9000};
  const uint32_t id = h.Send(aim);
  const auto& reply = h.Reply(id);
  EXPECT_EQ(reply.type, dmc::ToWire(dmc::MsgType::kVirtAimPoint));
  ASSERT_TRUE(std::holds_alternative<dmc::VirtAimPoint>(reply.msg));
  EXPECT_EQ(std::get<dmc::VirtAimPoint>(reply.msg), aim);
  ASSERT_EQ(h.Request(Config(BoomRig())), kOk);
  const auto r = Positions(h);
  ASSERT_TRUE(r.aim.has_value());
  EXPECT_EQ(*r.aim, (dmc::VirtAim{1, 1500, -250, 9000}));
}

TEST(Dmc16VirtAim, PanFollowsSoTheCameraKeepsLookingAtTheAimPoint) {
  Host h(VirtualProfile());
  auto b = BoomRig();
  b.track.position_x100000 = 0;                // the nodal point reads (EW 0, NS 0, track 0)
  ASSERT_EQ(h.Request(RawConfig(4, b)), kOk);  // x-y-z: nodal = (swing, track, boom)
  // Aim 10 units down the track (Kuper Z): straight ahead, offsets zero.
  ASSERT_EQ(h.Request(dmc::VirtAimPoint{1, 0, 0, 10000}), std::nullopt);
  auto r = Positions(h);
  EXPECT_EQ(r.pan_x100000, 0);
  EXPECT_EQ(r.tilt_x100000, 0);
  // Move the nodal point 1 unit east: d = (-1, 10, 0), pan = atan2(1, 10)
  // = 5.7105931 deg -> 5711 pan steps; the offsets stay zero.
  ASSERT_EQ(h.Request(dmc::VirtMove{2, 100000}), kOk);
  h.Settle();
  EXPECT_EQ(h.Pos(kPan), 5711);
  EXPECT_EQ(h.Pos(kTilt), 0);
  r = Positions(h);
  EXPECT_NEAR(r.pan_x100000, 0, 100);  // within half a pan step (0.0005 deg)
  // And 2 units up: d = (-1, 10, -2), tilt = atan2(-2, hypot(1, 10))
  // = -atan(2 / 10.0498756) = -11.2552 deg.
  ASSERT_EQ(h.Request(dmc::VirtMove{3, 200000}), kOk);
  h.Settle();
  EXPECT_EQ(h.Pos(kTilt), -11255);
  // Disabled again: vPan is the heading itself (5.71 deg).
  ASSERT_EQ(h.Request(dmc::VirtAimPoint{0, 0, 0, 10000}), std::nullopt);
  r = Positions(h);
  EXPECT_NEAR(r.pan_x100000, 571100, 100);
}

TEST(Dmc16VirtAim, TargetInsideTheSafeDistanceIsOutOfRange) {
  Host h(VirtualProfile());
  auto b = BoomRig();
  b.safe_distance_x1000 = 1000;  // 1 unit around the aim point
  ASSERT_EQ(h.Request(Config(b)), kOk);
  // Aim at track 4.0 (Kuper Z), nodal at track 2.5: 1.5 away.
  ASSERT_EQ(h.Request(dmc::VirtAimPoint{1, 0, 0, 4000}), std::nullopt);
  EXPECT_EQ(h.Request(dmc::VirtMove{1, 320000}), AckCode::kErrRange);  // 0.8 away
  EXPECT_FALSE(h.device().rig_ref().AnyMoving());
  EXPECT_EQ(h.Request(dmc::VirtMove{1, 280000}), kOk);  // 1.2 away
}

TEST(Dmc16VirtAim, VirtualMotionDuringPlaybackIsRefused) {
  Host h(VirtualProfile());
  ASSERT_EQ(h.Request(Config(BoomRig())), kOk);
  ASSERT_EQ(h.Request(dmc::RtUploadMoveBegin{0, 10}), kOk);
  dmc::RtUploadMoveAxis axis;
  axis.motor = 7;
  axis.start_index = 0;
  axis.last_set = true;
  axis.positions_steps = {0};
  ASSERT_EQ(h.Request(axis), kOk);
  ASSERT_EQ(h.Request(dmc::RtUploadMoveEnd{}), kOk);
  ASSERT_EQ(h.Request(dmc::RtPositionFrame{0}), kOk);
  h.Settle();
  ASSERT_EQ(h.Request(dmc::RtJogAll{24000, 10}), kOk);
  EXPECT_EQ(h.Request(dmc::VirtMove{1, 300000}), AckCode::kErrMoving);
  EXPECT_EQ(h.Request(dmc::VirtJogOnLine{2, 100}), AckCode::kErrMoving);
}

}  // namespace
}  // namespace moco::devices
