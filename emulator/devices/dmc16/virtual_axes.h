// The DMC-16's virtual axes (dmc-v2-protocol.txt "Virtuals", MSG_VIRT_CONFIG ..
// MSG_VIRT_AIM_POINT; FACTS "Boom rig virtual axes"): the configured rig, its
// motor mapping and scales, coordinated joint moves from inverse kinematics,
// jogs along the camera's line, and positions from forward kinematics.
//
// Readings taken (docs/devices/dmc16.md "Virtual axes"): angles are degrees on
// the wire; each triple's POSITION is the matching virtual axis's value at
// configuration time (BOOM -> vNS, SWING -> vEW, TRACK -> vTrack, PAN, TILT,
// ROLL), reported as that value + (FK(now) - FK(at configuration)); motor 0
// leaves a joint undriven; aim and nodal X/Y/Z are Kuper (EW, up, track).
#ifndef MOCO_DEVICES_DMC16_VIRTUAL_AXES_H_
#define MOCO_DEVICES_DMC16_VIRTUAL_AXES_H_

#include <array>
#include <cstdint>
#include <optional>
#include <variant>
#include <vector>

#include <nlohmann/json.hpp>

#include "devices/dmc16/dmc16_profile.h"
#include "devices/dmc16/script_planner.h"
#include "physics/kinematics.h"
#include "sim/rig.h"
#include "sim/scheduler.h"
#include "wire/dmc.h"

namespace moco::devices {

class VirtualAxes {
 public:
  // The device's mapping of a refused motor command to its ACK code.
  using AckFromStatus = dmc::AckCode (*)(sim::MoveStatus);

  // `scheduler`, `rig` and `planners` (index motor-1, owned by the motors)
  // must outlive this; `planners` may be filled after construction.
  // `advertised` is the HI CAPABILITIES (mode and aim bits).
  VirtualAxes(sim::Scheduler& scheduler, sim::Rig& rig, const std::vector<ScriptPlanner*>& planners,
              const Dmc16Virtual& settings, uint32_t advertised, AckFromStatus from_status);
  ~VirtualAxes();
  VirtualAxes(const VirtualAxes&) = delete;
  VirtualAxes& operator=(const VirtualAxes&) = delete;

  // Forgets the rig and the aim point and ends a jog (power-on, reset).
  void Reset();
  // Ends a jog along the line; the motors are left to the caller.
  void CancelJog();

  // Each returns the ACK code of the request. Motion requests start the
  // mapped motors (the caller handles ERR_MOVING during playback).
  dmc::AckCode Configure(const dmc::VirtConfig& m);
  dmc::AckCode Move(const dmc::VirtMove& m);
  dmc::AckCode Stop(const dmc::VirtStop& m);
  dmc::AckCode Jog(const dmc::VirtJog& m);
  dmc::AckCode JogOnLine(const dmc::VirtJogOnLine& m);
  // MSG_VIRT_GET_POSITION's response (zeros before VIRT_CONFIG), or
  // ERR_NOT_IN_POSITION when the boom sits outside its compensation table.
  std::variant<dmc::VirtPositionReport, dmc::AckCode> Position() const;
  // MSG_VIRT_AIM_POINT: the configuration now in force (echoed), or the error.
  std::variant<dmc::VirtAimPoint, dmc::AckCode> SetAimPoint(const dmc::VirtAimPoint& m);

  bool configured() const { return config_.has_value(); }
  bool jogging() const { return jog_timer_ != sim::Scheduler::kNoTimer; }
  nlohmann::json State() const;

 private:
  // Joint order of VIRT_CONFIG's triples.
  enum Joint : int { kBoom = 0, kSwing, kTrack, kPan, kTilt, kRoll, kJoints };
  struct Axis {
    int motor = 0;  // 0: not driven
    int32_t steps_per_unit = 0;
  };
  struct Config {
    uint8_t wire_type = 0;
    physics::RigGeometry geometry;
    std::array<Axis, kJoints> axes{};
    // Added to the kinematic virtual pose, per virtual axis (wire units:
    // user units or degrees), from the POSITION fields.
    std::array<double, 6> offset{};
  };
  using Wire6 = std::array<double, 6>;  // vTrack, vEW, vNS, vPan, vTilt, vRoll in wire units

  bool JointIsAngle(int joint) const;
  // Joint pose of the motors' positions (targets: where they are heading).
  physics::JointPose Joints(bool targets) const;
  std::optional<physics::Vec3> AimWorking() const;
  Wire6 ToWire(const physics::VirtualPose& v) const;
  physics::VirtualPose FromWire(const Wire6& w) const;
  // The commanded virtual pose in wire units, or the error.
  std::variant<Wire6, dmc::AckCode> Commanded() const;
  // Inverse kinematics of `w` to motor steps (index motor-1 of the mapped
  // motors), or the error code.
  std::variant<std::vector<std::pair<int, int64_t>>, dmc::AckCode> Solve(const Wire6& w) const;
  // Starts every motor on its target, arriving together from rest; speeds
  // and accelerations scaled by `fraction` (0..1].
  dmc::AckCode MoveMotors(const std::vector<std::pair<int, int64_t>>& targets, double fraction);
  void StopMotors();
  void OnJogTick();

  sim::Scheduler& scheduler_;
  sim::Rig& rig_;
  const std::vector<ScriptPlanner*>& planners_;
  Dmc16Virtual settings_;
  uint32_t advertised_;
  AckFromStatus from_status_;
  std::optional<Config> config_;
  dmc::VirtAimPoint aim_;

  struct JogLine {
    uint8_t axis = 0;
    double rate = 0;          // wire units per second, signed
    physics::Vec3 direction;  // working frame, for X/Y/Z
  };
  JogLine jog_;
  sim::Scheduler::TimerId jog_timer_ = sim::Scheduler::kNoTimer;
};

}  // namespace moco::devices

#endif  // MOCO_DEVICES_DMC16_VIRTUAL_AXES_H_
