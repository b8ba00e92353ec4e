// The DFMoco Arduino sketch that Dragonframe ships, as an emulated device in
// virtual time (dfmoco-protocol.txt "Messages", ERRATA part 2, FACTS.md
// "DFMoco"; where FACTS and the protocol text disagree, FACTS wins).
//
// Model (docs/devices/dfmoco.md has the full account):
//  - Input: LineFramer kSketch (only "\r\n" ends a line), read byte by byte as
//    the sketch does (wire/dfmoco_sketch_reader.h: lenient numbers, wrapping
//    int32), then judged by ParseHostLine with the profile's dialect. Unknown
//    words get no reply. Codec errors, invalid
//    motors, `bf` / `go` while a motor moves, `go` before a `bf`, `bf` without
//    channels or with an exposure <= 0 answer `parse error`; 40 or more
//    arguments answer `error: too many args`. Both bypass the outgoing queue.
//  - Output: every other reply is a (message, motor) pair in a 16-slot ring
//    (15 waiting) feeding one transmit buffer, i.e. at most 16 messages
//    outstanding; one more is dropped silently. The text is formatted when the
//    message reaches the transmit buffer (so `mp` carries the position then).
//    The UART sends Line().serial.BytesPerSecond() bytes per second (5760 at
//    57600 8N1); a message is written to the ByteSink whole at the moment its
//    first byte starts.
//  - Motion: one sim::Rig; every motor follows the sketch's own planner
//    (SketchAxis: 50 ms chunks planned one chunk ahead of their steps, 20 kHz,
//    25 us steps), computed 2 s ahead and extended window by window; `pr v`
//    sets max velocity v (clamped 100..20000) and max acceleration v/2.
//    Reported positions are the sketch's position counter: the end of the
//    chunk it planned last. Go-motion runs on GoMotionPlanner (go_motion.h).
//  - Position reports: once per second (chunk-clock ticks 0.5 s + k s after the
//    sketch starts) every moving motor and every motor that stopped, or was
//    zeroed, since the previous tick gets `mp m pos`.
#ifndef MOCO_DEVICES_DFMOCO_ARDUINO_DFMOCO_ARDUINO_H_
#define MOCO_DEVICES_DFMOCO_ARDUINO_DFMOCO_ARDUINO_H_

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "devices/device.h"
#include "devices/dfmoco_arduino/dfmoco_profile.h"
#include "devices/dfmoco_arduino/go_motion.h"
#include "devices/dfmoco_arduino/sketch_motion.h"
#include "sim/rig.h"
#include "sim/scheduler.h"
#include "wire/dfmoco.h"
#include "wire/protocol.h"

namespace moco::devices {

// Deliberate deviations from the sketch, for testing hosts and the conformance
// runner against a broken device. The default (every field off) is the sketch.
struct DfmocoFaults {
  int32_t ms_width_delta = 0;            // `ms` carries motor count + this many digits
  std::string silent_word;               // commands with this word get no reply ("pr")
  int64_t report_period_ms = 0;          // periodic `mp` period; 0: the sketch's 1000 ms
  int32_t stop_report_offset_steps = 0;  // added to the `mp` report of a motor at rest
  std::string extra_line_after_ms;       // a line (without "\r\n") sent after each `ms` reply
};

class DfmocoArduino final : public Device, private sim::RigObserver {
 public:
  // Messages outstanding at most: 15 waiting in the 16-slot ring (one slot
  // always stays free) plus the one being transmitted.
  static constexpr size_t kTxRingSlots = 16;
  static constexpr size_t kMaxOutstanding = kTxRingSlots;
  // `bf` answer when the move is prepared (ERRATA 2.5, FACTS).
  static constexpr int32_t kBlurReady = 1000;

  // `scheduler` and `sink` must outlive the device. Constructed powered off.
  DfmocoArduino(sim::Scheduler& scheduler, ByteSink& sink, DfmocoProfile profile = {},
                DfmocoFaults faults = {});
  ~DfmocoArduino() override;
  DfmocoArduino(const DfmocoArduino&) = delete;
  DfmocoArduino& operator=(const DfmocoArduino&) = delete;

  // --- Device ---
  std::string_view Model() const override { return "dfmoco"; }
  DeviceLine Line() const override {
    return {wire::Info(wire::Protocol::kDfmoco).line, profile_.usb_bridge};
  }
  // Boots: after profile.boot_delay_ms the sketch starts and queues `hi`.
  void PowerOn() override;
  // Halts every motor, forgets positions, pulse rates, the go-motion set-up,
  // queued output and any partial input line, and cancels every timer.
  void PowerOff() override;
  bool Powered() const override { return powered_; }
  void OnHostBytes(wire::ByteView bytes) override;
  void OnHostLink(bool open) override;
  sim::Rig* rig() override { return &rig_; }
  sim::GioPort* gio() override { return nullptr; }  // the sketch has no general I/O
  // {"model", "board", "firmware", "powered", "running", "motors": [{"motor",
  //  "position_steps", "reported_position_steps", "target_steps", "moving",
  //  "pulse_rate_steps_per_s"}...], "go_motion": {"state", ...},
  //  "tx_queue": {"outstanding", "capacity", "dropped"}}
  nlohmann::json State() const override;

  // --- observation for tests and logs ---
  const DfmocoProfile& profile() const { return profile_; }
  const dfmoco::Dialect& dialect() const { return dialect_; }
  // True once the sketch runs (after the boot delay) until power-off.
  bool Running() const { return running_; }
  // The position the sketch reports for motor `motor` (1-based) now: the
  // planned position at the end of the chunk in progress.
  // REQUIRES: 1 <= motor <= motor count.
  int64_t ReportedPosition(int motor) const;
  bool MotorMoving(int motor) const;
  int32_t PulseRate(int motor) const { return motors_[Index(motor)].pulse_rate_steps_per_s; }
  // Messages dropped on a full outgoing queue since power-on.
  uint64_t DroppedMessages() const { return dropped_; }
  // Messages queued or being transmitted.
  size_t OutstandingMessages() const;

  enum class GoMotionState : uint8_t {
    kIdle,   // no `bf` accepted
    kArmed,  // `bf` accepted (motors may still be pre-positioning); `go` allowed at rest
    kRunning,
  };
  GoMotionState go_motion_state() const;

 private:
  enum class Msg : uint8_t { kHi, kMm, kMp, kMs, kPr, kSm, kSa, kBf, kGo, kJm, kIm };
  struct TxMsg {
    Msg msg = Msg::kHi;
    uint8_t motor_index = 0;
    int32_t offset_steps = 0;  // DfmocoFaults::stop_report_offset_steps
  };
  struct MotorState {
    int32_t pulse_rate_steps_per_s = dfmoco::kDefaultPulseRate;
    bool report_pending = false;      // stopped or zeroed since the last tick
    sim::TimeNs last_report_ns = -1;  // time of the last periodic report
    sim::TimeNs chunk_phase_ns = 0;   // chunk clock of the motion in progress
    std::optional<BlurMove> blur;     // set by the last accepted `bf`
    bool in_go_motion = false;        // running the blur move (or its stop)
    // The sketch's plan (sketch_motion.h): `base` is the state after the
    // update at chunk boundary base_k (and any command since); window[i] the
    // state after update base_k + 1 + i, computed ahead.
    SketchAxis base;
    int64_t base_k = 0;
    int32_t position_before_base = 0;  // position after update base_k - 1
    std::vector<SketchAxis> window;
    sim::Scheduler::TimerId extend_timer = sim::Scheduler::kNoTimer;
  };
  // Chunks of the sketch's plan computed ahead of time (2 s); a longer move
  // is extended when its window runs out, so planning costs O(window).
  static constexpr size_t kWindowChunks = 40;

  static size_t Index(int motor) { return static_cast<size_t>(motor - 1); }
  sim::StepperMotor& Motor(int motor) { return rig_.motor(motor); }
  const sim::StepperMotor& Motor(int motor) const { return rig_.motor(motor); }
  bool AnyMoving() const;

  // Lifecycle.
  void Boot();
  void ResetVolatileState();
  void CancelTimers();

  // Input.
  void OnLine(std::string_view line);
  void Handle(const dfmoco::HostCommand& command);
  void HandleMove(int motor, int32_t position_steps);
  void HandleJog(const dfmoco::JogMotor& jog);
  void HandleInch(int motor, int32_t destination_steps);
  void HandleBlur(const dfmoco::BlurFrame& bf);
  void HandleGo();
  void SetPulseRate(int motor, int32_t rate_steps_per_s);
  // Halts (if moving) and sets the position without motion (`zm`, `np`).
  void SetPosition(int motor, int64_t steps);
  // Any new motion command ends a go-motion for that motor (it stops dead).
  void LeaveGoMotion(int motor);
  // stopMotor (`sm`, `sa`).
  void StopSketchMotor(int motor);
  // The sketch state of `motor` after the update at chunk boundary k.
  const SketchAxis& SketchAt(int motor, int64_t k) const;
  int32_t SketchPositionAfter(int motor, int64_t k) const;
  // The destination the sketch reports in `mm`.
  int32_t TargetOf(int motor) const;
  // Takes the sketch state at the latest chunk boundary as the base for a
  // command; Commit plans ahead from it and drives the motor. Commit returns
  // false when the rig refuses the motion (the motor then rests where it is).
  SketchAxis& Begin(int motor);
  bool Commit(int motor);
  void ArmExtendTimer(int motor);

  // Output.
  void Send(Msg msg, int motor_index = 0, int32_t offset_steps = 0);
  // `parse error` and `error: too many args`: straight to the UART.
  void SendDirect(const dfmoco::DeviceReply& reply);
  void Transmit(const std::string& bytes);
  std::string Format(const TxMsg& m) const;
  void OnUartFree();
  void ArmUartTimer();

  // Periodic position reports.
  void ArmReportTimer();
  void OnReportTick();
  sim::TimeNs NextReportTick(sim::TimeNs after_ns) const;
  sim::TimeNs ReportPeriodNs() const;

  // sim::RigObserver
  void OnMotionFinished(int motor_id, sim::TimeNs time_ns, int64_t steps) override;

  sim::Scheduler& scheduler_;
  ByteSink& sink_;
  DfmocoProfile profile_;
  DfmocoFaults faults_;
  bool mute_ = false;  // DfmocoFaults::silent_word: the command being handled gets no reply
  dfmoco::Dialect dialect_;
  sim::Rig rig_;
  dfmoco::LineFramer framer_;

  bool powered_ = false;
  bool running_ = false;
  sim::TimeNs start_ns_ = 0;  // when the sketch started running
  std::vector<MotorState> motors_;
  bool go_ready_ = false;
  int32_t blur_reply_ = kBlurReady;

  // Outgoing queue and UART.
  std::array<TxMsg, kTxRingSlots> ring_{};
  size_t ring_head_ = 0;  // next to transmit
  size_t ring_count_ = 0;
  uint64_t dropped_ = 0;
  sim::TimeNs uart_free_ns_ = 0;     // when the bytes handed to the UART are all out
  sim::TimeNs burst_anchor_ns_ = 0;  // start of the current back-to-back burst
  uint64_t burst_bytes_ = 0;

  sim::Scheduler::TimerId boot_timer_ = sim::Scheduler::kNoTimer;
  sim::Scheduler::TimerId uart_timer_ = sim::Scheduler::kNoTimer;
  sim::Scheduler::TimerId report_timer_ = sim::Scheduler::kNoTimer;
};

}  // namespace moco::devices

#endif  // MOCO_DEVICES_DFMOCO_ARDUINO_DFMOCO_ARDUINO_H_
