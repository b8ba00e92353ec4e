// GIO with debounce, camera lines with a trace, DMX ramps in closed form
// (dmc-v2-protocol.txt MSG_GIO_OUT / MSG_GIO_IN / MSG_GIO_CAM / MSG_DMX).
#include "sim/io.h"

#include <cmath>
#include <utility>

namespace moco::sim {

// --- GioPort ---

GioPort::GioPort(Scheduler& scheduler, TimeNs debounce_ns, InputListener listener)
    : scheduler_(scheduler),
      debounce_ns_(debounce_ns > 0 ? debounce_ns : 0),
      listener_(std::move(listener)) {}

GioPort::~GioPort() {
  for (Scheduler::TimerId id : pending_) scheduler_.Cancel(id);
}

void GioPort::SetRawInputs(uint32_t bits) {
  for (int b = 0; b < 32; ++b) SetRawInput(b, ((bits >> b) & 1u) != 0);
}

void GioPort::SetRawInput(int bit, bool level) {
  if (bit < 0 || bit >= 32) return;
  const uint32_t mask = 1u << bit;
  const bool was = (raw_ & mask) != 0;
  if (was == level) return;
  raw_ = level ? (raw_ | mask) : (raw_ & ~mask);
  Scheduler::TimerId& pending = pending_[static_cast<size_t>(bit)];
  scheduler_.Cancel(pending);  // the level must hold a full debounce time
  pending = Scheduler::kNoTimer;
  if (((stable_ & mask) != 0) == level) return;  // back to the stable level: a glitch
  pending = scheduler_.After(debounce_ns_, [this, bit] { OnSettled(bit); });
}

void GioPort::OnSettled(int bit) {
  const uint32_t mask = 1u << bit;
  pending_[static_cast<size_t>(bit)] = Scheduler::kNoTimer;
  stable_ = (stable_ & ~mask) | (raw_ & mask);
  if (listener_) listener_(stable_, mask, scheduler_.Now());
}

// --- CameraPort ---

CameraPort::CameraPort(Scheduler& scheduler, size_t trace_capacity)
    : scheduler_(scheduler), capacity_(trace_capacity) {
  trace_.reserve(capacity_);
}

CameraPort::~CameraPort() { scheduler_.Cancel(close_timer_); }

void CameraPort::SetFlags(uint32_t flags) {
  Set(kShutter, (flags & kShutter) != 0);
  Set(kMeter, (flags & kMeter) != 0);
}

void CameraPort::Set(Line line, bool level) {
  if (line == kShutter) {
    scheduler_.Cancel(close_timer_);
    close_timer_ = Scheduler::kNoTimer;
  }
  if (this->level(line) == level) return;
  flags_ = level ? (flags_ | line) : (flags_ & ~static_cast<uint32_t>(line));
  if (line == kShutter && level) ++exposures_;
  Record(line, level);
}

TimeNs CameraPort::Expose(TimeNs exposure_ns) {
  Set(kShutter, true);
  const TimeNs close = scheduler_.Now() + (exposure_ns > 0 ? exposure_ns : 0);
  close_timer_ = scheduler_.At(close, [this] {
    close_timer_ = Scheduler::kNoTimer;
    Set(kShutter, false);
  });
  return close;
}

void CameraPort::Record(Line line, bool level) {
  if (capacity_ == 0) {
    ++dropped_;
    return;
  }
  const Edge e{scheduler_.Now(), line, level};
  if (trace_.size() < capacity_) {
    trace_.push_back(e);
    return;
  }
  trace_[head_] = e;
  head_ = (head_ + 1) % capacity_;
  ++dropped_;
}

std::vector<CameraPort::Edge> CameraPort::Trace() const {
  std::vector<Edge> out;
  out.reserve(trace_.size());
  for (size_t i = 0; i < trace_.size(); ++i) out.push_back(trace_[(head_ + i) % trace_.size()]);
  return out;
}

// --- DmxUniverse ---

DmxUniverse::DmxUniverse(Scheduler& scheduler, double ramp_rate_per_s, SettledListener listener)
    : scheduler_(scheduler),
      rate_(std::isfinite(ramp_rate_per_s) && ramp_rate_per_s > 0 ? ramp_rate_per_s : 1),
      listener_(std::move(listener)) {}

DmxUniverse::~DmxUniverse() { scheduler_.Cancel(settle_timer_); }

void DmxUniverse::Update(int channel, uint8_t value, bool ramp) {
  Channel& c = ch_[static_cast<size_t>(channel - 1)];
  const TimeNs now = scheduler_.Now();
  if (!ramp) {
    c = Channel{value, value, now, now, rate_};
    return;
  }
  const uint8_t from = ValueAt(channel, now);
  const int delta = value > from ? value - from : from - value;
  const auto span_ns = static_cast<TimeNs>(std::ceil(delta / rate_ * 1e9));
  c = Channel{from, value, now, now + span_ns, rate_};
}

bool DmxUniverse::Set(int channel, uint8_t value) {
  if (channel < 1 || channel > kChannels) return false;
  const TimeNs old_end = ch_[static_cast<size_t>(channel - 1)].end_ns;
  Update(channel, value, false);
  RescheduleAfter(old_end, ch_[static_cast<size_t>(channel - 1)].end_ns);
  return true;
}

bool DmxUniverse::RampTo(int channel, uint8_t value) {
  if (channel < 1 || channel > kChannels) return false;
  const TimeNs old_end = ch_[static_cast<size_t>(channel - 1)].end_ns;
  Update(channel, value, true);
  RescheduleAfter(old_end, ch_[static_cast<size_t>(channel - 1)].end_ns);
  return true;
}

void DmxUniverse::RescheduleAfter(TimeNs old_end, TimeNs new_end) {
  const TimeNs now = scheduler_.Now();
  // Nothing was adjusting and nothing is: the settle time is now.
  if (settle_ns_ <= now && new_end <= now) {
    if (settle_ns_ < now) settle_ns_ = now;
    return;
  }
  // Another channel's ramp ends last, before and after: the timer stands.
  if (settle_ns_ > now && old_end < settle_ns_ && new_end <= settle_ns_) return;
  Reschedule();
}

bool DmxUniverse::Apply(bool ramp, int start_channel, const std::vector<uint8_t>& values) {
  if (start_channel < 1 || start_channel > kChannels) return false;
  // Every channel first, then one settle-time update (not one per channel).
  for (size_t i = 0; i < values.size(); ++i) {
    const int ch = start_channel + static_cast<int>(i);
    if (ch > kChannels) break;
    Update(ch, values[i], ramp);
  }
  Reschedule();
  return true;
}

uint8_t DmxUniverse::ValueAt(int channel, TimeNs t) const {
  if (channel < 1 || channel > kChannels) return 0;
  const Channel& c = ch_[static_cast<size_t>(channel - 1)];
  if (t >= c.end_ns) return c.to;
  if (t <= c.t0_ns) return c.from;
  const int delta = c.to > c.from ? c.to - c.from : c.from - c.to;
  const double moved = std::floor(c.rate_per_s * static_cast<double>(t - c.t0_ns) / 1e9);
  const int step = moved >= delta ? delta : static_cast<int>(moved);
  return static_cast<uint8_t>(c.to > c.from ? c.from + step : c.from - step);
}

TimeNs DmxUniverse::ReachTime(int channel) const {
  if (channel < 1 || channel > kChannels) return 0;
  return ch_[static_cast<size_t>(channel - 1)].end_ns;
}

void DmxUniverse::Reschedule() {
  const TimeNs now = scheduler_.Now();
  TimeNs latest = now;
  for (const Channel& c : ch_) {
    if (c.end_ns > latest) latest = c.end_ns;
  }
  if (latest == settle_ns_ && settle_timer_ != Scheduler::kNoTimer) return;
  scheduler_.Cancel(settle_timer_);
  settle_timer_ = Scheduler::kNoTimer;
  const bool was_adjusting = now < settle_ns_;
  settle_ns_ = latest;
  if (latest > now) {
    settle_timer_ = scheduler_.At(latest, [this] {
      settle_timer_ = Scheduler::kNoTimer;
      if (listener_) listener_(scheduler_.Now());
    });
  } else if (was_adjusting && listener_) {
    listener_(now);  // a Set cut the last ramp short
  }
}

}  // namespace moco::sim
