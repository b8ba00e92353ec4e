// Rig kinematics of the DMC v2 virtual axes (see kinematics.h; FACTS "Boom rig
// virtual axes" gives the boom-swing-track formulas followed here).
#include "physics/kinematics.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace moco::physics {

namespace {

constexpr double kDegPerRad = 180.0 / std::numbers::pi;
// Slack on the table's end angles, so that an angle read back from the first
// or last entry (one rounding away from +-60 degrees) stays inside.
constexpr double kTableEdgeDeg = 1e-9;
// Swing-pan: the largest mismatch between a target's ew/ns and those the swing
// implies, relative to the rig's size.
constexpr double kSwingPanTolerance = 1e-6;
// Swing-pan with an aim point and a nodal offset: fixed-point iterations.
constexpr int kSwingPanAimIterations = 64;

bool Finite(double v) { return std::isfinite(v); }
bool Finite(Vec3 v) { return Finite(v.x) && Finite(v.y) && Finite(v.z); }
bool Finite(const JointPose& q) {
  return Finite(q.track) && Finite(q.swing) && Finite(q.boom) && Finite(q.pan_rad) &&
         Finite(q.tilt_rad) && Finite(q.roll_rad);
}
bool Finite(const VirtualPose& v) {
  return Finite(v.track) && Finite(v.ew) && Finite(v.ns) && Finite(v.pan_rad) &&
         Finite(v.tilt_rad) && Finite(v.roll_rad);
}

// The horizontal reach of an arm that swings level (swing-pan, y-swing-track).
double LevelReach(const RigGeometry& g) { return g.boom_length + g.boom_ext; }

// Head pivot of a swinging arm of horizontal reach h at swing s, from (0, y0, z).
Vec3 SwungHead(double h, double s, double y0, double z) {
  return {h * std::sin(s), y0 + h * std::cos(s), z};
}

}  // namespace

double Dot(Vec3 a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
Vec3 Cross(Vec3 a, Vec3 b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
double Norm(Vec3 a) { return std::sqrt(Dot(a, a)); }

std::string_view RigTypeName(RigType t) {
  switch (t) {
    case RigType::kBoomSwingTrack:
      return "boom-swing-track";
    case RigType::kSwingPan:
      return "swing-pan";
    case RigType::kYSwingTrack:
      return "y-swing-track";
    case RigType::kXyz:
      return "x-y-z";
  }
  return "?";
}

// --- compensation table -------------------------------------------------------------------

Solved<CompensationTable> CompensationTable::Make(const std::array<double, kEntries>& axis_rad) {
  for (double v : axis_rad) {
    if (!Finite(v)) return KinError::kNotMonotonic;
  }
  const bool increasing = axis_rad[1] > axis_rad[0];
  for (size_t i = 1; i < axis_rad.size(); ++i) {
    const bool up = axis_rad[i] > axis_rad[i - 1];
    const bool down = axis_rad[i] < axis_rad[i - 1];
    if (increasing ? !up : !down) return KinError::kNotMonotonic;
  }
  CompensationTable t;
  t.axis_rad_ = axis_rad;
  t.increasing_ = increasing;
  return t;
}

Solved<double> CompensationTable::AxisFromAngle(double angle_rad) const {
  if (!Finite(angle_rad)) return KinError::kBadInput;
  double deg = angle_rad * kDegPerRad;
  if (deg < kFirstDeg - kTableEdgeDeg || deg > kLastDeg + kTableEdgeDeg) {
    return KinError::kTableOutOfRange;
  }
  deg = std::clamp(deg, double{kFirstDeg}, double{kLastDeg});
  const double u = deg - kFirstDeg;  // 0..120
  const int i = std::min(static_cast<int>(std::floor(u)), kEntries - 2);
  const double frac = u - i;
  const double a = axis_rad_[static_cast<size_t>(i)];
  const double b = axis_rad_[static_cast<size_t>(i) + 1];
  return a + frac * (b - a);
}

Solved<double> CompensationTable::AngleFromAxis(double axis_rad) const {
  if (!Finite(axis_rad)) return KinError::kBadInput;
  const double lo = increasing_ ? axis_rad_.front() : axis_rad_.back();
  const double hi = increasing_ ? axis_rad_.back() : axis_rad_.front();
  if (axis_rad < lo || axis_rad > hi) return KinError::kTableOutOfRange;
  // First entry past the value in the table's direction of travel.
  size_t lo_i = 0, hi_i = kEntries - 1;
  while (hi_i - lo_i > 1) {
    const size_t mid = (lo_i + hi_i) / 2;
    const bool before = increasing_ ? axis_rad_[mid] <= axis_rad : axis_rad_[mid] >= axis_rad;
    (before ? lo_i : hi_i) = mid;
  }
  const double a = axis_rad_[lo_i];
  const double b = axis_rad_[hi_i];
  const double frac = std::clamp((axis_rad - a) / (b - a), 0.0, 1.0);
  const double deg = kFirstDeg + static_cast<double>(lo_i) + frac;
  return deg / kDegPerRad;
}

// --- geometry -------------------------------------------------------------------------

std::optional<KinError> CheckGeometry(const RigGeometry& g) {
  if (!Finite(g.boom_length) || !Finite(g.boom_ext) || !Finite(g.nodal_offset) ||
      !Finite(g.safe_distance) || g.safe_distance < 0) {
    return KinError::kBadGeometry;
  }
  switch (g.type) {
    case RigType::kBoomSwingTrack:
      if (g.boom_length <= 0) return KinError::kBadGeometry;
      break;
    case RigType::kYSwingTrack:
    case RigType::kSwingPan:
      if (LevelReach(g) < 0) return KinError::kBadGeometry;
      break;
    case RigType::kXyz:
      break;
  }
  return std::nullopt;
}

Vec3 Rotate(double pan_rad, double tilt_rad, double roll_rad, Vec3 v) {
  // Ry(roll), then Rx(tilt), then Rz(pan).
  const double cr = std::cos(roll_rad), sr = std::sin(roll_rad);
  const Vec3 a{cr * v.x + sr * v.z, v.y, -sr * v.x + cr * v.z};
  const double ct = std::cos(tilt_rad), st = std::sin(tilt_rad);
  const Vec3 b{a.x, ct * a.y - st * a.z, st * a.y + ct * a.z};
  const double cp = std::cos(pan_rad), sp = std::sin(pan_rad);
  return {cp * b.x - sp * b.y, sp * b.x + cp * b.y, b.z};
}

Vec3 LookDirection(double pan_rad, double tilt_rad, double roll_rad) {
  return Rotate(pan_rad, tilt_rad, roll_rad, {0, 1, 0});
}

AimAngles AnglesOf(Vec3 d) {
  // atan2(0, 0) is 0: a zero direction gives (0, 0), never a NaN.
  return {std::atan2(-d.x, d.y), std::atan2(d.z, std::hypot(d.x, d.y))};
}

// --- forward --------------------------------------------------------------------------

Solved<CameraPose> Camera(const RigGeometry& g, const JointPose& q) {
  if (auto e = CheckGeometry(g)) return *e;
  if (!Finite(q)) return KinError::kBadInput;
  CameraPose c;
  c.tilt_rad = q.tilt_rad;
  c.roll_rad = q.roll_rad;
  Vec3 head;
  switch (g.type) {
    case RigType::kBoomSwingTrack: {
      double b = q.boom;
      if (g.compensation) {
        const Solved<double> angle = g.compensation->AngleFromAxis(q.boom);
        if (!angle) return angle.error();
        b = *angle;
      }
      const double s = q.swing;
      const double l = g.boom_length;
      // FACTS: tip = (L cos b sin s, T + L cos b cos s, L sin b); the
      // extension stays level along the swing.
      const Vec3 tip{l * std::cos(b) * std::sin(s), q.track + l * std::cos(b) * std::cos(s),
                     l * std::sin(b)};
      head = tip + g.boom_ext * Vec3{std::sin(s), std::cos(s), 0};
      c.pan_rad = q.pan_rad + s;
      break;
    }
    case RigType::kSwingPan:
      head = SwungHead(LevelReach(g), q.swing, 0, 0);
      c.pan_rad = q.pan_rad + q.swing;
      break;
    case RigType::kYSwingTrack:
      head = SwungHead(LevelReach(g), q.swing, q.track, q.boom);
      c.pan_rad = q.pan_rad + q.swing;
      break;
    case RigType::kXyz:
      head = {q.swing, q.track, q.boom};
      c.pan_rad = q.pan_rad;
      break;
  }
  c.nodal = head + Rotate(c.pan_rad, c.tilt_rad, c.roll_rad, g.nodal_offset);
  return c;
}

Solved<VirtualPose> Forward(const RigGeometry& g, const JointPose& q,
                            const std::optional<Vec3>& aim) {
  if (aim && !Finite(*aim)) return KinError::kBadInput;
  const Solved<CameraPose> cam = Camera(g, q);
  if (!cam) return cam.error();
  VirtualPose v;
  v.track = g.type == RigType::kSwingPan ? q.swing : cam->nodal.y;
  v.ew = cam->nodal.x;
  v.ns = cam->nodal.z;
  v.pan_rad = cam->pan_rad;
  v.tilt_rad = cam->tilt_rad;
  v.roll_rad = cam->roll_rad;
  if (aim) {
    const AimAngles base = AnglesOf(*aim - cam->nodal);
    v.pan_rad -= base.pan_rad;
    v.tilt_rad -= base.tilt_rad;
  }
  return v;
}

// --- inverse --------------------------------------------------------------------------

namespace {

Solved<JointPose> InverseSwingPan(const RigGeometry& g, const VirtualPose& v,
                                  const std::optional<Vec3>& aim) {
  JointPose q;
  q.swing = v.track;
  q.tilt_rad = v.tilt_rad;
  q.roll_rad = v.roll_rad;
  const Vec3 head = SwungHead(LevelReach(g), q.swing, 0, 0);
  double pan_w = v.pan_rad;
  double tilt_w = v.tilt_rad;
  Vec3 nodal = head + Rotate(pan_w, tilt_w, v.roll_rad, g.nodal_offset);
  if (aim) {
    // The nodal point turns with the head, the head follows the aim point:
    // iterate to the fixed point (exact at once without a nodal offset).
    bool settled = false;
    for (int i = 0; i < kSwingPanAimIterations && !settled; ++i) {
      const AimAngles base = AnglesOf(*aim - nodal);
      pan_w = base.pan_rad + v.pan_rad;
      tilt_w = base.tilt_rad + v.tilt_rad;
      const Vec3 next = head + Rotate(pan_w, tilt_w, v.roll_rad, g.nodal_offset);
      settled = Norm(next - nodal) <= 1e-15 * (1 + Norm(nodal));
      nodal = next;
    }
    if (!settled) return KinError::kUnreachable;
    if (g.safe_distance > 0 && std::hypot(nodal.x - aim->x, nodal.y - aim->y) < g.safe_distance) {
      return KinError::kInsideSafeDistance;
    }
  }
  const double size = 1 + std::abs(LevelReach(g)) + Norm(g.nodal_offset);
  if (std::abs(nodal.x - v.ew) > kSwingPanTolerance * size ||
      std::abs(nodal.z - v.ns) > kSwingPanTolerance * size) {
    return KinError::kUnreachable;
  }
  q.pan_rad = pan_w - q.swing;
  q.tilt_rad = tilt_w;
  return q;
}

}  // namespace

Solved<JointPose> Inverse(const RigGeometry& g, const VirtualPose& v,
                          const std::optional<Vec3>& aim) {
  if (auto e = CheckGeometry(g)) return *e;
  if (!Finite(v) || (aim && !Finite(*aim))) return KinError::kBadInput;
  if (g.type == RigType::kSwingPan) return InverseSwingPan(g, v, aim);

  const Vec3 target = v.Nodal();
  double pan_w = v.pan_rad;
  double tilt_w = v.tilt_rad;
  if (aim) {
    // FACTS: a vertical cylinder of radius SAFE DISTANCE around the aim point.
    if (g.safe_distance > 0 && std::hypot(target.x - aim->x, target.y - aim->y) < g.safe_distance) {
      return KinError::kInsideSafeDistance;
    }
    const AimAngles base = AnglesOf(*aim - target);
    pan_w += base.pan_rad;
    tilt_w += base.tilt_rad;
  }
  // The head pivot: the nodal target less the rotated nodal offset.
  const Vec3 p = target - Rotate(pan_w, tilt_w, v.roll_rad, g.nodal_offset);

  JointPose q;
  q.tilt_rad = tilt_w;
  q.roll_rad = v.roll_rad;
  switch (g.type) {
    case RigType::kBoomSwingTrack: {
      const double l = g.boom_length;
      if (std::abs(p.z) > l) return KinError::kUnreachable;
      const double b = std::asin(std::clamp(p.z / l, -1.0, 1.0));
      const double h = l * std::cos(b) + g.boom_ext;
      if (h <= 0 || std::abs(p.x) > h) return KinError::kUnreachable;
      const double s = std::asin(std::clamp(p.x / h, -1.0, 1.0));
      q.swing = s;
      q.track = p.y - h * std::cos(s);
      q.boom = b;
      if (g.compensation) {
        const Solved<double> axis = g.compensation->AxisFromAngle(b);
        if (!axis) return axis.error();
        q.boom = *axis;
      }
      q.pan_rad = pan_w - s;
      break;
    }
    case RigType::kYSwingTrack: {
      const double h = LevelReach(g);
      if (std::abs(p.x) > h || (h == 0 && p.x != 0)) return KinError::kUnreachable;
      const double s = h == 0 ? 0 : std::asin(std::clamp(p.x / h, -1.0, 1.0));
      q.swing = s;
      q.track = p.y - h * std::cos(s);
      q.boom = p.z;
      q.pan_rad = pan_w - s;
      break;
    }
    case RigType::kXyz:
      q.swing = p.x;
      q.track = p.y;
      q.boom = p.z;
      q.pan_rad = pan_w;
      break;
    case RigType::kSwingPan:
      break;  // handled above
  }
  return q;
}

}  // namespace moco::physics
