// A run's whole exchange with its target, recorded and played back
// (docs/certificates.md): RecordingTarget passes every call through to the
// target it wraps and writes the call, its arguments and its result to a
// call log; PlaybackTarget answers the same calls from that log, with no
// device. The runner is deterministic given what its target answers (one
// thread, the seed in RunOptions, every time read through Now()), so the
// same suite played against the log takes the same path and reaches the same
// verdicts; a runner that asks anything else (other rules, another seed) is
// told the log diverged, as a lost link.
//
// The log holds every byte each way with the target time it crossed, every
// clock read, the restarts and inputs set (e-stop, limits, I/O, buttons), the
// watched pins (a simavr: target with --board), every read of the outputs an
// in-process device exposes (Target::Outputs(): DMX levels, I/O outputs,
// camera edges) and the target's name whenever it changes (a simavr: target
// names its MCU once open).
#ifndef MOCO_CONFORMANCE_TARGETS_RECORDED_TARGET_H_
#define MOCO_CONFORMANCE_TARGETS_RECORDED_TARGET_H_

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "conformance/targets/target.h"

namespace moco::conformance {

// What a call log says about its run without playing it: the target's name
// and clock, and the traffic in it.
struct CallLogSummary {
  std::string target;
  bool virtual_clock = false;
  bool can_restart = false;
  size_t calls = 0;
  size_t host_bytes = 0, device_bytes = 0;
  size_t restarts = 0;
  TimeNs last_ns = 0;  // the last clock value the log holds
};

// One chunk of traffic in a log, as the transcript shows it: `from_host`
// bytes written at `t_ns`, or device bytes received by then. `restart` marks
// a restart of the device (no bytes) at `t_ns`.
struct LoggedChunk {
  TimeNs t_ns = 0;
  bool from_host = true;
  bool restart = false;
  std::string bytes;
};

class RecordingTarget final : public Target {
 public:
  // Records the calls made to `inner` from now on (its clock and restart
  // ability are read once, here).
  explicit RecordingTarget(std::unique_ptr<Target> inner);

  // The call log so far (a binary format only PlaybackTarget and
  // SummarizeCallLog read; its first bytes name the format and version).
  const std::string& log() const { return log_; }
  Target& inner() { return *inner_; }

  std::string Name() const override;
  bool VirtualClock() const override { return virtual_clock_; }
  bool CanRestart() const override { return can_restart_; }
  std::optional<std::string> Open() override;
  void Restart() override;
  TimeNs Now() const override;
  bool Send(wire::ByteView bytes) override;
  bool Receive(TimeNs deadline_ns, wire::Bytes& out) override;
  bool SetEStop(bool engaged) override;
  bool SetLimitInput(int set, bool high, bool active) override;
  bool SetGioInput(int bit, bool level) override;
  bool CanPressButton(std::string_view button) const override;
  bool PressButton(std::string_view button) override;
  DeviceOutputs Outputs() const override;
  std::optional<std::string> LinkLost() const override;
  std::optional<std::string> FirmwareStopped() const override;
  std::optional<FirmwareFault> FirmwareFaulted() const override;
  std::vector<std::string> FirmwareBacktrace() const override;
  std::optional<std::string> WatchPins(const Board& board) override {
    return inner_->WatchPins(board);
  }
  const PinTrace* Pins() const override;
  std::vector<std::string> Caveats() const override;

 private:
  // The inner target's outputs, each read logged.
  class OutputReads final : public DmxOutput, public GioOutput, public CameraOutput {
   public:
    explicit OutputReads(const RecordingTarget& t) : t_(t) {}
    int Value(int channel) const override;
    uint32_t outputs() const override;
    std::vector<sim::CameraPort::Edge> Trace() const override;
    DeviceOutputs inner;

   private:
    const RecordingTarget& t_;
  };

  std::unique_ptr<Target> inner_;
  bool virtual_clock_ = false;
  bool can_restart_ = false;
  mutable std::string log_;
  mutable std::string name_;  // the name last logged
  mutable TimeNs last_now_ = 0;
  mutable OutputReads outputs_{*this};
  // The pin edges already logged per signal (Pins() logs what is new).
  mutable std::vector<size_t> pins_logged_;
};

struct LogEntry;  // one decoded call of a log (recorded_target.cpp)

class PlaybackTarget final : public Target {
 public:
  // Checks the log's format; nullopt and `error` set when it is not one.
  static std::unique_ptr<PlaybackTarget> FromLog(std::string log, std::string* error);
  ~PlaybackTarget() override;

  // Where the runner first asked what the log does not hold ("" while it
  // has asked nothing else): "call 1234: the run sent 3 bytes (...) where
  // the recorded run sent ...".
  const std::string& divergence() const { return divergence_; }
  // True when the runner made every call of the log (a run that stopped
  // early leaves calls unplayed).
  bool Exhausted() const { return at_ == log_.size(); }
  size_t calls_played() const { return calls_; }

  std::string Name() const override;
  bool VirtualClock() const override { return virtual_clock_; }
  bool CanRestart() const override { return can_restart_; }
  std::optional<std::string> Open() override;
  void Restart() override;
  TimeNs Now() const override;
  bool Send(wire::ByteView bytes) override;
  bool Receive(TimeNs deadline_ns, wire::Bytes& out) override;
  bool SetEStop(bool engaged) override;
  bool SetLimitInput(int set, bool high, bool active) override;
  bool SetGioInput(int bit, bool level) override;
  bool CanPressButton(std::string_view button) const override;
  bool PressButton(std::string_view button) override;
  DeviceOutputs Outputs() const override;
  std::optional<std::string> LinkLost() const override;
  std::optional<std::string> FirmwareStopped() const override;
  std::optional<FirmwareFault> FirmwareFaulted() const override;
  std::vector<std::string> FirmwareBacktrace() const override;
  std::optional<std::string> WatchPins(const Board& board) override;
  const PinTrace* Pins() const override;
  std::vector<std::string> Caveats() const override;

 private:
  // The recorded outputs, each read answered from the log.
  class OutputReads final : public DmxOutput, public GioOutput, public CameraOutput {
   public:
    explicit OutputReads(const PlaybackTarget& t) : t_(t) {}
    int Value(int channel) const override;
    uint32_t outputs() const override;
    std::vector<sim::CameraPort::Edge> Trace() const override;

   private:
    const PlaybackTarget& t_;
  };

  PlaybackTarget() = default;
  // The next call's entry, which must be `op` (with no divergence so far);
  // null (and the divergence noted) otherwise. Valid until the next call.
  const LogEntry* Next(uint8_t op) const;
  // Takes the name changes logged before the next call.
  void TakeNames() const;
  void Diverge(std::string what) const;

  std::string log_;
  mutable std::string name_;
  bool virtual_clock_ = false;
  bool can_restart_ = false;
  mutable size_t at_ = 0;
  mutable size_t calls_ = 0;
  mutable TimeNs last_now_ = 0;
  mutable std::string divergence_;
  std::optional<Board> board_;
  mutable std::optional<PinTrace> pins_;
  std::unique_ptr<LogEntry> entry_;
  OutputReads outputs_{*this};
};

// The header of a call log and its traffic totals; nullopt and `error` set
// when `log` is not a call log or is cut short.
std::optional<CallLogSummary> SummarizeCallLog(std::string_view log, std::string* error);
// The traffic of a call log, chunk by chunk (bytes written, bytes received,
// restarts), for a transcript; empty and `error` set when it is damaged.
std::vector<LoggedChunk> TrafficOfCallLog(std::string_view log, std::string* error);

}  // namespace moco::conformance

#endif  // MOCO_CONFORMANCE_TARGETS_RECORDED_TARGET_H_
