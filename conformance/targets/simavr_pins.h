// The pins a motion-control firmware drives, as a step driver and a camera see
// them (issue "firmware truth at the pins"; FACTS "Step drivers", "DFMoco"
// boards): a board profile (fixtures/boards/*.json) naming each motor's STEP,
// DIR and ENABLE and the camera's shutter and focus outputs, a step-driver
// profile (fixtures/drivers/*.json) with the timing its STEP/DIR inputs need,
// and the trace of every level change on those pins on the firmware's clock.
#ifndef MOCO_CONFORMANCE_TARGETS_SIMAVR_PINS_H_
#define MOCO_CONFORMANCE_TARGETS_SIMAVR_PINS_H_

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "sim/scheduler.h"

namespace moco::conformance {

// One bit of an AVR I/O port: "PD4" is port 'D', bit 4; or, for a board whose
// pins are numbered (a native target's ESP32 or Teensy), pin `number`: "D26"
// or "GPIO26".
struct PinRef {
  char port = 'B';  // 'A'..'L'
  uint8_t bit = 0;  // 0..7
  int number = -1;  // >= 0: a numbered pin (port and bit unused)
  bool numbered() const { return number >= 0; }
  std::string Name() const {
    if (numbered()) return "D" + std::to_string(number);
    return std::string("P") + port + static_cast<char>('0' + bit);
  }
  bool operator==(const PinRef&) const = default;
};
// Parses "PD4" (also "pd4"), "D26" or "GPIO26" (a pin number 0..255); nullopt
// for anything else.
std::optional<PinRef> ParsePinRef(std::string_view text);

struct BoardMotor {
  PinRef step;
  PinRef dir;
  std::optional<PinRef> enable;
};

// A board profile: which pins carry what, and the firmware's limits the pin
// rules judge against.
struct Board {
  std::string name;
  std::string description;
  std::vector<BoardMotor> motors;  // motor 1 first
  std::optional<PinRef> shutter;
  std::optional<PinRef> focus;
  // The firmware's highest step rate (DFMoco on an Uno: 20 kHz, FACTS "DFMoco").
  double max_step_rate_hz = 20000;
  // The highest step rate at which DIR may change (the sketch reverses only
  // after a slowed-down chunk).
  double reversal_max_rate_hz = 1000;
  // How often a moving motor's position is reported (DFMoco: once a second).
  int64_t report_period_ms = 1000;
};

// Reads a board profile. The error names the file, the field and the fix.
std::variant<Board, std::string> LoadBoard(const std::string& path);
// The same from JSON text; `name` labels errors.
std::variant<Board, std::string> ParseBoard(std::string_view text, const std::string& name);

// What a step driver's STEP/DIR inputs need (datasheet figures, FACTS "Step drivers").
struct DriverProfile {
  std::string name;  // "a4988"
  int64_t step_high_min_ns = 0;
  int64_t step_low_min_ns = 0;
  int64_t dir_setup_min_ns = 0;  // DIR stable before the STEP rising edge
  int64_t dir_hold_min_ns = 0;   // and after it
  std::string source;            // where the figures are from
};
// The built-in profiles: a4988, drv8825, tmc2209.
const std::vector<DriverProfile>& BuiltInDrivers();
// A built-in name, or the path of a driver profile (JSON). The error names the
// problem and the fix.
std::variant<DriverProfile, std::string> LoadDriver(const std::string& name_or_path);
std::variant<DriverProfile, std::string> ParseDriver(std::string_view text,
                                                     const std::string& name);

// One level change of a watched pin.
struct PinEdge {
  sim::TimeNs t_ns = 0;
  uint64_t cycle = 0;
  bool level = false;
};

struct PinSignal {
  std::string name;  // "m1_step", "m1_dir", "m1_enable", "shutter", "focus"
  PinRef pin;
  bool initial = false;  // the level at time 0
  std::vector<PinEdge> edges;
  // The level just after time t (edges at t included).
  bool LevelAt(sim::TimeNs t_ns) const;
};

// Every watched pin since the firmware (re)started, in the board's order:
// per motor its step, dir and (when wired) enable, then shutter and focus.
struct PinTrace {
  struct MotorSignals {
    int step = -1;
    int dir = -1;
    int enable = -1;
  };
  std::string board;
  uint32_t frequency_hz = 0;
  std::vector<PinSignal> signals;
  std::vector<MotorSignals> motors;  // indexes into signals
  int shutter = -1;
  int focus = -1;
  // Edges after this time were not kept (a case longer than the trace holds).
  sim::TimeNs complete_until_ns = INT64_MAX;

  // Signals and indexes for `board`, every level low, no edges.
  static PinTrace For(const Board& board);
  size_t EdgeCount() const;
};

}  // namespace moco::conformance

#endif  // MOCO_CONFORMANCE_TARGETS_SIMAVR_PINS_H_
