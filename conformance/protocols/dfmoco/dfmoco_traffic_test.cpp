// Recorded DFMoco traffic read back with the codec (dfmoco_traffic.cpp): the
// position events the pin rules judge, and the reported positions.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "conformance/protocols/dfmoco/dfmoco_protocol.h"

namespace moco::conformance {
namespace {

using Kind = PinPositionEvent::Kind;

Chunk Line(sim::TimeNs t, bool from_host, std::string_view text) {
  return {t, from_host, wire::Bytes(text.begin(), text.end())};
}

TEST(DfmocoTraffic, LinesBecomeReportsResetsAndPulseRates) {
  const std::vector<Chunk> traffic = {Line(0, true, "np 1 7\r\n"), Line(10, false, "mp 1 7\r\n"),
                                      Line(20, false, "mp 1 9\r\n"),
                                      Line(30, false, "pr 2 99\r\n")};
  const auto e = DfmocoProtocol::PinEvents(traffic);
  ASSERT_EQ(e.size(), 3u);
  EXPECT_EQ(e[0].kind, Kind::kReset);  // the sketch answers np with mp
  EXPECT_EQ(e[0].t_ns, 10);
  EXPECT_EQ(e[1].kind, Kind::kReport);
  EXPECT_EQ(e[1].position, 9);
  EXPECT_EQ(e[2].kind, Kind::kPulseRate);
  EXPECT_EQ(e[2].motor, 2);
  EXPECT_EQ(e[2].position, 99);
}

TEST(DfmocoTraffic, ZeroAndNewPositionAnswersAreResets) {
  const std::vector<Chunk> traffic = {
      Line(0, true, "zm 2\r\n"), Line(5, false, "zm 2\r\n"),     // the protocol's own answer
      Line(6, true, "mp 3\r\n"), Line(8, false, "mp 3 40\r\n"),  // nothing asked: a report
      Line(9, false, "np 1 -5\r\n")};
  const auto e = DfmocoProtocol::PinEvents(traffic);
  ASSERT_EQ(e.size(), 3u);
  EXPECT_EQ(e[0].kind, Kind::kReset);
  EXPECT_EQ(e[0].motor, 2);
  EXPECT_EQ(e[0].position, 0);
  EXPECT_EQ(e[1].kind, Kind::kReport);
  EXPECT_EQ(e[1].motor, 3);
  EXPECT_EQ(e[2].kind, Kind::kReset);
  EXPECT_EQ(e[2].position, -5);
}

// Several resets for one motor in one write, a garbled line between them:
// the real sketch answers `mp 1 1`, `parse error`, `mp 1 4000`, and both
// answers are resets (a parse error answers the garbled line, not an np).
TEST(DfmocoTraffic, ResetsAskedInOneWriteAreMatchedInOrderPastAParseError) {
  const std::vector<Chunk> traffic = {
      Line(0, true, "np 1 1\r\nnp 1 x\r\nnp 1 4000\r\nzm 2\r\nmp 1\r\n"),
      Line(10, false, "mp 1 1\r\n"),
      Line(11, false, "parse error\r\n"),
      Line(12, false, "mp 1 4000\r\n"),
      Line(13, false, "mp 1 4000\r\n"),  // the answer to `mp 1`: a report
      Line(14, false, "mp 2 0\r\n")};    // the sketch answers zm later, with mp
  const auto e = DfmocoProtocol::PinEvents(traffic);
  ASSERT_EQ(e.size(), 4u);
  EXPECT_EQ(e[0].kind, Kind::kReset);
  EXPECT_EQ(e[0].position, 1);
  EXPECT_EQ(e[1].kind, Kind::kReset);
  EXPECT_EQ(e[1].position, 4000);
  EXPECT_EQ(e[2].kind, Kind::kReport) << "each reset asked for is answered once";
  EXPECT_EQ(e[3].kind, Kind::kReset);
  EXPECT_EQ(e[3].motor, 2);
}

// An answer to a later reset gives up the earlier ones for that motor (the
// device answers in order): a report equal to one of them is a report.
TEST(DfmocoTraffic, AnAnswerGivesUpTheResetsAskedBeforeIt) {
  const std::vector<Chunk> traffic = {Line(0, true, "np 1 5\r\nnp 1 9\r\n"),
                                      Line(10, false, "mp 1 9\r\n"), Line(20, false, "mp 1 5\r\n")};
  const auto e = DfmocoProtocol::PinEvents(traffic);
  ASSERT_EQ(e.size(), 2u);
  EXPECT_EQ(e[0].kind, Kind::kReset);
  EXPECT_EQ(e[1].kind, Kind::kReport);
}

// Lines are framed as the codec frames them, whatever the chunking and the
// line end; a line the codec does not read as a reply is no event.
TEST(DfmocoTraffic, LinesSplitAcrossChunksAndEitherLineEndAreRead) {
  const std::vector<Chunk> traffic = {Line(0, false, "mp 1 1"), Line(4, false, "23\nmp 2 5\r"),
                                      Line(9, false, "mp 2 6 junk\r\nmp 99 1\r\nmp 4 -8\r\n")};
  const PositionSeries s = DfmocoProtocol::Positions(traffic);
  ASSERT_EQ(s.count(1), 1u);
  ASSERT_EQ(s.at(1).size(), 1u);
  EXPECT_EQ(s.at(1)[0], (std::pair<sim::TimeNs, int64_t>{4, 123}));
  ASSERT_EQ(s.count(2), 1u);
  EXPECT_EQ(s.at(2).size(), 1u) << "the line with a third argument is no position reply";
  EXPECT_EQ(s.count(99), 0u) << "beyond any board's motors";
  ASSERT_EQ(s.count(4), 1u);
  EXPECT_EQ(s.at(4)[0].second, -8);
  EXPECT_EQ(DfmocoProtocol::PinEvents(traffic).size(), 3u);
}

}  // namespace
}  // namespace moco::conformance
