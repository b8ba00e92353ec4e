// The real-time driver of the one clock (ARCHITECTURE "One clock"): an Asio
// steady_timer wakes the Scheduler at its next event, mapped to the wall clock.
#ifndef MOCO_TRANSPORT_REALTIME_DRIVER_H_
#define MOCO_TRANSPORT_REALTIME_DRIVER_H_

#include <chrono>
#include <cstdint>

#include "sim/scheduler.h"
#include "transport/asio.h"

namespace moco::transport {

// Runs a Scheduler in real time on one io_context thread. Scheduler time t
// maps to the wall instant origin() + t, where origin() is the Start() instant
// minus the scheduler's Now() at that moment (a fresh scheduler: sim time 0 =
// the start instant). Sim time never runs ahead of the wall clock and never
// goes back: the scheduler only ever advances to NowNs().
//
// Whoever may add events to the scheduler from outside a scheduler callback
// (an I/O handler delivering host bytes, a control command) calls Kick()
// afterwards so the timer is re-armed at the new earliest event. Inside a
// scheduler callback Kick() is not needed (the driver re-arms after the run).
//
// Both the io_context and the scheduler must outlive the driver. All calls
// come from the thread running the io_context.
class RealtimeDriver {
 public:
  using Clock = std::chrono::steady_clock;

  RealtimeDriver(asio::io_context& io, sim::Scheduler& scheduler);
  ~RealtimeDriver();
  RealtimeDriver(const RealtimeDriver&) = delete;
  RealtimeDriver& operator=(const RealtimeDriver&) = delete;

  // Starts the clock (see the class comment), runs what is due and arms the
  // timer. Calling it again does nothing.
  void Start();
  // Stops: cancels the timer; later Kick()s do nothing. The scheduler keeps
  // its pending events.
  void Stop();
  bool running() const { return started_ && !stopped_; }

  // Runs the events due by the wall clock (one slice), then arms the timer at
  // the next pending event (at once when the slice left some due). Cheap when nothing changed.
  // No-op before Start(), after Stop(), and inside a scheduler callback.
  void Kick();

  // Advances the scheduler to the wall clock (running the events due by then,
  // at most one slice: see kMaxSliceEvents) and returns its Now(). Call before handing the device
  // anything from outside the scheduler, so the device sees a current time. Inside a scheduler
  // callback, returns the scheduler's Now() unchanged.
  sim::TimeNs Sync();

  // The scheduler time of the wall clock now: non-decreasing, and never less
  // than scheduler().Now(). Before Start(), the scheduler's Now().
  sim::TimeNs NowNs();

  // Wall instant of scheduler time t_ns. REQUIRES: Start() was called.
  Clock::time_point WallTimeOf(sim::TimeNs t_ns) const;
  Clock::time_point origin() const { return origin_; }

  sim::Scheduler& scheduler() { return scheduler_; }
  asio::io_context& io() { return io_; }

  // Number of timer expiries handled (for tests and benchmarks).
  uint64_t wakeups() const { return wakeups_; }
  // Number of runs that stopped at the slice bound with events still due.
  uint64_t catch_up_slices() const { return catch_up_slices_; }

  // One run of due events (Kick, Sync, a timer expiry) runs at most this
  // many events, and stops early once it has taken kMaxSliceWall; what is
  // left runs from the next expiry of the timer, armed at once, so the
  // io_context reaches signals and I/O between slices however far behind
  // the scheduler is.
  static constexpr size_t kMaxSliceEvents = 4096;
  static constexpr size_t kEventsPerWallCheck = 256;
  static constexpr std::chrono::milliseconds kMaxSliceWall{10};

 private:
  void RunDue();
  void Arm();

  asio::io_context& io_;
  sim::Scheduler& scheduler_;
  asio::steady_timer timer_;
  Clock::time_point origin_{};
  sim::TimeNs last_now_ns_ = 0;
  bool started_ = false;
  bool stopped_ = false;
  bool in_run_ = false;
  bool armed_ = false;
  sim::TimeNs armed_at_ns_ = 0;
  uint64_t wakeups_ = 0;
  uint64_t catch_up_slices_ = 0;
};

}  // namespace moco::transport

#endif  // MOCO_TRANSPORT_REALTIME_DRIVER_H_
