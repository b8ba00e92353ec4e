// Rig profiles for the boom-swing-track dynamics (docs/rig-dynamics.md), the
// ideal forward kinematics (FACTS "Boom rig virtual axes") and the boom
// compensation table (FACTS "Boom compensation table"). Pure math, no Bullet.
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <sstream>

#include <nlohmann/json.hpp>

#include "base/file_io.h"
#include "base/json_fields.h"
#include "physics/bullet/rig_dynamics.h"

namespace moco::physics {
namespace {

using nlohmann::json;

constexpr double kDegToRad = std::numbers::pi / 180.0;

using base::FieldProblem;
using base::JsonFields;
using base::kOptional;
using base::kRequired;

std::string Shown(const json& v) {
  std::string s = v.dump();
  if (s.size() > 40) s = s.substr(0, 37) + "...";
  return s;
}

// A refusal in the rig profiles' words: "joints.boom.kp: expected a number
// 0.001..1000000000.0, found a string; write a number in N/m".
RigProfileError RigError(const FieldProblem& p) {
  const std::string field = p.field.empty() ? "(root)" : p.field;
  std::string problem = p.problem;
  switch (p.kind) {
    case FieldProblem::Kind::kNotObject:
    case FieldProblem::Kind::kType:
      problem = "expected " + p.expected + ", found " + p.found;
      break;
    case FieldProblem::Kind::kMissing:
      problem = "missing";
      break;
    case FieldProblem::Kind::kRange:
      problem = p.value + " is out of range";
      break;
    case FieldProblem::Kind::kUnknown:
      problem = "unknown field";
      break;
    case FieldProblem::Kind::kOther:
      break;
  }
  return RigProfileError{field, field + ": " + problem + "; " + p.fix};
}

// Three numbers [x, y, z] in metres, each within +-1000 (above 0 when
// `positive`).
Point3 Vector(JsonFields& r, std::string_view key, Point3 def, base::Presence presence,
              bool positive) {
  const json* v = r.Raw(key);
  if (v != nullptr && (!v->is_array() || v->size() != 3)) {
    r.Fail(key, "expected [x, y, z], found " + Shown(*v), "write three numbers in metres");
    return def;
  }
  const double min = positive ? std::numeric_limits<double>::min() : -1e3;
  const std::vector<double> xyz = r.Numbers(key, min, 1e3, 3, 3, presence);
  if (xyz.size() != 3) return def;
  return {xyz[0], xyz[1], xyz[2]};
}

BodySpec ReadBody(JsonFields& bodies, std::string_view name) {
  JsonFields r = bodies.Child(name, kRequired);
  BodySpec b;
  b.mass_kg = r.Number("mass_kg", 1.0, 1e-3, 1e4, kRequired, "kg");
  b.com_m = Vector(r, "com_m", {0, 0, 0}, kOptional, false);
  b.inertia_kg_m2 = Vector(r, "inertia_kg_m2", {0.01, 0.01, 0.01}, kRequired, true);
  r.Finish();
  return b;
}

JointSpec ReadJoint(JsonFields& joints, Joint j) {
  const bool prismatic = RigProfile::Prismatic(j);
  const double scale = prismatic ? 1.0 : kDegToRad;
  const std::string_view unit = prismatic ? "m" : "deg";
  const double span = prismatic ? 100.0 : 720.0;
  JsonFields r = joints.Child(kJointNames[Index(j)], kRequired);
  JointSpec s;
  s.min = r.Number("min", 0, -span, span, kRequired, unit) * scale;
  s.max = r.Number("max", 0, -span, span, kRequired, unit) * scale;
  if (!r.failed() && !(s.min < s.max)) r.Fail("max", "must be above min", "swap min and max");
  s.home = r.Number("home", 0, -span, span, kOptional, unit) * scale;
  if (!r.failed() && (s.home < s.min || s.home > s.max)) {
    r.Fail("home", "lies outside [min, max]", "move home inside the end stops");
  }
  s.motor_steps_per_rev = r.Int("motor_steps_per_rev", 3200, 1, 1'000'000, kRequired);
  s.gear_ratio = r.Number("gear_ratio", 1, 1e-3, 1e5, kRequired,
                          prismatic ? "motor rev per metre" : "motor rev per joint rev");
  JsonFields curve = r.Child("pull_out", kRequired);
  s.pull_out_speed_rev_s = curve.Numbers("speed_rev_s", 0, 1e4, 1, 64, kRequired);
  s.pull_out_torque_n_m = curve.Numbers("torque_n_m", 0, 1e4, 1, 64, kRequired);
  if (!curve.failed()) {
    if (s.pull_out_speed_rev_s.size() != s.pull_out_torque_n_m.size()) {
      curve.Fail("torque_n_m", "has a different length than speed_rev_s",
                 "give one torque per speed");
    } else if (s.pull_out_speed_rev_s.front() != 0) {
      curve.Fail("speed_rev_s", "must start at 0", "add the holding torque at speed 0");
    } else if (s.pull_out_torque_n_m.front() <= 0) {
      curve.Fail("torque_n_m", "the torque at speed 0 must be positive",
                 "give the motor's holding torque");
    } else {
      for (size_t i = 1; i < s.pull_out_speed_rev_s.size(); ++i) {
        if (!(s.pull_out_speed_rev_s[i] > s.pull_out_speed_rev_s[i - 1])) {
          curve.Fail("speed_rev_s", "must be strictly increasing", "sort the speeds");
          break;
        }
      }
    }
  }
  curve.Finish();
  const std::string_view k_unit = prismatic ? "N/m" : "N m/rad";
  const std::string_view d_unit = prismatic ? "N s/m" : "N m s/rad";
  s.kp = r.Number("kp", 0, 1e-3, 1e9, kRequired, k_unit);
  s.kd = r.Number("kd", 0, 0, 1e8, kRequired, d_unit);
  s.damping = r.Number("damping", 0, 0, 1e8, kOptional, d_unit);
  r.Finish();
  return s;
}

}  // namespace

double JointSpec::StepsPerUnit(bool prismatic) const {
  const double steps = static_cast<double>(motor_steps_per_rev) * gear_ratio;
  return prismatic ? steps : steps / (2.0 * std::numbers::pi);
}

double JointSpec::MotorRadPerUnit(bool prismatic) const {
  return prismatic ? 2.0 * std::numbers::pi * gear_ratio : gear_ratio;
}

double JointSpec::PullOutTorque(double speed_rev_s) const {
  const double v = std::abs(speed_rev_s);
  const std::vector<double>& xs = pull_out_speed_rev_s;
  const std::vector<double>& ys = pull_out_torque_n_m;
  if (xs.empty()) return 0;
  if (v >= xs.back()) return ys.back();
  const size_t i = static_cast<size_t>(std::upper_bound(xs.begin(), xs.end(), v) - xs.begin());
  // xs[0] == 0 <= v < xs.back(), so 1 <= i < size.
  const double f = (v - xs[i - 1]) / (xs[i] - xs[i - 1]);
  return ys[i - 1] + f * (ys[i] - ys[i - 1]);
}

RigProfileResult ParseRigProfile(std::string_view json_text, std::string_view where) {
  json doc;
  std::string duplicate;
  try {
    doc = base::ParseJsonNotingDuplicateKeys(json_text, duplicate);
  } catch (const json::exception&) {
    return RigProfileError{
        "(root)", std::string(where) + ": not valid JSON; check brackets, commas and quotes"};
  }
  if (!duplicate.empty()) {
    return RigProfileError{duplicate, std::string(where) + ": field \"" + duplicate +
                                          "\" is given twice in one object; only one would "
                                          "count: keep the one you mean and delete the other"};
  }
  JsonFields root(doc);
  RigProfile p;
  p.name = root.String("name", "rig");
  p.gravity_m_s2 = root.Number("gravity_m_s2", 9.81, 0, 100, kOptional, "m/s^2");

  JsonFields geo = root.Child("geometry", kRequired);
  p.boom_length_m = geo.Number("boom_length_m", 1.5, 0.05, 50, kRequired, "m");
  p.level_extension_m = geo.Number("level_extension_m", 0, 0, 10, kOptional, "m");
  p.nodal_offset_m = Vector(geo, "nodal_offset_m", {0, 0, 0}, kOptional, false);
  p.floor_z_m = geo.Number("floor_z_m", -1, -100, 0, kRequired, "m (below the swing pivot)");
  geo.Finish();

  JsonFields head = root.Child("head_box", kRequired);
  p.head_box_center_m = Vector(head, "center_m", {0, 0, 0}, kOptional, false);
  p.head_box_half_m = Vector(head, "half_extents_m", {0.1, 0.1, 0.1}, kRequired, true);
  head.Finish();

  if (const json* obstacles = root.Array("obstacles"); obstacles != nullptr) {
    if (obstacles->size() > kMaxObstacles) {
      root.Fail("obstacles", "has " + std::to_string(obstacles->size()) + " boxes",
                "give at most " + std::to_string(kMaxObstacles));
    }
    for (size_t i = 0; i < obstacles->size() && !root.failed(); ++i) {
      JsonFields o = root.Item("obstacles", i);
      Box b;
      b.name = o.String("name", "obstacle " + std::to_string(i + 1));
      b.min_m = Vector(o, "min_m", {0, 0, 0}, kRequired, false);
      b.max_m = Vector(o, "max_m", {0, 0, 0}, kRequired, false);
      if (!root.failed() &&
          !(b.min_m[0] < b.max_m[0] && b.min_m[1] < b.max_m[1] && b.min_m[2] < b.max_m[2])) {
        o.Fail("max_m", "must exceed min_m on every axis", "give the box's two opposite corners");
      }
      if (!root.failed() && b.name == "floor") o.Fail("name", "\"floor\" is reserved", "rename it");
      o.Finish();
      p.obstacles.push_back(std::move(b));
    }
  }

  JsonFields bodies = root.Child("bodies", kRequired);
  p.cart = ReadBody(bodies, "cart");
  p.swing = ReadBody(bodies, "swing");
  p.boom = ReadBody(bodies, "boom");
  p.extension = ReadBody(bodies, "extension");
  p.pan = ReadBody(bodies, "pan");
  p.tilt = ReadBody(bodies, "tilt");
  p.camera = ReadBody(bodies, "camera");
  bodies.Finish();

  JsonFields joints = root.Child("joints", kRequired);
  for (size_t i = 0; i < kJointCount; ++i) p.joints[i] = ReadJoint(joints, static_cast<Joint>(i));
  joints.Finish();

  JsonFields level = root.Child("parallelogram", kOptional);
  p.level_kp_n_m_rad = level.Number("kp_n_m_rad", 5e4, 1, 1e9, kOptional, "N m/rad");
  p.level_kd_n_m_s_rad = level.Number("kd_n_m_s_rad", 2e2, 0, 1e8, kOptional, "N m s/rad");
  level.Finish();
  root.Finish();

  std::optional<RigProfileError> error;
  if (root.failed()) error = RigError(root.problem());
  if (!error) {
    // The boom drive must hold the boom level at rest, or it stalls at once.
    const JointSpec& boom = p.joint(Joint::kBoom);
    const double holding = boom.PullOutTorque(0) * boom.MotorRadPerUnit(/*prismatic=*/false);
    const double load = BoomSagRad(p, 0) * boom.kp;
    if (load >= holding) {
      std::ostringstream m;
      m << "joints.boom.pull_out: holding torque " << holding << " N m at the joint cannot hold "
        << "the boom's static load " << load
        << " N m; raise joints.boom.gear_ratio or the torque at speed 0";
      error = RigProfileError{"joints.boom.pull_out", m.str()};
    }
  }
  if (error) {
    error->message = std::string(where) + ": " + error->message;
    return *error;
  }
  return p;
}

RigProfileResult ReadRigProfile(const std::string& path) {
  std::string text;
  if (auto error = base::ReadFileBounded(path, &text)) {
    return RigProfileError{"(file)", "rig profile " + path + " " + *error +
                                         " (the shipped rigs are in fixtures/rigs/, e.g. "
                                         "fixtures/rigs/boom-jib.json)"};
  }
  return ParseRigProfile(text, "rig profile " + path);
}

Point3 IdealNodal(const RigProfile& p, const JointVector& q) {
  const double t = q[Index(Joint::kTrack)];
  const double s = q[Index(Joint::kSwing)];
  const double b = q[Index(Joint::kBoom)];
  const double heading = s + q[Index(Joint::kPan)];
  const double tilt = q[Index(Joint::kTilt)];
  const double roll = q[Index(Joint::kRoll)];
  const double l = p.boom_length_m;
  const double e = p.level_extension_m;
  // head = tip + E (sin s, cos s, 0), tip = (L cos b sin s, T + L cos b cos s, L sin b).
  const Point3 head = {(l * std::cos(b) + e) * std::sin(s), t + (l * std::cos(b) + e) * std::cos(s),
                       l * std::sin(b)};
  // R = Rz(-heading) Rx(tilt) Ry(roll) applied to the nodal offset.
  const Point3& o = p.nodal_offset_m;
  const Point3 a = {o[0] * std::cos(roll) + o[2] * std::sin(roll), o[1],
                    -o[0] * std::sin(roll) + o[2] * std::cos(roll)};
  const Point3 c = {a[0], a[1] * std::cos(tilt) - a[2] * std::sin(tilt),
                    a[1] * std::sin(tilt) + a[2] * std::cos(tilt)};
  const Point3 d = {c[0] * std::cos(heading) + c[1] * std::sin(heading),
                    -c[0] * std::sin(heading) + c[1] * std::cos(heading), c[2]};
  return {head[0] + d[0], head[1] + d[1], head[2] + d[2]};
}

double BoomSagRad(const RigProfile& p, double boom_rad) {
  // The parallelogram carries the head's moment to the swing, so the boom
  // drive sees the boom's own weight and the head's weight at the boom tip.
  const double head_kg = p.extension.mass_kg + p.pan.mass_kg + p.tilt.mass_kg + p.camera.mass_kg;
  const double boom_arm_m =
      p.boom.com_m[1] * std::cos(boom_rad) - p.boom.com_m[2] * std::sin(boom_rad);
  const double torque_n_m = p.gravity_m_s2 * (p.boom.mass_kg * boom_arm_m +
                                              head_kg * p.boom_length_m * std::cos(boom_rad));
  return torque_n_m / p.joint(Joint::kBoom).kp;
}

std::vector<int64_t> BoomCompensationTable(const RigProfile& p) {
  const JointSpec& boom = p.joint(Joint::kBoom);
  const double spu = boom.StepsPerUnit(false);
  std::vector<int64_t> table;
  table.reserve(121);
  for (int deg = -60; deg <= 60; ++deg) {
    const double angle = deg * kDegToRad;
    const double motor = angle + BoomSagRad(p, angle) - boom.home;
    table.push_back(static_cast<int64_t>(std::llround(motor * spu)));
  }
  return table;
}

double BoomCompensatedSteps(const std::vector<int64_t>& table, double boom_rad) {
  if (table.empty()) return 0;
  const double x =
      std::clamp(boom_rad / kDegToRad + 60.0, 0.0, static_cast<double>(table.size() - 1));
  const size_t i = std::min(static_cast<size_t>(x), table.size() - 1);
  if (i + 1 >= table.size()) return static_cast<double>(table.back());
  const double f = x - static_cast<double>(i);
  return static_cast<double>(table[i]) + f * static_cast<double>(table[i + 1] - table[i]);
}

}  // namespace moco::physics
