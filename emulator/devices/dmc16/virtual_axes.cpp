// The DMC-16's virtual axes (see virtual_axes.h; dmc-v2-protocol.txt MSG_VIRT_*).
#include "devices/dmc16/virtual_axes.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <utility>

namespace moco::devices {

using dmc::AckCode;
using physics::JointPose;
using physics::Vec3;
using physics::VirtualPose;

namespace {

constexpr double kDegPerRad = 180.0 / std::numbers::pi;
constexpr double kPositionScale = dmc::kVirtPositionScale;  // x100000 on the wire
constexpr double kLengthScale = dmc::kVirtLengthScale;      // x1000 on the wire
// An undriven joint may not be asked to move by more than this (wire units).
constexpr double kUndrivenTolerance = 1e-6;
// VIRT_JOG_ON_LINE retargets the motors this often, aiming this far ahead
// along the line, so that they cruise instead of braking between targets.
constexpr sim::TimeNs kJogTickNs = 100 * sim::kNsPerMs;
constexpr double kJogLookaheadS = 1.0;
constexpr int kJogLineAxes = 5;  // X, Y, Z, PAN, TILT
constexpr int kVirtualAxisCount = 6;

// Virtual axis index (0-based: vTrack, vEW, vNS, vPan, vTilt, vRoll) that a
// VIRT_CONFIG triple's POSITION stands for (FACTS reading).
constexpr std::array<int, 6> kOffsetOfJoint = {2, 1, 0, 3, 4, 5};  // boom, swing, track, ...

uint32_t CapabilityOfType(uint8_t type) {
  switch (static_cast<dmc::RigType>(type)) {
    case dmc::RigType::kBoomSwingTrack:
      return dmc::kCapVirtBoomSwingTrack;
    case dmc::RigType::kSwingPan:
      return dmc::kCapVirtSwingPan;
    case dmc::RigType::kYSwingTrack:
      return dmc::kCapVirtYSwingTrack;
    case dmc::RigType::kXyz:
    case dmc::RigType::kXyzFlag:
      return dmc::kCapVirtXyz;
    case dmc::RigType::kNone:
      break;
  }
  return 0;
}

physics::RigType RigOfType(uint8_t type) {
  switch (static_cast<dmc::RigType>(type)) {
    case dmc::RigType::kSwingPan:
      return physics::RigType::kSwingPan;
    case dmc::RigType::kYSwingTrack:
      return physics::RigType::kYSwingTrack;
    case dmc::RigType::kXyz:
    case dmc::RigType::kXyzFlag:
      return physics::RigType::kXyz;
    default:
      return physics::RigType::kBoomSwingTrack;
  }
}

int32_t ToWireInt(double v) {
  const double r = std::round(v);
  if (!std::isfinite(r)) return 0;
  return static_cast<int32_t>(std::clamp(r, double{std::numeric_limits<int32_t>::min()},
                                         double{std::numeric_limits<int32_t>::max()}));
}

}  // namespace

VirtualAxes::VirtualAxes(sim::Scheduler& scheduler, sim::Rig& rig,
                         const std::vector<ScriptPlanner*>& planners, const Dmc16Virtual& settings,
                         uint32_t advertised, AckFromStatus from_status)
    : scheduler_(scheduler),
      rig_(rig),
      planners_(planners),
      settings_(settings),
      advertised_(advertised),
      from_status_(from_status) {}

VirtualAxes::~VirtualAxes() { CancelJog(); }

void VirtualAxes::Reset() {
  CancelJog();
  config_.reset();
  aim_ = {};
}

void VirtualAxes::CancelJog() {
  if (jog_timer_ != sim::Scheduler::kNoTimer) scheduler_.Cancel(jog_timer_);
  jog_timer_ = sim::Scheduler::kNoTimer;
}

// --- units --------------------------------------------------------------------------------

bool VirtualAxes::JointIsAngle(int joint) const {
  if (joint == kPan || joint == kTilt || joint == kRoll) return true;
  const physics::RigType t = config_->geometry.type;
  if (joint == kSwing) return t != physics::RigType::kXyz;
  if (joint == kBoom) return t == physics::RigType::kBoomSwingTrack;
  return false;
}

JointPose VirtualAxes::Joints(bool targets) const {
  std::array<double, kJoints> v{};
  for (int j = 0; j < kJoints; ++j) {
    const Axis& a = config_->axes[static_cast<size_t>(j)];
    if (a.motor == 0) continue;
    const sim::StepperMotor& m = rig_.motor(a.motor);
    const double units =
        static_cast<double>(targets ? m.Target() : m.Position()) / a.steps_per_unit;
    v[static_cast<size_t>(j)] = JointIsAngle(j) ? units / kDegPerRad : units;
  }
  return {v[kTrack], v[kSwing], v[kBoom], v[kPan], v[kTilt], v[kRoll]};
}

std::optional<Vec3> VirtualAxes::AimWorking() const {
  if (aim_.enable == 0 || !config_) return std::nullopt;
  // The aim point is given in the reported (offset) space, Kuper X/Y/Z.
  const auto& d = config_->offset;
  const Vec3 kuper{aim_.x_x1000 / kLengthScale - d[1], aim_.y_x1000 / kLengthScale - d[2],
                   aim_.z_x1000 / kLengthScale - d[0]};
  return physics::FromKuper(kuper);
}

VirtualAxes::Wire6 VirtualAxes::ToWire(const VirtualPose& v) const {
  const bool swing_pan = config_->geometry.type == physics::RigType::kSwingPan;
  const bool aim = aim_.enable != 0;
  const auto& d = config_->offset;
  // With the aim point, vPan/vTilt are offsets from the aim direction and are
  // reported as such, without the configuration offsets.
  return {(swing_pan ? v.track * kDegPerRad : v.track) + d[0],
          v.ew + d[1],
          v.ns + d[2],
          v.pan_rad * kDegPerRad + (aim ? 0 : d[3]),
          v.tilt_rad * kDegPerRad + (aim ? 0 : d[4]),
          v.roll_rad * kDegPerRad + d[5]};
}

VirtualPose VirtualAxes::FromWire(const Wire6& w) const {
  const bool swing_pan = config_->geometry.type == physics::RigType::kSwingPan;
  const bool aim = aim_.enable != 0;
  const auto& d = config_->offset;
  VirtualPose v;
  v.track = swing_pan ? (w[0] - d[0]) / kDegPerRad : w[0] - d[0];
  v.ew = w[1] - d[1];
  v.ns = w[2] - d[2];
  v.pan_rad = (w[3] - (aim ? 0 : d[3])) / kDegPerRad;
  v.tilt_rad = (w[4] - (aim ? 0 : d[4])) / kDegPerRad;
  v.roll_rad = (w[5] - d[5]) / kDegPerRad;
  return v;
}

// --- VIRT_CONFIG ----------------------------------------------------------------------------

AckCode VirtualAxes::Configure(const dmc::VirtConfig& m) {
  const uint8_t type = m.rig_type();
  if (type == static_cast<uint8_t>(dmc::RigType::kNone)) {
    CancelJog();
    config_.reset();
    return AckCode::kOk;
  }
  // A mode the device does not advertise (or no mode at all: 5..7, 9..).
  const uint32_t cap = CapabilityOfType(type);
  if (cap == 0 || (advertised_ & cap) == 0) return AckCode::kErrRange;
  if (rig_.AnyMoving()) return AckCode::kErrMoving;

  Config c;
  c.wire_type = type;
  c.geometry.type = RigOfType(type);
  std::array<int32_t, kJoints> pos_x100000{};
  bool have_positions = false;
  if (const auto* sp = std::get_if<dmc::VirtRigSwingPan>(&m.rig)) {
    // TYPE 2 carries motors and scales only: an arm of no length, no offsets.
    c.geometry.boom_length = 0;
    c.geometry.boom_ext = 0;
    c.axes[kSwing] = {static_cast<int>(std::min<uint32_t>(sp->swing.motor, 255)),
                      sp->swing.steps_per_unit};
    c.axes[kPan] = {static_cast<int>(std::min<uint32_t>(sp->pan.motor, 255)),
                    sp->pan.steps_per_unit};
  } else {
    // TYPE 1, and 3, 4, 8, which the spec gives no layout: read with TYPE 1's.
    dmc::VirtRigBoomSwingTrack b;
    if (const auto* bst = std::get_if<dmc::VirtRigBoomSwingTrack>(&m.rig)) {
      b = *bst;
    } else if (const auto* raw = std::get_if<dmc::VirtRigRaw>(&m.rig)) {
      wire::Bytes data{static_cast<uint8_t>(dmc::RigType::kBoomSwingTrack)};
      data.insert(data.end(), raw->data.begin(), raw->data.end());
      const auto decoded = dmc::DecodeHostMessage(dmc::ToWire(dmc::MsgType::kVirtConfig), data);
      if (!decoded.ok()) return AckCode::kErrGeneral;  // a length that fits no layout
      b = std::get<dmc::VirtRigBoomSwingTrack>(std::get<dmc::VirtConfig>(*decoded).rig);
    } else {
      return AckCode::kErrGeneral;
    }
    const dmc::VirtAxisSetup* setups[kJoints] = {&b.boom, &b.swing, &b.track,
                                                 &b.pan,  &b.tilt,  &b.roll};
    for (int j = 0; j < kJoints; ++j) {
      const dmc::VirtAxisSetup& s = *setups[j];
      c.axes[static_cast<size_t>(j)] = {static_cast<int>(std::min<uint32_t>(s.motor, 255)),
                                        s.steps_per_unit};
      pos_x100000[static_cast<size_t>(j)] = s.position_x100000;
    }
    have_positions = true;
    c.geometry.boom_length = b.boom_length_x1000 / kLengthScale;
    c.geometry.boom_ext = b.boom_ext_x1000 / kLengthScale;
    c.geometry.nodal_offset =
        physics::FromKuper({b.nodal_x_x1000 / kLengthScale, b.nodal_y_x1000 / kLengthScale,
                            b.nodal_z_x1000 / kLengthScale});
    if (b.safe_distance_x1000) c.geometry.safe_distance = *b.safe_distance_x1000 / kLengthScale;
    if (b.compensation && c.geometry.type == physics::RigType::kBoomSwingTrack) {
      std::array<double, physics::CompensationTable::kEntries> t{};
      for (size_t i = 0; i < t.size(); ++i) {
        t[i] = (*b.compensation)[i] / kPositionScale / kDegPerRad;
      }
      const auto table = physics::CompensationTable::Make(t);
      if (!table) return AckCode::kErrRange;
      c.geometry.compensation = *table;
    }
  }
  if (physics::CheckGeometry(c.geometry)) return AckCode::kErrRange;
  // Motor numbers 1..MOTOR COUNT (0: the joint is not driven), each used once,
  // with a non-zero scale.
  uint64_t used = 0;
  for (const Axis& a : c.axes) {
    if (a.motor == 0) continue;
    if (!rig_.ValidMotor(a.motor) || a.steps_per_unit == 0) return AckCode::kErrRange;
    const uint64_t bit = uint64_t{1} << a.motor;
    if ((used & bit) != 0) return AckCode::kErrRange;
    used |= bit;
  }

  std::optional<Config> previous = std::move(config_);
  config_ = std::move(c);
  const auto now = physics::Forward(config_->geometry, Joints(false));
  if (!now) {
    config_ = std::move(previous);
    return AckCode::kErrNotInPosition;  // boom outside its compensation table
  }
  if (have_positions) {
    const Wire6 w = ToWire(*now);  // offsets still zero
    for (int j = 0; j < kJoints; ++j) {
      const size_t axis = static_cast<size_t>(kOffsetOfJoint[static_cast<size_t>(j)]);
      config_->offset[axis] = pos_x100000[static_cast<size_t>(j)] / kPositionScale - w[axis];
    }
  }
  CancelJog();
  return AckCode::kOk;
}

// --- motion ---------------------------------------------------------------------------------

std::variant<VirtualAxes::Wire6, AckCode> VirtualAxes::Commanded() const {
  const auto v = physics::Forward(config_->geometry, Joints(true), AimWorking());
  if (!v) return AckCode::kErrNotInPosition;
  return ToWire(*v);
}

std::variant<std::vector<std::pair<int, int64_t>>, AckCode> VirtualAxes::Solve(
    const Wire6& w) const {
  const auto q = physics::Inverse(config_->geometry, FromWire(w), AimWorking());
  // Unreachable, inside the safe distance, past the compensation table.
  if (!q) return AckCode::kErrRange;
  const JointPose now = Joints(true);
  const std::array<double, kJoints> want = {q->boom,    q->swing,    q->track,
                                            q->pan_rad, q->tilt_rad, q->roll_rad};
  const std::array<double, kJoints> have = {now.boom,    now.swing,    now.track,
                                            now.pan_rad, now.tilt_rad, now.roll_rad};
  std::vector<std::pair<int, int64_t>> out;
  for (int j = 0; j < kJoints; ++j) {
    const size_t i = static_cast<size_t>(j);
    const double scale = JointIsAngle(j) ? kDegPerRad : 1.0;
    const Axis& a = config_->axes[i];
    if (a.motor == 0) {
      if (std::abs((want[i] - have[i]) * scale) > kUndrivenTolerance) return AckCode::kErrRange;
      continue;
    }
    const double steps = std::round(want[i] * scale * a.steps_per_unit);
    if (!std::isfinite(steps) || std::abs(steps) > std::numeric_limits<int32_t>::max()) {
      return AckCode::kErrRange;
    }
    out.emplace_back(a.motor, static_cast<int64_t>(steps));
  }
  return out;
}

AckCode VirtualAxes::MoveMotors(const std::vector<std::pair<int, int64_t>>& targets,
                                double fraction) {
  // Refuse before anything moves.
  for (const auto& [motor, target] : targets) {
    const sim::StepperMotor& m = rig_.motor(motor);
    if (target == m.Target()) continue;
    if (!m.enabled() || rig_.estop_engaged()) return AckCode::kErrGeneral;
    const sim::SoftLimits& s = m.soft_limits();
    if (s.upper_enabled && target > s.upper_steps) return AckCode::kErrSoftUp;
    if (s.lower_enabled && target < s.lower_steps) return AckCode::kErrSoftLow;
  }
  bool at_rest = true;
  for (const auto& [motor, target] : targets) at_rest = at_rest && !rig_.motor(motor).IsMoving();
  // From rest every motor gets the same duration: the slowest motor's
  // shortest time, the others at a lower cruise speed under their full
  // acceleration (a coordinated joint move; the path between is not straight).
  double duration_s = 0;
  if (at_rest) {
    for (const auto& [motor, target] : targets) {
      const sim::StepperMotor& m = rig_.motor(motor);
      const double d = std::abs(static_cast<double>(target - m.Position()));
      const double v = m.profile().max_velocity_steps_per_s * fraction;
      const double a = m.profile().max_accel_steps_per_s2 * fraction;
      const double t = d >= v * v / a ? d / v + v / a : 2 * std::sqrt(d / a);
      duration_s = std::max(duration_s, t);
    }
  }
  for (const auto& [motor, target] : targets) {
    sim::StepperMotor& m = rig_.motor(motor);
    if (target == m.Target() && !m.IsMoving()) continue;
    const double a = m.profile().max_accel_steps_per_s2 * fraction;
    double v = m.profile().max_velocity_steps_per_s * fraction;
    if (at_rest && duration_s > 0) {
      // d = v (T - v / a): the cruise speed that takes exactly T.
      const double d = std::abs(static_cast<double>(target - m.Position()));
      const double disc = std::max(0.0, a * a * duration_s * duration_s - 4 * a * d);
      v = std::max((a * duration_s - std::sqrt(disc)) / 2, 1e-3);
    }
    planners_[static_cast<size_t>(motor - 1)]->Cap(v, a);
    const sim::MoveStatus status = m.MoveTo(target);
    if (status != sim::MoveStatus::kOk) {
      planners_[static_cast<size_t>(motor - 1)]->Drop();
      StopMotors();
      return from_status_(status);
    }
  }
  return AckCode::kOk;
}

void VirtualAxes::StopMotors() {
  if (!config_) return;
  for (const Axis& a : config_->axes) {
    if (a.motor != 0) rig_.motor(a.motor).Stop();
  }
}

AckCode VirtualAxes::Move(const dmc::VirtMove& m) {
  if (!config_) return AckCode::kErrGeneral;
  if (m.axis < 1 || m.axis > kVirtualAxisCount) return AckCode::kErrRange;
  CancelJog();
  auto cmd = Commanded();
  if (const auto* e = std::get_if<AckCode>(&cmd)) return *e;
  Wire6 w = std::get<Wire6>(cmd);
  w[m.axis - 1u] = m.position_x100000 / kPositionScale;
  const auto targets = Solve(w);
  if (const auto* e = std::get_if<AckCode>(&targets)) return *e;
  return MoveMotors(std::get<0>(targets), 1.0);
}

AckCode VirtualAxes::Jog(const dmc::VirtJog& m) {
  if (!config_) return AckCode::kErrGeneral;
  if (m.axis < 1 || m.axis > kVirtualAxisCount) return AckCode::kErrRange;
  if (m.speed < dmc::kJogSpeedInch || m.speed > dmc::kJogSpeedMax) return AckCode::kErrRange;
  CancelJog();
  auto cmd = Commanded();
  if (const auto* e = std::get_if<AckCode>(&cmd)) return *e;
  Wire6 w = std::get<Wire6>(cmd);
  w[m.axis - 1u] = m.destination_x100000 / kPositionScale;
  const auto targets = Solve(w);
  if (const auto* e = std::get_if<AckCode>(&targets)) return *e;
  return MoveMotors(std::get<0>(targets), sim::JogSpeedFraction(m.speed));
}

AckCode VirtualAxes::Stop(const dmc::VirtStop& m) {
  if (m.axis < 1 || m.axis > kVirtualAxisCount) return AckCode::kErrRange;
  // A virtual axis moves several joints: stopping part of them would leave
  // the others on a pose nobody asked for, so every mapped motor decelerates.
  CancelJog();
  StopMotors();
  return AckCode::kOk;
}

AckCode VirtualAxes::JogOnLine(const dmc::VirtJogOnLine& m) {
  if (!config_) return AckCode::kErrGeneral;
  if (m.axis >= kJogLineAxes) return AckCode::kErrRange;
  if (m.speed < -static_cast<int>(dmc::kJogSpeedMax) || m.speed > dmc::kJogSpeedMax) {
    return AckCode::kErrRange;
  }
  CancelJog();
  if (m.speed == 0) {
    StopMotors();
    return AckCode::kOk;
  }
  const auto cam = physics::Camera(config_->geometry, Joints(false));
  if (!cam) return AckCode::kErrNotInPosition;
  // The same 1%..100% as MSG_MOTOR_JOG, with the sign giving the direction.
  const double fraction =
      m.speed < 0 ? -sim::JogSpeedFraction(-m.speed) : sim::JogSpeedFraction(m.speed);
  jog_ = {};
  jog_.axis = m.axis;
  // Camera-local Kuper axes: X right, Y up, Z out of the back of the camera
  // (the lens looks along -Z).
  const auto local = [&](Vec3 v) {
    return physics::Rotate(cam->pan_rad, cam->tilt_rad, cam->roll_rad, v);
  };
  switch (static_cast<dmc::JogLineAxis>(m.axis)) {
    case dmc::JogLineAxis::kX:
      jog_.direction = local({1, 0, 0});
      break;
    case dmc::JogLineAxis::kY:
      jog_.direction = local({0, 0, 1});
      break;
    case dmc::JogLineAxis::kZ:
      jog_.direction = local({0, -1, 0});
      break;
    case dmc::JogLineAxis::kPan:
    case dmc::JogLineAxis::kTilt:
      break;
  }
  const bool angular = m.axis >= static_cast<uint8_t>(dmc::JogLineAxis::kPan);
  jog_.rate = fraction * (angular ? settings_.jog_angle_deg_per_s : settings_.jog_line_units_per_s);
  // The first step is checked; later ones end the jog at the workspace's edge.
  Wire6 w;
  {
    const auto v = physics::Forward(config_->geometry, Joints(false), AimWorking());
    if (!v) return AckCode::kErrNotInPosition;
    w = ToWire(*v);
  }
  const double ahead = jog_.rate * kJogLookaheadS;
  if (angular) {
    w[m.axis == static_cast<uint8_t>(dmc::JogLineAxis::kPan) ? 3 : 4] += ahead;
  } else {
    w[0] += jog_.direction.y * ahead;
    w[1] += jog_.direction.x * ahead;
    w[2] += jog_.direction.z * ahead;
  }
  const auto targets = Solve(w);
  if (const auto* e = std::get_if<AckCode>(&targets)) return *e;
  const AckCode code = MoveMotors(std::get<0>(targets), 1.0);
  if (code != AckCode::kOk) return code;
  jog_timer_ = scheduler_.After(kJogTickNs, [this] { OnJogTick(); });
  return AckCode::kOk;
}

void VirtualAxes::OnJogTick() {
  jog_timer_ = sim::Scheduler::kNoTimer;
  if (!config_) return;
  const auto v = physics::Forward(config_->geometry, Joints(false), AimWorking());
  if (!v) {
    StopMotors();
    return;
  }
  Wire6 w = ToWire(*v);
  const double ahead = jog_.rate * kJogLookaheadS;
  if (jog_.axis >= static_cast<uint8_t>(dmc::JogLineAxis::kPan)) {
    w[jog_.axis == static_cast<uint8_t>(dmc::JogLineAxis::kPan) ? 3 : 4] += ahead;
  } else {
    w[0] += jog_.direction.y * ahead;
    w[1] += jog_.direction.x * ahead;
    w[2] += jog_.direction.z * ahead;
  }
  const auto targets = Solve(w);
  if (std::holds_alternative<AckCode>(targets)) {
    StopMotors();  // the edge of the workspace: the jog ends there
    return;
  }
  // Each motor cruises at the speed that keeps it on the line.
  for (const auto& [motor, target] : std::get<0>(targets)) {
    sim::StepperMotor& m = rig_.motor(motor);
    const double v_steps = std::abs(static_cast<double>(target - m.Position())) / kJogLookaheadS;
    planners_[static_cast<size_t>(motor - 1)]->Cap(std::max(v_steps, 1.0),
                                                   m.profile().max_accel_steps_per_s2);
    if (m.MoveTo(target) != sim::MoveStatus::kOk) {
      planners_[static_cast<size_t>(motor - 1)]->Drop();
      StopMotors();
      return;
    }
  }
  jog_timer_ = scheduler_.After(kJogTickNs, [this] { OnJogTick(); });
}

// --- reports --------------------------------------------------------------------------------

std::variant<dmc::VirtPositionReport, AckCode> VirtualAxes::Position() const {
  dmc::VirtPositionReport r;
  // "This and below are only if device supports aim point".
  if ((advertised_ & dmc::kCapAimPoint) != 0) {
    r.aim = dmc::VirtAim{aim_.enable, aim_.x_x1000, aim_.y_x1000, aim_.z_x1000};
  }
  // Without a rig every virtual axis reads 0.
  if (!config_) return r;
  const auto v = physics::Forward(config_->geometry, Joints(false), AimWorking());
  if (!v) return AckCode::kErrNotInPosition;
  const Wire6 w = ToWire(*v);
  r.track_x100000 = ToWireInt(w[0] * kPositionScale);
  r.ew_x100000 = ToWireInt(w[1] * kPositionScale);
  r.ns_x100000 = ToWireInt(w[2] * kPositionScale);
  r.pan_x100000 = ToWireInt(w[3] * kPositionScale);
  r.tilt_x100000 = ToWireInt(w[4] * kPositionScale);
  r.roll_x100000 = ToWireInt(w[5] * kPositionScale);
  return r;
}

std::variant<dmc::VirtAimPoint, AckCode> VirtualAxes::SetAimPoint(const dmc::VirtAimPoint& m) {
  if (m.enable > 1) return AckCode::kErrRange;
  // Enabling does not move the rig: vPan/vTilt turn into offsets from the
  // aim direction, and later moves keep them.
  aim_ = m;
  return aim_;
}

nlohmann::json VirtualAxes::State() const {
  nlohmann::json j = {{"configured", config_.has_value()},
                      {"jogging", jogging()},
                      {"aim",
                       {{"enabled", aim_.enable != 0},
                        {"x_x1000", aim_.x_x1000},
                        {"y_x1000", aim_.y_x1000},
                        {"z_x1000", aim_.z_x1000}}}};
  if (!config_) return j;
  j["type"] = config_->wire_type;
  j["rig"] = physics::RigTypeName(config_->geometry.type);
  static constexpr const char* kNames[kJoints] = {"boom", "swing", "track", "pan", "tilt", "roll"};
  nlohmann::json axes = nlohmann::json::object();
  for (int i = 0; i < kJoints; ++i) {
    const Axis& a = config_->axes[static_cast<size_t>(i)];
    axes[kNames[i]] = {{"motor", a.motor}, {"steps_per_unit", a.steps_per_unit}};
  }
  j["axes"] = axes;
  j["offset"] = config_->offset;
  if (const auto p = Position(); const auto* r = std::get_if<dmc::VirtPositionReport>(&p)) {
    j["position_x100000"] = {r->track_x100000, r->ew_x100000,   r->ns_x100000,
                             r->pan_x100000,   r->tilt_x100000, r->roll_x100000};
  }
  return j;
}

}  // namespace moco::devices
