// The fault settings of an emulated serial or TCP line (docs/control.md
// "faults", mocosim --faults): per-byte drop, corrupt, duplicate and delay
// rates for each direction and a seed, and their text form
// "seed=42,dir=to-host,drop=0.01". Plain values: the control vocabulary parses
// them, the transport's FaultInjector applies them.
#ifndef MOCO_SIM_LINE_FAULTS_H_
#define MOCO_SIM_LINE_FAULTS_H_

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <variant>

#include "sim/scheduler.h"

namespace moco::sim {

// Per-byte probabilities for one direction, each in [0, 1]. Faults are
// applied to each byte in this order: drop (the byte vanishes; nothing else
// applies), corrupt (one uniformly chosen bit flips), delay (the link stalls
// for delay_ns before this byte; bytes keep their order, so every later byte
// of the direction waits too), duplicate (the byte is delivered twice).
struct DirectionFaults {
  double drop_rate = 0;
  double corrupt_rate = 0;
  double duplicate_rate = 0;
  double delay_rate = 0;
  TimeNs delay_ns = 20 * kNsPerMs;

  bool Any() const {
    return drop_rate > 0 || corrupt_rate > 0 || duplicate_rate > 0 || delay_rate > 0;
  }
};

// Off by default (all rates 0).
struct FaultConfig {
  uint64_t seed = 1;
  DirectionFaults to_device;  // host -> device
  DirectionFaults to_host;    // device -> host

  bool Any() const { return to_device.Any() || to_host.Any(); }
  // nullopt when valid, else a message naming the bad field.
  std::optional<std::string> Validate() const;
};

// Parses a comma-separated fault list, e.g.
//   "seed=42,drop=0.01,corrupt=0.001,dup=0.002,delay=0.01,delay_ms=50,dir=to-host"
// Keys: seed, drop, corrupt, dup, delay (rates), delay_ms, and dir
// (to-device | to-host | both, default both; applies to the rates given
// after it and before the next dir=). Returns the config or a message that
// names the bad item.
std::variant<FaultConfig, std::string> ParseFaultConfig(std::string_view spec);

}  // namespace moco::sim

#endif  // MOCO_SIM_LINE_FAULTS_H_
