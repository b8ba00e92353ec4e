// Dynamics of a boom-swing-track camera rig driven by open-loop steppers
// (FACTS "Boom rig virtual axes" geometry, docs/rig-dynamics.md): profile,
// one fixed 1 ms step at a time, following error, stalls, head collisions.
// No Bullet type appears here (ARCHITECTURE house style 15).
#ifndef MOCO_PHYSICS_BULLET_RIG_DYNAMICS_H_
#define MOCO_PHYSICS_BULLET_RIG_DYNAMICS_H_

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "base/result.h"

namespace moco::physics {

// The six motor-driven joints, in chain order from the floor to the camera.
enum class Joint : int { kTrack = 0, kSwing, kBoom, kPan, kTilt, kRoll };
inline constexpr size_t kJointCount = 6;
inline constexpr std::array<std::string_view, kJointCount> kJointNames = {"track", "swing", "boom",
                                                                          "pan",   "tilt",  "roll"};
inline constexpr size_t Index(Joint j) { return static_cast<size_t>(j); }

// Joint positions (or velocities, errors) in SI units: metres for the track,
// radians for the five revolute joints. Indexed by Index(Joint).
using JointVector = std::array<double, kJointCount>;
using Point3 = std::array<double, 3>;

// The fixed simulation step: 1 ms (1 kHz).
inline constexpr int64_t kStepNs = 1'000'000;
inline constexpr double kStepS = 1e-3;

// A rigid body of the chain. `com_m` is the centre of mass relative to the
// body's joint pivot, in the body's frame (at zero joint angles every frame is
// parallel to the world frame: x east-west, y along the track, z up).
struct BodySpec {
  double mass_kg = 1.0;
  Point3 com_m = {0, 0, 0};
  Point3 inertia_kg_m2 = {0.01, 0.01, 0.01};  // principal moments about the COM
};

// One stepper-driven joint. Profile units ("joint units"): metres for the
// track, degrees for revolute joints; SI (m, rad) once loaded.
struct JointSpec {
  double min = 0;                      // end stop, SI
  double max = 0;                      // end stop, SI
  double home = 0;                     // joint position at motor step 0, SI
  int64_t motor_steps_per_rev = 3200;  // microsteps per motor revolution
  // Motor revolutions per metre of travel (track) or per joint revolution.
  double gear_ratio = 1.0;
  // Pull-out torque at the motor shaft vs motor speed: speeds strictly
  // increasing from 0 (rev/s), torques >= 0 (N m); linear in between, the last
  // value beyond the last speed.
  std::vector<double> pull_out_speed_rev_s;
  std::vector<double> pull_out_torque_n_m;
  double kp = 0;       // stiffness: N/m (track) or N m/rad
  double kd = 0;       // damping against the commanded velocity: N s/m or N m s/rad
  double damping = 0;  // viscous joint friction: N s/m or N m s/rad

  // Motor steps per SI joint unit (per metre, per radian).
  double StepsPerUnit(bool prismatic) const;
  // Motor shaft radians per SI joint unit (the torque multiplier).
  double MotorRadPerUnit(bool prismatic) const;
  // Pull-out torque (N m at the motor) at |speed_rev_s|.
  double PullOutTorque(double speed_rev_s) const;
};

// An axis-aligned box in the world frame.
struct Box {
  std::string name;
  Point3 min_m = {0, 0, 0};
  Point3 max_m = {0, 0, 0};
};

inline constexpr size_t kMaxObstacles = 63;

// Everything the model needs, read from a rig profile (fixtures/rigs/*.json,
// fields in docs/rig-dynamics.md). The world frame's origin is the swing pivot
// with the cart at track position 0.
struct RigProfile {
  std::string name;
  double gravity_m_s2 = 9.81;
  double boom_length_m = 1.5;
  double level_extension_m = 0.0;        // level arm from boom tip to head point
  Point3 nodal_offset_m = {0, 0, 0};     // head point -> nodal point, head frame
  double floor_z_m = -1.0;               // floor height in the world frame
  Point3 head_box_center_m = {0, 0, 0};  // head collision box, head frame
  Point3 head_box_half_m = {0.1, 0.1, 0.1};
  std::vector<Box> obstacles;  // at most kMaxObstacles
  // Bodies: cart (pivot = swing pivot), swing, boom (pivot = swing pivot),
  // extension (pivot = boom tip), pan, tilt, camera (pivot = head point).
  BodySpec cart, swing, boom, extension, pan, tilt, camera;
  std::array<JointSpec, kJointCount> joints;
  // The parallelogram keeping the extension level, as a stiff spring-damper.
  double level_kp_n_m_rad = 5e4;
  double level_kd_n_m_s_rad = 2e2;

  static constexpr bool Prismatic(Joint j) { return j == Joint::kTrack; }
  const JointSpec& joint(Joint j) const { return joints[Index(j)]; }
};

// Why a profile was refused: the field (a JSON path such as
// "joints.boom.kp") and a message saying what was found and what to write.
struct RigProfileError {
  std::string field;
  std::string message;
};

// A profile, or why there is none.
using RigProfileResult = base::Result<RigProfile, RigProfileError>;

// Parses a rig profile from JSON text. `where` prefixes messages (a path).
RigProfileResult ParseRigProfile(std::string_view json_text, std::string_view where = "profile");
// Reads and parses a rig profile file.
RigProfileResult ReadRigProfile(const std::string& path);

// The geometric ideal (FACTS forward kinematics with the conventions of
// docs/rig-dynamics.md): nodal point for joint positions `q`, rigid links.
Point3 IdealNodal(const RigProfile& profile, const JointVector& q);

// Static sag of the boom (rad, positive = below the commanded angle) at boom
// angle `boom_rad` from gravity on a rigid boom and head against the boom
// drive's stiffness.
double BoomSagRad(const RigProfile& profile, double boom_rad);

// Boom compensation table (FACTS "Boom compensation table"): geometric boom
// angle -60..+60 deg in 1 deg steps (121 entries) -> boom motor position in
// steps that holds that angle at rest. Strictly monotonic for a usable rig.
std::vector<int64_t> BoomCompensationTable(const RigProfile& profile);
// Motor steps for geometric angle `boom_rad` by linear interpolation in
// `table` (clamped to its ends).
double BoomCompensatedSteps(const std::vector<int64_t>& table, double boom_rad);

// The head's pose: nodal point and orientation (columns of the rotation from
// head frame to world: x right, y through the lens, z up of the image).
struct HeadPose {
  Point3 nodal_m = {0, 0, 0};
  Point3 right = {1, 0, 0};
  Point3 view = {0, 1, 0};
  Point3 up = {0, 0, 1};
};

// A stepper lost synchronism (demanded torque above its pull-out torque at the
// current speed). Reported once per episode, when the motor is back in step:
// time_ns is the episode's first step, lost_steps its whole-step total
// (positive: the joint fell behind a positive command).
struct StallEvent {
  Joint joint = Joint::kTrack;
  int64_t time_ns = 0;
  int64_t end_ns = 0;
  int64_t lost_steps = 0;
};

// The camera head box began to touch the floor or an obstacle. A contact
// that bounces is one event: the same object is reported again only after
// the head has been clear of it for 100 ms.
struct CollisionEvent {
  std::string what;  // "floor" or the obstacle's name
  int64_t time_ns = 0;
};

// What one Step produced. Valid until the next Step.
struct StepEvents {
  std::vector<StallEvent> stalls;
  std::vector<CollisionEvent> collisions;
  bool empty() const { return stalls.empty() && collisions.empty(); }
};

// The rig's dynamics: a Featherstone multibody of cart, swing, boom, level
// extension, pan, tilt and camera under gravity, each joint pulled towards its
// commanded position by a torque-limited stepper. Deterministic: the same
// profile and the same command sequence give bit-identical states.
// Not thread-safe; movable (a moved-from rig may only be destroyed or
// assigned), not copyable.
class BoomRigDynamics {
 public:
  // Starts at rest at the home positions. REQUIRES: a profile that
  // ParseRigProfile accepted.
  explicit BoomRigDynamics(const RigProfile& profile);
  ~BoomRigDynamics();
  BoomRigDynamics(BoomRigDynamics&&) noexcept;
  BoomRigDynamics& operator=(BoomRigDynamics&&) noexcept;
  BoomRigDynamics(const BoomRigDynamics&) = delete;
  BoomRigDynamics& operator=(const BoomRigDynamics&) = delete;

  // Places the rig at rest at `q` (SI), commanded = physical, no lost steps,
  // no contact; time is kept.
  void Reset(const JointVector& q);

  // Advances one fixed 1 ms step; `commanded` (SI) is the drivers' position
  // at the end of the step (a non-finite value holds the previous command, a
  // value more than the joint's travel beyond an end stop is clamped there). Over the step each
  // driver moves at a constant rate from the previous command to this one; the torque is computed
  // at the step's start from the previous command and that rate.
  const StepEvents& Step(const JointVector& commanded);

  int64_t time_ns() const;
  const RigProfile& profile() const;
  JointVector CommandedJoints() const;
  JointVector PhysicalJoints() const;
  JointVector PhysicalVelocities() const;
  // Commanded minus physical, SI (includes lost steps and sag).
  JointVector FollowingError() const;
  // Whole steps lost so far per joint (sum of the episodes, signed).
  std::array<int64_t, kJointCount> LostSteps() const;
  std::array<int64_t, kJointCount> StallCounts() const;
  // True while a stepper is out of synchronism.
  bool Stalled(Joint j) const;
  // From the simulated link transforms.
  HeadPose Pose() const;
  // The obstacle ("floor" or name) the head touches now, if any.
  std::optional<std::string> Contact() const;
  // Largest |joint velocity| (SI units per second), the level joint included.
  double MaxSpeed() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace moco::physics

#endif  // MOCO_PHYSICS_BULLET_RIG_DYNAMICS_H_
