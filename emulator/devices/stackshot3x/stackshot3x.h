// The Cognisys StackShot 3X controller as an emulated device in virtual time
// (stackshot-protocol.txt sections 1 and 2, the binary protocol at 38400 8N1;
// section 3, the DfMoco dialect at 57600 8N1; ERRATA.md part 3; FACTS.md
// "StackShot"). docs/devices/stackshot3x.md has the full account.
//
// Model in brief:
//  - Input: PacketDecoder (host sync 0x55), fed one byte at a time so that a
//    mode switch or a reset inside a chunk takes effect at the right byte. On
//    the serial (USB) link a partial packet is dropped after the spec's 2 ms
//    inter-frame gap; on Wi-Fi (TCP) a packet may arrive in segments any time
//    apart. The checksum byte is never verified (ERRATA 3.2, FACTS).
//  - Every packet gets exactly one reply with the packet's command id and
//    upper nibble, the status in the low nibble (ERRATA 3.3). Decode errors
//    answer ErrorReplyStatus(): UNSUPPORTED_CMD, UNSUPPORTED_ACTION or
//    BAD_PARAM. CC_SOFTWARE_CHECKSUM answers after profile.checksum_delay_ms;
//    packets arriving meanwhile wait their turn.
//  - Motion: one sim::Rig of 3 motors, a StackshotPlanner on each (ramp-time
//    trapezoids, Bezier splines). Positions are reported in the rail frame:
//    the motor's steps minus the backlash take-up steps (see RailPosition).
//  - NVM (serial number, NVM registers with register 0 = axis id, the saved
//    configuration slots 0-10, the log) lives in a StateStore and is re-read
//    at every power-on; the active configuration is volatile and starts as
//    slot 0 (the power-on configuration) or the factory defaults. Without a
//    store the device keeps its NVM in memory of its own, so a power cycle
//    or CC_RESET loses nothing of it while the device object lives.
#ifndef MOCO_DEVICES_STACKSHOT3X_STACKSHOT3X_H_
#define MOCO_DEVICES_STACKSHOT3X_STACKSHOT3X_H_

#include <array>
#include <cstdint>
#include <deque>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "devices/device.h"
#include "devices/stackshot3x/stackshot3x_profile.h"
#include "devices/stackshot3x/state_store.h"
#include "sim/planner_stackshot.h"
#include "sim/rig.h"
#include "sim/scheduler.h"
#include "wire/dfmoco.h"
#include "wire/stackshot.h"

namespace moco::devices {

// The active configuration: everything CC_RAIL_CONFIG_* reads and writes
// except the axis id (NVM register 0). CC_RAIL_CONFIG_SAVE copies it to a
// slot, CC_RAIL_CONFIG_LOAD back. Distances are kept in mm (converted on
// the wire with the axis's steps per unit); f32 wire values are kept as
// floats so that a value written reads back bit for bit.
struct Stackshot3xConfig {
  // Per shutter output (bits 4-5 of the action byte: 0 = shutter 1, 1 =
  // shutter 2); times per sub-item (bit 7 clear: first pulse, set: second
  // and subsequent pulses).
  struct Shutter {
    uint16_t num_pulses = 1;
    std::array<float, 2> pulse_time_s{0.1f, 0.1f};
    std::array<float, 2> off_time_s{0.5f, 0.5f};
    bool operator==(const Shutter&) const = default;
  };
  // Per axis (bits 4-5 of the action byte: 0 = X, 1 = Y, 2 = Z).
  struct Axis {
    uint8_t torque = 10;               // 1-10
    uint8_t holding_torque = 5;        // 0-10
    double speed_mm_per_s = 2.0;       // CC_RAIL_CONFIG_SPEED (stacking speed)
    double move_speed_mm_per_s = 4.0;  // CC_RAIL_CONFIG_SPEED_MOVE
    float ramp_time_s = 0.25f;
    double distance_per_rev_mm = 2.0;
    double backlash_mm = 0.1;
    bool reverse = false;  // CC_RAIL_CONFIG_POLARITY
    float rotary_backlash_deg = 0.0f;
    float rotary_ratio = 1.0f;
    float rotary_degrees = 10.0f;
    stackshot::ShutterSetting shutter = stackshot::ShutterSetting::kShutter1;
    uint16_t num_steps = 10;  // CC_RAIL_CONFIG_NUM_STEPS
    double total_distance_mm = 5.0;
    double distance_per_step_mm = 0.5;
    bool operator==(const Axis&) const = default;
  };

  std::string name;       // "" reads as the single byte 0xFF (power-on / saved)
  uint8_t backlight = 5;  // 1-10
  stackshot::RailMode mode = stackshot::RailMode::kAutoStep;
  stackshot::Units units = stackshot::Units::kMm;
  stackshot::GlobalMode global_mode = stackshot::GlobalMode::kAdvanced;
  float settle_time_s = 1.0f;
  float timelapse_s = 0.0f;
  bool shutter_disable = false;
  bool auto_return = false;
  bool toff_final = true;
  stackshot::IoMode io_mode = stackshot::IoMode::kNormal;
  stackshot::Direction io_dir = stackshot::Direction::kForward;
  std::array<Shutter, 2> shutters{};
  std::array<Axis, 3> axes{};

  bool operator==(const Stackshot3xConfig&) const = default;

  // Factory defaults for a profile (distance per revolution from the axes).
  static Stackshot3xConfig Defaults(const Stackshot3xProfile& profile);
  nlohmann::json ToJson() const;
  // nullopt when `j` is not a config this device wrote (type or range).
  static std::optional<Stackshot3xConfig> FromJson(const nlohmann::json& j);
};

// Deliberate misbehaviour, for testing a conformance runner against a broken
// controller. Everything is off by default.
struct Stackshot3xFaults {
  bool bad_reply_checksum = false;  // every reply's checksum byte is one off
  uint16_t drop_reply_to = 0;       // replies to this command id are not sent (0: none)
  uint16_t misecho_reply_to = 0;    // replies to this command id carry the next id (0: none)
  bool serial_rewritable = false;   // CC_SERIAL_NUMBER takes every write
  bool busy_never_clears = false;   // an axis that has moved reports MOVING (and BUSY) for good
};

class Stackshot3x : public Device, private sim::RigObserver {
 public:
  // What carries the host's bytes (stackshot-protocol.txt sections 3 and 4).
  // kSerial: the USB serial port (binary protocol, or the DfMoco dialect in
  // GLOBAL_MODE_MOTION_DFMOCO; the 2 ms inter-frame gap). kWifi: a TCP
  // connection (binary protocol only: DfMoco "runs over USB"; no gap).
  using HostLink = devices::HostLink;

  static constexpr int kAxes = 3;
  static constexpr int kShutters = 2;
  static constexpr size_t kMaxLogEntries = 64;
  static constexpr size_t kMaxNameBytes = 32;
  // One CC_LOG entry and its NUL fit one packet's 255 data bytes.
  static constexpr size_t kMaxLogEntryBytes = 254;  // fits COMM_BUFFER_SIZE (40) with header
  // SHUTTER_FIRE bounds ("bounded to the minimum/maximum allowed").
  static constexpr float kShutterMinS = 0.001f;
  static constexpr float kShutterMaxS = 3600.0f;
  static constexpr uint16_t kShutterMinPulses = 1;
  // CC_RAIL_CONFIG_* time values (settle, off, timelapse...) accept 0..this.
  static constexpr float kMaxConfigTimeS = 3600.0f;
  static constexpr float kMaxRampTimeS = 10.0f;
  static constexpr double kMmPerMil = 0.0254;
  // Longest travel a distance, position or move may ask for, in steps (far
  // beyond any rail; keeps step arithmetic in range). Beyond it: BAD_PARAM.
  static constexpr double kMaxTravelSteps = 1e9;
  // `im` crawls at this fraction of the axis's maximum speed.
  static constexpr double kInchFraction = 0.02;

  // `scheduler`, `sink` and `store` must outlive the device. `store` may be
  // null (embedded use): the NVM then lives in the device's own memory and
  // survives power cycles and CC_RESET, but not the device object.
  // Constructed powered off, on the serial link.
  Stackshot3x(sim::Scheduler& scheduler, ByteSink& sink, Stackshot3xProfile profile = {},
              StateStore* store = nullptr);
  ~Stackshot3x() override;
  Stackshot3x(const Stackshot3x&) = delete;
  Stackshot3x& operator=(const Stackshot3x&) = delete;

  // --- Device ---
  std::string_view Model() const override { return "stackshot3x"; }
  // The protocol table's line of the dialect spoken: stackshot::kBaudRate 8N1
  // in binary mode, stackshot::kDfMocoBaudRate 8N1 in DfMoco mode (ERRATA 3.7).
  DeviceLine Line() const override;
  // Reads the NVM from the store, takes slot 0 (or the factory defaults) as
  // the active configuration and answers after profile.boot_delay_ms.
  void PowerOn() override;
  // Halts every motor, drops every volatile state and timer.
  void PowerOff() override;
  bool Powered() const override { return powered_; }
  void OnHostBytes(wire::ByteView bytes) override;
  sim::Rig* rig() override { return &rig_; }
  sim::GioPort* gio() override { return nullptr; }
  // {"model", "powered", "mode" ("binary"|"dfmoco"), "serial_number",
  //  "axes": [{"axis", "position_steps", "motor_steps", "target_steps",
  //  "moving", "user_aborted", "spline"}...], "shutter_firing", "stack": {...},
  //  "config": {...}, "store_error"}
  nlohmann::json State() const override;

  // --- front panel ---
  // A button pressed: every moving axis stops dead and gets the sticky
  // RAIL_STATUS_USER_ABORTED bit; a stack run is abandoned.
  void UserAbort();
  // The panel's buttons as HasButton()/PressButton() name them: kAbortButton
  // (any button pressed while the rail moves: UserAbort()).
  static constexpr std::string_view kAbortButton = "abort";
  bool HasButton(std::string_view button) const override { return button == kAbortButton; }
  void PressButton(std::string_view button) override {
    if (button == kAbortButton) UserAbort();
  }
  // Settings->Mode on the panel: switches at once and, as the menu's settings
  // are the power-on settings, stores the mode in slot 0 (created from the
  // factory defaults when empty). The way out of DfMoco mode.
  void SetGlobalModeFromPanel(stackshot::GlobalMode mode);
  // The same on a unit powered up for it and off again: the next power-on
  // starts in `mode` (how the registry starts a unit in DfMoco mode).
  void SetPowerOnMode(stackshot::GlobalMode mode);

  // Which link the host's bytes arrive on (default kSerial); the serving
  // layer sets it before PowerOn().
  void SetHostLink(HostLink link) override;
  HostLink host_link() const { return host_link_; }

  // Test-only: makes the device misbehave as `faults` says, from now on.
  void SetFaults(const Stackshot3xFaults& faults) { faults_ = faults; }

  // --- observation ---
  const Stackshot3xProfile& profile() const { return profile_; }
  const Stackshot3xConfig& config() const { return config_; }
  // GLOBAL_MODE_MOTION_DFMOCO is the active mode (whatever the link).
  bool InDfmocoMode() const;
  // The host's bytes are read as DfMoco lines: DfMoco mode on the serial link.
  bool SpeaksDfmoco() const;
  // The protocol the line speaks: wire::Protocol::kStackshot, or
  // kStackshotDfmoco when SpeaksDfmoco().
  wire::Protocol Speaking() const;
  bool Ready() const { return ready_; }
  // Rail position of `axis` (0..2) in steps: motor steps less the backlash
  // take-up (the first steps after a compensated reversal move only the
  // slack, not the carriage).
  int64_t RailPosition(int axis) const;
  bool AxisMoving(int axis) const;
  uint32_t SerialNumber() const { return serial_number_; }
  const std::vector<std::string>& Log() const { return log_; }
  // The last store fault (corrupt state at load, failed save); "" when none.
  const std::string& StoreError() const { return store_error_; }
  bool StackRunning() const { return stack_.active; }
  uint32_t StackFramesShot() const { return stack_.frames_shot; }
  bool ShutterFiring() const;

  // Every shutter pulse since power-on.
  struct ShutterPulse {
    int output = 0;  // 0 = shutter 1, 1 = shutter 2
    sim::TimeNs on_ns = 0;
    sim::TimeNs off_ns = 0;
    bool suppressed = false;  // CC_RAIL_CONFIG_SHUTTER_DISABLE: timed, output not driven
    bool operator==(const ShutterPulse&) const = default;
  };
  const std::vector<ShutterPulse>& ShutterPulses() const { return pulses_; }

 private:
  // A time in seconds as the device's timers count it: whole microseconds.
  static sim::TimeNs SecondsToNs(double s);
  struct Takeup {
    int dir = 0;  // 0: none in progress
    int64_t start_motor_steps = 0;
    int64_t steps = 0;
  };
  struct AxisState {
    int64_t offset_steps = 0;  // motor steps - rail steps at rest
    int64_t target_rail_steps = 0;
    int last_dir = 0;  // +1 / -1: direction of the last move, 0: none yet
    Takeup takeup;
    bool user_aborted = false;
    // From the last valid CC_MOTION_CONFIG: the spline cut at each position
    // jump into runs that are continuous (empty: no curve configured).
    std::vector<sim::BezierSpline> runs;
    sim::Scheduler::TimerId dfmoco_timer = sim::Scheduler::kNoTimer;
  };
  struct ShutterRun {
    bool active = false;
    uint32_t pulses_left = 0;
    uint32_t pulse_index = 0;
    std::array<float, 2> on_s{};  // first, subsequent
    std::array<float, 2> off_s{};
    bool final_off = false;
    sim::TimeNs on_since_ns = 0;
    sim::Scheduler::TimerId timer = sim::Scheduler::kNoTimer;
  };
  enum class StackPhase : uint8_t {
    kToStart,
    kMoving,
    kSettling,
    kShooting,
    kReturning,
    kPanoNext,  // the pano axis goes on to the pano-frame stop
  };
  struct StackRun {
    bool active = false;
    StackPhase phase = StackPhase::kToStart;
    uint32_t frames = 0;
    uint32_t frames_shot = 0;
    std::array<bool, 3> used{};
    std::array<int64_t, 3> start{};
    std::array<int64_t, 3> end{};
    // AUTO_DIST: a frame every `step` steps from the start, the last on the
    // end; otherwise frames evenly spaced from start to end.
    bool fixed_step = false;
    std::array<int64_t, 3> step{};
    // The pano fields: the axis standing at pano_start for the stack and
    // moving on to pano_stop after it (-1: no pano frame).
    int pano_axis = -1;
    int64_t pano_start = 0;
    int64_t pano_stop = 0;
    stackshot::RailStack request;
    sim::Scheduler::TimerId timer = sim::Scheduler::kNoTimer;
  };
  struct MotionRun {
    bool pending = false;  // positioning to the splines' start steps
    std::array<bool, 3> axes{};
    // Per axis once started: 2i = playing run i, 2i + 1 = travelling from
    // the end of run i to the start of run i + 1 (a position jump).
    std::array<size_t, 3> stage{};
    std::array<bool, 3> playing{};
  };

  static size_t Index(int axis) { return static_cast<size_t>(axis); }
  sim::StepperMotor& Motor(int axis) { return rig_.motor(axis + 1); }
  const sim::StepperMotor& Motor(int axis) const { return rig_.motor(axis + 1); }

  // Lifecycle.
  void Boot();
  void ResetVolatile();
  void CancelTimers();
  void LoadNvm();
  void SaveNvm();
  nlohmann::json NvmJson() const;
  void AddLog(std::string text);

  // Binary protocol.
  void OnByte(uint8_t byte);
  void OnPacket(const stackshot::Packet& packet);
  void Handle(const stackshot::Packet& packet, const stackshot::HostCommand& c);
  void Reply(const stackshot::Packet& packet, stackshot::Action status,
             stackshot::Payload payload = stackshot::Empty{}, bool read_response = false);
  void DrainQueue();
  void ArmGapTimer();

  // Command groups; each returns the status of the reply it wants (RSP_OK
  // replies with data are sent by the handler itself).
  void HandleRail(const stackshot::Packet& p, const stackshot::HostCommand& c);
  void HandleConfig(const stackshot::Packet& p, const stackshot::HostCommand& c);
  // A CC_RAIL_CONFIG_* command being answered, in steps (stackshot3x_config_commands.cpp).
  struct ConfigCall;
  void HandleSystem(const stackshot::Packet& p, const stackshot::HostCommand& c);
  void HandleMotion(const stackshot::Packet& p, const stackshot::HostCommand& c);

  // Units.
  double StepsPerUnit(int axis, stackshot::Units units) const;
  double StepsPerMm(int axis) const;
  float ToUnits(int axis, double steps, stackshot::Units units) const;
  // mm value of a distance given in `units`; nullopt for a non-finite value.
  std::optional<double> ToMm(int axis, float value, stackshot::Units units) const;

  // Motion.
  double SpeedStepsPerS(int axis, double mm_per_s) const;
  // Moves the rail of `axis` to `target_rail` at `max_v` steps/s, adding the
  // backlash take-up on a reversal when `backlash`. The motor's ramp comes
  // from the axis's ramp time.
  sim::MoveStatus MoveAxisTo(int axis, int64_t target_rail, double max_v, bool backlash);
  void FinishTakeup(int axis);
  void OnMotionFinished(int motor_id, sim::TimeNs time_ns, int64_t steps) override;
  void OnEStop(bool engaged, sim::TimeNs time_ns) override;

  // Shutter.
  bool FireShutter(int output, uint32_t pulses, std::array<float, 2> on_s,
                   std::array<float, 2> off_s, bool final_off);
  void ShutterStep(int output);
  void AbortShutters();

  // Stack run (CC_RAIL_STACK).
  void StackAdvance();
  void StackMoveTo(uint32_t frame);
  int64_t StackFramePosition(int axis, uint32_t frame) const;
  // Builds the run a CC_RAIL_STACK asks for (section 2, comm_rail_mode_t);
  // nullopt for a request the mode cannot run (BAD_PARAM).
  std::optional<StackRun> PlanStack(const stackshot::RailStack& request, int axis) const;
  void StackShoot();
  void AbortStack(std::string_view why);
  bool StackAxesAtRest() const;

  // Motion start (CC_MOTION_START).
  void MotionAdvance();
  // The next stage of `axis`'s runs once it rests (see MotionRun::stage).
  void MotionAxisNext(int axis);
  bool MotionPlaying() const {
    return motion_.playing[0] || motion_.playing[1] || motion_.playing[2];
  }
  // The runs of a CC_MOTION_CONFIG in steps; nullopt when a run's speed is
  // unbounded (no time scale brings it within the axis's maximum).
  std::optional<std::vector<sim::BezierSpline>> MakeRuns(const sim::MotionCurves& curves,
                                                         double steps_per_unit, int axis) const;

  // DfMoco dialect.
  void OnDfmocoLine(std::string_view line);
  void SendLine(const dfmoco::DeviceReply& reply);
  void ArmDfmocoReport(int axis);
  void EnterMode(stackshot::GlobalMode mode);
  // Announces the line's protocol when it is not the one last announced
  // (Device::AnnounceLineSwitch).
  void AnnounceSpeaking();

  sim::Scheduler& scheduler_;
  ByteSink& sink_;
  Stackshot3xProfile profile_;
  std::unique_ptr<MemoryStateStore> own_store_;  // the NVM when no store is given
  StateStore* store_;
  HostLink host_link_ = HostLink::kSerial;
  wire::Protocol announced_ = wire::Protocol::kStackshot;  // the last line switch announced
  sim::Rig rig_;
  std::array<sim::StackshotPlanner*, 3> planners_{};
  stackshot::PacketDecoder decoder_;
  dfmoco::LineFramer framer_;
  dfmoco::Dialect dialect_;

  bool powered_ = false;
  bool ready_ = false;
  uint64_t generation_ = 0;  // bumped at every power-on / reset
  Stackshot3xConfig config_;
  std::array<AxisState, 3> axes_{};
  std::array<ShutterRun, 2> shutter_runs_{};
  StackRun stack_;
  MotionRun motion_;
  std::vector<ShutterPulse> pulses_;
  std::array<int32_t, 3> dfmoco_rate_{};

  // NVM.
  uint32_t serial_number_ = stackshot::kUnprogrammed;
  std::vector<uint32_t> nvm_;
  std::array<std::optional<Stackshot3xConfig>, stackshot::kConfigSlotMax + 1> slots_{};
  std::vector<std::string> log_;
  std::string store_error_;

  // Input scheduling.
  std::deque<stackshot::Packet> queue_;
  bool busy_ = false;  // a delayed reply (checksum) is being computed
  sim::Scheduler::TimerId busy_timer_ = sim::Scheduler::kNoTimer;
  sim::Scheduler::TimerId gap_timer_ = sim::Scheduler::kNoTimer;
  sim::Scheduler::TimerId boot_timer_ = sim::Scheduler::kNoTimer;
  std::vector<stackshot::DecodedPacket> scratch_;
  Stackshot3xFaults faults_;
};

}  // namespace moco::devices

#endif  // MOCO_DEVICES_STACKSHOT3X_STACKSHOT3X_H_
