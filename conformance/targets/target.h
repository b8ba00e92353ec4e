// Where mococheck's bytes go (ARCHITECTURE "conformance", "One clock"): a
// device reached in-process on the runner's own virtual clock, or outside the
// process over a PTY/serial path or TCP on the steady clock.
#ifndef MOCO_CONFORMANCE_TARGETS_TARGET_H_
#define MOCO_CONFORMANCE_TARGETS_TARGET_H_

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include <sys/stat.h>

#include "conformance/targets/simavr_pins.h"
#include "devices/device.h"
#include "sim/io.h"
#include "sim/scheduler.h"
#include "wire/bytes.h"
#include "wire/dmc_constants.h"

namespace moco::conformance {

using sim::TimeNs;

// What stopped a firmware a target runs (Target::FirmwareFaulted): a crash (an
// illegal instruction, a jump past the program image, the core halted or
// stuck), the stack grown into .data/.bss, and with WatchFirmwareFaults() a
// return address overwritten, a division by zero, a jump to the reset vector.
enum class FirmwareFaultKind { kCrash, kStackOverflow, kStackSmash, kDivisionByZero, kReset };

struct FirmwareFault {
  FirmwareFaultKind kind = FirmwareFaultKind::kCrash;
  std::string what;                    // as FirmwareStopped() says it
  std::vector<std::string> backtrace;  // the PC, then the open frames' call sites
};

// What of a firmware's code the runs reached (Target::CodeCoverageOf): its
// instructions in the functions its symbols size, its static control-flow
// edges (each instruction's fall-through or taken outcome; a conditional
// branch or skip has both) and how many of each ran or were taken, and the
// functions never entered.
struct CodeCoverage {
  size_t instructions = 0, instructions_reached = 0;
  size_t edges = 0, edges_reached = 0;
  size_t functions = 0;
  std::vector<std::string> never_entered;
};

// The outputs of a device that the runner can read where it reaches the
// device (in-process): its DMX universe, general I/O outputs and camera lines
// (with their edges). Each read is a call on the target's reader, so a
// recording target logs what was read (recorded_target.h).
class DmxOutput {
 public:
  virtual ~DmxOutput() = default;
  // DMX channel 1..512's level now, 0..255.
  virtual int Value(int channel) const = 0;
};
class GioOutput {
 public:
  virtual ~GioOutput() = default;
  // The general outputs now, bit 0 = output 1.
  virtual uint32_t outputs() const = 0;
};
class CameraOutput {
 public:
  virtual ~CameraOutput() = default;
  // The camera lines' edges kept so far, oldest first (sim::CameraPort::Trace).
  virtual std::vector<sim::CameraPort::Edge> Trace() const = 0;
};
// Each is null when the target cannot observe it. Valid until the target's
// next Open() or Restart().
struct DeviceOutputs {
  const DmxOutput* dmx = nullptr;
  const GioOutput* gio = nullptr;
  const CameraOutput* camera = nullptr;

  // The outputs present (dmx, gio, camera) read through one object that
  // serves all three.
  template <typename Reader>
  static DeviceOutputs Through(const Reader& reader, bool dmx, bool gio, bool camera) {
    return {dmx ? &reader : nullptr, gio ? &reader : nullptr, camera ? &reader : nullptr};
  }
};

// Carries bytes both ways and keeps the clock timing rules are judged on.
// One thread uses a Target.
class Target {
 public:
  virtual ~Target() = default;

  // e.g. "in-process:dmc16", "pty:/tmp/dmc16 @115200", "tcp:127.0.0.1:5000".
  virtual std::string Name() const = 0;
  // True when Now() is the runner's virtual clock (waiting costs nothing).
  virtual bool VirtualClock() const = 0;
  // True when Restart() gives a freshly powered device (in-process only).
  virtual bool CanRestart() const = 0;

  // Opens the link (and powers an in-process device on). Returns an error
  // message naming the problem and the fix, or nullopt.
  virtual std::optional<std::string> Open() = 0;
  // Powers the device off and on again, with time restarted at 0 (in-process);
  // external targets keep their connection and only drop unread input.
  virtual void Restart() = 0;

  // The target's clock, in nanoseconds since Open() / Restart().
  virtual TimeNs Now() const = 0;
  // Writes `bytes` to the device. False when the link is gone.
  virtual bool Send(wire::ByteView bytes) = 0;
  // When every byte sent so far will have reached the device: later than
  // Now() on a target that paces the host's bytes at the line rate (simavr),
  // so that a host's timeout for an answer can start when its request has
  // arrived (the fuzzer's laws). Now() where bytes arrive at once.
  virtual TimeNs SentBy() const { return Now(); }
  // Waits until device bytes arrive or Now() reaches `deadline_ns` and appends
  // what arrived to `out`. Returns false when the link is gone.
  virtual bool Receive(TimeNs deadline_ns, wire::Bytes& out) = 0;

  // Presses (true) or releases the device's e-stop button, where the runner
  // can reach it (in-process only). False when it cannot.
  virtual bool SetEStop(bool /*engaged*/) { return false; }
  // Drives an input of hardware limit set `set` (1-based; `high`: the HIGH
  // switch, else LOW) on or off, as a switch closing would, where the runner
  // can reach it (in-process only). False when it cannot or the set is unknown.
  virtual bool SetLimitInput(int /*set*/, bool /*high*/, bool /*active*/) { return false; }
  // Drives general I/O input `bit` (0-based) to `level`, as a wired trigger
  // would (in-process only). False when it cannot.
  virtual bool SetGioInput(int /*bit*/, bool /*level*/) { return false; }
  // Whether the runner can press the device's front-panel button `button`
  // (its model's name for it, devices::Device::HasButton; in-process only),
  // and pressing it once. PressButton is false when it cannot.
  virtual bool CanPressButton(std::string_view /*button*/) const { return false; }
  virtual bool PressButton(std::string_view /*button*/) { return false; }
  // What the runner can read of the device's outputs now (in-process only);
  // all null when it cannot observe them (an external device).
  virtual DeviceOutputs Outputs() const { return {}; }

  // Why the link is gone for good (the device closed the connection, a
  // write or read failed), or nullopt while it is up. A lost link makes the
  // run a target error: what follows proves nothing about the device.
  virtual std::optional<std::string> LinkLost() const { return std::nullopt; }

  // For a target that runs firmware here (simavr): why the firmware stopped
  // running (it crashed, executed an illegal instruction, halted, or makes no
  // progress), with its simulated time; nullopt while it runs, and for every
  // other target. A finding about the device, not a target error.
  virtual std::optional<std::string> FirmwareStopped() const { return std::nullopt; }
  // The same, with what kind of fault it was and where: the program counter
  // and the call sites of the frames still open, innermost first, named by the
  // firmware's symbols where it has them.
  virtual std::optional<FirmwareFault> FirmwareFaulted() const { return std::nullopt; }
  // From the next Open() / Restart() on, also stops the firmware at the faults
  // only a fuzzer looks for (FirmwareFaultKind kStackSmash, kDivisionByZero,
  // kReset: each costs a check per instruction). False when the target runs no
  // firmware it can watch.
  virtual bool WatchFirmwareFaults() { return false; }
  // Where the firmware runs now, as FirmwareFault::backtrace (a hang's
  // report); empty for a target that runs none.
  virtual std::vector<std::string> FirmwareBacktrace() const { return {}; }
  // Edge coverage of the firmware's code, for a target that can observe it
  // (simavr: each pair of consecutive program counters, AFL-style): from now
  // on the target adds each edge it executes to `map` (`size` a power of two;
  // a count saturating at 255 per slot); nullptr stops. False when the target
  // cannot observe its device's code.
  virtual bool SetCoverageMap(uint8_t* /*map*/, size_t /*size*/) { return false; }
  // Which instructions ran and which way each went, for a target that runs a
  // firmware image (after Open()): the bytes the map needs (0: none), then
  // from now on marking each instruction in `map` (kept across runs; never
  // cleared), and what a map shows of the image's code.
  virtual size_t InstructionMapBytes() const { return 0; }
  virtual bool SetInstructionMap(uint8_t* /*map*/, size_t /*size*/) { return false; }
  virtual std::optional<CodeCoverage> CodeCoverageOf(std::span<const uint8_t> /*map*/) const {
    return std::nullopt;
  }

  // Watches the firmware's pins that `board` names from the next Open() /
  // Restart() on (a simavr: target only). Returns an error naming the fix, or
  // nullopt.
  virtual std::optional<std::string> WatchPins(const Board& /*board*/) {
    return "pins can be watched only on a firmware target (--board needs "
           "--target simavr:PATH.elf or --target native:PATH)";
  }
  // The watched pins since the last Open() / Restart(); nullptr when none are.
  virtual const PinTrace* Pins() const { return nullptr; }

  // What the run report should say about how far this target reproduces the
  // device (e.g. hardware a simulator does not model that the firmware used,
  // a timer interrupt that is enabled but never fired), one sentence each.
  virtual std::vector<std::string> Caveats() const { return {}; }
};

// Asks a running conformance run to stop (from a SIGINT, SIGTERM or SIGHUP
// handler: async-signal-safe). External targets' Send() and Receive() then
// return false at once and the case loop runs no further case.
void RequestStop(int signal_number);
// The signal number given to RequestStop(), 0 when none was.
int StopRequested();

// Builds a device for an in-process target; it writes its output to `sink`.
// `scheduler` and `sink` outlive the device.
using DeviceFactory = std::function<std::unique_ptr<devices::Device>(sim::Scheduler& scheduler,
                                                                     devices::ByteSink& sink)>;

// A device in this process on a virtual clock: Receive() runs the scheduler's
// events up to the deadline, stopping as soon as the device has written.
class InProcessTarget final : public Target {
 public:
  // `name` is the model for Name(); `factory` builds the device (again on Restart()).
  InProcessTarget(std::string name, DeviceFactory factory);
  // A registered model (devices::CreateDevice) with its profile (empty: built-in).
  // A model with NVM (keeps_state) keeps it in memory across Restart(), as a
  // real power cycle does; each target starts with empty NVM.
  // `speaking`: the protocol its line speaks from power-on, one the model
  // also speaks (devices::DeviceStart; a StackShot 3X's DfMoco mode, kept in
  // its NVM as a real unit keeps it); nullopt: the model's own.
  static std::unique_ptr<InProcessTarget> ForModel(
      const std::string& model, const std::string& profile_path,
      std::optional<wire::Protocol> speaking = std::nullopt);
  ~InProcessTarget() override;

  std::string Name() const override { return "in-process:" + name_; }
  bool VirtualClock() const override { return true; }
  bool CanRestart() const override { return true; }
  std::optional<std::string> Open() override;
  void Restart() override;
  TimeNs Now() const override { return scheduler_->Now(); }
  bool Send(wire::ByteView bytes) override;
  bool Receive(TimeNs deadline_ns, wire::Bytes& out) override;
  bool SetEStop(bool engaged) override;
  bool SetLimitInput(int set, bool high, bool active) override;
  bool SetGioInput(int bit, bool level) override;
  bool CanPressButton(std::string_view button) const override;
  bool PressButton(std::string_view button) override;
  DeviceOutputs Outputs() const override;

  // The device under test (null before Open()).
  devices::Device* device() { return device_.get(); }

 private:
  class Sink final : public devices::ByteSink {
   public:
    void Write(wire::ByteView bytes) override {
      pending.insert(pending.end(), bytes.begin(), bytes.end());
    }
    wire::Bytes pending;
  };
  // The device's own I/O objects, read as DeviceOutputs.
  class SimOutputs final : public DmxOutput, public GioOutput, public CameraOutput {
   public:
    int Value(int channel) const override { return dmx->Value(channel); }
    uint32_t outputs() const override { return gio->outputs(); }
    std::vector<sim::CameraPort::Edge> Trace() const override { return camera->Trace(); }
    const sim::DmxUniverse* dmx = nullptr;
    const sim::GioPort* gio = nullptr;
    const sim::CameraPort* camera = nullptr;
  };
  void Build();

  std::string name_;
  DeviceFactory factory_;
  std::unique_ptr<sim::Scheduler> scheduler_;
  Sink sink_;
  std::unique_ptr<devices::Device> device_;
  mutable SimOutputs outputs_;
};

// A device outside the process: a PTY or serial path (termios raw, 8N1 at
// `baud`) or a TCP connection. The clock is std::chrono::steady_clock.
class FdTarget final : public Target {
 public:
  enum class Kind { kSerial, kTcp };
  // kSerial: `address` is a path; kTcp: "host:port" (IPv4 literal or a name).
  // `scheme` labels a kSerial target in Name() ("pty" or "serial", as given).
  // `baud` defaults to a DMC v2 device's line.
  FdTarget(Kind kind, std::string address, uint32_t baud = dmc::kBaudRate,
           std::string scheme = "pty");
  ~FdTarget() override;
  FdTarget(const FdTarget&) = delete;
  FdTarget& operator=(const FdTarget&) = delete;

  std::string Name() const override;
  bool VirtualClock() const override { return false; }
  bool CanRestart() const override { return false; }
  std::optional<std::string> Open() override;
  void Restart() override;
  TimeNs Now() const override;
  bool Send(wire::ByteView bytes) override;
  bool Receive(TimeNs deadline_ns, wire::Bytes& out) override;
  std::optional<std::string> LinkLost() const override { return lost_; }

  // A PTY or serial port whose far end has been closed (EIO on every read and
  // write) for this long is lost: the emulator serving it died or the adapter
  // was unplugged. Shorter hang-ups are waited out (a device that reopens).
  static constexpr TimeNs kHangUpGraceNs = 3 * sim::kNsPerSecond;

 private:
  // Notes an EIO (the far end closed) at Now(); loses the link once the
  // hang-up has lasted kHangUpGraceNs. Returns false when it did.
  bool HungUp();

  // Why a path that is not a terminal, character device or socket is refused.
  std::string NotADevice(const struct stat& st) const;
  // Marks the link lost for good (`why`: what happened) and returns false.
  bool Lose(std::string why);

  Kind kind_;
  std::string address_;
  uint32_t baud_;
  std::string scheme_;
  std::optional<std::string> lost_;
  int fd_ = -1;
  int64_t origin_ns_ = 0;                   // steady_clock at Open()
  std::optional<TimeNs> hung_up_since_ns_;  // first EIO of the current hang-up
};

// A parsed --target: "in-process:MODEL", "pty:PATH" (also "serial:PATH"),
// "tcp:HOST:PORT", "simavr:PATH.elf[@MCU[:HZ]]" or "native:PATH[@PORT]".
struct TargetSpec {
  enum class Kind { kInProcess, kSerial, kTcp, kSimavr, kNative };
  Kind kind = Kind::kInProcess;
  std::string address;  // model, path, host:port, PATH.elf[@MCU[:HZ]] or PATH[@PORT]
  std::string scheme;   // as written: "in-process", "pty", "serial", "tcp", "simavr" or "native"
};

// AVR firmware to run under simavr: the address of a "simavr:" target.
struct SimavrSpec {
  std::string elf_path;
  std::string mcu;            // empty: the ELF's .mmcu section names it, else atmega328p
  uint32_t frequency_hz = 0;  // 0: the ELF's .mmcu section gives it, else 16 MHz
};

// Parses "PATH.elf[@MCU[:HZ]]" (the last '@' splits; HZ is a decimal number of
// hertz, 1..4294967295). On failure the message names the problem and the fix.
std::variant<SimavrSpec, std::string> ParseSimavrAddress(std::string_view address);

// Parses a --target value; on failure the message names the problem and the fix.
std::variant<TargetSpec, std::string> ParseTargetSpec(std::string_view text);

// Builds the target for `spec`. Unknown in-process models and bad profiles
// come back as an error message.
std::variant<std::unique_ptr<Target>, std::string> MakeTarget(const TargetSpec& spec,
                                                              const std::string& profile_path,
                                                              uint32_t baud);

}  // namespace moco::conformance

#endif  // MOCO_CONFORMANCE_TARGETS_TARGET_H_
