// The link every protocol's host drives (core/host_link.h), against a scripted
// target: what it writes and reads is kept in order with its times, reads stop
// at their deadline, and a lost link ends every wait at once.
#include "conformance/core/host_link.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <deque>
#include <string>
#include <utility>
#include <vector>

#include "conformance/core/transcript.h"

namespace moco::conformance {
namespace {

// A target on a virtual clock that answers each write with scripted bytes
// after a delay, and can lose the link.
class ScriptedTarget final : public Target {
 public:
  std::string Name() const override { return "scripted"; }
  bool VirtualClock() const override { return true; }
  bool CanRestart() const override { return false; }
  std::optional<std::string> Open() override { return std::nullopt; }
  void Restart() override {}
  TimeNs Now() const override { return now_; }
  bool Send(wire::ByteView bytes) override {
    if (lost_) return false;
    written.emplace_back(bytes.begin(), bytes.end());
    if (!answers.empty()) {
      pending_.push_back({now_ + answer_delay_ns, answers.front()});
      answers.pop_front();
    }
    return true;
  }
  bool Receive(TimeNs deadline_ns, wire::Bytes& out) override {
    if (lose_at_ns >= 0 && deadline_ns >= lose_at_ns) {
      now_ = std::max(now_, lose_at_ns);
      lost_ = true;
    }
    if (lost_) return false;
    if (!pending_.empty() && pending_.front().first <= deadline_ns) {
      now_ = std::max(now_, pending_.front().first);
      const wire::Bytes& b = pending_.front().second;
      out.insert(out.end(), b.begin(), b.end());
      pending_.pop_front();
      return true;
    }
    now_ = std::max(now_, deadline_ns);
    return true;
  }

  std::deque<wire::Bytes> answers;  // one per write, in order
  TimeNs answer_delay_ns = 0;
  TimeNs lose_at_ns = -1;  // the link goes at this time (-1: never)
  std::vector<wire::Bytes> written;

 private:
  TimeNs now_ = 0;
  bool lost_ = false;
  std::deque<std::pair<TimeNs, wire::Bytes>> pending_;
};

wire::Bytes B(std::string_view s) { return wire::Bytes(s.begin(), s.end()); }

TEST(HostLink, AWriteReadsWhatTheDeviceWroteAtOnceAndKeepsBothInTheTraffic) {
  ScriptedTarget t;
  t.answers = {B("ok\r\n")};
  std::string seen;
  HostLink link(t, [&](wire::ByteView b) { seen.append(b.begin(), b.end()); });
  link.Write(B("hi\r\n"));
  EXPECT_EQ(seen, "ok\r\n");
  ASSERT_EQ(link.traffic().size(), 2u);
  EXPECT_TRUE(link.traffic()[0].from_host);
  EXPECT_EQ(link.traffic()[0].bytes, B("hi\r\n"));
  EXPECT_FALSE(link.traffic()[1].from_host);
  EXPECT_EQ(link.traffic()[1].bytes, B("ok\r\n"));
}

TEST(HostLink, WriteWithoutReadingLeavesTheAnswerUnread) {
  ScriptedTarget t;
  t.answers = {B("x")};
  int reads = 0;
  HostLink link(t, [&](wire::ByteView) { ++reads; });
  link.WriteWithoutReading(B("a"));
  EXPECT_EQ(reads, 0);
  link.Pump(0);
  EXPECT_EQ(reads, 1);
}

TEST(HostLink, BytewiseWritesOneChunkPerByte) {
  ScriptedTarget t;
  HostLink link(t, [](wire::ByteView) {});
  link.WriteBytewise(B("abc"));
  ASSERT_EQ(t.written.size(), 3u);
  EXPECT_EQ(link.traffic().size(), 3u);
  EXPECT_EQ(t.written[2], B("c"));
}

TEST(HostLink, ReadUntilStopsAtItsDeadlineWhenNothingComes) {
  ScriptedTarget t;
  HostLink link(t, [](wire::ByteView) {});
  EXPECT_FALSE(link.ReadUntil(500, [] { return false; }));
  EXPECT_EQ(link.Now(), 500);
  EXPECT_FALSE(link.lost());
}

TEST(HostLink, ReadUntilReturnsWhenTheAnswerArrivesBeforeTheDeadline) {
  ScriptedTarget t;
  t.answers = {B("late")};
  t.answer_delay_ns = 300;
  bool got = false;
  HostLink link(t, [&](wire::ByteView) { got = true; });
  link.Write(B("q"));
  EXPECT_FALSE(got);  // not yet: it comes 300 ns later
  EXPECT_TRUE(link.ReadUntil(1000, [&] { return got; }));
  EXPECT_EQ(link.Now(), 300);
}

TEST(HostLink, WaitForFindsTheFirstMatchingItemFromAnIndex) {
  ScriptedTarget t;
  t.answers = {B("3")};
  t.answer_delay_ns = 50;
  std::vector<int> items = {1, 2};
  HostLink link(t, [&](wire::ByteView b) { items.push_back(b[0] - '0'); });
  EXPECT_EQ(link.WaitFor(items, 0, 10, [](int v) { return v == 2; }), 1);
  EXPECT_EQ(link.WaitFor(items, 2, 10, [](int v) { return v == 2; }), -1);  // none from 2 on
  link.WriteWithoutReading(B("x"));
  EXPECT_EQ(link.WaitFor(items, 2, 1000, [](int v) { return v == 3; }), 2);
}

TEST(HostLink, ALostLinkEndsEveryWaitAtOnce) {
  ScriptedTarget t;
  t.lose_at_ns = 100;
  HostLink link(t, [](wire::ByteView) {});
  EXPECT_FALSE(link.ReadUntil(10'000, [] { return false; }));
  EXPECT_TRUE(link.lost());
  EXPECT_EQ(link.Now(), 100);  // not the deadline
  link.Idle(10'000);
  EXPECT_EQ(link.Now(), 100);
  link.Write(B("after"));  // a write on a lost link is kept but changes nothing
  EXPECT_TRUE(link.lost());
  EXPECT_EQ(link.WaitFor(std::vector<int>{}, 0, 10'000, [](int) { return true; }), -1);
}

TEST(Transcript, EveryProtocolDescribesTheTrafficOneMessageALine) {
  std::vector<Chunk> traffic = {{1'000'000, true, B("hi\r\n")},
                                {2'500'000, false, B("hi 1 4 2.0.0\r\n")}};
  const std::string text = Transcript(wire::Protocol::kDfmoco, traffic);
  EXPECT_NE(text.find("     1.000 ms  host   > "), std::string::npos) << text;
  EXPECT_NE(text.find("     2.500 ms  device < "), std::string::npos) << text;
  EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 2);
  const auto lines = DecodeTraffic(wire::Protocol::kDfmoco, {{0, false, B("mp 1")}});
  ASSERT_EQ(lines.size(), 1u);  // an unterminated line is a problem at the end
  EXPECT_TRUE(lines[0].problem);
}

}  // namespace
}  // namespace moco::conformance
