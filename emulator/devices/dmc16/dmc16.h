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
  // `scheduler` and `out` must outlive the device. The device starts powered off.
  Dmc16(sim::Scheduler& scheduler, ByteSink& out, Dmc16Profile profile = {});
  ~Dmc16() override;
  Dmc16(const Dmc16&) = delete;
  Dmc16& operator=(const Dmc16&) = delete;

  // --- Device ---
  std::string_view Model() const override { return "dmc16"; }
  LineSettings Line() const override;
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
  // "idle", "armed-run", "armed-shoot", "running", "shooting", "jogging-all".
  std::string_view ModeName() const;
  // MOVE TIME the device reports now (thousandths of a frame).
  uint32_t MoveTimeX1000() const { return move_time_x1000_; }

 private:
  enum class Mode : uint8_t { kIdle, kArmedRun, kArmedShoot, kPass, kShooting, kJogAll };
  struct RunSetup {
    dmc::RtRunMove request;
    std::vector<int> motors;  // uploaded, enabled motors taking part
  };
  struct BlurAxis {
    int motor = 0;
    double x_open_steps = 0;   // continuous position when the shutter opens
    double x_close_steps = 0;  // ... when it closes
    int64_t pre_steps = 0;     // rest position before the ramp up
    int64_t post_steps = 0;    // rest position after the ramp down
  };
  struct Pass {
    uint32_t from_frame = 0;
    uint32_t to_frame = 0;
    int dir = 1;  // +1 forward through the frames, -1 backward
    double fps = 0;
    double preroll_s = 0;
    double postroll_s = 0;
    sim::TimeNs t_first_frame_ns = 0;  // when the rig passes from_frame
    uint32_t frames_done = 0;          // frame intervals completed
    bool video = false;
    bool stills = false;
    bool live = false;  // a RUN_MOVE pass (camera, DMX, triggers, bloop); false for JOG_ALL
  };

  // --- protocol plumbing ---
  void OnFrame(const dmc::FrameRef& f);
  void Handle(uint32_t id, const dmc::HostMessage& m);
  void Send(uint32_t id, const dmc::DeviceMessage& m);
  void SendUnsolicited(const dmc::DeviceMessage& m);
  void Ack(uint32_t id, uint16_t type, dmc::AckCode code);
  void SendPositions(uint32_t id);
  void SendPositionUpdate();
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
  dmc::AckCode OnSetSpeed(const dmc::MotorSetSpeed& m);
  dmc::AckCode OnSetLimits(const dmc::MotorSetLimits& m);
  dmc::AckCode OnPositionFrame(const dmc::RtPositionFrame& m);
  dmc::AckCode OnRunMove(const dmc::RtRunMove& m);
  dmc::AckCode OnShootFrame(uint32_t frame, int dir, uint32_t exposure_ms, double open_deg,
                            double close_deg, const std::vector<dmc::BlurMotor>& motors);
  dmc::AckCode OnGo();
  dmc::AckCode OnStopLoop();
  dmc::AckCode OnJogAll(const dmc::RtJogAll& m);

  // --- motion helpers ---
  // A live pass, a shoot or a jog-all is under way (motion commands wait).
  bool Playing() const {
    return mode_ == Mode::kPass || mode_ == Mode::kShooting || mode_ == Mode::kJogAll;
  }
  static dmc::AckCode FromMoveStatus(sim::MoveStatus s);
  bool MotorValid(int motor) const { return motor >= 1 && motor <= profile_.motor_count; }
  // Motors of the upload that are enabled (they take part in playback).
  std::vector<int> PlaybackMotors() const;
  // Whether every playback motor rests on its position at `frame`.
  bool OnFramePosition(uint32_t frame) const;
  // Starts motor `motor` on `segments` (from rest), ending at rest on `target`.
  void Script(int motor, std::vector<sim::Segment> segments, int64_t target_steps);
  // Frame-path segments of `motor` for frame intervals [k0, k1) of the pass.
  void AppendPath(int motor, const Pass& p, uint32_t k0, uint32_t k1,
                  std::vector<sim::Segment>& out) const;
  int32_t PassPosition(int motor, const Pass& p, uint32_t k) const;
  double PassVelocity(int motor, const Pass& p, uint32_t k) const;  // interval k, steps/s
  // Pre-roll: rest position before the pass and the time to reach speed.
  int64_t PrerollStart(int motor, const Pass& p) const;
  int64_t PostrollEnd(int motor, const Pass& p) const;
  dmc::AckCode CheckPass(const Pass& p) const;
  Pass MakePass(uint32_t from, uint32_t to, double fps, double pre_s, double post_s) const;
  void StartPass(const Pass& p);
  void PlanWindow(uint32_t k0);
  void OnFrameTick();
  void EndPass();
  void StartNextPassOrEnd();
  void StartShoot();
  void FinishRun(bool send_end);
  void Abort(bool send_end);
  void ApplyFrameOutputs(uint32_t frame);
  void EnsurePositionReports();
  void OnReportTimer();
  void CancelTimer(sim::Scheduler::TimerId& id);
  void AddIoTimer(sim::TimeNs at_ns, sim::Callback cb);
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

  Mode mode_ = Mode::kIdle;
  std::optional<RunSetup> run_;
  std::vector<BlurAxis> blur_;
  uint32_t shoot_frame_ = 0;
  uint32_t exposure_ms_ = 0;
  Pass pass_;
  bool stop_loop_ = false;
  bool reposition_pending_ = false;  // a loop pass waits for the rig to reach its pre-roll
  uint32_t reported_inputs_ = 0;
  uint32_t passes_done_ = 0;
  std::optional<uint32_t> on_frame_;  // last frame the rig was sent to
  uint32_t move_time_x1000_ = 0;
  sim::TimeNs last_stop_all_ns_ = -1;
  bool silent_stop_ = false;

  sim::Scheduler::TimerId report_timer_ = sim::Scheduler::kNoTimer;
  sim::Scheduler::TimerId frame_timer_ = sim::Scheduler::kNoTimer;
  sim::Scheduler::TimerId phase_timer_ = sim::Scheduler::kNoTimer;
  struct IoTimer {
    sim::Scheduler::TimerId id;
    sim::TimeNs at_ns;
  };
  std::vector<IoTimer> io_timers_;  // camera and bloop edges of the running pass
};

}  // namespace moco::devices

#endif  // MOCO_DEVICES_DMC16_DMC16_H_
