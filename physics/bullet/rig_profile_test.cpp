// Tests of rig profiles (docs/rig-dynamics.md "Profile fields"): the fixture
// loads in SI units, every refusal names its field and the fix, and no JSON
// crashes the reader.
#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>

#include <cmath>
#include <fstream>
#include <numbers>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "physics/bullet/rig_dynamics.h"
#include "physics/bullet/rig_test_support.h"

namespace moco::physics {
namespace {

using nlohmann::json;
using test_support::kDeg;
using test_support::SourcePath;

json Fixture() {
  std::ifstream in(SourcePath("fixtures/rigs/boom-jib.json"));
  std::stringstream text;
  text << in.rdbuf();
  return json::parse(text.str());
}

RigProfileError ErrorOf(const json& doc) {
  const RigProfileResult r = ParseRigProfile(doc.dump(), "test");
  EXPECT_FALSE(r.ok());
  return r.ok() ? RigProfileError{} : r.error();
}

TEST(RigProfileTest, TheBoomJibFixtureLoadsInSiUnits) {
  const RigProfileResult r = ReadRigProfile(SourcePath("fixtures/rigs/boom-jib.json"));
  ASSERT_TRUE(r.ok()) << r.error().message;
  const RigProfile& p = r.value();
  EXPECT_EQ(p.boom_length_m, 1.5);
  EXPECT_EQ(p.level_extension_m, 0.15);
  EXPECT_EQ(p.floor_z_m, -1.4);
  EXPECT_EQ(p.cart.mass_kg, 40.0);
  EXPECT_EQ(p.boom.mass_kg, 8.0);
  ASSERT_EQ(p.obstacles.size(), 1u);
  EXPECT_EQ(p.obstacles[0].name, "light stand");
  // Track limits in metres, revolute limits read in degrees.
  EXPECT_EQ(p.joint(Joint::kTrack).max, 2.5);
  EXPECT_NEAR(p.joint(Joint::kBoom).max, 60 * kDeg, 1e-15);
  EXPECT_NEAR(p.joint(Joint::kSwing).min, -170 * kDeg, 1e-15);
  // 3200 microsteps x 50 motor revolutions per metre.
  EXPECT_EQ(p.joint(Joint::kTrack).StepsPerUnit(true), 160000.0);
  EXPECT_NEAR(p.joint(Joint::kBoom).StepsPerUnit(false), 3200 * 100 / (2 * std::numbers::pi), 1e-9);
  EXPECT_NEAR(p.joint(Joint::kTrack).MotorRadPerUnit(true), 2 * std::numbers::pi * 50, 1e-12);
}

TEST(RigProfileTest, PullOutTorqueInterpolatesLinearlyAndHoldsItsLastValue) {
  const RigProfile p = test_support::BoomJib();
  const JointSpec& boom = p.joint(Joint::kBoom);  // [0,1,3,6,10] -> [3.0,2.8,2.2,1.3,0.5]
  EXPECT_DOUBLE_EQ(boom.PullOutTorque(0), 3.0);
  EXPECT_DOUBLE_EQ(boom.PullOutTorque(1), 2.8);
  EXPECT_DOUBLE_EQ(boom.PullOutTorque(2), 2.5);
  EXPECT_DOUBLE_EQ(boom.PullOutTorque(-2), 2.5);  // either direction
  EXPECT_DOUBLE_EQ(boom.PullOutTorque(8), 0.9);
  EXPECT_DOUBLE_EQ(boom.PullOutTorque(10), 0.5);
  EXPECT_DOUBLE_EQ(boom.PullOutTorque(50), 0.5);
}

struct BadField {
  const char* name;
  json::json_pointer pointer;
  json value;  // null: remove the field
  const char* field;
  const char* says;
};

void PrintTo(const BadField& bad, std::ostream* os) { *os << bad.name; }

class RigProfileRefusalTest : public ::testing::TestWithParam<BadField> {};

TEST_P(RigProfileRefusalTest, NamesTheFieldAndTheFix) {
  const BadField& bad = GetParam();
  json doc = Fixture();
  if (bad.value.is_null()) {
    doc[bad.pointer.parent_pointer()].erase(bad.pointer.back());
  } else {
    doc[bad.pointer] = bad.value;
  }
  const RigProfileError e = ErrorOf(doc);
  EXPECT_EQ(e.field, bad.field);
  EXPECT_NE(e.message.find(bad.field), std::string::npos) << e.message;
  EXPECT_NE(e.message.find(bad.says), std::string::npos) << e.message;
  EXPECT_EQ(e.message.rfind("test: ", 0), 0u) << e.message;  // where it came from
  EXPECT_NE(e.message.find("; "), std::string::npos) << "no fix in: " << e.message;
}

INSTANTIATE_TEST_SUITE_P(
    Fields, RigProfileRefusalTest,
    ::testing::Values(
        BadField{"KpAString", "/joints/boom/kp"_json_pointer, "stiff", "joints.boom.kp",
                 "expected a number"},
        BadField{"KpNegative", "/joints/boom/kp"_json_pointer, -5, "joints.boom.kp",
                 "out of range"},
        BadField{"BoomLengthMissing", "/geometry/boom_length_m"_json_pointer, nullptr,
                 "geometry.boom_length_m", "missing"},
        BadField{"UnknownKey", "/joints/track/kpp"_json_pointer, 1, "joints.track.kpp",
                 "unknown field"},
        BadField{"MaxBelowMin", "/joints/tilt/max"_json_pointer, -95, "joints.tilt.max",
                 "above min"},
        BadField{"HomeOutside", "/joints/roll/home"_json_pointer, 50, "joints.roll.home",
                 "outside"},
        BadField{"SpeedsNotIncreasing", "/joints/swing/pull_out/speed_rev_s"_json_pointer,
                 json::array({0, 5, 2, 10, 15}), "joints.swing.pull_out.speed_rev_s",
                 "strictly increasing"},
        BadField{"CurveLengthsDiffer", "/joints/pan/pull_out/torque_n_m"_json_pointer,
                 json::array({0.5, 0.4}), "joints.pan.pull_out.torque_n_m", "different length"},
        BadField{"ObstacleInsideOut", "/obstacles/0/max_m"_json_pointer,
                 json::array({0.0, 0.0, 0.0}), "obstacles[0].max_m", "exceed min_m"},
        BadField{"NodalOffsetNotAVector", "/geometry/nodal_offset_m"_json_pointer,
                 json::array({1, 2}), "geometry.nodal_offset_m", "[x, y, z]"},
        BadField{"MassZero", "/bodies/camera/mass_kg"_json_pointer, 0, "bodies.camera.mass_kg",
                 "out of range"},
        BadField{"StepsPerRevFractional", "/joints/track/motor_steps_per_rev"_json_pointer, 3200.5,
                 "joints.track.motor_steps_per_rev", "integer"},
        BadField{"BoomMotorTooWeak", "/joints/boom/gear_ratio"_json_pointer, 10,
                 "joints.boom.pull_out", "cannot hold"},
        BadField{"BodiesNotAnObject", "/bodies"_json_pointer, 3, "bodies", "expected an object"}),
    [](const ::testing::TestParamInfo<BadField>& param_info) {
      return std::string(param_info.param.name);
    });

TEST(RigProfileTest, BrokenJsonAndMissingFilesAreValuesNotCrashes) {
  const RigProfileResult broken = ParseRigProfile("{\"geometry\": ", "test");
  ASSERT_FALSE(broken.ok());
  EXPECT_NE(broken.error().message.find("not valid JSON"), std::string::npos);
  const RigProfileResult missing = ReadRigProfile("/nonexistent/rig.json");
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(missing.error().message.find("/nonexistent/rig.json"), std::string::npos);
  EXPECT_FALSE(ParseRigProfile("[]").ok());
  EXPECT_FALSE(ParseRigProfile("").ok());
}

// Any value put at any field of the fixture is either accepted or refused
// with a message naming a field: never a crash, never an exception.
RC_GTEST_PROP(RigProfileProperty, AnyValueAtAnyFieldIsAcceptedOrNamed, ()) {
  json doc = Fixture();
  std::vector<json::json_pointer> pointers;
  const json flat = doc.flatten();
  for (auto it = flat.begin(); it != flat.end(); ++it) pointers.emplace_back(it.key());
  const auto index = *rc::gen::inRange<size_t>(0, pointers.size());
  const int kind = *rc::gen::inRange(0, 6);
  json value;
  switch (kind) {
    case 0:
      value = *rc::gen::arbitrary<double>();
      break;
    case 1:
      value = *rc::gen::arbitrary<int64_t>();
      break;
    case 2:
      value = *rc::gen::arbitrary<std::string>();
      break;
    case 3:
      value = json::array();
      break;
    case 4:
      value = json::object();
      break;
    default:
      value = *rc::gen::arbitrary<bool>();
      break;
  }
  doc[pointers[index]] = value;
  const RigProfileResult r =
      ParseRigProfile(doc.dump(-1, ' ', false, json::error_handler_t::replace), "p");
  if (!r.ok()) {
    RC_ASSERT(!r.error().field.empty());
    RC_ASSERT(r.error().message.find(r.error().field) != std::string::npos);
  }
}

}  // namespace
}  // namespace moco::physics
