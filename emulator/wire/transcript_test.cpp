// Tests for the transcript decoder: each protocol's traffic framed per
// direction, described, and problems (checksum, parse, leftovers) flagged.
#include "wire/transcript.h"

#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>

#include <string>

#include "wire/dfmoco.h"
#include "wire/dmc.h"
#include "wire/stackshot.h"

namespace moco::wire {
namespace {

ByteView View(std::string_view s) { return {reinterpret_cast<const uint8_t*>(s.data()), s.size()}; }

TEST(TranscriptTest, ProtocolNamesRoundTrip) {
  for (Protocol p :
       {Protocol::kDmc, Protocol::kDfmoco, Protocol::kStackshot, Protocol::kStackshotDfmoco}) {
    EXPECT_EQ(ParseProtocol(ProtocolName(p)), p);
  }
  EXPECT_FALSE(ParseProtocol("dmc2").has_value());
}

TEST(TranscriptTest, DmcFramesAreDescribedPerDirectionAndChecksumFailuresFlagged) {
  TranscriptDecoder d(Protocol::kDmc);
  Bytes hi;
  dmc::Encode(7, dmc::HostMessage{dmc::HiRequest{}}, hi);
  auto lines = d.Feed(Side::kHost, hi);
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_FALSE(lines[0].problem);
  EXPECT_EQ(lines[0].from, Side::kHost);
  EXPECT_EQ(lines[0].text.rfind("#7 ", 0), 0u) << lines[0].text;
  EXPECT_NE(lines[0].text.find("HI"), std::string::npos) << lines[0].text;

  Bytes bad = hi;
  bad[6] ^= 0x01;  // the Type field: the checksum no longer verifies
  lines = d.Feed(Side::kHost, bad);
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_TRUE(lines[0].problem);
  EXPECT_NE(lines[0].text.find("BAD CHECKSUM"), std::string::npos) << lines[0].text;
}

// A session with a device whose receive buffer is larger than the spec's 1048
// (FACTS: dmc-lite, 2048) and which sends positions under ID 0: the transcript
// (`mocosim decode`) reads with the spec's buffer, flags the 2048-byte frame,
// finds the next one, and describes the ID-0 message like any other.
TEST(TranscriptTest, DmcTranscriptCopesWithA2048ByteFrameAndIdZeroPositions) {
  TranscriptDecoder d(Protocol::kDmc);
  Bytes host;
  dmc::EncodeFrame(9, 0x0101, Bytes(2036, 0x11), host);
  dmc::Encode(10, dmc::HostMessage{dmc::MotorGetPositionRequest{}}, host);
  auto lines = d.Feed(Side::kHost, host);
  ASSERT_GE(lines.size(), 2u);
  EXPECT_TRUE(lines[0].problem);
  EXPECT_NE(lines[0].text.find("2036"), std::string::npos) << lines[0].text;
  EXPECT_EQ(lines.back().text.rfind("#10 MOTOR_GET_POSITION", 0), 0u) << lines.back().text;
  Bytes device;
  dmc::Encode(0, dmc::DeviceMessage{dmc::MotorPositionReport{0, {5, -6}}}, device);
  dmc::Encode(10, dmc::DeviceMessage{dmc::Ack{0x0034, dmc::ToWire(dmc::AckCode::kOk)}}, device);
  lines = d.Feed(Side::kDevice, device);
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_FALSE(lines[0].problem);
  EXPECT_EQ(lines[0].text.rfind("#0 MOTOR_GET_POSITION", 0), 0u) << lines[0].text;
  EXPECT_EQ(lines[1].text.rfind("#10 ACK MOTOR_GET_POSITION", 0), 0u) << lines[1].text;
  d.Finish();
}

TEST(TranscriptTest, DfmocoLearnsDialectFromHiAndFlagsUnterminatedLine) {
  TranscriptDecoder d(Protocol::kDfmoco);
  auto lines = d.Feed(Side::kDevice, View("hi 1 4 1.3.0\r\n"));
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_FALSE(lines[0].problem);
  // Protocol 1 has no jm velocity: a third argument is a parse problem.
  lines = d.Feed(Side::kHost, View("jm 1 100 5000\r\n"));
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_TRUE(lines[0].problem) << lines[0].text;
  lines = d.Feed(Side::kHost, View("mm 1 25"));
  EXPECT_TRUE(lines.empty());
  lines = d.Finish();
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_TRUE(lines[0].problem);
  EXPECT_EQ(lines[0].from, Side::kHost);
}

// What a device sends reaches the terminal as text: an ESC sequence, a NUL
// or a byte above ASCII in a reply is written as \xNN, and the rest of the
// line after it is kept.
TEST(TranscriptTest, DeviceBytesThatAreNotPrintableAreEscaped) {
  TranscriptDecoder d(Protocol::kDfmoco);
  d.Feed(Side::kDevice, View("hi 2 4 2.0.0\r\n"));
  static constexpr char kReply[] = "ms \x1b[2J\0tail\xff\r\n";
  const std::string reply(kReply, sizeof kReply - 1);  // the NUL inside kept
  std::vector<TranscriptLine> lines = d.Feed(Side::kDevice, View(reply));
  ASSERT_FALSE(lines.empty());
  std::string all;
  for (const TranscriptLine& l : lines) {
    all += l.text + "\n";
    for (const char c : l.text) {
      const auto u = static_cast<unsigned char>(c);
      EXPECT_TRUE(u >= 0x20 && u < 0x7f) << "byte " << int{u} << " in " << l.text;
    }
  }
  EXPECT_NE(all.find("\\x1b[2J"), std::string::npos) << all;
  EXPECT_NE(all.find("\\x00tail\\xff"), std::string::npos) << all;
}

// Any bytes either way give printable lines, whatever the protocol.
RC_GTEST_PROP(TranscriptTest, EveryLineIsPrintableAscii,
              (const std::vector<uint8_t>& bytes, bool host)) {
  for (const Protocol p : {Protocol::kDmc, Protocol::kDfmoco, Protocol::kStackshot}) {
    TranscriptDecoder d(p);
    std::vector<TranscriptLine> lines = d.Feed(host ? Side::kHost : Side::kDevice, bytes);
    for (TranscriptLine& l : d.Finish()) lines.push_back(std::move(l));
    for (const TranscriptLine& l : lines) {
      for (const char c : l.text) {
        const auto u = static_cast<unsigned char>(c);
        RC_ASSERT(u >= 0x20 && u < 0x7f);
      }
    }
  }
}

TEST(TranscriptTest, StackshotReplyReadAsAnswerToLastHostAction) {
  TranscriptDecoder d(Protocol::kStackshot);
  // Spec section 2 example: read current position, X axis (checksum byte as hosts send it).
  auto lines = d.Feed(Side::kHost, *FromHex("55 10 02 00 00 69"));
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_FALSE(lines[0].problem);
  EXPECT_NE(lines[0].text.find("CC_RAIL_POSITION_CURRENT"), std::string::npos) << lines[0].text;
}

// Junk after the last packet with no sync byte in it is a problem, as DMC's
// stray bytes are: 36 bytes of it are reported at the end, either way.
TEST(TranscriptTest, StackshotJunkAfterTheLastPacketIsReported) {
  for (const Side side : {Side::kHost, Side::kDevice}) {
    TranscriptDecoder d(Protocol::kStackshot);
    auto lines = d.Feed(Side::kHost, *FromHex("55 10 02 00 00 69"));
    ASSERT_EQ(lines.size(), 1u);
    EXPECT_TRUE(d.Feed(side, Bytes(36, 0x11)).empty());
    lines = d.Finish();
    ASSERT_EQ(lines.size(), 1u);
    EXPECT_TRUE(lines[0].problem);
    EXPECT_EQ(lines[0].from, side);
    EXPECT_NE(lines[0].text.find("skipped 36 byte(s) at the end"), std::string::npos)
        << lines[0].text;
  }
  // A partial packet at the end is reported as such, not as junk too.
  TranscriptDecoder d(Protocol::kStackshot);
  d.Feed(Side::kHost, *FromHex("55 10 02"));
  const auto lines = d.Finish();
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_NE(lines[0].text.find("3 byte(s) of an incomplete packet"), std::string::npos);
}

// A StackShot acknowledging CC_RAIL_CONFIG_GLOBAL_MODE = DfMoco speaks
// DFMoco from the byte after the acknowledgement (section 3): the transcript
// follows the line, whether the first DFMoco bytes share a chunk with the
// acknowledgement or not; a refused switch changes nothing.
TEST(TranscriptTest, StackshotFollowsTheLineIntoDfmocoMode) {
  stackshot::HostCommand c;
  c.command = static_cast<uint16_t>(stackshot::Command::kRailConfigGlobalMode);
  c.action = stackshot::Action::kWrite;
  c.payload = stackshot::EnumValue<stackshot::GlobalMode>{stackshot::GlobalMode::kMotionDfMoco};
  Bytes write;
  ASSERT_TRUE(stackshot::EncodeHostCommand(c, write));
  auto answer = [](stackshot::Action status) {
    stackshot::DeviceReply r;
    r.command = static_cast<uint16_t>(stackshot::Command::kRailConfigGlobalMode);
    r.status = status;
    r.kind = status == stackshot::Action::kRspOk ? stackshot::ReplyKind::kWriteAck
                                                 : stackshot::ReplyKind::kError;
    r.payload = stackshot::Empty{};
    Bytes out;
    EXPECT_TRUE(stackshot::EncodeDeviceReply(r, out));
    return out;
  };
  for (const bool same_chunk : {false, true}) {
    TranscriptDecoder d(Protocol::kStackshot);
    std::vector<TranscriptLine> all = d.Feed(Side::kHost, write);
    Bytes ack = answer(stackshot::Action::kRspOk);
    const std::string hello = "hi 2 1 1.2.6\r\n";
    if (same_chunk) ack.insert(ack.end(), hello.begin(), hello.end());
    for (auto& l : d.Feed(Side::kDevice, ack)) all.push_back(l);
    for (const char* text : {"hi\r\n", "ms\r\n", "mm 1 100\r\n"}) {
      for (auto& l : d.Feed(Side::kHost, View(text))) all.push_back(l);
    }
    if (!same_chunk) {
      for (auto& l : d.Feed(Side::kDevice, View(hello))) all.push_back(l);
    }
    for (auto& l : d.Feed(Side::kDevice, View("ms 0\r\nmm 1 100\r\n"))) all.push_back(l);
    for (auto& l : d.Finish()) all.push_back(l);
    std::string text;
    size_t problems = 0;
    for (const TranscriptLine& l : all) {
      text += l.text + "\n";
      problems += l.problem;
    }
    EXPECT_EQ(problems, 0u) << text;
    EXPECT_NE(text.find("switches to DfMoco mode"), std::string::npos) << text;
    // 3 host commands and 3 device lines, each its own transcript line.
    EXPECT_EQ(all.size(), 2u + 1u + 6u) << text;
  }
  // Refused: the text after it is no StackShot packet, and says so.
  TranscriptDecoder d(Protocol::kStackshot);
  d.Feed(Side::kHost, write);
  d.Feed(Side::kDevice, answer(stackshot::Action::kBadParam));
  d.Feed(Side::kHost, View("hi\r\n"));
  size_t problems = 0;
  for (const TranscriptLine& l : d.Finish()) problems += l.problem;
  EXPECT_EQ(problems, 1u);
}

// Idle line (docs/protocol-notes.md): a request whose Length was damaged
// hides the frames behind it only until its side's line is idle for 50 ms;
// the next chunk from that side gives it up and rescans its bytes, as the
// DMC-16 does. The other side's chunks change nothing.
// A switch the traffic does not show (a StackShot set to DfMoco mode on its
// panel): the caller says so, as `mocosim decode` does at a recorded
// "line_switch"; what the old protocol's decoders held is reported at the end.
TEST(TranscriptTest, SwitchToFollowsASwitchTheTrafficDoesNotShow) {
  TranscriptDecoder d(Protocol::kStackshot);
  EXPECT_EQ(d.protocol(), Protocol::kStackshot);
  std::vector<TranscriptLine> all = d.Feed(Side::kHost, Bytes{0x55, 0x10});  // a packet cut short
  d.SwitchTo(Protocol::kStackshotDfmoco);
  d.SwitchTo(Protocol::kStackshotDfmoco);  // already: nothing changes
  EXPECT_EQ(d.protocol(), Protocol::kStackshotDfmoco);
  for (auto& l : d.Feed(Side::kHost, View("hi\r\n"))) all.push_back(l);
  for (auto& l : d.Feed(Side::kDevice, View("hi 1 3 1.2.6\r\n"))) all.push_back(l);
  for (auto& l : d.Finish()) all.push_back(l);
  std::string text;
  size_t problems = 0;
  for (const TranscriptLine& l : all) {
    text += l.text + "\n";
    problems += l.problem;
  }
  EXPECT_EQ(problems, 1u) << text;  // the two bytes of the packet cut short
  EXPECT_NE(text.find("incomplete packet"), std::string::npos) << text;
  EXPECT_EQ(text.find("skipped"), std::string::npos) << text;
  EXPECT_NE(text.find("hello: protocol 1, 3 motors"), std::string::npos) << text;
}

TEST(TranscriptTest, DmcPartialFrameIsGivenUpAtTheNextChunkAfterAnIdleGap) {
  TranscriptDecoder d(Protocol::kDmc);
  Bytes damaged;
  dmc::Encode(1, dmc::HostMessage{dmc::HiRequest{}}, damaged);
  damaged[dmc::kLengthOffset] = 100;  // waits for 100 data bytes
  Bytes behind;
  dmc::Encode(2, dmc::HostMessage{dmc::HiRequest{}}, behind);
  EXPECT_TRUE(d.Feed(Side::kHost, damaged, 0).empty());
  EXPECT_TRUE(d.Feed(Side::kHost, behind, 10'000'000).empty());
  EXPECT_TRUE(d.Feed(Side::kDevice, {}, 70'000'000).empty());
  Bytes next;
  dmc::Encode(3, dmc::HostMessage{dmc::HiRequest{}}, next);
  const auto lines = d.Feed(Side::kHost, next, 10'000'000 + dmc::kLineIdleGapNs);
  ASSERT_EQ(lines.size(), 4u);
  EXPECT_EQ(lines[0].text, "frame given up after 50 ms idle (24 byte(s) of it)");
  EXPECT_TRUE(lines[0].problem);
  EXPECT_EQ(lines[1].text, "skipped 12 byte(s) outside any frame");
  EXPECT_EQ(lines[2].text, "#2 HI");
  EXPECT_EQ(lines[3].text, "#3 HI");
}

TEST(TranscriptTest, DmcJunkIsReportedAtTheNextChunkAfterAnIdleGap) {
  TranscriptDecoder d(Protocol::kDmc);
  EXPECT_TRUE(d.Feed(Side::kDevice, View("junk junk"), 0).empty());
  EXPECT_TRUE(d.Feed(Side::kDevice, View("more"), dmc::kLineIdleGapNs - 1).empty());
  const auto lines = d.Feed(Side::kDevice, View("x"), 2 * dmc::kLineIdleGapNs);
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_EQ(lines[0].text, "skipped 13 byte(s) outside any frame");
}

RC_GTEST_PROP(TranscriptProp, DmcChunkingDoesNotChangeTranscript,
              (const std::vector<uint32_t>& ids, size_t chunk)) {
  Bytes stream;
  for (uint32_t id : ids) dmc::Encode(id, dmc::HostMessage{dmc::HiRequest{}}, stream);
  const size_t step = 1 + chunk % 17;
  TranscriptDecoder whole(Protocol::kDmc), pieces(Protocol::kDmc);
  auto a = whole.Feed(Side::kHost, stream);
  std::vector<TranscriptLine> b;
  for (size_t i = 0; i < stream.size(); i += step) {
    auto part =
        pieces.Feed(Side::kHost, ByteView(stream).subspan(i, std::min(step, stream.size() - i)));
    b.insert(b.end(), part.begin(), part.end());
  }
  RC_ASSERT(a.size() == ids.size());
  RC_ASSERT(b.size() == a.size());
  for (size_t i = 0; i < a.size(); ++i) RC_ASSERT(a[i].text == b[i].text);
}

}  // namespace
}  // namespace moco::wire
