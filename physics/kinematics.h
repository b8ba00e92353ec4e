// Rig kinematics of the DMC v2 virtual axes (dmc-v2-protocol.txt MSG_VIRT_CONFIG,
// MSG_VIRT_GET_POSITION, MSG_VIRT_AIM_POINT; FACTS "Boom rig virtual axes"): joint
// pose <-> virtual pose for the four rig types, the boom compensation table and
// the aim point. Pure math: no clock, no I/O; frames in docs/rig-kinematics.md.
//
// Working frame (right-handed): x = east/west (vEW), y = along the track
// (vTrack), z = up (vNS). Lengths are in the user's units, angles in radians.
// The camera looks along R * (0, 1, 0) with R = Rz(pan) Rx(tilt) Ry(roll).
// The wire's "Kuper" coordinates (X, Y, Z) = (vEW, vNS, vTrack) are (x, z, y).
#ifndef MOCO_PHYSICS_KINEMATICS_H_
#define MOCO_PHYSICS_KINEMATICS_H_

#include <array>
#include <cstdint>
#include <optional>
#include <string_view>
#include <utility>
#include <variant>

namespace moco::physics {

struct Vec3 {
  double x = 0;
  double y = 0;
  double z = 0;
  bool operator==(const Vec3&) const = default;
};

inline Vec3 operator+(Vec3 a, Vec3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline Vec3 operator-(Vec3 a, Vec3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline Vec3 operator*(double k, Vec3 a) { return {k * a.x, k * a.y, k * a.z}; }
double Dot(Vec3 a, Vec3 b);
Vec3 Cross(Vec3 a, Vec3 b);
double Norm(Vec3 a);

// Kuper (X, Y, Z) = (EW, vertical, track) -> working (x, y, z) = (EW, track, up).
inline Vec3 FromKuper(Vec3 k) { return {k.x, k.z, k.y}; }

// Why a pose has no solution. Never a NaN: every failure is one of these.
enum class KinError : uint8_t {
  kUnreachable,         // the target lies outside the rig's workspace
  kInsideSafeDistance,  // the nodal point would enter the aim point's safe cylinder
  kTableOutOfRange,     // boom angle or axis value outside the compensation table
  kNotMonotonic,        // a compensation table that is not strictly monotonic
  kBadGeometry,         // lengths that define no rig (boom length <= 0, non-finite)
  kBadInput,            // a non-finite pose value
};

// A value or a KinError.
template <typename T>
class Solved {
 public:
  Solved(T value) : v_(std::move(value)) {}  // NOLINT: implicit by design
  Solved(KinError error) : v_(error) {}      // NOLINT: implicit by design
  bool ok() const { return v_.index() == 0; }
  explicit operator bool() const { return ok(); }
  // REQUIRES: ok().
  const T& value() const { return std::get<0>(v_); }
  const T& operator*() const { return value(); }
  const T* operator->() const { return &value(); }
  // REQUIRES: !ok().
  KinError error() const { return std::get<1>(v_); }

 private:
  std::variant<T, KinError> v_;
};

// The rig types of MSG_VIRT_CONFIG TYPE 1..4 (capability bits 0x04..0x20).
enum class RigType : uint8_t { kBoomSwingTrack, kSwingPan, kYSwingTrack, kXyz };
std::string_view RigTypeName(RigType t);

// Boom compensation (MSG_VIRT_CONFIG "Boom Compensation Table"; FACTS): the
// boom axis value at geometric boom angles -60, -59, ... +60 degrees, for a
// drive whose travel is not proportional to the angle. Linear between entries.
class CompensationTable {
 public:
  static constexpr int kEntries = 121;
  static constexpr int kFirstDeg = -60;
  static constexpr int kLastDeg = 60;

  // `axis_rad[i]` is the boom axis value (radians of the boom axis) at
  // geometric angle kFirstDeg + i degrees. kNotMonotonic unless every entry is
  // finite and the entries strictly increase or strictly decrease.
  static Solved<CompensationTable> Make(const std::array<double, kEntries>& axis_rad);

  // Geometric angle -> axis value. kTableOutOfRange outside -60..+60 degrees.
  Solved<double> AxisFromAngle(double angle_rad) const;
  // Axis value -> geometric angle (bracketing the entries). kTableOutOfRange
  // outside the first..last entry.
  Solved<double> AngleFromAxis(double axis_rad) const;
  const std::array<double, kEntries>& entries() const { return axis_rad_; }

 private:
  CompensationTable() = default;
  std::array<double, kEntries> axis_rad_{};
  bool increasing_ = true;
};

// The rig's fixed dimensions (MSG_VIRT_CONFIG BOOM LENGTH .. SAFE DISTANCE).
struct RigGeometry {
  RigType type = RigType::kBoomSwingTrack;
  // Boom-swing-track: pivot to boom tip (L). Y-swing-track and swing-pan: the
  // arm's horizontal reach. Unused by x-y-z.
  double boom_length = 1;
  // Level extension after the tip (E), kept horizontal along the swing.
  double boom_ext = 0;
  // Pivot of the pan/tilt/roll head to the nodal point, in the head's frame
  // (x right, y along the lens, z up at pan = tilt = roll = 0).
  Vec3 nodal_offset;
  // Boom-swing-track only: boom axis values per geometric angle.
  std::optional<CompensationTable> compensation;
  // Radius of the vertical cylinder around the aim point that the nodal point
  // must stay out of; 0 = none. Applies while an aim point is given.
  double safe_distance = 0;
};

// kBadGeometry for lengths that define no rig: non-finite values, a negative
// safe distance, or a boom length <= 0 for boom-swing-track.
std::optional<KinError> CheckGeometry(const RigGeometry& g);

// The driven joints, in the order of MSG_VIRT_CONFIG's motor triples. Their
// meaning per rig type (lengths in user units, angles in radians):
//   boom-swing-track: boom = boom axis (the geometric boom angle, or the table's
//                     axis value when there is a table), swing, track
//   swing-pan:        swing (boom and track unused)
//   y-swing-track:    boom = lift height of the arm, swing, track
//   x-y-z:            boom = z (up), swing = x (east/west), track = y
// pan, tilt and roll drive the head on every type.
struct JointPose {
  double track = 0;
  double swing = 0;
  double boom = 0;
  double pan_rad = 0;
  double tilt_rad = 0;
  double roll_rad = 0;
  bool operator==(const JointPose&) const = default;
};

// The virtual axes of MSG_VIRT_GET_POSITION. track/ew/ns: the nodal point in
// user units (swing-pan: `track` carries the swing angle in radians and ew/ns
// follow from it). pan/tilt: the camera's heading and elevation, or, with an
// aim point, offsets from the direction towards it. roll: always the head's.
struct VirtualPose {
  double track = 0;
  double ew = 0;
  double ns = 0;
  double pan_rad = 0;
  double tilt_rad = 0;
  double roll_rad = 0;
  bool operator==(const VirtualPose&) const = default;
  Vec3 Nodal() const { return {ew, track, ns}; }
};

// R = Rz(pan) Rx(tilt) Ry(roll) applied to `v`.
Vec3 Rotate(double pan_rad, double tilt_rad, double roll_rad, Vec3 v);
// Where the camera looks: R * (0, 1, 0).
Vec3 LookDirection(double pan_rad, double tilt_rad, double roll_rad);

// Heading and elevation of direction `d` (FACTS): pan = atan2(-dx, dy),
// tilt = atan2(dz, hypot(dx, dy)). (0, 0) for a zero vector.
struct AimAngles {
  double pan_rad = 0;
  double tilt_rad = 0;
};
AimAngles AnglesOf(Vec3 d);

// The nodal point and world orientation of joint pose `q` (FACTS forward
// kinematics). kTableOutOfRange when the boom axis lies outside the table.
struct CameraPose {
  Vec3 nodal;
  double pan_rad = 0;  // world heading = joint pan + swing (swing-moving rigs)
  double tilt_rad = 0;
  double roll_rad = 0;
};
Solved<CameraPose> Camera(const RigGeometry& g, const JointPose& q);

// Forward kinematics. With `aim`, pan/tilt are reported as offsets from the
// direction nodal -> aim (FACTS "Aim point"). REQUIRES nothing: bad input is
// kBadInput / kBadGeometry.
Solved<VirtualPose> Forward(const RigGeometry& g, const JointPose& q,
                            const std::optional<Vec3>& aim = std::nullopt);

// Inverse kinematics: the joint pose whose Forward is `v` (swing in
// -90..+90 degrees, boom angle in -90..+90). kUnreachable outside the
// workspace, kInsideSafeDistance when `aim` is given, g.safe_distance > 0 and
// the nodal target lies within it horizontally, kTableOutOfRange when the boom
// angle leaves the table. Swing-pan: `track` is the swing; ew/ns must agree
// with it (kUnreachable otherwise, tolerance 1e-6 units).
Solved<JointPose> Inverse(const RigGeometry& g, const VirtualPose& v,
                          const std::optional<Vec3>& aim = std::nullopt);

}  // namespace moco::physics

#endif  // MOCO_PHYSICS_KINEMATICS_H_
