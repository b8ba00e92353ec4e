// The protocol table (wire/protocol.h): names, line settings, message cutting
// and repair, greetings, checked against each protocol's own codec.
#include "wire/protocol.h"

#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>

#include "wire/dfmoco.h"
#include "wire/dmc.h"
#include "wire/dmc_constants.h"
#include "wire/dmc_frame.h"
#include "wire/stackshot.h"
#include "wire/stackshot_constants.h"

namespace moco::wire {
namespace {

TEST(ProtocolTable, RowsAreInTheEnumsOrderAndNamesRoundTrip) {
  ASSERT_EQ(Protocols().size(), 4u);
  for (size_t i = 0; i < Protocols().size(); ++i) {
    const ProtocolInfo& row = Protocols()[i];
    EXPECT_EQ(static_cast<size_t>(row.id), i);
    EXPECT_EQ(ParseProtocol(row.name), row.id);
    EXPECT_EQ(ParseProtocolOrAlias(row.name), row.id);
    if (!row.alias.empty()) {
      EXPECT_EQ(ParseProtocolOrAlias(row.alias), row.id);
      // Session files name a protocol exactly; aliases are for command lines.
      EXPECT_EQ(ParseProtocol(row.alias), std::nullopt);
    }
  }
  EXPECT_EQ(ParseProtocolOrAlias("dmc2"), Protocol::kDmc);
  EXPECT_EQ(ParseProtocolOrAlias("stackshot3x"), Protocol::kStackshot);
  EXPECT_EQ(ParseProtocol("DMC"), std::nullopt);
  EXPECT_EQ(ParseProtocolOrAlias(""), std::nullopt);
}

TEST(ProtocolTable, DefaultLinesAreTheDevicesOwn) {
  // DMC-16 115200; the DFMoco sketch's Serial.begin(57600); StackShot 38400,
  // 57600 once in DfMoco mode (ERRATA stackshot).
  EXPECT_EQ(Info(Protocol::kDmc).line.baud, 115200u);
  EXPECT_EQ(Info(Protocol::kDfmoco).line.baud, 57600u);
  EXPECT_EQ(Info(Protocol::kStackshot).line.baud, 38400u);
  EXPECT_EQ(Info(Protocol::kStackshotDfmoco).line.baud, 57600u);
  // Each row reads its codec's constant, and every line is 8N1.
  EXPECT_EQ(Info(Protocol::kDmc).line.baud, dmc::kBaudRate);
  EXPECT_EQ(Info(Protocol::kDfmoco).line.baud, dfmoco::kBaudRate);
  EXPECT_EQ(Info(Protocol::kStackshot).line.baud, stackshot::kBaudRate);
  EXPECT_EQ(Info(Protocol::kStackshotDfmoco).line.baud, stackshot::kDfMocoBaudRate);
  for (const ProtocolInfo& row : Protocols()) {
    EXPECT_EQ(row.line,
              (LineSettings{.baud = row.line.baud, .data_bits = 8, .stop_bits = 1, .parity = 'N'}))
        << row.name;
    EXPECT_EQ(row.line.BytesPerSecond(), row.line.baud / 10) << row.name;
  }
  EXPECT_EQ(DefaultBaudList(), "DMC v2 115200, DFMoco 57600, StackShot 38400");
}

TEST(LineSettings, BytesPerSecondCountsStartParityAndStopBits) {
  EXPECT_EQ((LineSettings{.baud = 115200}).BytesPerSecond(), 11520u);               // 8N1: 10 bits
  EXPECT_EQ((LineSettings{.baud = 11000, .parity = 'E'}).BytesPerSecond(), 1000u);  // 8E1: 11
  EXPECT_EQ(
      (LineSettings{.baud = 11000, .data_bits = 7, .stop_bits = 2, .parity = 'O'}).BytesPerSecond(),
      1000u);  // 7O2: 1 + 7 + 1 + 2 bits
  // No rate given: 0 bytes/s, which a transport takes as unpaced.
  EXPECT_EQ(LineSettings{}.BytesPerSecond(), 0u);
}

TEST(ProtocolTable, NameListReadsAsProse) {
  const Protocol three[] = {Protocol::kDmc, Protocol::kDfmoco, Protocol::kStackshot};
  EXPECT_EQ(NameList(three), "dmc, dfmoco or stackshot");
  EXPECT_EQ(NameList(std::span(three, 1)), "dmc");
}

TEST(ProtocolTable, GreetingsDecodeAsEachProtocolsHello) {
  const Bytes dmc_hi = Info(Protocol::kDmc).greeting();
  auto f = dmc::DecodeFrame(dmc_hi);
  ASSERT_TRUE(f.ok());
  auto m = dmc::DecodeHostMessage(f.value());
  ASSERT_TRUE(m.ok());
  EXPECT_TRUE(std::holds_alternative<dmc::HiRequest>(m.value()));

  const Bytes hi = Info(Protocol::kDfmoco).greeting();
  EXPECT_EQ(std::string(hi.begin(), hi.end()), "hi\r\n");

  const Bytes ping = Info(Protocol::kStackshot).greeting();
  auto p = stackshot::DecodePacket(ping);
  ASSERT_TRUE(p.ok());
  EXPECT_EQ(p.value().command, static_cast<uint16_t>(stackshot::Command::kPing));
  EXPECT_TRUE(stackshot::ChecksumMatches(p.value(), stackshot::kDefaultChecksum));
}

TEST(ProtocolTable, SplitsFramesFromNoiseAndKeepsACutFrameAsNoise) {
  Bytes stream = {0x00, 'D'};
  const Bytes a = dmc::EncodeFrame(dmc::Frame{7, 0x0001, {}});
  const Bytes b = dmc::EncodeFrame(dmc::Frame{8, 0x0030, {1, 2, 3}});
  stream.insert(stream.end(), a.begin(), a.end());
  stream.insert(stream.end(), b.begin(), b.end());
  stream.insert(stream.end(), a.begin(), a.begin() + 5);  // cut short
  const auto parts = SplitMessages(Protocol::kDmc, Side::kHost, stream);
  ASSERT_EQ(parts.size(), 4u);
  EXPECT_EQ(parts[0], (Bytes{0x00, 'D'}));
  EXPECT_EQ(parts[1], a);
  EXPECT_EQ(parts[2], b);
  EXPECT_EQ(parts[3], Bytes(a.begin(), a.begin() + 5));
}

TEST(ProtocolTable, SplitsLinesAndKeepsAnUnterminatedTail) {
  const std::string text = "hi\r\nmp 1\r\nms";
  const auto parts =
      SplitMessages(Protocol::kDfmoco, Side::kHost,
                    ByteView(reinterpret_cast<const uint8_t*>(text.data()), text.size()));
  ASSERT_EQ(parts.size(), 3u);
  EXPECT_EQ(std::string(parts[1].begin(), parts[1].end()), "mp 1\r\n");
  EXPECT_EQ(std::string(parts[2].begin(), parts[2].end()), "ms");
}

TEST(ProtocolTable, StackshotSplitFollowsTheSyncByteOfItsSide) {
  const Bytes ping = Info(Protocol::kStackshot).greeting();  // a host packet (0x55)
  EXPECT_EQ(SplitMessages(Protocol::kStackshot, Side::kHost, ping).size(), 1u);
  // From the device side a host packet is no packet: one run of noise.
  const auto as_device = SplitMessages(Protocol::kStackshot, Side::kDevice, ping);
  ASSERT_EQ(as_device.size(), 1u);
  EXPECT_EQ(as_device[0], ping);
  EXPECT_EQ(Info(Protocol::kStackshot).next_message(Side::kDevice, ping).length, 0u);
}

TEST(ProtocolTable, RepairMakesAFrameWithAWrongLengthAndChecksumDecodeAgain) {
  Bytes m = dmc::EncodeFrame(dmc::Frame{3, 0x0030, {1, 2, 3, 4}});
  m[dmc::kLengthOffset] = 0x40;  // declares more than is there
  m.back() ^= 0x5a;
  Info(Protocol::kDmc).repair(m);
  auto f = dmc::DecodeFrame(m);
  ASSERT_TRUE(f.ok());
  EXPECT_EQ(f.value().id, 3u);
  EXPECT_EQ(f.value().data, (Bytes{1, 2, 3, 4}));

  Bytes line = {'m', 'p', ' ', '1', '\r'};
  Info(Protocol::kDfmoco).repair(line);
  EXPECT_EQ(std::string(line.begin(), line.end()), "mp 1\r\n");

  Bytes ping = Info(Protocol::kStackshot).greeting();
  ping.back() ^= 0xff;
  Info(Protocol::kStackshot).repair(ping);
  auto p = stackshot::DecodePacket(ping);
  ASSERT_TRUE(p.ok());
  EXPECT_TRUE(stackshot::ChecksumMatches(p.value(), stackshot::kDefaultChecksum));

  Bytes noise = {0x01, 0x02};
  for (const ProtocolInfo& row : Protocols()) {
    if (row.id == Protocol::kDfmoco || row.id == Protocol::kStackshotDfmoco) continue;
    Bytes copy = noise;
    row.repair(copy);
    EXPECT_EQ(copy, noise) << row.name << ": bytes that start no message stay as they are";
  }
}

// The law every cut obeys: joining the messages gives the stream back, and
// every piece the cutter calls a message is one whole message of the codec.
RC_GTEST_PROP(ProtocolTable, SplitThenJoinIsTheStream, (const std::vector<uint8_t>& noise)) {
  for (const ProtocolInfo& row : Protocols()) {
    for (const Side side : {Side::kHost, Side::kDevice}) {
      Bytes stream = noise;
      const Bytes g = row.greeting();
      stream.insert(stream.begin() + static_cast<ptrdiff_t>(noise.size() / 2), g.begin(), g.end());
      const auto parts = SplitMessages(row.id, side, stream);
      RC_ASSERT(JoinMessages(parts) == stream);
      for (const Bytes& p : parts) RC_ASSERT(!p.empty());
    }
  }
}

}  // namespace
}  // namespace moco::wire
