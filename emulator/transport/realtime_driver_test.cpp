// Tests for the real-time driver of the one clock (ARCHITECTURE "One clock"):
// events run in order, sim time never runs ahead of the wall clock and never
// goes back, and Kick() re-arms after events are added from outside.
#include "transport/realtime_driver.h"

#include <gtest/gtest.h>

#include <csignal>
#include <vector>

#include "transport/test_support.h"

namespace moco::transport {
namespace {

using sim::kNsPerMs;
using sim::TimeNs;
using testing::RunUntil;

TimeNs WallNs(const RealtimeDriver& d) {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(RealtimeDriver::Clock::now() -
                                                              d.origin())
      .count();
}

TEST(RealtimeDriverTest, RunsEventsInOrderNeverAheadOfTheWallClock) {
  asio::io_context io;
  sim::Scheduler s;
  RealtimeDriver d(io, s);
  std::vector<TimeNs> seen;
  std::vector<int> order;
  bool ahead = false;
  for (int i = 0; i < 5; ++i) {
    s.At((5 - i) * 2 * kNsPerMs, [&, i] {
      order.push_back(i);
      seen.push_back(s.Now());
      if (s.Now() > WallNs(d)) ahead = true;
    });
  }
  d.Start();
  ASSERT_TRUE(RunUntil(io, [&] { return order.size() == 5; }));
  EXPECT_EQ(order, (std::vector<int>{4, 3, 2, 1, 0}));
  EXPECT_FALSE(ahead);
  for (size_t i = 0; i < seen.size(); ++i)
    EXPECT_EQ(seen[i], static_cast<TimeNs>(i + 1) * 2 * kNsPerMs);
}

TEST(RealtimeDriverTest, KickArmsForEventsAddedOutsideTheScheduler) {
  asio::io_context io;
  sim::Scheduler s;
  RealtimeDriver d(io, s);
  d.Start();
  bool ran = false;
  bool ahead = false;
  bool ran_in_kick = false;
  asio::post(io, [&] {
    d.Sync();  // sim time catches up with the wall clock, however late this runs
    s.After(20 * kNsPerMs, [&] {
      ran = true;
      ahead = s.Now() > WallNs(d);
    });
    d.Kick();
    // On a loaded machine 20 ms may pass before Kick: then Kick runs the due
    // event itself. Otherwise only the timer Kick armed can run it.
    ran_in_kick = ran;
  });
  ASSERT_TRUE(RunUntil(io, [&] { return ran; }));
  EXPECT_FALSE(ahead);
  if (!ran_in_kick) EXPECT_GE(d.wakeups(), 1u);
}

TEST(RealtimeDriverTest, EventsScheduledFromCallbacksRunWithoutKick) {
  asio::io_context io;
  sim::Scheduler s;
  RealtimeDriver d(io, s);
  int count = 0;
  std::function<void()> chain = [&] {
    ++count;
    d.Kick();  // harmless inside a callback
    if (count < 5) s.After(kNsPerMs, chain);
  };
  s.After(kNsPerMs, chain);
  d.Start();
  ASSERT_TRUE(RunUntil(io, [&] { return count == 5; }));
  EXPECT_EQ(s.PendingCount(), 0u);
}

TEST(RealtimeDriverTest, TimeIsMonotonicAndSyncCatchesUp) {
  asio::io_context io;
  sim::Scheduler s;
  RealtimeDriver d(io, s);
  d.Start();
  TimeNs prev = d.NowNs();
  for (int i = 0; i < 1000; ++i) {
    const TimeNs now = d.NowNs();
    ASSERT_GE(now, prev);
    ASSERT_GE(now, s.Now());
    prev = now;
  }
  const TimeNs before = d.NowNs();
  EXPECT_GE(d.Sync(), before);
  EXPECT_LE(s.Now(), WallNs(d));
}

TEST(RealtimeDriverTest, StartsAtTheSchedulersCurrentTime) {
  asio::io_context io;
  sim::Scheduler s;
  s.RunUntil(5 * sim::kNsPerSecond);  // advanced in virtual time first
  RealtimeDriver d(io, s);
  d.Start();
  EXPECT_GE(d.NowNs(), 5 * sim::kNsPerSecond);
  EXPECT_GE(WallNs(d), 5 * sim::kNsPerSecond);
  bool ran = false;
  s.After(kNsPerMs, [&] { ran = true; });
  d.Kick();
  ASSERT_TRUE(RunUntil(io, [&] { return ran; }));
}

TEST(RealtimeDriverTest, FarEventsStayPendingAndStopCancels) {
  asio::io_context io;
  sim::Scheduler s;
  RealtimeDriver d(io, s);
  bool far_ran = false;
  bool near_ran = false;
  s.After(3600 * sim::kNsPerSecond, [&] { far_ran = true; });
  s.After(kNsPerMs, [&] { near_ran = true; });
  d.Start();
  ASSERT_TRUE(RunUntil(io, [&] { return near_ran; }));
  EXPECT_FALSE(far_ran);
  EXPECT_EQ(s.PendingCount(), 1u);
  d.Stop();
  EXPECT_FALSE(d.running());
  // With the timer cancelled the io_context runs out of work.
  io.restart();
  io.run_for(std::chrono::milliseconds(50));
  EXPECT_TRUE(io.stopped());
  EXPECT_FALSE(far_ran);
}

// A scheduler far behind the wall clock (a scenario of hundreds of 1 ms
// events, a stalled machine) runs its backlog in bounded slices: a signal
// raised before the backlog starts is handled while most of it is still due,
// not after it, and the backlog still runs whole and in order.
TEST(RealtimeDriverTest, ABacklogOfDueEventsYieldsToSignalsBetweenSlices) {
  asio::io_context io;
  sim::Scheduler s;
  RealtimeDriver d(io, s);
  constexpr int kEvents = 100'000;
  std::vector<int> order;
  order.reserve(kEvents);
  for (int i = 0; i < kEvents; ++i) s.At(0, [&order, i] { order.push_back(i); });
  asio::signal_set signals(io, SIGUSR1);
  size_t ran_at_signal = SIZE_MAX;
  signals.async_wait([&](const ErrorCode& ec, int) {
    if (!ec) ran_at_signal = order.size();
  });
  ASSERT_EQ(::raise(SIGUSR1), 0);
  d.Start();
  EXPECT_LE(order.size(), RealtimeDriver::kMaxSliceEvents) << "Start ran past one slice";
  ASSERT_TRUE(RunUntil(
      io, [&] { return order.size() == kEvents && ran_at_signal != SIZE_MAX; },
      std::chrono::milliseconds(30000)));
  EXPECT_LT(ran_at_signal, static_cast<size_t>(kEvents / 2)) << "the signal waited for the backlog";
  EXPECT_GT(d.catch_up_slices(), 0u);
  for (int i = 0; i < kEvents; ++i) ASSERT_EQ(order[static_cast<size_t>(i)], i);
}

}  // namespace
}  // namespace moco::transport
