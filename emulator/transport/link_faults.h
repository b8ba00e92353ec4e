// Link fault injection (ARCHITECTURE "transport": link faults): per-byte drop,
// single-bit corruption, duplication and delay on either direction of a
// link, drawn from a seeded std::mt19937_64 so a run is reproducible. Pure:
// no I/O, no clock of its own; times are scheduler nanoseconds.
#ifndef MOCO_TRANSPORT_LINK_FAULTS_H_
#define MOCO_TRANSPORT_LINK_FAULTS_H_

#include <cstdint>
#include <optional>
#include <random>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "sim/line_faults.h"
#include "sim/scheduler.h"
#include "transport/traffic.h"
#include "wire/bytes.h"

namespace moco::transport {

// The settings (sim/line_faults.h), by their transport names.
using sim::DirectionFaults;
using sim::FaultConfig;
using sim::ParseFaultConfig;

struct FaultCounts {
  uint64_t bytes_in = 0;
  uint64_t dropped = 0;
  uint64_t corrupted = 0;
  uint64_t duplicated = 0;
  uint64_t delayed = 0;
};

// Bytes released at a time: the output of the fault injector.
struct TimedBytes {
  sim::TimeNs at_ns = 0;
  wire::Bytes bytes;
};

// Applies a FaultConfig to a byte stream. Each direction draws from its own
// generator (seeded from the config's seed and the direction), so its faults
// depend only on its own bytes, not on how the two directions interleave.
class FaultInjector {
 public:
  explicit FaultInjector(const FaultConfig& config = {});

  bool enabled() const { return config_.Any(); }
  const FaultConfig& config() const { return config_; }

  // Passes `bytes`, arriving at now_ns, through the faults of `dir`. Returns
  // chunks in stream order with non-decreasing at_ns >= now_ns (later than
  // now_ns only after a delay fault); adjacent bytes released at the same
  // time share a chunk. With no fault configured, returns {{now_ns, bytes}}.
  // REQUIRES: now_ns non-decreasing across calls for the same direction.
  std::vector<TimedBytes> Apply(Direction dir, wire::ByteView bytes, sim::TimeNs now_ns);

  // Whether `dir` has no fault configured: Apply() would return the bytes
  // unchanged at the time given. A caller that passes them on itself counts
  // them with CountPassed(), as Apply() would.
  bool PassesUnchanged(Direction dir) const { return !Side(dir).faults.Any(); }
  void CountPassed(Direction dir, size_t n) { Side(dir).counts.bytes_in += n; }

  const FaultCounts& counts(Direction dir) const { return Side(dir).counts; }

 private:
  struct SideState {
    DirectionFaults faults;
    std::mt19937_64 rng;
    sim::TimeNs stall_until_ns = 0;
    FaultCounts counts;
  };
  SideState& Side(Direction dir) { return dir == Direction::kToDevice ? to_device_ : to_host_; }
  const SideState& Side(Direction dir) const {
    return dir == Direction::kToDevice ? to_device_ : to_host_;
  }
  // True with probability p, from 53 random bits (the same on every platform).
  static bool Chance(std::mt19937_64& rng, double p);

  FaultConfig config_;
  SideState to_device_;
  SideState to_host_;
};

}  // namespace moco::transport

#endif  // MOCO_TRANSPORT_LINK_FAULTS_H_
