// Tests for the one clock (ARCHITECTURE "One clock"): (time, sequence) order,
// cancellation, reentrancy, the real-time driver's RunUntil contract.
#include "sim/scheduler.h"

#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>

#include <algorithm>
#include <array>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace moco::sim {
namespace {

TEST(SchedulerTest, StartsAtZeroAndIdle) {
  Scheduler s;
  EXPECT_EQ(s.Now(), 0);
  EXPECT_FALSE(s.NextEventTime().has_value());
  EXPECT_FALSE(s.RunNext());
  EXPECT_EQ(s.RunUntilIdle(), 0u);
}

TEST(SchedulerTest, RunsInTimeThenInsertionOrder) {
  Scheduler s;
  std::string log;
  s.At(30, [&] { log += 'c'; });
  s.At(10, [&] { log += 'a'; });
  s.At(20, [&] { log += 'b'; });
  s.At(10, [&] { log += 'A'; });  // same time as 'a', inserted later
  EXPECT_EQ(s.NextEventTime(), 10);
  EXPECT_EQ(s.RunUntilIdle(), 4u);
  EXPECT_EQ(log, "aAbc");
  EXPECT_EQ(s.Now(), 30);
}

TEST(SchedulerTest, PastTimeRunsAtNowAfterEventsAlreadyDue) {
  Scheduler s;
  std::vector<std::pair<char, TimeNs>> log;
  s.RunUntil(100);
  s.At(100, [&] { log.push_back({'x', s.Now()}); });
  s.At(5, [&] { log.push_back({'y', s.Now()}); });  // in the past: runs at 100
  EXPECT_EQ(s.NextEventTime(), 100);
  s.RunUntilIdle();
  ASSERT_EQ(log.size(), 2u);
  EXPECT_EQ(log[0], std::make_pair('x', TimeNs{100}));
  EXPECT_EQ(log[1], std::make_pair('y', TimeNs{100}));
}

TEST(SchedulerTest, AfterIsRelativeToNowAndSaturates) {
  Scheduler s;
  s.RunUntil(1000);
  TimeNs seen = -1;
  s.After(250, [&] { seen = s.Now(); });
  s.RunUntilIdle();
  EXPECT_EQ(seen, 1250);
  s.After(kTimeNever, [] {});
  EXPECT_EQ(s.NextEventTime(), kTimeNever);
  s.After(-5, [] {});
  EXPECT_EQ(s.NextEventTime(), 1250);
}

TEST(SchedulerTest, CancelRemovesOnlyPendingTimers) {
  Scheduler s;
  int ran = 0;
  const auto a = s.At(10, [&] { ran += 1; });
  const auto b = s.At(20, [&] { ran += 10; });
  EXPECT_NE(a, Scheduler::kNoTimer);
  EXPECT_NE(a, b);
  EXPECT_TRUE(s.Cancel(a));
  EXPECT_FALSE(s.Cancel(a));  // already cancelled
  EXPECT_FALSE(s.Cancel(Scheduler::kNoTimer));
  EXPECT_FALSE(s.Cancel(0xdeadbeef12345ull));
  EXPECT_EQ(s.NextEventTime(), 20);  // the cancelled earliest is not reported
  EXPECT_EQ(s.PendingCount(), 1u);
  s.RunUntilIdle();
  EXPECT_EQ(ran, 10);
  EXPECT_FALSE(s.Cancel(b));  // already ran
}

TEST(SchedulerTest, StaleIdDoesNotCancelATimerReusingItsSlot) {
  Scheduler s;
  int ran = 0;
  const auto a = s.At(10, [&] { ran += 1; });
  s.RunUntilIdle();
  const auto b = s.At(20, [&] { ran += 10; });  // reuses a's slot
  EXPECT_NE(a, b);
  EXPECT_FALSE(s.Cancel(a));
  s.RunUntilIdle();
  EXPECT_EQ(ran, 11);
}

TEST(SchedulerTest, CallbacksMayScheduleAndCancelReentrantly) {
  Scheduler s;
  std::vector<std::string> log;
  Scheduler::TimerId victim = 0;
  Scheduler::TimerId self = 0;
  self = s.At(10, [&] {
    log.push_back("first@" + std::to_string(s.Now()));
    EXPECT_FALSE(s.Cancel(self));  // running: no longer pending
    EXPECT_TRUE(s.Cancel(victim));
    s.At(10, [&] { log.push_back("same-time@" + std::to_string(s.Now())); });
    s.After(5, [&] { log.push_back("later@" + std::to_string(s.Now())); });
    s.At(0, [&] { log.push_back("past@" + std::to_string(s.Now())); });
  });
  victim = s.At(12, [&] { log.push_back("victim"); });
  s.At(10, [&] { log.push_back("second@10"); });
  s.RunUntilIdle();
  const std::vector<std::string> want = {"first@10", "second@10", "same-time@10", "past@10",
                                         "later@15"};
  EXPECT_EQ(log, want);
}

TEST(SchedulerTest, RunUntilRunsDueEventsIncludingNewOnesThenSetsNow) {
  Scheduler s;
  std::vector<TimeNs> times;
  s.At(10, [&] {
    times.push_back(s.Now());
    s.At(50, [&] { times.push_back(s.Now()); });   // due before 100: runs
    s.At(150, [&] { times.push_back(s.Now()); });  // after 100: waits
  });
  s.At(100, [&] { times.push_back(s.Now()); });  // exactly t: runs
  s.RunUntil(100);
  EXPECT_EQ(times, (std::vector<TimeNs>{10, 50, 100}));
  EXPECT_EQ(s.Now(), 100);
  EXPECT_EQ(s.NextEventTime(), 150);
  s.RunUntil(40);  // backwards: no change
  EXPECT_EQ(s.Now(), 100);
  s.RunUntil(200);
  EXPECT_EQ(times.back(), 150);
  EXPECT_EQ(s.Now(), 200);
}

TEST(SchedulerTest, RunUntilIdleHonoursMaxEvents) {
  Scheduler s;
  int n = 0;
  std::function<void()> tick = [&] {
    ++n;
    s.After(1, tick);
  };
  s.After(1, tick);
  EXPECT_EQ(s.RunUntilIdle(1000), 1000u);
  EXPECT_EQ(n, 1000);
  EXPECT_EQ(s.Now(), 1000);
}

TEST(SchedulerTest, NestedRunCallsAreRefused) {
  Scheduler s;
  bool nested_ran = false;
  s.At(1, [&] {
    s.At(2, [&] { nested_ran = true; });
    EXPECT_FALSE(s.RunNext());
    s.RunUntil(10);
    EXPECT_EQ(s.RunUntilIdle(), 0u);
    EXPECT_EQ(s.Now(), 1);
  });
  s.RunNext();
  EXPECT_FALSE(nested_ran);
  s.RunNext();
  EXPECT_TRUE(nested_ran);
}

TEST(SchedulerTest, LargeAndMoveOnlyClosuresWork) {
  Scheduler s;
  std::array<int64_t, 32> big{};  // larger than the inline buffer
  big[31] = 7;
  int64_t got = 0;
  auto owned = std::make_unique<int>(5);
  s.At(1, [big, &got] { got += big[31]; });
  s.At(2, [p = std::move(owned), &got] { got += *p; });
  s.RunUntilIdle();
  EXPECT_EQ(got, 12);
}

TEST(SchedulerTest, CancelledClosuresAreDestroyed) {
  Scheduler s;
  auto token = std::make_shared<int>(0);
  const auto id = s.At(5, [token] {});
  EXPECT_EQ(token.use_count(), 2);
  s.Cancel(id);
  EXPECT_EQ(token.use_count(), 1);
}

TEST(SchedulerTest, ManyCancellationsKeepOrderThroughCompaction) {
  Scheduler s;
  std::vector<Scheduler::TimerId> ids;
  std::vector<std::pair<TimeNs, int>> ran;
  uint32_t rng = 12345;
  auto next = [&rng] {
    rng = rng * 1664525u + 1013904223u;
    return rng >> 8;
  };
  std::vector<std::pair<TimeNs, int>> want;
  for (int i = 0; i < 5000; ++i) {
    const TimeNs t = next() % 1000;
    ids.push_back(s.At(t, [&ran, &s, i] { ran.push_back({s.Now(), i}); }));
    if (i % 10 == 3) want.push_back({t, i});
  }
  for (int i = 0; i < 5000; ++i) {
    if (i % 10 != 3) {
      EXPECT_TRUE(s.Cancel(ids[static_cast<size_t>(i)]));
    }
  }
  EXPECT_EQ(s.PendingCount(), want.size());
  std::stable_sort(want.begin(), want.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  s.RunUntilIdle();
  EXPECT_EQ(ran, want);
}

// Law: whatever the mix of schedules and cancels, the events that run are
// exactly the non-cancelled ones, in (time, insertion) order, each at its time.
RC_GTEST_PROP(SchedulerProp, RunsSurvivorsInTimeSequenceOrder,
              (const std::vector<std::pair<uint16_t, bool>>& ops)) {
  Scheduler s;
  struct Rec {
    TimeNs time;
    size_t index;
  };
  std::vector<Rec> expected;
  std::vector<std::pair<TimeNs, size_t>> ran;
  for (size_t i = 0; i < ops.size(); ++i) {
    const TimeNs t = ops[i].first % 64;
    const auto id = s.At(t, [&ran, &s, i] { ran.push_back({s.Now(), i}); });
    if (ops[i].second) {
      RC_ASSERT(s.Cancel(id));
    } else {
      expected.push_back({t, i});
    }
  }
  RC_ASSERT(s.PendingCount() == expected.size());
  std::stable_sort(expected.begin(), expected.end(),
                   [](const Rec& a, const Rec& b) { return a.time < b.time; });
  if (!expected.empty()) RC_ASSERT(s.NextEventTime() == expected.front().time);
  s.RunUntilIdle();
  RC_ASSERT(ran.size() == expected.size());
  for (size_t k = 0; k < ran.size(); ++k) {
    RC_ASSERT(ran[k].first == expected[k].time);
    RC_ASSERT(ran[k].second == expected[k].index);
  }
}

// Law: splitting a run into RunUntil steps of any size gives the same order
// as one virtual-time run (the real-time driver's determinism).
RC_GTEST_PROP(SchedulerProp, RunUntilChunkingDoesNotChangeOrder,
              (const std::vector<uint16_t>& times, const std::vector<uint8_t>& steps)) {
  auto run = [&](bool chunked) {
    Scheduler s;
    std::vector<std::pair<TimeNs, size_t>> log;
    for (size_t i = 0; i < times.size(); ++i) {
      s.At(times[i] % 500, [&log, &s, i] {
        log.push_back({s.Now(), i});
        if (i % 3 == 0)
          s.After(static_cast<TimeNs>(i % 7), [&log, &s, i] {
            log.push_back({s.Now(), 100000 + i});
          });
      });
    }
    if (chunked) {
      TimeNs t = 0;
      size_t k = 0;
      while (s.NextEventTime().has_value()) {
        t += 1 + (steps.empty() ? 0 : steps[k++ % steps.size()]);
        s.RunUntil(t);
      }
    } else {
      s.RunUntilIdle();
    }
    return log;
  };
  RC_ASSERT(run(true) == run(false));
}

// Law: a bounded RunUntil (the real-time driver's catch-up slices) runs the
// same events in the same order at the same times as an unbounded one, in
// however small slices, and ends at the same Now().
RC_GTEST_PROP(SchedulerProp, BoundedRunUntilSlicesDoNotChangeOrderOrTime,
              (const std::vector<uint16_t>& times, const std::vector<uint8_t>& bounds)) {
  const auto until = static_cast<TimeNs>(*rc::gen::inRange(0, 600));
  auto run = [&](bool sliced) {
    Scheduler s;
    std::vector<std::pair<TimeNs, size_t>> log;
    for (size_t i = 0; i < times.size(); ++i) {
      s.At(times[i] % 500, [&log, &s, i] {
        log.push_back({s.Now(), i});
        if (i % 2 == 0) {
          s.After(static_cast<TimeNs>(i % 5), [&log, &s, i] {
            log.push_back({s.Now(), 100000 + i});
          });
        }
      });
    }
    if (sliced) {
      size_t k = 0;
      size_t slices = 0;
      while (!s.RunUntil(until, bounds.empty() ? 1 : 1 + bounds[k++ % bounds.size()] % 8)) {
        RC_ASSERT(s.Now() <= until);
        ++slices;
        RC_ASSERT(slices <= 4 * times.size() + 4);
      }
    } else {
      s.RunUntil(until);
    }
    log.push_back({s.Now(), SIZE_MAX});
    return log;
  };
  RC_ASSERT(run(true) == run(false));
}

TEST(SchedulerTest, BoundedRunUntilStopsAtTheBoundAndResumes) {
  Scheduler s;
  std::vector<int> ran;
  for (int i = 0; i < 5; ++i) s.At(10 * i, [&ran, i] { ran.push_back(i); });
  EXPECT_FALSE(s.RunUntil(100, 2));
  EXPECT_EQ(ran, (std::vector<int>{0, 1}));
  EXPECT_EQ(s.Now(), 10);  // the last event run, not the target
  EXPECT_FALSE(s.RunUntil(100, 2));
  EXPECT_TRUE(s.RunUntil(100, 2));
  EXPECT_EQ(ran, (std::vector<int>{0, 1, 2, 3, 4}));
  EXPECT_EQ(s.Now(), 100);
  EXPECT_TRUE(s.RunUntil(50, 0));  // nothing due: done, time does not go back
  EXPECT_EQ(s.Now(), 100);
}

}  // namespace
}  // namespace moco::sim
