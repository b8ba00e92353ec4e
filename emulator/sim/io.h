// Device I/O below the protocols (dmc-v2-protocol.txt MSG_GIO_OUT, MSG_GIO_IN
// "use some hysteresis", MSG_GIO_CAM GIO_CAM_SHUTTER 0x0001 / GIO_CAM_METER
// 0x0002, MSG_DMX channels 1-512 with RAMP): GIO with debounce, camera lines
// with a timed trace, DMX values in closed form.
#ifndef MOCO_SIM_IO_H_
#define MOCO_SIM_IO_H_

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

#include "sim/scheduler.h"

namespace moco::sim {

// 32 general outputs and 32 debounced general inputs. An input change is
// reported once the new raw level has held for debounce_ns; shorter glitches
// are never seen. `scheduler` must outlive the port.
class GioPort {
 public:
  // Called with the debounced inputs after each accepted change.
  using InputListener = std::function<void(uint32_t inputs, uint32_t changed, TimeNs time_ns)>;

  GioPort(Scheduler& scheduler, TimeNs debounce_ns, InputListener listener = nullptr);
  ~GioPort();
  GioPort(const GioPort&) = delete;
  GioPort& operator=(const GioPort&) = delete;

  void SetListener(InputListener listener) { listener_ = std::move(listener); }

  // Outputs (MSG_GIO_OUT TRIGGERS).
  void SetOutputs(uint32_t bits) { outputs_ = bits; }
  uint32_t outputs() const { return outputs_; }

  // Raw input levels as wired (the run-time control channel drives these).
  void SetRawInputs(uint32_t bits);
  // REQUIRES: bit < 32 (others ignored).
  void SetRawInput(int bit, bool level);
  uint32_t raw_inputs() const { return raw_; }
  // Debounced inputs (MSG_GIO_IN TRIGGERS).
  uint32_t inputs() const { return stable_; }
  TimeNs debounce_ns() const { return debounce_ns_; }

 private:
  void OnSettled(int bit);

  Scheduler& scheduler_;
  TimeNs debounce_ns_;
  InputListener listener_;
  uint32_t outputs_ = 0;
  uint32_t raw_ = 0;
  uint32_t stable_ = 0;
  std::array<Scheduler::TimerId, 32> pending_{};
};

// Camera lines (MSG_GIO_CAM flags) and the record of their transitions.
class CameraPort {
 public:
  enum Line : uint8_t { kShutter = 0x01, kMeter = 0x02 };
  struct Edge {
    TimeNs time_ns;
    Line line;
    bool level;  // true = closed contact (shutter open / metering)
    bool operator==(const Edge&) const = default;
  };

  // Keeps the last `trace_capacity` edges. `scheduler` must outlive the port.
  CameraPort(Scheduler& scheduler, size_t trace_capacity = 1024);
  ~CameraPort();
  CameraPort(const CameraPort&) = delete;
  CameraPort& operator=(const CameraPort&) = delete;

  // Sets both lines from GIO_CAM flags (bit 0 shutter, bit 1 meter).
  void SetFlags(uint32_t flags);
  void Set(Line line, bool level);
  bool level(Line line) const { return (flags_ & line) != 0; }
  uint32_t flags() const { return flags_; }
  // Opens the shutter now and closes it after exposure_ns (a later Set or
  // Expose cancels the pending close). Returns the close time.
  TimeNs Expose(TimeNs exposure_ns);

  // Edges, oldest first (at most trace_capacity; dropped() were discarded).
  std::vector<Edge> Trace() const;
  uint64_t dropped() const { return dropped_; }
  uint64_t exposures() const { return exposures_; }

 private:
  void Record(Line line, bool level);

  Scheduler& scheduler_;
  size_t capacity_;
  uint32_t flags_ = 0;
  std::vector<Edge> trace_;  // ring
  size_t head_ = 0;
  uint64_t dropped_ = 0;
  uint64_t exposures_ = 0;
  Scheduler::TimerId close_timer_ = Scheduler::kNoTimer;
};

// DMX universe: channels 1..512, values 0..255, set at once or ramped at a
// rate in value units per second. Value at any time in closed form: a ramp
// from v0 to v1 started at t0 is v0 +- floor(rate * (t - t0)) until it
// reaches v1, at t0 + ceil(|v1 - v0| / rate) (in ns).
class DmxUniverse {
 public:
  static constexpr int kChannels = 512;
  // Called when the last ramp ends (the universe stops "adjusting").
  using SettledListener = std::function<void(TimeNs time_ns)>;

  // REQUIRES: ramp_rate_per_s > 0. `scheduler` must outlive the universe.
  DmxUniverse(Scheduler& scheduler, double ramp_rate_per_s, SettledListener listener = nullptr);
  ~DmxUniverse();
  DmxUniverse(const DmxUniverse&) = delete;
  DmxUniverse& operator=(const DmxUniverse&) = delete;

  void SetListener(SettledListener listener) { listener_ = std::move(listener); }
  double ramp_rate_per_s() const { return rate_; }

  // Channel outside 1..512: returns false, nothing changes.
  bool Set(int channel, uint8_t value);
  // Ramps from the channel's current value to `value` at the ramp rate.
  bool RampTo(int channel, uint8_t value);
  // MSG_DMX: values for start_channel, start_channel+1, ... (those past 512
  // are dropped); ramp or immediate. Returns false if start_channel is out
  // of range.
  bool Apply(bool ramp, int start_channel, const std::vector<uint8_t>& values);

  uint8_t Value(int channel) const { return ValueAt(channel, scheduler_.Now()); }
  // Value at time t (t >= the start of the channel's current ramp).
  uint8_t ValueAt(int channel, TimeNs t) const;
  // Time the channel reaches its target (its ramp end, or when it was set).
  TimeNs ReachTime(int channel) const;
  // Any ramp still running (MSG_MOTOR_STATUS DMX STATUS).
  bool Adjusting() const { return scheduler_.Now() < settle_ns_; }

 private:
  struct Channel {
    uint8_t from = 0;
    uint8_t to = 0;
    TimeNs t0_ns = 0;
    TimeNs end_ns = 0;
    double rate_per_s = 1;
  };
  // Sets one channel (1..kChannels) without touching the settle timer.
  void Update(int channel, uint8_t value, bool ramp);
  // The settle timer after one channel's end moved from old_end to new_end:
  // O(1) unless the channel that ends last changed.
  void RescheduleAfter(TimeNs old_end, TimeNs new_end);
  void Reschedule();

  Scheduler& scheduler_;
  double rate_;
  SettledListener listener_;
  std::array<Channel, kChannels> ch_{};
  TimeNs settle_ns_ = 0;
  Scheduler::TimerId settle_timer_ = Scheduler::kNoTimer;
};

}  // namespace moco::sim

#endif  // MOCO_SIM_IO_H_
