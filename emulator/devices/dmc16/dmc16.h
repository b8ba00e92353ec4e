// The emulated DMC-16 (dmc-v2-protocol.txt, every MSG_* section; ERRATA dmc
// 1-11; FACTS "DMC v2"): a DMC v2 device on the one clock. It frames and
// decodes host bytes, answers every request exactly once with the request's
// ID, drives the simulated rig, DMX, GIO and camera lines, and sends the
// unsolicited messages (HI, position updates, GIO_IN, HARD_STOP, RT_END).
#ifndef MOCO_DEVICES_DMC16_DMC16_H_
#define MOCO_DEVICES_DMC16_DMC16_H_

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "devices/device.h"
#include "devices/dmc16/dmc16_profile.h"
#include "devices/dmc16/playback.h"
#include "devices/dmc16/rt_move.h"
#include "devices/dmc16/script_planner.h"
#include "devices/dmc16/virtual_axes.h"
#include "physics/bullet/physical_rig.h"
#include "sim/callback.h"
#include "sim/io.h"
#include "sim/rig.h"
#include "sim/scheduler.h"
#include "wire/dmc.h"

namespace moco::devices {

// Counters of what the device saw and did, for State() and tests.
struct Dmc16Stats {
  uint64_t requests = 0;         // host frames answered
  uint64_t checksum_errors = 0;  // answered ERR_CHECKSUM
  uint64_t framing_errors = 0;   // bytes skipped, oversize or truncated candidates
  uint64_t host_acks = 0;        // host ACKs of unsolicited messages (ignored)
  uint64_t unsolicited = 0;      // messages the device sent unprompted
  uint64_t error_replies = 0;    // ACKs with a code other than OK
  uint64_t collisions = 0;       // physical rig: head collisions (each an e-stop)
  uint64_t stalls = 0;           // physical rig: stall episodes (steps lost)
};

class Dmc16 final : public Device, private sim::RigObserver {
 public:
  // The line-idle gap after which a partial frame is given up and its bytes
  // rescanned (dmc-v2-protocol.txt has no inter-byte timeout; the reading is
  // in docs/protocol-notes.md "Idle line"): far longer than any pause inside
  // a frame a host writes in one piece (a byte takes 87 us at 115200 baud; a
  // USB-serial bridge holds a partial packet for at most its 16 ms latency
  // timer), and a fifth of the 250 ms a host waits for an answer, so a request
  // held behind a false header is still answered in time.
  static constexpr sim::TimeNs kLineIdleGapNs = dmc::kLineIdleGapNs;  // 50 ms

  // `scheduler` and `out` must outlive the device. The device starts powered off.
  Dmc16(sim::Scheduler& scheduler, ByteSink& out, Dmc16Profile profile = {});
  ~Dmc16() override;
  Dmc16(const Dmc16&) = delete;
  Dmc16& operator=(const Dmc16&) = delete;

  // --- Device ---
  std::string_view Model() const override { return "dmc16"; }
  DeviceLine Line() const override;
  // Boots: motors at rest on step 0 with the profile's speeds, outputs off,
  // no upload; sends the unsolicited HI (dmc-v2-protocol.txt MSG_HI).
  void PowerOn() override;
  // Drops every volatile state and timer; the rig halts where it is.
  void PowerOff() override;
  bool Powered() const override { return powered_; }
  void OnHostBytes(wire::ByteView bytes) override;
  // A host closing the port ends a partial frame (the decoder starts afresh).
  void OnHostLink(bool open) override;
  sim::Rig* rig() override { return &rig_; }
  sim::GioPort* gio() override { return &gio_; }
  const sim::DmxUniverse* dmx_out() const override { return &dmx_; }
  const sim::CameraPort* camera_out() const override { return &camera_; }
  nlohmann::json State() const override;

  // --- observation (tests, control channel) ---
  const Dmc16Profile& profile() const { return profile_; }
  const Dmc16Stats& stats() const { return stats_; }
  const sim::Rig& rig_ref() const { return rig_; }
  const sim::DmxUniverse& dmx() const { return dmx_; }
  const sim::CameraPort& camera() const { return camera_; }
  const sim::GioPort& gio_ref() const { return gio_; }
  const RtMove& upload() const { return upload_; }
  // The physical rig (profile `physical_rig`), or null.
  const physics::PhysicalRig* physical_rig() const { return physical_.get(); }
  const VirtualAxes& virtual_axes() const { return virtual_; }
  const Playback& playback() const { return playback_; }
  // "idle", "armed-run", "armed-shoot", "running", "shooting", "jogging-all".
  std::string_view ModeName() const { return playback_.ModeName(); }
  // MOVE TIME the device reports now (thousandths of a frame).
  uint32_t MoveTimeX1000() const { return playback_.MoveTimeX1000(); }

 private:
  // --- protocol plumbing ---
  void OnFrameEvent(const dmc::FrameEvent& e);
  // A fresh decoder for the profile's receive buffer and resync reading.
  std::unique_ptr<dmc::FrameDecoder> NewDecoder() const;
  // Forgets a partial frame (power, a host closing the link).
  void ResetFraming();
  // (Re)arms the idle-gap timer while the decoder holds bytes.
  void ArmIdleGap();
  void OnIdleGap();
  void OnFrame(const dmc::FrameRef& f);
  void Handle(uint32_t id, const dmc::HostMessage& m);
  // The MSG_RT_* and MSG_VIRT_* requests, and those the device does not know.
  void HandleRealTimeAndVirtual(uint32_t id, const dmc::HostMessage& msg);
  void Send(uint32_t id, const dmc::DeviceMessage& m);
  void SendUnsolicited(const dmc::DeviceMessage& m);
  void Ack(uint32_t id, uint16_t type, dmc::AckCode code);
  void SendPositions(uint32_t id);
  void SendPositionUpdate();
  uint32_t UnsolicitedId();
  bool Advertised(uint16_t type) const;

  // --- handlers: each returns the ACK code, or sends its specific response ---
  dmc::AckCode OnDmx(const dmc::Dmx& m);
  dmc::AckCode OnGioOut(const dmc::GioOut& m);
  void OnMotorMove(uint32_t id, const dmc::MotorMove& m);
  dmc::AckCode OnMotorStop(const dmc::MotorStop& m);
  dmc::AckCode OnStopAll(const dmc::MotorStopAll& m);
  dmc::AckCode OnResetPosition(const dmc::MotorResetPosition& m);
  dmc::AckCode OnJog(const dmc::MotorJog& m);
  dmc::AckCode OnConfigure(const dmc::MotorConfigure& m);
  // behaviour.coupling kDrivesNext: MOTOR_CONFIGURE with the couplings
  // taken from every motor's flags.
  dmc::AckCode ConfigureDrivingNext(const dmc::MotorConfigure& m);
  dmc::AckCode OnSetSpeed(const dmc::MotorSetSpeed& m);
  dmc::AckCode OnSetLimits(const dmc::MotorSetLimits& m);
  dmc::AckCode OnPositionFrame(uint32_t frame);

  // --- motion helpers ---
  bool MotorValid(int motor) const { return motor >= 1 && motor <= profile_.motor_count; }
  // behaviour.disabled_motors_ignore_motion: a motor not enabled takes a
  // motion command and stays where it is. REQUIRES: MotorValid(motor).
  bool IgnoresMotion(int motor) const {
    return profile_.behaviour.disabled_motors_ignore_motion && !rig_.motor(motor).enabled();
  }
  // MSG_MOTOR_MOVE's motion (not answered here).
  dmc::AckCode MoveMotor(int motor, int64_t target_steps);
  // The position the device reports for `motor` (behaviour.positions_truncate,
  // behaviour.coupling).
  int64_t ReportedPosition(int motor) const;
  // behaviour.coupling kDrivesNext: steps `motor` made while driven by
  // another, which its reported position leaves out.
  int64_t UncountedSteps(int motor) const;
  // ... until its own motion ends (OnMotionFinished).
  void ResyncUncounted(int motor);
  // behaviour.stop_all_lockout_ms: the hard-stop state after a STOP_ALL
  // refuses a request of `type`.
  bool HardStopLockout(uint16_t type);
  bool LockoutActive() const;
  void EnsurePositionReports();
  void OnReportTimer();
  // The velocity tick (behaviour.playback_tick_ms), in ns; 0 without one.
  sim::TimeNs Tick() const {
    return sim::TimeNs{profile_.behaviour.playback_tick_ms} * sim::kNsPerMs;
  }
  // The first tick after now: where a direct move or stop starts with a
  // velocity tick (the firmware plans it on arrival and samples it from its
  // next tick on).
  sim::TimeNs NextTickNs() const { return (scheduler_.Now() / Tick() + 1) * Tick(); }
  void EnsureTick();
  void OnTick();
  void CancelTimer(sim::Scheduler::TimerId& id);
  void CancelAllTimers();
  // Builds the physical rig from the profile (none when not enabled).
  void StartPhysicalRig();
  void ResetState();

  // --- RigObserver ---
  void OnMotionStarted(int motor_id, sim::TimeNs time_ns) override;
  void OnMotionFinished(int motor_id, sim::TimeNs time_ns, int64_t steps) override;
  void OnLimitTripped(int motor_id, sim::LimitEnd end, int set, sim::SwitchInput input,
                      sim::TimeNs time_ns, int64_t steps) override;
  void OnEStop(bool engaged, sim::TimeNs time_ns) override;
  void OnGioInputs(uint32_t inputs);
  // After a virtual motion request: what any motion command does when it starts.
  dmc::AckCode AfterVirtualMotion(dmc::AckCode code);

  sim::Scheduler& scheduler_;
  ByteSink& out_;
  Dmc16Profile profile_;
  sim::Rig rig_;
  sim::GioPort gio_;
  sim::DmxUniverse dmx_;
  sim::CameraPort camera_;
  RtMove upload_;
  std::vector<ScriptPlanner*> planners_;  // owned by the motors, index motor-1
  VirtualAxes virtual_;
  // The Bullet-modelled rig driven by the motors (profile `physical_rig`), or null.
  std::unique_ptr<physics::PhysicalRig> physical_;
  std::string last_collision_;
  std::unique_ptr<dmc::FrameDecoder> decoder_;
  bool powered_ = false;
  uint32_t next_id_ = 1;  // device-side IDs of unsolicited messages (ERRATA 1.9)
  wire::Bytes tx_;        // scratch for encoding
  Dmc16Stats stats_;

  uint32_t reported_inputs_ = 0;
  sim::TimeNs last_stop_all_ns_ = -1;
  bool silent_stop_ = false;
  // The hard-stop state of behaviour.stop_all_lockout_ms, and when the
  // STOP_ALL that set it came.
  bool hard_stop_lock_ = false;
  sim::TimeNs hard_stop_lock_ns_ = 0;
  // Per motor (index motor-1): the MSG_MOTOR_CONFIGURE flags as last received.
  std::vector<uint8_t> config_flags_;
  // behaviour.coupling kDrivesNext, per motor: steps made while driven and
  // since let go; the step count when the current driving began; whether the
  // engine exception went out since power-on.
  std::vector<int64_t> uncounted_;
  std::vector<std::optional<int64_t>> follow_origin_;
  bool engine_exception_sent_ = false;

  sim::Scheduler::TimerId report_timer_ = sim::Scheduler::kNoTimer;
  // The velocity tick's timer; an update due at the next tick; the last
  // position message sent (any, answers included).
  sim::Scheduler::TimerId tick_timer_ = sim::Scheduler::kNoTimer;
  bool report_due_ = false;
  sim::TimeNs last_report_ns_ = -1;
  // The line-idle gap: fires kLineIdleGapNs after the last host chunk.
  sim::Scheduler::TimerId idle_timer_ = sim::Scheduler::kNoTimer;
  sim::TimeNs last_host_bytes_ns_ = 0;
  // The real-time playback of the upload (after the rig, I/O, upload and planners it uses).
  Playback playback_;
};

}  // namespace moco::devices

#endif  // MOCO_DEVICES_DMC16_DMC16_H_
