// Link fault injection: seeded per-byte drop, corrupt, delay and duplicate.
#include "transport/link_faults.h"

#include <algorithm>
#include <cmath>

namespace moco::transport {
namespace {

// Distinct, fixed streams for the two directions of one seed.
constexpr uint64_t kToHostSalt = 0x9E3779B97F4A7C15ull;

}  // namespace

FaultInjector::FaultInjector(const FaultConfig& config) : config_(config) {
  to_device_.faults = config.to_device;
  to_device_.rng.seed(config.seed);
  to_host_.faults = config.to_host;
  to_host_.rng.seed(config.seed ^ kToHostSalt);
}

bool FaultInjector::Chance(std::mt19937_64& rng, double p) {
  if (p <= 0) return false;
  const double u = static_cast<double>(rng() >> 11) * 0x1.0p-53;  // uniform in [0, 1)
  return u < p;
}

std::vector<TimedBytes> FaultInjector::Apply(Direction dir, wire::ByteView bytes,
                                             sim::TimeNs now_ns) {
  SideState& side = Side(dir);
  side.counts.bytes_in += bytes.size();
  std::vector<TimedBytes> out;
  if (!side.faults.Any()) {
    if (!bytes.empty()) {
      const sim::TimeNs at = std::max(now_ns, side.stall_until_ns);
      out.push_back({at, wire::Bytes(bytes.begin(), bytes.end())});
    }
    return out;
  }
  const DirectionFaults& f = side.faults;
  auto emit = [&out](sim::TimeNs at, uint8_t b) {
    if (out.empty() || out.back().at_ns != at) out.push_back({at, {}});
    out.back().bytes.push_back(b);
  };
  for (uint8_t b : bytes) {
    if (Chance(side.rng, f.drop_rate)) {
      ++side.counts.dropped;
      continue;
    }
    if (Chance(side.rng, f.corrupt_rate)) {
      b = static_cast<uint8_t>(b ^ (1u << (side.rng() % 8)));
      ++side.counts.corrupted;
    }
    if (Chance(side.rng, f.delay_rate)) {
      side.stall_until_ns = std::max(side.stall_until_ns, now_ns) + f.delay_ns;
      ++side.counts.delayed;
    }
    const sim::TimeNs at = std::max(now_ns, side.stall_until_ns);
    emit(at, b);
    if (Chance(side.rng, f.duplicate_rate)) {
      emit(at, b);
      ++side.counts.duplicated;
    }
  }
  return out;
}

std::string_view DirectionName(Direction d) {
  return d == Direction::kToDevice ? "to-device" : "to-host";
}

}  // namespace moco::transport
