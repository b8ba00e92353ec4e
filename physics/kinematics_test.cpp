// Rig kinematics against FACTS "Boom rig virtual axes": hand-computed poses,
// and the laws Inverse(Forward(q)) = q, Forward(Inverse(v)) = v, no NaN ever,
// table round trips, and the aim point keeping the camera on its target.
#include "physics/kinematics.h"

#include <gtest/gtest.h>
#include <rapidcheck.h>
#include <rapidcheck/gtest.h>

#include <cmath>
#include <numbers>

namespace moco::physics {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kEps = 1e-12;
constexpr double kLaw = 1e-7;  // tolerance of the round-trip laws

double Deg(double d) { return d * kPi / 180; }

RigGeometry Bst(double l, double e, Vec3 o = {}) {
  RigGeometry g;
  g.type = RigType::kBoomSwingTrack;
  g.boom_length = l;
  g.boom_ext = e;
  g.nodal_offset = o;
  return g;
}

JointPose Joints(double track, double swing, double boom, double pan = 0, double tilt = 0,
                 double roll = 0) {
  return {track, swing, boom, pan, tilt, roll};
}

void ExpectNear(const VirtualPose& a, const VirtualPose& b, double tol) {
  EXPECT_NEAR(a.track, b.track, tol);
  EXPECT_NEAR(a.ew, b.ew, tol);
  EXPECT_NEAR(a.ns, b.ns, tol);
  EXPECT_NEAR(a.pan_rad, b.pan_rad, tol);
  EXPECT_NEAR(a.tilt_rad, b.tilt_rad, tol);
  EXPECT_NEAR(a.roll_rad, b.roll_rad, tol);
}

// --- hand-computed forward kinematics -----------------------------------------------------

TEST(KinematicsForward, LevelBoomStraightAheadAddsLengthAndExtensionToTrack) {
  // tip = (0, T + L, 0) = (0, 1 + 2, 0); head = tip + E (0, 1, 0) = (0, 3.5, 0).
  const auto v = Forward(Bst(2, 0.5), Joints(1, 0, 0));
  ASSERT_TRUE(v.ok());
  ExpectNear(*v, VirtualPose{3.5, 0, 0, 0, 0, 0}, kEps);
}

TEST(KinematicsForward, BoomThirtySwingThirty) {
  // L = 2, E = 0, T = 0, b = s = 30 deg: cos b = sqrt(3)/2, sin b = 1/2.
  // tip = (2 * 0.866 * 0.5, 2 * 0.866 * 0.866, 2 * 0.5) = (0.8660254, 1.5, 1.0);
  // vPan = p + s = 30 deg.
  const auto v = Forward(Bst(2, 0), Joints(0, Deg(30), Deg(30)));
  ASSERT_TRUE(v.ok());
  ExpectNear(*v, VirtualPose{1.5, std::sqrt(3.0) / 2, 1.0, Deg(30), 0, 0}, kEps);
}

TEST(KinematicsForward, ExtensionStaysLevelAlongTheSwing) {
  // As above with E = 1: head = tip + 1 * (sin 30, cos 30, 0)
  //   = (0.8660254 + 0.5, 1.5 + 0.8660254, 1.0) = (1.3660254, 2.3660254, 1.0).
  const auto v = Forward(Bst(2, 1), Joints(0, Deg(30), Deg(30)));
  ASSERT_TRUE(v.ok());
  EXPECT_NEAR(v->ew, 1.3660254037844386, 1e-12);
  EXPECT_NEAR(v->track, 2.3660254037844386, 1e-12);
  EXPECT_NEAR(v->ns, 1.0, 1e-12);
}

TEST(KinematicsForward, NodalOffsetTurnsWithThePan) {
  // L = 1, E = 0, head = (0, 1, 0); pan 90 deg: Rz(90) (x, y, z) = (-y, x, z),
  // so o = (0, 0.1, 0.2) (0.1 along the lens, 0.2 up) becomes (-0.1, 0, 0.2):
  // the camera looks west (-x) and the nodal point sits 0.1 west of the head.
  const auto v = Forward(Bst(1, 0, {0, 0.1, 0.2}), Joints(0, 0, 0, Deg(90)));
  ASSERT_TRUE(v.ok());
  ExpectNear(*v, VirtualPose{1.0, -0.1, 0.2, Deg(90), 0, 0}, kEps);
  const Vec3 look = LookDirection(Deg(90), 0, 0);
  EXPECT_NEAR(look.x, -1, kEps);
  EXPECT_NEAR(look.y, 0, kEps);
}

TEST(KinematicsForward, TiltRaisesTheLensOffset) {
  // Rx(90): (x, y, z) -> (x, -z, y); o = (0, 0.1, 0) -> (0, 0, 0.1).
  const auto v = Forward(Bst(1, 0, {0, 0.1, 0}), Joints(0, 0, 0, 0, Deg(90)));
  ASSERT_TRUE(v.ok());
  ExpectNear(*v, VirtualPose{1.0, 0, 0.1, 0, Deg(90), 0}, kEps);
}

TEST(KinematicsForward, OtherRigTypes) {
  RigGeometry g;
  // y-swing-track, reach L + E = 2: head = (2 sin 30, T + 2 cos 30, lift)
  //   = (1, 5 + 1.7320508, 0.75).
  g.type = RigType::kYSwingTrack;
  g.boom_length = 1.5;
  g.boom_ext = 0.5;
  auto v = Forward(g, Joints(5, Deg(30), 0.75));
  ASSERT_TRUE(v.ok());
  ExpectNear(*v, VirtualPose{5 + std::sqrt(3.0), 1, 0.75, Deg(30), 0, 0}, kEps);
  // x-y-z: boom = z, swing = x, track = y; pan unchanged.
  g.type = RigType::kXyz;
  v = Forward(g, Joints(3, -2, 1, Deg(10)));
  ASSERT_TRUE(v.ok());
  ExpectNear(*v, VirtualPose{3, -2, 1, Deg(10), 0, 0}, kEps);
  // swing-pan with no arm: track carries the swing, the heading adds it.
  g.type = RigType::kSwingPan;
  g.boom_length = 0;
  g.boom_ext = 0;
  v = Forward(g, Joints(0, Deg(20), 0, Deg(5)));
  ASSERT_TRUE(v.ok());
  ExpectNear(*v, VirtualPose{Deg(20), 0, 0, Deg(25), 0, 0}, kEps);
}

// --- hand-computed inverse kinematics -----------------------------------------------------

TEST(KinematicsInverse, BoomThirtySwingThirty) {
  // b = asin(1 / 2) = 30 deg; h = 2 cos 30 = sqrt(3); s = asin((sqrt(3)/2) / sqrt(3))
  // = 30 deg; T = 1.5 - sqrt(3) cos 30 = 1.5 - 1.5 = 0; pan = vPan - s = 0.
  const auto q = Inverse(Bst(2, 0), VirtualPose{1.5, std::sqrt(3.0) / 2, 1.0, Deg(30), 0, 0});
  ASSERT_TRUE(q.ok());
  EXPECT_NEAR(q->boom, Deg(30), kEps);
  EXPECT_NEAR(q->swing, Deg(30), kEps);
  EXPECT_NEAR(q->track, 0, kEps);
  EXPECT_NEAR(q->pan_rad, 0, kEps);
}

TEST(KinematicsInverse, AboveTheBoomOrBeyondItsReachIsUnreachable) {
  // |P.z| = 2.5 > L = 2.
  auto q = Inverse(Bst(2, 0), VirtualPose{0, 0, 2.5, 0, 0, 0});
  ASSERT_FALSE(q.ok());
  EXPECT_EQ(q.error(), KinError::kUnreachable);
  // Level boom: h = L + E = 2.5 < |P.x| = 3.
  q = Inverse(Bst(2, 0.5), VirtualPose{0, 3, 0, 0, 0, 0});
  ASSERT_FALSE(q.ok());
  EXPECT_EQ(q.error(), KinError::kUnreachable);
  // Exactly at full height the boom stands vertical: h = E.
  q = Inverse(Bst(2, 0.5), VirtualPose{0.5, 0, 2, 0, 0, 0});
  ASSERT_TRUE(q.ok());
  EXPECT_NEAR(q->boom, Deg(90), 1e-9);
  EXPECT_NEAR(q->track, 0, 1e-9);
}

TEST(KinematicsInverse, BadGeometryAndNonFiniteInputAreErrors) {
  EXPECT_EQ(Inverse(Bst(0, 0), VirtualPose{}).error(), KinError::kBadGeometry);
  EXPECT_EQ(Forward(Bst(-1, 0), JointPose{}).error(), KinError::kBadGeometry);
  EXPECT_EQ(Inverse(Bst(1, 0), VirtualPose{NAN, 0, 0, 0, 0, 0}).error(), KinError::kBadInput);
  EXPECT_EQ(Forward(Bst(1, 0), Joints(0, INFINITY, 0)).error(), KinError::kBadInput);
  RigGeometry g = Bst(1, 0);
  g.safe_distance = -1;
  EXPECT_EQ(CheckGeometry(g), KinError::kBadGeometry);
}

// --- compensation table -------------------------------------------------------------------

std::array<double, CompensationTable::kEntries> Table(double (*f)(double deg)) {
  std::array<double, CompensationTable::kEntries> t{};
  for (int i = 0; i < CompensationTable::kEntries; ++i) t[static_cast<size_t>(i)] = f(i - 60.0);
  return t;
}

TEST(KinematicsTable, InterpolatesLinearlyBetweenEntries) {
  // Entry at angle a deg = 2a deg (in radians). 10.5 deg lies half-way between
  // the 10 deg (20) and 11 deg (22) entries: 21 deg.
  const auto t = CompensationTable::Make(Table([](double d) { return Deg(2 * d); }));
  ASSERT_TRUE(t.ok());
  EXPECT_NEAR(*t->AxisFromAngle(Deg(10.5)), Deg(21), kEps);
  EXPECT_NEAR(*t->AngleFromAxis(Deg(21)), Deg(10.5), kEps);
  EXPECT_NEAR(*t->AxisFromAngle(Deg(-60)), Deg(-120), kEps);
  EXPECT_NEAR(*t->AxisFromAngle(Deg(60)), Deg(120), kEps);
  EXPECT_EQ(t->AxisFromAngle(Deg(60.5)).error(), KinError::kTableOutOfRange);
  EXPECT_EQ(t->AngleFromAxis(Deg(121)).error(), KinError::kTableOutOfRange);
  // A decreasing drive: entry = -angle.
  const auto d = CompensationTable::Make(Table([](double x) { return Deg(-x); }));
  ASSERT_TRUE(d.ok());
  EXPECT_NEAR(*d->AxisFromAngle(Deg(10.5)), Deg(-10.5), kEps);
  EXPECT_NEAR(*d->AngleFromAxis(Deg(-10.5)), Deg(10.5), kEps);
}

TEST(KinematicsTable, NotStrictlyMonotonicIsRefused) {
  auto t = Table([](double d) { return Deg(d); });
  t[70] = t[69];  // a flat step
  EXPECT_EQ(CompensationTable::Make(t).error(), KinError::kNotMonotonic);
  t = Table([](double d) { return Deg(d * d); });  // down then up
  EXPECT_EQ(CompensationTable::Make(t).error(), KinError::kNotMonotonic);
  t = Table([](double d) { return Deg(d); });
  t[3] = NAN;
  EXPECT_EQ(CompensationTable::Make(t).error(), KinError::kNotMonotonic);
}

TEST(KinematicsTable, BoomAxisGoesThroughTheTable) {
  // Axis = 2 x angle: an axis value of 60 deg is the geometric 30 deg of
  // KinematicsForward.BoomThirtySwingThirty.
  RigGeometry g = Bst(2, 0);
  g.compensation = *CompensationTable::Make(Table([](double d) { return Deg(2 * d); }));
  const auto v = Forward(g, Joints(0, Deg(30), Deg(60)));
  ASSERT_TRUE(v.ok());
  ExpectNear(*v, VirtualPose{1.5, std::sqrt(3.0) / 2, 1.0, Deg(30), 0, 0}, kEps);
  const auto q = Inverse(g, *v);
  ASSERT_TRUE(q.ok());
  EXPECT_NEAR(q->boom, Deg(60), 1e-9);
  // 1.9 up on a boom of 2 is 71.8 deg: past the table.
  EXPECT_EQ(Inverse(g, VirtualPose{0, 0, 1.9, 0, 0, 0}).error(), KinError::kTableOutOfRange);
  EXPECT_EQ(Forward(g, Joints(0, 0, Deg(130))).error(), KinError::kTableOutOfRange);
}

// --- aim point ----------------------------------------------------------------------------

TEST(KinematicsAim, HandComputedAngles) {
  // d = (1, 1, 0): pan = atan2(-1, 1) = -45 deg, tilt = 0; the look direction
  // at pan -45 is (sin 45, cos 45, 0), towards d.
  AimAngles a = AnglesOf({1, 1, 0});
  EXPECT_NEAR(a.pan_rad, Deg(-45), kEps);
  EXPECT_NEAR(a.tilt_rad, 0, kEps);
  // d = (0, 1, 1): tilt = atan2(1, 1) = 45 deg.
  a = AnglesOf({0, 1, 1});
  EXPECT_NEAR(a.pan_rad, 0, kEps);
  EXPECT_NEAR(a.tilt_rad, Deg(45), kEps);
  a = AnglesOf({0, 0, 0});
  EXPECT_EQ(a.pan_rad, 0);
  EXPECT_EQ(a.tilt_rad, 0);
}

TEST(KinematicsAim, OffsetsAreZeroWhenLookingAtTheAimPoint) {
  RigGeometry g;
  g.type = RigType::kXyz;
  // Nodal at the origin, looking at pan -45 deg: straight at (1, 1, 0).
  const auto v = Forward(g, Joints(0, 0, 0, Deg(-45)), Vec3{1, 1, 0});
  ASSERT_TRUE(v.ok());
  EXPECT_NEAR(v->pan_rad, 0, kEps);
  EXPECT_NEAR(v->tilt_rad, 0, kEps);
  // Moving the nodal point to (2, 0, 0) with zero offsets turns the head to
  // d = (-1, 1, 0): pan = atan2(1, 1) = +45 deg.
  const auto q = Inverse(g, VirtualPose{0, 2, 0, 0, 0, 0}, Vec3{1, 1, 0});
  ASSERT_TRUE(q.ok());
  EXPECT_NEAR(q->pan_rad, Deg(45), kEps);
  EXPECT_NEAR(q->swing, 2, kEps);
}

TEST(KinematicsAim, SafeDistanceIsAVerticalCylinder) {
  RigGeometry g;
  g.type = RigType::kXyz;
  g.safe_distance = 1;
  const Vec3 aim{0, 5, 0};
  // 0.8 away horizontally, far below: inside the cylinder whatever the height.
  EXPECT_EQ(Inverse(g, VirtualPose{5, 0.8, -10, 0, 0, 0}, aim).error(),
            KinError::kInsideSafeDistance);
  // 1.2 away: outside.
  EXPECT_TRUE(Inverse(g, VirtualPose{5, 1.2, -10, 0, 0, 0}, aim).ok());
  // Without an aim point the cylinder does not apply.
  EXPECT_TRUE(Inverse(g, VirtualPose{5, 0.8, -10, 0, 0, 0}).ok());
}

// --- laws -----------------------------------------------------------------------------------

// Uniform over [lo, hi] at every size (inRange alone narrows at small sizes).
rc::Gen<double> Uniform(double lo, double hi) {
  return rc::gen::map(rc::gen::resize(rc::kNominalSize, rc::gen::inRange(0, 1'000'001)),
                      [lo, hi](int i) { return lo + (hi - lo) * (i / 1e6); });
}

RigGeometry GenGeometry(RigType type) {
  RigGeometry g;
  g.type = type;
  g.boom_length = *Uniform(0.5, 5);
  g.boom_ext = *Uniform(0, 2);
  g.nodal_offset = {*Uniform(-0.3, 0.3), *Uniform(-0.3, 0.3), *Uniform(-0.3, 0.3)};
  return g;
}

// A joint pose in the branch Inverse returns: swing and boom angle within
// +-85 degrees.
JointPose GenJoints(RigType type) {
  JointPose q;
  q.track = *Uniform(-10, 10);
  q.swing = type == RigType::kXyz ? *Uniform(-10, 10) : *Uniform(Deg(-85), Deg(85));
  q.boom = type == RigType::kBoomSwingTrack ? *Uniform(Deg(-85), Deg(85)) : *Uniform(-5, 5);
  if (type == RigType::kSwingPan) q.track = q.boom = 0;
  q.pan_rad = *Uniform(-kPi, kPi);
  q.tilt_rad = *Uniform(-kPi / 2, kPi / 2);
  q.roll_rad = *Uniform(-kPi, kPi);
  return q;
}

void CheckRoundTrip(RigType type) {
  const RigGeometry g = GenGeometry(type);
  const JointPose q = GenJoints(type);
  const auto v = Forward(g, q);
  RC_ASSERT(v.ok());
  const auto back = Inverse(g, *v);
  RC_ASSERT(back.ok());
  RC_ASSERT(std::abs(back->track - q.track) < kLaw);
  RC_ASSERT(std::abs(back->swing - q.swing) < kLaw);
  RC_ASSERT(std::abs(back->boom - q.boom) < kLaw);
  RC_ASSERT(std::abs(back->pan_rad - q.pan_rad) < kLaw);
  RC_ASSERT(std::abs(back->tilt_rad - q.tilt_rad) < kLaw);
  RC_ASSERT(std::abs(back->roll_rad - q.roll_rad) < kLaw);
}

RC_GTEST_PROP(KinematicsLaw, InverseOfForwardIsIdentityBoomSwingTrack, ()) {
  CheckRoundTrip(RigType::kBoomSwingTrack);
}
RC_GTEST_PROP(KinematicsLaw, InverseOfForwardIsIdentityYSwingTrack, ()) {
  CheckRoundTrip(RigType::kYSwingTrack);
}
RC_GTEST_PROP(KinematicsLaw, InverseOfForwardIsIdentityXyz, ()) { CheckRoundTrip(RigType::kXyz); }
RC_GTEST_PROP(KinematicsLaw, InverseOfForwardIsIdentitySwingPan, ()) {
  CheckRoundTrip(RigType::kSwingPan);
}

RC_GTEST_PROP(KinematicsLaw, ForwardOfInverseIsIdentity, ()) {
  // Targets anywhere in a box around the rig; those with a solution come back.
  RigGeometry g = GenGeometry(RigType::kBoomSwingTrack);
  const VirtualPose v{*Uniform(-10, 10),   *Uniform(-3, 3),     *Uniform(-3, 3),
                      *Uniform(-kPi, kPi), *Uniform(-1.5, 1.5), *Uniform(-kPi, kPi)};
  const auto q = Inverse(g, v);
  RC_PRE(q.ok());
  const auto back = Forward(g, *q);
  RC_ASSERT(back.ok());
  RC_ASSERT(std::abs(back->track - v.track) < kLaw);
  RC_ASSERT(std::abs(back->ew - v.ew) < kLaw);
  RC_ASSERT(std::abs(back->ns - v.ns) < kLaw);
  RC_ASSERT(std::abs(back->pan_rad - v.pan_rad) < kLaw);
  RC_ASSERT(std::abs(back->tilt_rad - v.tilt_rad) < kLaw);
  RC_ASSERT(std::abs(back->roll_rad - v.roll_rad) < kLaw);
}

RC_GTEST_PROP(KinematicsLaw, NeverNaNOnlyErrors, ()) {
  // Any geometry and any target, however wild: an error or finite joints.
  RigGeometry g;
  g.type = *rc::gen::element(RigType::kBoomSwingTrack, RigType::kSwingPan, RigType::kYSwingTrack,
                             RigType::kXyz);
  g.boom_length = *Uniform(-2, 5);
  g.boom_ext = *Uniform(-3, 3);
  g.nodal_offset = {*Uniform(-2, 2), *Uniform(-2, 2), *Uniform(-2, 2)};
  const VirtualPose v{*Uniform(-1e6, 1e6), *Uniform(-20, 20),   *Uniform(-20, 20),
                      *Uniform(-100, 100), *Uniform(-100, 100), *Uniform(-100, 100)};
  const std::optional<Vec3> aim =
      *rc::gen::arbitrary<bool>()
          ? std::optional<Vec3>(Vec3{*Uniform(-20, 20), *Uniform(-20, 20), *Uniform(-20, 20)})
          : std::nullopt;
  const auto q = Inverse(g, v, aim);
  if (q.ok()) {
    RC_ASSERT(std::isfinite(q->track) && std::isfinite(q->swing) && std::isfinite(q->boom));
    RC_ASSERT(std::isfinite(q->pan_rad) && std::isfinite(q->tilt_rad) &&
              std::isfinite(q->roll_rad));
    const auto back = Forward(g, *q, aim);
    RC_ASSERT(back.ok());
  }
}

RC_GTEST_PROP(KinematicsLaw, TableRoundTrip, ()) {
  // A strictly monotonic table from positive increments, either direction.
  std::array<double, CompensationTable::kEntries> t{};
  const bool up = *rc::gen::arbitrary<bool>();
  double acc = *Uniform(-3, 3);
  for (double& e : t) {
    e = acc;
    acc += (up ? 1 : -1) * *Uniform(1e-4, 0.05);
  }
  const auto table = CompensationTable::Make(t);
  RC_ASSERT(table.ok());
  const double angle = *Uniform(Deg(-60), Deg(60));
  const auto axis = table->AxisFromAngle(angle);
  RC_ASSERT(axis.ok());
  const auto angle_back = table->AngleFromAxis(*axis);
  RC_ASSERT(angle_back.ok());
  RC_ASSERT(std::abs(*angle_back - angle) < 1e-9);
  const double lo = std::min(t.front(), t.back()), hi = std::max(t.front(), t.back());
  const double x = lo + (hi - lo) * *Uniform(0, 1);
  const auto a2 = table->AngleFromAxis(x);
  RC_ASSERT(a2.ok());
  RC_ASSERT(std::abs(*table->AxisFromAngle(*a2) - x) < 1e-9);
}

RC_GTEST_PROP(KinematicsLaw, AimPointKeepsTheCameraOnIt, ()) {
  // Zero offsets: wherever the nodal point goes, the lens points at the aim.
  const RigType type =
      *rc::gen::element(RigType::kBoomSwingTrack, RigType::kYSwingTrack, RigType::kXyz);
  const RigGeometry g = GenGeometry(type);
  const auto start = Forward(g, GenJoints(type));
  RC_ASSERT(start.ok());
  const Vec3 aim{start->ew + *Uniform(-5, 5), start->track + *Uniform(2, 8),
                 start->ns + *Uniform(-3, 3)};
  VirtualPose v = *start;
  v.pan_rad = 0;
  v.tilt_rad = 0;
  const auto q = Inverse(g, v, aim);
  RC_PRE(q.ok());
  const auto cam = Camera(g, *q);
  RC_ASSERT(cam.ok());
  const Vec3 look = LookDirection(cam->pan_rad, cam->tilt_rad, cam->roll_rad);
  const Vec3 to_aim = aim - cam->nodal;
  RC_ASSERT(Norm(Cross(look, to_aim)) < 1e-7 * Norm(to_aim));
  RC_ASSERT(Dot(look, to_aim) > 0);
  // Forward with the aim point reads the offsets back as zero, and any other
  // offsets round-trip.
  const auto back = Forward(g, *q, aim);
  RC_ASSERT(back.ok());
  RC_ASSERT(std::abs(back->pan_rad) < kLaw && std::abs(back->tilt_rad) < kLaw);
  v.pan_rad = *Uniform(-0.5, 0.5);
  v.tilt_rad = *Uniform(-0.5, 0.5);
  const auto q2 = Inverse(g, v, aim);
  RC_PRE(q2.ok());
  const auto back2 = Forward(g, *q2, aim);
  RC_ASSERT(back2.ok());
  RC_ASSERT(std::abs(back2->pan_rad - v.pan_rad) < kLaw);
  RC_ASSERT(std::abs(back2->tilt_rad - v.tilt_rad) < kLaw);
  RC_ASSERT(std::abs(back2->ew - v.ew) < kLaw);
}

}  // namespace
}  // namespace moco::physics
