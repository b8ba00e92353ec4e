// Tests of the boom rig dynamics (docs/rig-dynamics.md; FACTS "Boom rig
// virtual axes" forward kinematics, "Bullet" determinism): pose, inertia lag,
// boom sag and its compensation, lost steps, head contacts.
#include "physics/bullet/rig_dynamics.h"

#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

#include "physics/bullet/rig_test_support.h"

namespace moco::physics {
namespace {

using test_support::BoomJib;
using test_support::kDeg;
using test_support::Trapezoid;

// FACTS "Boom rig virtual axes" forward kinematics, written out here from the
// text: tip = (L cos b sin s, T + L cos b cos s, L sin b); head = tip +
// E (sin s, cos s, 0); nodal = head + R o, R turning the head by heading s + p
// (clockwise from +y seen from above, as the swing), then tilt, then roll.
Point3 FactsNodal(const RigProfile& p, const JointVector& q) {
  const double t = q[0], s = q[1], b = q[2], h = q[1] + q[3], ti = q[4], r = q[5];
  const double l = p.boom_length_m, e = p.level_extension_m;
  const double hx = l * std::cos(b) * std::sin(s) + e * std::sin(s);
  const double hy = t + l * std::cos(b) * std::cos(s) + e * std::cos(s);
  const double hz = l * std::sin(b);
  // Columns of R: right, view, up of the head.
  const double right[3] = {std::cos(h) * std::cos(r) + std::sin(h) * std::sin(ti) * std::sin(r),
                           -std::sin(h) * std::cos(r) + std::cos(h) * std::sin(ti) * std::sin(r),
                           -std::cos(ti) * std::sin(r)};
  const double view[3] = {std::sin(h) * std::cos(ti), std::cos(h) * std::cos(ti), std::sin(ti)};
  const double up[3] = {std::cos(h) * std::sin(r) - std::sin(h) * std::sin(ti) * std::cos(r),
                        -std::sin(h) * std::sin(r) - std::cos(h) * std::sin(ti) * std::cos(r),
                        std::cos(ti) * std::cos(r)};
  const Point3& o = p.nodal_offset_m;
  return {hx + right[0] * o[0] + view[0] * o[1] + up[0] * o[2],
          hy + right[1] * o[0] + view[1] * o[1] + up[1] * o[2],
          hz + right[2] * o[0] + view[2] * o[1] + up[2] * o[2]};
}

double Distance(const Point3& a, const Point3& b) {
  return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                   (a[2] - b[2]) * (a[2] - b[2]));
}

// Holds `q` for `steps` steps; returns every event seen.
StepEvents Hold(BoomRigDynamics& rig, const JointVector& q, int steps) {
  StepEvents all;
  for (int i = 0; i < steps; ++i) {
    const StepEvents& e = rig.Step(q);
    all.stalls.insert(all.stalls.end(), e.stalls.begin(), e.stalls.end());
    all.collisions.insert(all.collisions.end(), e.collisions.begin(), e.collisions.end());
  }
  return all;
}

// Runs joint `j` through `move` from `start` (other joints held), then holds
// for `settle_s`. Returns every event seen.
StepEvents RunMove(BoomRigDynamics& rig, JointVector start, Joint j, const Trapezoid& move,
                   double settle_s) {
  StepEvents all;
  const int steps = static_cast<int>((move.Duration() + settle_s) / kStepS) + 1;
  for (int i = 1; i <= steps; ++i) {
    start[Index(j)] = move.At(i * kStepS);
    const StepEvents& e = rig.Step(start);
    all.stalls.insert(all.stalls.end(), e.stalls.begin(), e.stalls.end());
    all.collisions.insert(all.collisions.end(), e.collisions.begin(), e.collisions.end());
  }
  return all;
}

TEST(RigDynamicsTest, PoseFollowsTheFactsKinematicsWithoutGravity) {
  RigProfile p = BoomJib();
  p.gravity_m_s2 = 0;
  BoomRigDynamics rig(p);
  const std::vector<JointVector> poses = {
      {0, 0, 0, 0, 0, 0},
      {1.2, 30 * kDeg, 20 * kDeg, 0, 0, 0},
      {0.4, -50 * kDeg, -30 * kDeg, 40 * kDeg, -20 * kDeg, 10 * kDeg},
      {2.0, 120 * kDeg, 45 * kDeg, -90 * kDeg, 60 * kDeg, -30 * kDeg},
  };
  for (const JointVector& q : poses) {
    rig.Reset(q);
    EXPECT_LT(Distance(rig.Pose().nodal_m, FactsNodal(p, q)), 1e-9);
    EXPECT_LT(Distance(IdealNodal(p, q), FactsNodal(p, q)), 1e-12);
    Hold(rig, q, 200);  // weightless and commanded where it is: it stays
    EXPECT_LT(Distance(rig.Pose().nodal_m, FactsNodal(p, q)), 1e-6);
  }
  // Heading: the camera looks along the boom when pan and tilt are zero.
  rig.Reset({0, 30 * kDeg, 0, 0, 0, 0});
  const HeadPose pose = rig.Pose();
  EXPECT_NEAR(pose.view[0], std::sin(30 * kDeg), 1e-9);
  EXPECT_NEAR(pose.view[1], std::cos(30 * kDeg), 1e-9);
  EXPECT_NEAR(pose.view[2], 0, 1e-9);
  EXPECT_NEAR(pose.up[2], 1, 1e-9);
}

TEST(RigDynamicsTest, TwoRunsAreBitwiseEqual) {
  const RigProfile p = BoomJib();
  auto run = [&p] {
    BoomRigDynamics rig(p);
    std::vector<double> trace;
    std::vector<int64_t> lost;
    size_t events = 0;
    const Trapezoid swing{0, 40 * kDeg, 20 * kDeg, 40 * kDeg};
    const Trapezoid boom{0, -30 * kDeg, 10 * kDeg, 20 * kDeg};
    for (int i = 1; i <= 4000; ++i) {
      const double t = i * kStepS;
      // A jump of the track at 1 s loses steps; the rest is smooth.
      const JointVector cmd = {t < 1 ? 0.0 : 0.3, swing.At(t), boom.At(t),
                               0.2 * std::sin(t), 0.1 * t,     0};
      const StepEvents& e = rig.Step(cmd);
      events += e.stalls.size() + e.collisions.size();
      for (double v : rig.PhysicalJoints()) trace.push_back(v);
      for (double v : rig.PhysicalVelocities()) trace.push_back(v);
      for (double v : rig.Pose().nodal_m) trace.push_back(v);
    }
    for (int64_t l : rig.LostSteps()) lost.push_back(l);
    return std::make_tuple(trace, lost, events);
  };
  const auto [a, lost_a, events_a] = run();
  const auto [b, lost_b, events_b] = run();
  ASSERT_EQ(a.size(), b.size());
  EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(double)), 0);
  EXPECT_EQ(lost_a, lost_b);
  EXPECT_EQ(events_a, events_b);
  EXPECT_GT(events_a, 0u);  // the run did exercise a stall
}

TEST(RigDynamicsTest, TrackLagsDuringAccelerationByInertiaOverStiffnessThenCatchesUp) {
  const RigProfile p = BoomJib();
  BoomRigDynamics rig(p);
  const JointSpec& track = p.joint(Joint::kTrack);
  // Everything rides on the cart.
  const double moving_kg = p.cart.mass_kg + p.swing.mass_kg + p.boom.mass_kg + p.extension.mass_kg +
                           p.pan.mass_kg + p.tilt.mass_kg + p.camera.mass_kg;
  const double accel = 0.5;
  const Trapezoid move{0, 1.0, 0.2, accel};  // 0.4 s accelerating
  JointVector cmd{};
  double error_mid_accel = 0;
  double peak = 0;
  const int move_steps = static_cast<int>(move.Duration() / kStepS);
  for (int i = 1; i <= move_steps; ++i) {
    cmd[0] = move.At(i * kStepS);
    rig.Step(cmd);
    const double e = rig.FollowingError()[0];
    if (i > 50 && i < 400) {
      EXPECT_GT(e, 0) << "step " << i;  // behind while speeding up
    }
    if (i == 300) error_mid_accel = e;
    peak = std::max(peak, std::abs(e));
  }
  // Steady-state lag of a PD with velocity feed-forward: m a / kp
  // (viscous friction adds c v / kp).
  const double expected = (moving_kg * accel + track.damping * 0.15) / track.kp;
  EXPECT_NEAR(error_mid_accel, expected, 0.25 * expected);
  // After the move the error decays to nothing (no load on the track).
  Hold(rig, cmd, 200);
  const double after_200ms = std::abs(rig.FollowingError()[0]);
  Hold(rig, cmd, 800);
  const double after_1s = std::abs(rig.FollowingError()[0]);
  EXPECT_LT(after_200ms, peak / 10);
  EXPECT_LT(after_1s, after_200ms);
  EXPECT_LT(after_1s, 1e-7);
  EXPECT_EQ(rig.LostSteps()[0], 0);
}

TEST(RigDynamicsTest, BoomSagsUnderGravityAndTheCompensationTableRemovesMostOfIt) {
  const RigProfile p = BoomJib();
  const double angle = 20 * kDeg;
  const JointSpec& boom = p.joint(Joint::kBoom);

  BoomRigDynamics plain(p);
  JointVector cmd{0, 0, angle, 0, 0, 0};
  plain.Reset(cmd);
  Hold(plain, cmd, 3000);
  const double sag = plain.FollowingError()[Index(Joint::kBoom)];
  // Statics: the boom's own weight at its COM and the head's weight at the
  // tip (the parallelogram takes the head's moment) against the drive's kp.
  const double head_kg = p.extension.mass_kg + p.pan.mass_kg + p.tilt.mass_kg + p.camera.mass_kg;
  const double statics = p.gravity_m_s2 * std::cos(angle) *
                         (p.boom.mass_kg * p.boom.com_m[1] + head_kg * p.boom_length_m) / boom.kp;
  EXPECT_GT(sag, 0);  // below the commanded angle
  EXPECT_NEAR(sag, statics, 0.05 * statics);
  const double tip_drop_m = IdealNodal(p, cmd)[2] - plain.Pose().nodal_m[2];
  EXPECT_GT(tip_drop_m, 0.01);  // more than a centimetre at the lens

  const std::vector<int64_t> table = BoomCompensationTable(p);
  ASSERT_EQ(table.size(), 121u);
  for (size_t i = 1; i < table.size(); ++i) EXPECT_GT(table[i], table[i - 1]);
  BoomRigDynamics compensated(p);
  JointVector biased = cmd;
  biased[Index(Joint::kBoom)] =
      boom.home + BoomCompensatedSteps(table, angle) / boom.StepsPerUnit(false);
  compensated.Reset(biased);
  Hold(compensated, biased, 3000);
  const double residual = compensated.PhysicalJoints()[Index(Joint::kBoom)] - angle;
  EXPECT_LT(std::abs(residual), 0.1 * sag);
  EXPECT_LT(Distance(compensated.Pose().nodal_m, IdealNodal(p, cmd)), 0.1 * tip_drop_m);
}

TEST(RigDynamicsTest, AJumpFarBeyondTheTorqueCurveLosesWholeSteps) {
  const RigProfile p = BoomJib();
  BoomRigDynamics rig(p);
  const double spu = p.joint(Joint::kTrack).StepsPerUnit(true);
  JointVector cmd{};
  cmd[0] = 0.5;  // half a metre in one millisecond
  const StepEvents events = Hold(rig, cmd, 3000);
  ASSERT_FALSE(events.stalls.empty());
  EXPECT_EQ(events.stalls.front().joint, Joint::kTrack);
  EXPECT_LE(events.stalls.front().time_ns, 2 * kStepNs);  // at once
  int64_t reported = 0;
  for (const StallEvent& s : events.stalls) reported += s.lost_steps;
  const int64_t lost = rig.LostSteps()[0];
  EXPECT_EQ(reported, lost);
  // Most of the jump is lost: the cart cannot start at that rate.
  EXPECT_GT(lost, static_cast<int64_t>(0.9 * 0.5 * spu));
  EXPECT_LE(lost, static_cast<int64_t>(0.5 * spu) + 1);
  // At rest the command and the cart differ by exactly the lost steps.
  EXPECT_NEAR(rig.FollowingError()[0] * spu, static_cast<double>(lost), 0.01);
  EXPECT_FALSE(rig.Stalled(Joint::kTrack));
  EXPECT_EQ(rig.StallCounts()[0], static_cast<int64_t>(events.stalls.size()));
}

TEST(RigDynamicsTest, AGentleMoveLosesNoSteps) {
  const RigProfile p = BoomJib();
  BoomRigDynamics rig(p);
  JointVector start{};
  StepEvents events = RunMove(rig, start, Joint::kTrack, {0, 1.5, 0.2, 0.5}, 1.0);
  start[0] = 1.5;
  const StepEvents boom =
      RunMove(rig, start, Joint::kBoom, {0, 30 * kDeg, 10 * kDeg, 20 * kDeg}, 1.0);
  EXPECT_TRUE(events.stalls.empty());
  EXPECT_TRUE(boom.stalls.empty());
  for (int64_t l : rig.LostSteps()) EXPECT_EQ(l, 0);
  EXPECT_NEAR(rig.PhysicalJoints()[0], 1.5, 1e-6);
}

TEST(RigDynamicsTest, RaisingTheBoomFasterThanTheMotorCanCarryItStalls) {
  // Pull-out torque falls with speed; at 40 deg/s the boom motor runs at
  // 11 rev/s where it has 0.5 N m, far below the boom's weight.
  const RigProfile p = BoomJib();
  BoomRigDynamics rig(p);
  const StepEvents events =
      RunMove(rig, {}, Joint::kBoom, {0, 40 * kDeg, 40 * kDeg, 400 * kDeg}, 2.0);
  ASSERT_FALSE(events.stalls.empty());
  EXPECT_EQ(events.stalls.front().joint, Joint::kBoom);
  EXPECT_GT(rig.LostSteps()[Index(Joint::kBoom)], 0);  // fell behind going up
}

TEST(RigDynamicsTest, DrivingTheHeadIntoTheFloorReportsACollisionOnce) {
  const RigProfile p = BoomJib();
  BoomRigDynamics rig(p);
  const StepEvents events =
      RunMove(rig, {}, Joint::kBoom, {0, -60 * kDeg, 10 * kDeg, 20 * kDeg}, 0.5);
  ASSERT_EQ(events.collisions.size(), 1u);
  EXPECT_EQ(events.collisions[0].what, "floor");
  ASSERT_TRUE(rig.Contact().has_value());
  EXPECT_EQ(*rig.Contact(), "floor");
  // The contact began where the head box's bottom met the floor: 0.2 m
  // below the head point, boom angle asin((floor + 0.2) / L) ~ -53 deg.
  const double touch = std::asin((p.floor_z_m + 0.2) / p.boom_length_m);
  const Trapezoid move{0, -60 * kDeg, 10 * kDeg, 20 * kDeg};
  double t_touch = 0;
  for (double t = 0; t < move.Duration(); t += kStepS) {
    if (move.At(t) <= touch) {
      t_touch = t;
      break;
    }
  }
  EXPECT_NEAR(static_cast<double>(events.collisions[0].time_ns) * 1e-9, t_touch, 0.15);
}

TEST(RigDynamicsTest, SwingingIntoTheLightStandReportsIt) {
  const RigProfile p = BoomJib();
  BoomRigDynamics rig(p);
  JointVector start{0.4, 0, 0, 0, 0, 0};
  rig.Reset(start);
  const StepEvents events =
      RunMove(rig, start, Joint::kSwing, {0, 45 * kDeg, 20 * kDeg, 40 * kDeg}, 0.2);
  ASSERT_EQ(events.collisions.size(), 1u);
  EXPECT_EQ(events.collisions[0].what, "light stand");
}

TEST(RigDynamicsTest, ASensibleMoveTouchesNothing) {
  const RigProfile p = BoomJib();
  BoomRigDynamics rig(p);
  JointVector q{};
  StepEvents all = RunMove(rig, q, Joint::kTrack, {0, 2.0, 0.25, 0.5}, 0.2);
  q[0] = 2.0;
  StepEvents more = RunMove(rig, q, Joint::kBoom, {0, -40 * kDeg, 10 * kDeg, 20 * kDeg}, 0.2);
  q[Index(Joint::kBoom)] = -40 * kDeg;
  StepEvents pan = RunMove(rig, q, Joint::kPan, {0, 90 * kDeg, 30 * kDeg, 60 * kDeg}, 0.2);
  EXPECT_TRUE(all.collisions.empty());
  EXPECT_TRUE(more.collisions.empty());
  EXPECT_TRUE(pan.collisions.empty());
  EXPECT_FALSE(rig.Contact().has_value());
}

TEST(RigDynamicsTest, NonFiniteOrAbsurdCommandsNeitherCrashNorPoisonTheState) {
  const RigProfile p = BoomJib();
  BoomRigDynamics rig(p);
  JointVector cmd{};
  cmd[Index(Joint::kBoom)] = std::nan("");
  cmd[Index(Joint::kPan)] = std::numeric_limits<double>::infinity();
  Hold(rig, cmd, 100);
  EXPECT_EQ(rig.CommandedJoints()[Index(Joint::kBoom)], 0.0);  // held the last command
  EXPECT_EQ(rig.CommandedJoints()[Index(Joint::kPan)], 0.0);
  cmd = {1e300, 0, 0, 0, 0, 0};
  const StepEvents events = Hold(rig, cmd, 2000);
  for (double q : rig.PhysicalJoints()) EXPECT_TRUE(std::isfinite(q));
  for (double v : rig.Pose().nodal_m) EXPECT_TRUE(std::isfinite(v));
  EXPECT_FALSE(events.stalls.empty());  // the jump is lost, as any jump that size
  EXPECT_LE(rig.PhysicalJoints()[0], p.joint(Joint::kTrack).max + 0.01);
}

// Law: whatever the track is commanded to do (jumps included), once it is
// at rest the command and the cart differ by a whole number of steps, and
// that number is the steps reported lost.
RC_GTEST_PROP(RigDynamicsProperty, AtRestTheTrackIsOffByExactlyTheLostSteps,
              (const std::vector<int>& targets_mm)) {
  const RigProfile p = BoomJib();
  BoomRigDynamics rig(p);
  const double spu = p.joint(Joint::kTrack).StepsPerUnit(true);
  JointVector cmd{};
  int64_t reported = 0;
  for (size_t i = 0; i < std::min<size_t>(targets_mm.size(), 4); ++i) {
    cmd[0] = std::clamp(targets_mm[i] % 2000, 0, 2000) * 1e-3;
    for (const StallEvent& s : Hold(rig, cmd, 150).stalls) reported += s.lost_steps;
  }
  for (const StallEvent& s : Hold(rig, cmd, 1500).stalls) reported += s.lost_steps;
  RC_ASSERT(!rig.Stalled(Joint::kTrack));
  RC_ASSERT(reported == rig.LostSteps()[0]);
  const double off_steps = rig.FollowingError()[0] * spu;
  RC_ASSERT(std::abs(off_steps - static_cast<double>(rig.LostSteps()[0])) < 0.01);
}

}  // namespace
}  // namespace moco::physics
