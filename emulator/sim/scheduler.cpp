// The one clock: discrete-event scheduler ordered by (time, sequence)
// (ARCHITECTURE "One clock"). 4-ary min-heap with lazy cancellation.
#include "sim/scheduler.h"

#include <algorithm>
#include <utility>

namespace moco::sim {

Scheduler::TimerId Scheduler::At(TimeNs when, Callback cb) {
  if (when < now_) when = now_;
  uint32_t slot;
  if (!free_slots_.empty()) {
    slot = free_slots_.back();
    free_slots_.pop_back();
  } else {
    slot = static_cast<uint32_t>(slots_.size());
    slots_.emplace_back();
  }
  const uint64_t seq = next_seq_++;
  Slot& s = slots_[slot];
  s.cb = std::move(cb);
  s.seq = seq;
  HeapPush(Entry{when, seq, slot});
  ++live_count_;
  return MakeId(s.generation, slot);
}

Scheduler::TimerId Scheduler::After(TimeNs delay_ns, Callback cb) {
  if (delay_ns < 0) delay_ns = 0;
  const TimeNs when = delay_ns > kTimeNever - now_ ? kTimeNever : now_ + delay_ns;
  return At(when, std::move(cb));
}

bool Scheduler::Cancel(TimerId id) {
  const auto slot = static_cast<uint32_t>(id & 0xffffffffu);
  const auto generation = static_cast<uint32_t>(id >> 32);
  if (id == kNoTimer || slot >= slots_.size()) return false;
  Slot& s = slots_[slot];
  if (s.generation != generation || s.seq == 0) return false;
  // The closure is destroyed after the bookkeeping, so a destructor that
  // touches the scheduler sees a consistent state.
  Callback dead = std::move(s.cb);
  ReleaseSlot(slot);
  --live_count_;
  PruneTop();
  MaybeCompact();
  return true;
}

std::optional<TimeNs> Scheduler::NextEventTime() const {
  if (heap_.empty()) return std::nullopt;
  return heap_.front().time;  // the top is always live (PruneTop)
}

bool Scheduler::RunNext() {
  if (running_ || heap_.empty()) return false;
  running_ = true;
  RunTop();
  running_ = false;
  return true;
}

void Scheduler::RunUntil(TimeNs t) {
  if (running_) return;
  running_ = true;
  while (!heap_.empty() && heap_.front().time <= t) RunTop();
  if (t > now_) now_ = t;
  running_ = false;
}

bool Scheduler::RunUntil(TimeNs t, size_t max_events) {
  if (running_) return false;
  running_ = true;
  size_t n = 0;
  while (!heap_.empty() && heap_.front().time <= t) {
    if (n == max_events) {
      running_ = false;
      return false;
    }
    RunTop();
    ++n;
  }
  if (t > now_) now_ = t;
  running_ = false;
  return true;
}

size_t Scheduler::RunUntilIdle(size_t max_events) {
  if (running_) return 0;
  running_ = true;
  size_t n = 0;
  while (n < max_events && !heap_.empty()) {
    RunTop();
    ++n;
  }
  running_ = false;
  return n;
}

// A 4-ary heap: shallower than binary, and the four children of a node share
// a cache line or two, which matters with thousands of pending timers.
void Scheduler::HeapPush(Entry e) {
  heap_.push_back(e);
  size_t hole = heap_.size() - 1;
  while (hole > 0) {
    const size_t parent = (hole - 1) / 4;
    if (!Later(heap_[parent], e)) break;
    heap_[hole] = heap_[parent];
    hole = parent;
  }
  heap_[hole] = e;
}

// Bottom-up deletion: move the hole down along the smallest children to a
// leaf (no comparison with the moved element on the way), then sift the last
// element up from there, which is usually a short trip.
void Scheduler::HeapPopTop() {
  const Entry last = heap_.back();
  heap_.pop_back();
  const size_t n = heap_.size();
  if (n == 0) return;
  size_t hole = 0;
  for (;;) {
    const size_t first = 4 * hole + 1;
    if (first >= n) break;
    size_t best = first;
    Key best_key = KeyOf(heap_[first]);
    const size_t end = first + 4 < n ? first + 4 : n;
    for (size_t c = first + 1; c < end; ++c) {
      const Key k = KeyOf(heap_[c]);
      const bool smaller = k < best_key;
      best = smaller ? c : best;
      best_key = smaller ? k : best_key;
    }
    heap_[hole] = heap_[best];
    hole = best;
  }
  const Key last_key = KeyOf(last);
  while (hole > 0) {
    const size_t parent = (hole - 1) / 4;
    if (KeyOf(heap_[parent]) <= last_key) break;
    heap_[hole] = heap_[parent];
    hole = parent;
  }
  heap_[hole] = last;
}

void Scheduler::ReleaseSlot(uint32_t slot) {
  Slot& s = slots_[slot];
  s.seq = 0;
  if (++s.generation == 0) s.generation = 1;  // keeps ids non-zero
  free_slots_.push_back(slot);
}

void Scheduler::PruneTop() {
  if (heap_.size() == live_count_) return;  // no cancelled entries anywhere
  while (!heap_.empty() && slots_[heap_.front().slot].seq != heap_.front().seq) HeapPopTop();
}

void Scheduler::MaybeCompact() {
  if (heap_.size() < 64 || heap_.size() <= 2 * live_count_) return;
  std::vector<Entry> live;
  live.reserve(live_count_);
  for (const Entry& e : heap_) {
    if (slots_[e.slot].seq == e.seq) live.push_back(e);
  }
  heap_.clear();
  for (const Entry& e : live) HeapPush(e);
}

void Scheduler::RunTop() {
  const Entry e = heap_.front();
  HeapPopTop();
  now_ = e.time;
  // Move the closure out first: it may schedule and grow slots_.
  Callback cb = std::move(slots_[e.slot].cb);
  ReleaseSlot(e.slot);
  --live_count_;
  PruneTop();
  cb();
}

}  // namespace moco::sim
