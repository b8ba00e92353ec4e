// The one clock: a deterministic discrete-event scheduler in integer
// nanoseconds (ARCHITECTURE "One clock"). Drivers: virtual time (RunNext,
// RunUntilIdle) and real time (an external driver calls NextEventTime and
// RunUntil with a wall-derived time).
#ifndef MOCO_SIM_SCHEDULER_H_
#define MOCO_SIM_SCHEDULER_H_

#include <cstddef>
#include <cstdint>
#include <limits>
#include <optional>
#include <vector>

#include "sim/callback.h"

namespace moco::sim {

// Nanoseconds since power-on of the simulation.
using TimeNs = int64_t;

inline constexpr TimeNs kNsPerUs = 1'000;
inline constexpr TimeNs kNsPerMs = 1'000'000;
inline constexpr TimeNs kNsPerSecond = 1'000'000'000;
inline constexpr TimeNs kTimeNever = std::numeric_limits<TimeNs>::max();

// Discrete-event scheduler. Events run in (time, insertion sequence) order, so
// two runs fed the same calls produce the same order. Time never goes back.
//
// Callbacks may call any method of the scheduler reentrantly (schedule, cancel,
// including their own id, which is no longer pending once it runs) except the
// Run* methods, which must not be nested.
//
// Not thread-safe: one thread owns a Scheduler (the real-time driver calls it
// from its event loop).
class Scheduler {
 public:
  using TimerId = uint64_t;  // 0 is never a valid id
  static constexpr TimerId kNoTimer = 0;

  Scheduler() = default;
  Scheduler(const Scheduler&) = delete;
  Scheduler& operator=(const Scheduler&) = delete;

  // Current simulated time. Starts at 0.
  TimeNs Now() const { return now_; }

  // Schedules `cb` to run at `when`; a `when` before Now() runs at Now() (after
  // every event already due at Now()). Returns an id for Cancel.
  TimerId At(TimeNs when, Callback cb);

  // Schedules `cb` at Now() + delay_ns (saturating; a negative delay is 0).
  TimerId After(TimeNs delay_ns, Callback cb);

  // Removes a pending timer. Returns true if it was pending (it will not run);
  // false for an id that already ran, is running, was cancelled, or is 0.
  bool Cancel(TimerId id);

  // Time of the earliest pending event, or nullopt when none is pending.
  std::optional<TimeNs> NextEventTime() const;

  // Number of pending (not cancelled) events.
  size_t PendingCount() const { return live_count_; }

  // Virtual-time driver: advances Now() to the earliest pending event and runs
  // it. Returns false (and does nothing) when nothing is pending.
  bool RunNext();

  // Runs every event with time <= t (including those scheduled meanwhile) in
  // (time, sequence) order, then sets Now() to t. A t before Now() runs the
  // events due at Now() and leaves Now() unchanged.
  void RunUntil(TimeNs t);

  // As RunUntil(t), but stops after max_events events. Returns true when
  // every event due by t ran (Now() is then t, or stays if t is earlier);
  // false when it stopped with events still due, leaving Now() at the time of
  // the last event run, so a later call resumes in order. A driver that is
  // behind (more due work than it can run in one go) uses it to return to its
  // event loop between slices.
  bool RunUntil(TimeNs t, size_t max_events);

  // Runs events until none is pending or max_events ran. Returns the number
  // of events run.
  size_t RunUntilIdle(size_t max_events = SIZE_MAX);

 private:
  struct Entry {
    TimeNs time;
    uint64_t seq;
    uint32_t slot;
  };
  struct Slot {
    Callback cb;
    uint64_t seq = 0;         // seq of the pending entry using this slot; 0 = free
    uint32_t generation = 1;  // bumped when the slot is released
  };

  // (time, seq) as one unsigned 128-bit key, so comparisons are branch-free.
  __extension__ using Key = unsigned __int128;
  static Key KeyOf(const Entry& e) {
    return (static_cast<Key>(static_cast<uint64_t>(e.time) ^ (uint64_t{1} << 63)) << 64) | e.seq;
  }
  static bool Later(const Entry& a, const Entry& b) { return KeyOf(a) > KeyOf(b); }
  static TimerId MakeId(uint32_t generation, uint32_t slot) {
    return (static_cast<uint64_t>(generation) << 32) | slot;
  }

  void HeapPush(Entry e);
  void HeapPopTop();
  void ReleaseSlot(uint32_t slot);
  // Drops cancelled entries from the top, so heap_.front() is always live.
  void PruneTop();
  // Rebuilds the heap without cancelled entries when they dominate it.
  void MaybeCompact();
  // Pops the (live) top entry and runs its callback at its time.
  void RunTop();

  TimeNs now_ = 0;
  uint64_t next_seq_ = 1;
  size_t live_count_ = 0;
  std::vector<Entry> heap_;  // min-heap on (time, seq); may hold stale entries
  std::vector<Slot> slots_;
  std::vector<uint32_t> free_slots_;
  bool running_ = false;
};

}  // namespace moco::sim

#endif  // MOCO_SIM_SCHEDULER_H_
