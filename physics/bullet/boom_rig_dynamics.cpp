// The boom rig as a Bullet Featherstone multibody (FACTS "Bullet (Debian 3.24,
// float64)", "Boom rig virtual axes"; model in docs/rig-dynamics.md): torque-
// limited stepper drives, lost steps, the parallelogram, head contact tests.
// Every Bullet type of the project lives in this file.
#include <algorithm>
#include <cmath>
#include <numbers>
#include <utility>

#include <BulletCollision/BroadphaseCollision/btDbvtBroadphase.h>
#include <BulletCollision/CollisionDispatch/btCollisionDispatcher.h>
#include <BulletCollision/CollisionDispatch/btCollisionWorld.h>
#include <BulletCollision/CollisionDispatch/btDefaultCollisionConfiguration.h>
#include <BulletCollision/CollisionShapes/btBoxShape.h>
#include <BulletCollision/NarrowPhaseCollision/btManifoldPoint.h>
#include <BulletDynamics/Featherstone/btMultiBody.h>
#include <BulletDynamics/Featherstone/btMultiBodyConstraintSolver.h>
#include <BulletDynamics/Featherstone/btMultiBodyDynamicsWorld.h>
#include <BulletDynamics/Featherstone/btMultiBodyLinkCollider.h>

#include "physics/bullet/rig_dynamics.h"

namespace moco::physics {
namespace {

// Multibody link indices, floor to camera. The extension is the parallelogram's
// level arm, not driven by a motor.
enum Link : int { kCart = 0, kSwing, kBoom, kExtension, kPan, kTilt, kCamera, kLinkCount };

constexpr std::array<int, kJointCount> kLinkOfJoint = {kCart, kSwing, kBoom, kPan, kTilt, kCamera};

// End stops: a spring this many times the joint's stiffness beyond min/max.
constexpr double kEndStopStiffnessFactor = 4.0;
// Box shapes keep their outer size; a small margin keeps corners sharp.
constexpr double kShapeMargin_m = 0.002;
// Filter bits: link colliders collide with nothing (FACTS: joint torques need
// link colliders to act, but the rig's own bodies never touch).
constexpr int kLinkGroup = 0x40;

btVector3 V(const Point3& v) { return btVector3(v[0], v[1], v[2]); }
Point3 V(const btVector3& v) { return {v.x(), v.y(), v.z()}; }
btVector3 Inertia(const BodySpec& b) { return V(b.inertia_kg_m2); }

// The floor and up to 63 obstacles, one bit each in a contact mask.
constexpr int kMaxEnvironmentObjects = 64;
// A contact that bounces (the head springing back on its drives after a
// stop) is one collision: a new one is reported only after the head has
// been clear of that object for this many steps.
constexpr int kContactReleaseSteps = 100;

// Half extents of a link's (non-colliding) collider: a box around its COM.
constexpr double kLinkColliderHalf_m = 0.05;

struct ContactCollector : btCollisionWorld::ContactResultCallback {
  uint64_t touched = 0;
  btScalar addSingleResult(btManifoldPoint& cp, const btCollisionObjectWrapper* w0, int, int,
                           const btCollisionObjectWrapper* w1, int, int) override {
    if (cp.getDistance() > 0) return 0;
    // One of the two is the head (user index -1); the other is the obstacle.
    const int a = w0->getCollisionObject()->getUserIndex();
    const int b = w1->getCollisionObject()->getUserIndex();
    const int hit = a >= 0 ? a : b;
    if (hit < 0 || hit >= kMaxEnvironmentObjects) return 0;
    touched |= uint64_t{1} << hit;
    return 0;
  }
};

}  // namespace

struct BoomRigDynamics::Impl {
  RigProfile profile;

  // Dynamics world (the multibody and its non-colliding link colliders).
  btDefaultCollisionConfiguration config;
  btCollisionDispatcher dispatcher{&config};
  btDbvtBroadphase broadphase;
  btMultiBodyConstraintSolver solver;
  btMultiBodyDynamicsWorld world{&dispatcher, &broadphase, &solver, &config};
  std::unique_ptr<btMultiBody> body;
  std::vector<std::unique_ptr<btBoxShape>> shapes;
  std::vector<std::unique_ptr<btMultiBodyLinkCollider>> colliders;

  // Environment world: floor (user index 0) and obstacles (1..n); the head
  // box is tested against it each step.
  btDefaultCollisionConfiguration env_config;
  btCollisionDispatcher env_dispatcher{&env_config};
  btDbvtBroadphase env_broadphase;
  btCollisionWorld env{&env_dispatcher, &env_broadphase, &env_config};
  std::vector<std::unique_ptr<btCollisionObject>> env_objects;
  std::unique_ptr<btBoxShape> head_shape;
  btCollisionObject head;
  btTransform head_in_camera;  // head box pose in the camera link's COM frame
  uint64_t touching = 0;       // geometric contact this step
  uint64_t in_contact = 0;     // contact episodes (released after kContactReleaseSteps clear)
  std::array<int, kMaxEnvironmentObjects> clear_steps{};

  // Drive state.
  int64_t time_ns = 0;
  JointVector commanded{};
  JointVector previous_commanded{};
  std::array<int64_t, kJointCount> offset_steps{};  // steps lost so far
  std::array<bool, kJointCount> stalled{};
  std::array<int64_t, kJointCount> episode_start_ns{};
  std::array<int64_t, kJointCount> episode_lost{};
  std::array<int64_t, kJointCount> stall_count{};
  std::array<double, kJointCount> steps_per_unit{};
  std::array<double, kJointCount> motor_rad_per_unit{};
  StepEvents events;

  btAlignedObjectArray<btQuaternion> scratch_rot;
  btAlignedObjectArray<btVector3> scratch_pos;

  explicit Impl(const RigProfile& p) : profile(p) {
    for (size_t j = 0; j < kJointCount; ++j) {
      const bool prismatic = RigProfile::Prismatic(static_cast<Joint>(j));
      steps_per_unit[j] = p.joints[j].StepsPerUnit(prismatic);
      motor_rad_per_unit[j] = p.joints[j].MotorRadPerUnit(prismatic);
    }
    BuildBody();
    BuildEnvironment();
    JointVector home{};
    for (size_t j = 0; j < kJointCount; ++j) home[j] = p.joints[j].home;
    Reset(home);
  }

  ~Impl() {
    for (auto& c : colliders) world.removeCollisionObject(c.get());
    world.removeMultiBody(body.get());
    for (auto& o : env_objects) env.removeCollisionObject(o.get());
  }

  void BuildBody() {
    const RigProfile& p = profile;
    // A fixed base at the world origin (the swing pivot at track 0).
    body = std::make_unique<btMultiBody>(kLinkCount, 1.0, btVector3(1, 1, 1), /*fixedBase=*/true,
                                         /*canSleep=*/false);
    body->setBasePos(btVector3(0, 0, 0));
    body->setWorldToBaseRot(btQuaternion::getIdentity());
    const btQuaternion same = btQuaternion::getIdentity();
    const btVector3 zero(0, 0, 0);
    // Positive swing and pan turn from +y towards +x (clockwise seen from
    // above), positive boom and tilt raise, positive roll turns the image
    // clockwise seen from behind the camera (docs/rig-dynamics.md "Frames").
    const btVector3 down(0, 0, -1);
    const btVector3 x_axis(1, 0, 0);
    const btVector3 y_axis(0, 1, 0);
    body->setupPrismatic(kCart, p.cart.mass_kg, Inertia(p.cart), -1, same, y_axis, zero,
                         V(p.cart.com_m), true);
    body->setupRevolute(kSwing, p.swing.mass_kg, Inertia(p.swing), kCart, same, down,
                        -V(p.cart.com_m), V(p.swing.com_m), true);
    body->setupRevolute(kBoom, p.boom.mass_kg, Inertia(p.boom), kSwing, same, x_axis,
                        -V(p.swing.com_m), V(p.boom.com_m), true);
    body->setupRevolute(kExtension, p.extension.mass_kg, Inertia(p.extension), kBoom, same, x_axis,
                        btVector3(0, p.boom_length_m, 0) - V(p.boom.com_m), V(p.extension.com_m),
                        true);
    body->setupRevolute(kPan, p.pan.mass_kg, Inertia(p.pan), kExtension, same, down,
                        btVector3(0, p.level_extension_m, 0) - V(p.extension.com_m), V(p.pan.com_m),
                        true);
    body->setupRevolute(kTilt, p.tilt.mass_kg, Inertia(p.tilt), kPan, same, x_axis, -V(p.pan.com_m),
                        V(p.tilt.com_m), true);
    body->setupRevolute(kCamera, p.camera.mass_kg, Inertia(p.camera), kTilt, same, y_axis,
                        -V(p.tilt.com_m), V(p.camera.com_m), true);
    body->finalizeMultiDof();
    // Bullet's default velocity damping is not a physical effect of the rig;
    // joint friction is applied explicitly.
    body->setLinearDamping(0);
    body->setAngularDamping(0);
    body->setUseGyroTerm(true);
    body->setHasSelfCollision(false);
    world.setGravity(btVector3(0, 0, -p.gravity_m_s2));
    world.addMultiBody(body.get());

    for (int i = 0; i < kLinkCount; ++i) {
      auto shape = std::make_unique<btBoxShape>(
          btVector3(kLinkColliderHalf_m, kLinkColliderHalf_m, kLinkColliderHalf_m));
      auto collider = std::make_unique<btMultiBodyLinkCollider>(body.get(), i);
      collider->setCollisionShape(shape.get());
      collider->setCollisionFlags(collider->getCollisionFlags() |
                                  btCollisionObject::CF_NO_CONTACT_RESPONSE);
      world.addCollisionObject(collider.get(), kLinkGroup, /*mask=*/0);
      body->getLink(i).m_collider = collider.get();
      shapes.push_back(std::move(shape));
      colliders.push_back(std::move(collider));
    }
  }

  void AddEnvironmentBox(const Point3& min_m, const Point3& max_m, int user_index) {
    const btVector3 lo = V(min_m);
    const btVector3 hi = V(max_m);
    auto shape = std::make_unique<btBoxShape>((hi - lo) * 0.5);
    shape->setMargin(kShapeMargin_m);
    auto object = std::make_unique<btCollisionObject>();
    object->setCollisionShape(shape.get());
    btTransform t;
    t.setIdentity();
    t.setOrigin((hi + lo) * 0.5);
    object->setWorldTransform(t);
    object->setUserIndex(user_index);
    env.addCollisionObject(object.get());
    shapes.push_back(std::move(shape));
    env_objects.push_back(std::move(object));
  }

  void BuildEnvironment() {
    const RigProfile& p = profile;
    // The floor: a slab 1 m thick whose top is floor_z_m, wide enough for any rig.
    AddEnvironmentBox({-1e3, -1e3, p.floor_z_m - 1.0}, {1e3, 1e3, p.floor_z_m}, 0);
    for (size_t i = 0; i < p.obstacles.size(); ++i) {
      AddEnvironmentBox(p.obstacles[i].min_m, p.obstacles[i].max_m, static_cast<int>(i + 1));
    }
    head_shape = std::make_unique<btBoxShape>(V(p.head_box_half_m));
    head_shape->setMargin(kShapeMargin_m);
    head.setCollisionShape(head_shape.get());
    head.setUserIndex(-1);
    head_in_camera.setIdentity();
    head_in_camera.setOrigin(V(p.head_box_center_m) - V(p.camera.com_m));
  }

  void UpdateTransforms() {
    body->forwardKinematics(scratch_rot, scratch_pos);
    body->updateCollisionObjectWorldTransforms(scratch_rot, scratch_pos);
  }

  void Reset(const JointVector& q) {
    for (size_t j = 0; j < kJointCount; ++j) {
      body->setJointPos(kLinkOfJoint[j], q[j]);
      body->setJointVel(kLinkOfJoint[j], 0);
    }
    body->setJointPos(kExtension, -q[Index(Joint::kBoom)]);
    body->setJointVel(kExtension, 0);
    body->clearForcesAndTorques();
    UpdateTransforms();
    commanded = q;
    previous_commanded = q;
    offset_steps = {};
    stalled = {};
    episode_lost = {};
    touching = 0;
    in_contact = 0;
    CheckContacts(/*report=*/false);
  }

  // Torque (force) of joint j's stepper towards the command; stall bookkeeping.
  double DriveTorque(size_t j, double q, double qd) {
    const JointSpec& spec = profile.joints[j];
    const double spu = steps_per_unit[j];
    // The torque over the step is evaluated at its start (explicit in the
    // drive, as Bullet is in applied torques): the driver's count at the
    // start against the joint at the start, and the count's rate over the step.
    const double commanded_velocity = (commanded[j] - previous_commanded[j]) / kStepS;
    double error = previous_commanded[j] - static_cast<double>(offset_steps[j]) / spu - q;
    const double error_rate = commanded_velocity - qd;
    double demand = spec.kp * error + spec.kd * error_rate;
    const double motor_rev_s = qd * motor_rad_per_unit[j] / (2.0 * std::numbers::pi);
    const double available = spec.PullOutTorque(motor_rev_s) * motor_rad_per_unit[j];
    if (std::abs(demand) <= available) {
      if (stalled[j]) {
        stalled[j] = false;
        events.stalls.push_back(
            StallEvent{static_cast<Joint>(j), episode_start_ns[j], time_ns, episode_lost[j]});
      }
      return demand;
    }
    // Beyond pull-out the rotor falls out of step with the driver's field and
    // re-locks a whole number of steps away: the driver's count and the
    // joint diverge by the steps it slipped (open loop: nobody notices).
    const int64_t lost = std::llround(error * spu);
    if (lost != 0) {
      if (!stalled[j]) {
        stalled[j] = true;
        episode_start_ns[j] = time_ns;
        episode_lost[j] = 0;
        ++stall_count[j];
      }
      offset_steps[j] += lost;
      episode_lost[j] += lost;
      error -= static_cast<double>(lost) / spu;
      demand = spec.kp * error + spec.kd * error_rate;
    }
    return std::clamp(demand, -available, available);
  }

  void CheckContacts(bool report) {
    btTransform camera = body->getLink(kCamera).m_collider->getWorldTransform();
    head.setWorldTransform(camera * head_in_camera);
    ContactCollector collector;
    env.contactTest(&head, collector);
    touching = collector.touched;
    for (int i = 0; i < static_cast<int>(env_objects.size()); ++i) {
      const uint64_t bit = uint64_t{1} << i;
      if ((touching & bit) != 0) {
        clear_steps[static_cast<size_t>(i)] = 0;
        if ((in_contact & bit) == 0 && report) {
          events.collisions.push_back(CollisionEvent{Name(i), time_ns});
        }
        in_contact |= bit;
      } else if ((in_contact & bit) != 0 &&
                 ++clear_steps[static_cast<size_t>(i)] >= kContactReleaseSteps) {
        in_contact &= ~bit;
      }
    }
  }

  std::string Name(int user_index) const {
    if (user_index == 0) return "floor";
    return profile.obstacles[static_cast<size_t>(user_index - 1)].name;
  }

  const StepEvents& Step(const JointVector& command) {
    events.stalls.clear();
    events.collisions.clear();
    previous_commanded = commanded;
    for (size_t j = 0; j < kJointCount; ++j) {
      // A non-finite command holds the last one; a command far beyond the
      // end stops is clamped (the drive would only push into the stop).
      if (std::isfinite(command[j])) {
        const JointSpec& spec = profile.joints[j];
        const double span = spec.max - spec.min;
        commanded[j] = std::clamp(command[j], spec.min - span, spec.max + span);
      }
    }
    for (size_t j = 0; j < kJointCount; ++j) {
      const int link = kLinkOfJoint[j];
      const JointSpec& spec = profile.joints[j];
      const double q = body->getJointPos(link);
      const double qd = body->getJointVel(link);
      double tau = DriveTorque(j, q, qd) - spec.damping * qd;
      if (q > spec.max) tau -= kEndStopStiffnessFactor * spec.kp * (q - spec.max) + spec.kd * qd;
      if (q < spec.min) tau -= kEndStopStiffnessFactor * spec.kp * (q - spec.min) + spec.kd * qd;
      body->addJointTorque(link, tau);
    }
    // The parallelogram holds the extension level: a couple between the swing
    // and the extension, so the boom joint feels it too and the boom drive
    // carries only the head's weight, not its moment.
    const double level_error = -body->getJointPos(kBoom) - body->getJointPos(kExtension);
    const double level_rate = -body->getJointVel(kBoom) - body->getJointVel(kExtension);
    const double level =
        profile.level_kp_n_m_rad * level_error + profile.level_kd_n_m_s_rad * level_rate;
    body->addJointTorque(kExtension, level);
    body->addJointTorque(kBoom, level);

    world.stepSimulation(kStepS, 0, kStepS);
    time_ns += kStepNs;
    CheckContacts(/*report=*/true);
    return events;
  }

  HeadPose Pose() const {
    const btTransform& camera = body->getLink(kCamera).m_collider->getWorldTransform();
    const btVector3 nodal_in_camera = V(profile.nodal_offset_m) - V(profile.camera.com_m);
    const btMatrix3x3& r = camera.getBasis();
    HeadPose pose;
    pose.nodal_m = V(camera * nodal_in_camera);
    pose.right = V(r.getColumn(0));
    pose.view = V(r.getColumn(1));
    pose.up = V(r.getColumn(2));
    return pose;
  }
};

BoomRigDynamics::BoomRigDynamics(const RigProfile& profile)
    : impl_(std::make_unique<Impl>(profile)) {}
BoomRigDynamics::~BoomRigDynamics() = default;
BoomRigDynamics::BoomRigDynamics(BoomRigDynamics&&) noexcept = default;
BoomRigDynamics& BoomRigDynamics::operator=(BoomRigDynamics&&) noexcept = default;

void BoomRigDynamics::Reset(const JointVector& q) { impl_->Reset(q); }
const StepEvents& BoomRigDynamics::Step(const JointVector& commanded) {
  return impl_->Step(commanded);
}
int64_t BoomRigDynamics::time_ns() const { return impl_->time_ns; }
const RigProfile& BoomRigDynamics::profile() const { return impl_->profile; }
JointVector BoomRigDynamics::CommandedJoints() const { return impl_->commanded; }

JointVector BoomRigDynamics::PhysicalJoints() const {
  JointVector q{};
  for (size_t j = 0; j < kJointCount; ++j) q[j] = impl_->body->getJointPos(kLinkOfJoint[j]);
  return q;
}

JointVector BoomRigDynamics::PhysicalVelocities() const {
  JointVector v{};
  for (size_t j = 0; j < kJointCount; ++j) v[j] = impl_->body->getJointVel(kLinkOfJoint[j]);
  return v;
}

JointVector BoomRigDynamics::FollowingError() const {
  JointVector e = PhysicalJoints();
  for (size_t j = 0; j < kJointCount; ++j) e[j] = impl_->commanded[j] - e[j];
  return e;
}

std::array<int64_t, kJointCount> BoomRigDynamics::LostSteps() const { return impl_->offset_steps; }
std::array<int64_t, kJointCount> BoomRigDynamics::StallCounts() const { return impl_->stall_count; }
bool BoomRigDynamics::Stalled(Joint j) const { return impl_->stalled[Index(j)]; }
HeadPose BoomRigDynamics::Pose() const { return impl_->Pose(); }

std::optional<std::string> BoomRigDynamics::Contact() const {
  for (int i = 0; i < kMaxEnvironmentObjects; ++i) {
    if ((impl_->touching >> i) & 1U) return impl_->Name(i);
  }
  return std::nullopt;
}

double BoomRigDynamics::MaxSpeed() const {
  double m = 0;
  for (int i = 0; i < kLinkCount; ++i) m = std::max(m, std::abs(impl_->body->getJointVel(i)));
  return m;
}

}  // namespace moco::physics
