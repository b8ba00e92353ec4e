// The real-time driver of the one clock (ARCHITECTURE "One clock").
#include "transport/realtime_driver.h"

#include <algorithm>

namespace moco::transport {

RealtimeDriver::RealtimeDriver(asio::io_context& io, sim::Scheduler& scheduler)
    : io_(io), scheduler_(scheduler), timer_(io) {}

RealtimeDriver::~RealtimeDriver() { Stop(); }

void RealtimeDriver::Start() {
  if (started_) return;
  started_ = true;
  last_now_ns_ = scheduler_.Now();
  origin_ = Clock::now() - std::chrono::nanoseconds(last_now_ns_);
  Kick();
}

void RealtimeDriver::Stop() {
  if (stopped_) return;
  stopped_ = true;
  armed_ = false;
  timer_.cancel();
}

sim::TimeNs RealtimeDriver::NowNs() {
  if (!started_) return scheduler_.Now();
  const auto wall =
      std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now() - origin_).count();
  last_now_ns_ = std::max({last_now_ns_, static_cast<sim::TimeNs>(wall), scheduler_.Now()});
  return last_now_ns_;
}

RealtimeDriver::Clock::time_point RealtimeDriver::WallTimeOf(sim::TimeNs t_ns) const {
  // Far-future events (kTimeNever) saturate instead of overflowing the clock.
  constexpr sim::TimeNs kMaxAheadNs = 100LL * 365 * 24 * 3600 * sim::kNsPerSecond;
  return origin_ + std::chrono::nanoseconds(std::min(t_ns, kMaxAheadNs));
}

void RealtimeDriver::RunDue() {
  in_run_ = true;
  const sim::TimeNs until = NowNs();
  const Clock::time_point slice_end = Clock::now() + kMaxSliceWall;
  size_t run = 0;
  bool done = false;
  // Bounded catch-up: when more is due than a slice may run (a scenario of
  // thousands of 1 ms events, a machine that fell behind), the rest runs from
  // the next timer expiry, so signals and I/O get their turn in between.
  while (!done && run < kMaxSliceEvents) {
    done = scheduler_.RunUntil(until, kEventsPerWallCheck);
    run += kEventsPerWallCheck;
    if (Clock::now() >= slice_end) break;
  }
  if (!done) ++catch_up_slices_;
  in_run_ = false;
}

sim::TimeNs RealtimeDriver::Sync() {
  if (running() && !in_run_) RunDue();
  return scheduler_.Now();
}

void RealtimeDriver::Kick() {
  if (!running() || in_run_) return;
  RunDue();
  Arm();
}

void RealtimeDriver::Arm() {
  const auto next = scheduler_.NextEventTime();
  if (!next) {
    if (armed_) timer_.cancel();
    armed_ = false;
    return;
  }
  if (armed_ && armed_at_ns_ == *next) return;
  armed_ = true;
  armed_at_ns_ = *next;
  timer_.expires_at(WallTimeOf(*next));
  timer_.async_wait([this](const ErrorCode& ec) {
    // A cancelled wait was superseded by a newer one (or Stop); an expiry
    // that was already queued when re-armed is harmless: Kick is idempotent.
    if (ec == asio::error::operation_aborted) return;
    ++wakeups_;
    armed_ = false;
    Kick();
  });
}

}  // namespace moco::transport
