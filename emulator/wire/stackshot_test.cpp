// Tests for the StackShot binary codec (stackshot-protocol.txt section 2 and
// 4; ERRATA.md part 3): golden vectors from fixtures/wire/stackshot.json, the
// command-id readings, framing, the streaming decoder and round-trip laws.
#include "wire/stackshot.h"

#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>

#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

namespace moco::stackshot {
namespace {

using wire::FromHex;
using wire::ToHex;

// ---------------------------------------------------------------------------
// Golden vectors
// ---------------------------------------------------------------------------
nlohmann::json LoadFixture() {
  const char* root = std::getenv("MOCO_SOURCE_DIR");
  const std::string path = std::string(root ? root : ".") + "/fixtures/wire/stackshot.json";
  std::ifstream in(path);
  EXPECT_TRUE(in.good()) << "cannot open " << path;
  if (!in.good()) return nlohmann::json::object();
  return nlohmann::json::parse(in);
}

ChecksumAlgorithm VectorChecksum(const nlohmann::json& v) {
  if (!v.contains("checksum")) return kDefaultChecksum;
  auto a = ParseChecksumAlgorithm(v["checksum"].get<std::string>());
  EXPECT_TRUE(a.has_value()) << v["checksum"];
  return a.value_or(kDefaultChecksum);
}

ReplyContext VectorContext(const nlohmann::json& v) {
  ReplyContext ctx;
  if (v.contains("request")) {
    ctx.request_action = v["request"] == "read" ? Action::kRead : Action::kWrite;
  }
  return ctx;
}

TEST(StackshotGolden, EveryVectorDecodesDescribesAndReencodes) {
  const nlohmann::json fixture = LoadFixture();
  ASSERT_EQ(fixture.value("protocol", ""), "stackshot");
  ASSERT_EQ(fixture.value("checksum_default", ""), ChecksumAlgorithmName(kDefaultChecksum));
  ASSERT_GE(fixture["vectors"].size(), 60u);
  for (const auto& v : fixture["vectors"]) {
    SCOPED_TRACE(v["name"].get<std::string>());
    const auto bytes = FromHex(v["hex"].get<std::string>());
    ASSERT_TRUE(bytes.has_value());
    const bool from_device = v["direction"] == "device";
    const ChecksumAlgorithm algorithm = VectorChecksum(v);

    PacketDecoder decoder(from_device, algorithm);
    std::vector<DecodedPacket> got;
    ASSERT_EQ(decoder.Feed(*bytes, got), 1u);
    EXPECT_EQ(got[0].skipped_before, 0u);
    EXPECT_EQ(decoder.pending_bytes(), 0u);
    EXPECT_EQ(got[0].checksum_ok, v.value("checksum_ok", true));
    const Packet& packet = got[0].packet;
    EXPECT_EQ(packet.from_device, from_device);

    Packet reencoded;
    if (from_device) {
      auto reply = DecodeDevicePacket(packet, VectorContext(v));
      ASSERT_TRUE(reply.ok()) << wire::Describe(reply.error());
      EXPECT_EQ(Describe(*reply), v["describe"].get<std::string>());
      reencoded = ToPacket(*reply, algorithm);
      // The kind the decoder inferred without context matches the one with it.
      auto inferred = DecodeDevicePacket(packet);
      ASSERT_TRUE(inferred.ok());
      EXPECT_EQ(*inferred, *reply);
    } else {
      auto command = DecodeHostPacket(packet);
      ASSERT_TRUE(command.ok()) << wire::Describe(command.error());
      EXPECT_EQ(Describe(*command), v["describe"].get<std::string>());
      reencoded = ToPacket(*command, algorithm);
    }
    if (!v.value("checksum_ok", true)) reencoded.checksum = packet.checksum;
    Bytes out;
    ASSERT_TRUE(EncodePacket(reencoded, out));
    EXPECT_EQ(ToHex(out), ToHex(*bytes));
  }
}

TEST(StackshotGolden, EveryCommandHasAVector) {
  const nlohmann::json fixture = LoadFixture();
  std::set<uint16_t> seen;
  for (const auto& v : fixture["vectors"]) {
    const auto bytes = FromHex(v["hex"].get<std::string>());
    ASSERT_TRUE(bytes && bytes->size() >= kMinPacketBytes);
    seen.insert(static_cast<uint16_t>(((*bytes)[1] << 8) | (*bytes)[2]));
  }
  for (const CommandInfo& c : AllCommands()) {
    EXPECT_TRUE(seen.count(c.id)) << c.name << " has no golden vector";
  }
}

TEST(StackshotGolden, ErrorVectorsGiveTypedErrorsWithOffsets) {
  const nlohmann::json fixture = LoadFixture();
  ASSERT_GE(fixture["errors"].size(), 5u);
  for (const auto& v : fixture["errors"]) {
    SCOPED_TRACE(v["name"].get<std::string>());
    const auto bytes = FromHex(v["hex"].get<std::string>());
    ASSERT_TRUE(bytes.has_value());
    auto packet = DecodePacket(*bytes);
    ASSERT_TRUE(packet.ok());
    std::optional<DecodeError> error;
    if (v["direction"] == "device") {
      auto r = DecodeDevicePacket(*packet, VectorContext(v));
      ASSERT_FALSE(r.ok()) << Describe(*r);
      error = r.error();
    } else {
      auto c = DecodeHostPacket(*packet);
      ASSERT_FALSE(c.ok()) << Describe(*c);
      error = c.error();
    }
    EXPECT_EQ(wire::KindName(error->kind), v["kind"].get<std::string>()) << error->detail;
    EXPECT_EQ(error->offset, v["offset"].get<size_t>()) << error->detail;
    if (v.contains("reply")) {
      EXPECT_EQ(ActionName(ErrorReplyStatus(*error)), v["reply"].get<std::string>());
    }
  }
}

// ---------------------------------------------------------------------------
// Command ids: the readings of the enum listing vs. the tables
// ---------------------------------------------------------------------------
TEST(StackshotIds, TableIdsOfSection2) {
  // IDs printed in the per-command tables of section 2.
  const std::map<std::string, uint16_t> table = {
      {"CC_RAIL_MOVE", 0x1000},
      {"CC_RAIL_MOVE_AT_SPEED", 0x1007},
      {"CC_RAIL_POSITION_TARGET", 0x1001},
      {"CC_RAIL_POSITION_CURRENT", 0x1002},
      {"CC_RAIL_POSITION_ZERO", 0x1003},
      {"CC_RAIL_SHUTTER_FIRE", 0x1004},
      {"CC_RAIL_STATUS", 0x1005},
      {"CC_RAIL_STACK", 0x1008},
      {"CC_RAIL_CONFIG_NAME", 0x1080},
      {"CC_RAIL_CONFIG_BACKLIGHT", 0x1081},
      {"CC_RAIL_CONFIG_MODE", 0x1082},
      {"CC_RAIL_CONFIG_UNITS", 0x1083},
      {"CC_RAIL_CONFIG_TORQUE", 0x1084},
      {"CC_RAIL_CONFIG_HOLDING_TORQUE", 0x1096},
      {"CC_RAIL_CONFIG_NUM_STEPS", 0x1085},
      {"CC_RAIL_CONFIG_NUM_PULSES", 0x1086},
      {"CC_RAIL_CONFIG_TOTAL_DISTANCE", 0x1087},
      {"CC_RAIL_CONFIG_DISTANCE_PER_STEP", 0x1088},
      {"CC_RAIL_CONFIG_SETTLE_TIME", 0x1089},
      {"CC_RAIL_CONFIG_PULSE_TIME", 0x1094},
      {"CC_RAIL_CONFIG_OFF_TIME", 0x108A},
      {"CC_RAIL_CONFIG_TIMELAPSE", 0x1093},
      {"CC_RAIL_CONFIG_SPEED", 0x108B} /* table: STACK_SPEED */,
      {"CC_RAIL_CONFIG_SPEED_MOVE", 0x1097} /* table: MOVE_SPEED */,
      {"CC_RAIL_CONFIG_RAMP_TIME", 0x108C},
      {"CC_RAIL_CONFIG_DISTANCE_PER_REV", 0x108D},
      {"CC_RAIL_CONFIG_BACKLASH", 0x1095},
      {"CC_RAIL_CONFIG_ROTARY_BACKLASH", 0x109B},
      {"CC_RAIL_CONFIG_SHUTTER_DISABLE", 0x108E},
      {"CC_RAIL_CONFIG_AUTO_RETURN", 0x108F},
      {"CC_RAIL_CONFIG_SAVE", 0x1090},
      {"CC_RAIL_CONFIG_LOAD", 0x1091},
      {"CC_RAIL_CONFIG_AXIS", 0x1092},
      {"CC_RAIL_CONFIG_POLARITY", 0x1098},
      {"CC_RAIL_CONFIG_ROTARY_RATIO", 0x109C},
      {"CC_RAIL_CONFIG_ROTARY_DEGREES", 0x109D},
      {"CC_RAIL_CONFIG_GLOBAL_MODE", 0x109E},
      {"CC_RAIL_CONFIG_TOFF_FINAL", 0x109F},
      {"CC_RAIL_CONFIG_SHUTTER", 0x10A0},
      {"CC_CLOSE", 0x110E},
      {"CC_RESET", 0x1100},
      {"CC_REFLASH", 0x1101},
      {"CC_SOFTWARE_STRING", 0x1102},
      {"CC_SOFTWARE_ID", 0x1103},
      {"CC_HARDWARE_ID", 0x1104},
      {"CC_BOOTLOADER_ID", 0x1105},
      {"CC_SOFTWARE_CHECKSUM", 0x1106},
      {"CC_SERIAL_NUMBER", 0x1107},
      {"CC_NVM_ACCESS", 0x1108},
      {"CC_LOG", 0x110C},
      {"CC_MOTION_CONFIG", 0x1600},
      {"CC_WAD", 0x1200}};
  for (const auto& [name, id] : table) {
    const CommandInfo* c = FindCommand(id);
    ASSERT_NE(c, nullptr) << name;
    EXPECT_EQ(c->name, name);
  }
  // CC_PING is the one table id not taken (see stackshot_constants.h).
  EXPECT_EQ(CommandName(kPingTableId), "CC_NOR_ACCESS");
  EXPECT_EQ(Id(Command::kPing), 0x110B);
}

TEST(StackshotIds, EnumListingCountsConsecutivelyWithHoldingTorqueInserted) {
  // Section 1.2 listing order from each explicit value; HOLDING_TORQUE is the
  // one name inserted (after BACKLASH).
  const std::vector<std::pair<uint16_t, std::vector<std::string>>> runs = {
      {0x1000,
       {"CC_RAIL_MOVE", "CC_RAIL_POSITION_TARGET", "CC_RAIL_POSITION_CURRENT",
        "CC_RAIL_POSITION_ZERO", "CC_RAIL_SHUTTER_FIRE", "CC_RAIL_STATUS", "CC_RAIL_STOP",
        "CC_RAIL_MOVE_AT_SPEED", "CC_RAIL_STACK", "CC_RAIL_STACK_STATUS", "CC_RAIL_STACK_POSITION",
        "CC_RAIL_STOP_RAMP"}},
      {0x1080,
       {"CC_RAIL_CONFIG_NAME",
        "CC_RAIL_CONFIG_BACKLIGHT",
        "CC_RAIL_CONFIG_MODE",
        "CC_RAIL_CONFIG_UNITS",
        "CC_RAIL_CONFIG_TORQUE",
        "CC_RAIL_CONFIG_NUM_STEPS",
        "CC_RAIL_CONFIG_NUM_PULSES",
        "CC_RAIL_CONFIG_TOTAL_DISTANCE",
        "CC_RAIL_CONFIG_DISTANCE_PER_STEP",
        "CC_RAIL_CONFIG_SETTLE_TIME",
        "CC_RAIL_CONFIG_OFF_TIME",
        "CC_RAIL_CONFIG_SPEED",
        "CC_RAIL_CONFIG_RAMP_TIME",
        "CC_RAIL_CONFIG_DISTANCE_PER_REV",
        "CC_RAIL_CONFIG_SHUTTER_DISABLE",
        "CC_RAIL_CONFIG_AUTO_RETURN",
        "CC_RAIL_CONFIG_SAVE",
        "CC_RAIL_CONFIG_LOAD",
        "CC_RAIL_CONFIG_AXIS",
        "CC_RAIL_CONFIG_TIMELAPSE",
        "CC_RAIL_CONFIG_PULSE_TIME",
        "CC_RAIL_CONFIG_BACKLASH",
        "CC_RAIL_CONFIG_HOLDING_TORQUE",
        "CC_RAIL_CONFIG_SPEED_MOVE",
        "CC_RAIL_CONFIG_POLARITY",
        "CC_RAIL_CONFIG_IO_MODE",
        "CC_RAIL_CONFIG_IO_DIR",
        "CC_RAIL_CONFIG_ROTARY_BACKLASH",
        "CC_RAIL_CONFIG_ROTARY_RATIO",
        "CC_RAIL_CONFIG_ROTARY_DEGREES",
        "CC_RAIL_CONFIG_GLOBAL_MODE",
        "CC_RAIL_CONFIG_TOFF_FINAL",
        "CC_RAIL_CONFIG_SHUTTER"}},
      {0x1100,
       {"CC_RESET", "CC_REFLASH", "CC_SOFTWARE_STRING", "CC_SOFTWARE_ID", "CC_HARDWARE_ID",
        "CC_BOOTLOADER_ID", "CC_SOFTWARE_CHECKSUM", "CC_SERIAL_NUMBER", "CC_NVM_ACCESS",
        "CC_NAND_ACCESS", "CC_NOR_ACCESS", "CC_PING", "CC_LOG", "CC_WIFI", "CC_CLOSE"}},
      {0x1200, {"CC_WAD"}},
      {0x1600, {"CC_MOTION_CONFIG", "CC_MOTION_START"}},
  };
  size_t total = 0;
  for (const auto& [first, names] : runs) {
    for (size_t i = 0; i < names.size(); ++i) {
      EXPECT_EQ(CommandName(static_cast<uint16_t>(first + i)), names[i]);
    }
    total += names.size();
  }
  EXPECT_EQ(AllCommands().size(), total);
}

TEST(StackshotIds, ActionAndStatusValues) {
  EXPECT_EQ(static_cast<int>(Action::kRead), 0);
  EXPECT_EQ(static_cast<int>(Action::kWrite), 1);
  EXPECT_EQ(static_cast<int>(Action::kRspOk), 2);
  EXPECT_EQ(static_cast<int>(Action::kBadParam), 3);
  EXPECT_EQ(static_cast<int>(Action::kUnsupportedAction), 4);
  EXPECT_EQ(static_cast<int>(Action::kUnsupportedCmd), 5);
  EXPECT_EQ(static_cast<int>(Action::kFailed), 6);
  EXPECT_EQ(static_cast<int>(Action::kNotEmpty), 7);
  EXPECT_EQ(static_cast<int>(Action::kBusy), 8);
  EXPECT_EQ(kRailStatusMoving | kRailStatusShutter | kRailStatusUserAborted, 7u);
  EXPECT_EQ(kBaudRate, 38400u);
  EXPECT_EQ(kWifiHostTcpPort, kWifiDiscoveryUdpPort + 1);
  EXPECT_EQ(kMaxPacketBytes, 261u);
}

// ---------------------------------------------------------------------------
// Framing
// ---------------------------------------------------------------------------
TEST(StackshotFraming, ActionByteCarriesAxisAndSubItem) {
  Packet p;
  p.command = 0x1094;
  p.action = 0;
  p.axis = 1;
  p.sub_item = true;
  Seal(p, ChecksumAlgorithm::kConstant00);
  Bytes out;
  ASSERT_TRUE(EncodePacket(p, out));
  EXPECT_EQ(ToHex(out),
            "5510949000"
            "00");  // the spec's "0x55 10 94 90 00 ck"
}

TEST(StackshotFraming, NegatedSumMakesTheBytesAfterSyncSumToZero) {
  const auto bytes = FromHex("55 10 00 01 07 01 01 01 00 00 20 41");
  ASSERT_TRUE(bytes);
  Packet p = *DecodePacket([&] {
    Bytes b = *bytes;
    b.push_back(0);
    return b;
  }());
  Seal(p, ChecksumAlgorithm::kNegatedSum);
  unsigned sum = p.checksum;
  for (size_t i = 1; i < bytes->size(); ++i) sum += (*bytes)[i];
  EXPECT_EQ(sum & 0xFF, 0u);
  Seal(p, ChecksumAlgorithm::kConstant69);
  EXPECT_EQ(p.checksum, 0x69);
}

TEST(StackshotFraming, EncodeRefusesOversizedData) {
  Packet p;
  p.data.assign(256, 0);
  Bytes out = {1, 2};
  EXPECT_FALSE(EncodePacket(p, out));
  EXPECT_EQ(out.size(), 2u);
  p.data.resize(255);
  EXPECT_TRUE(EncodePacket(p, out));
  EXPECT_EQ(out.size(), 2u + kMaxPacketBytes);
}

TEST(StackshotFraming, DecodePacketErrors) {
  EXPECT_EQ(DecodePacket(*FromHex("56100000 00 00")).error().offset, 0u);
  EXPECT_EQ(DecodePacket(*FromHex("5510050000")).error().kind, DecodeError::Kind::kTruncated);
  auto r = DecodePacket(*FromHex("551005000100"));  // announces 1 data byte, has none + ck
  EXPECT_EQ(r.error().kind, DecodeError::Kind::kTruncated);
  r = DecodePacket(*FromHex("55100500 00 ee ff"));
  EXPECT_EQ(r.error().kind, DecodeError::Kind::kTrailing);
  EXPECT_EQ(r.error().offset, 6u);
}

TEST(StackshotFraming, ReservedBit6IsCarried) {
  auto p = DecodePacket(*FromHex("55 10 05 40 00 00"));
  ASSERT_TRUE(p.ok());
  EXPECT_TRUE(p->reserved_bit6);
  EXPECT_EQ(p->action, 0);
  auto c = DecodeHostPacket(*p);
  ASSERT_TRUE(c.ok());
  EXPECT_EQ(Describe(*c), "CC_RAIL_STATUS read axis=X bit6=1");
  Bytes out;
  ASSERT_TRUE(EncodePacket(*p, out));
  EXPECT_EQ(ToHex(out),
            "5510054000"
            "00");
}

// ---------------------------------------------------------------------------
// Typed decode details
// ---------------------------------------------------------------------------
Packet HostPacket(uint16_t command, uint8_t action, Bytes data) {
  Packet p;
  p.command = command;
  p.action = action;
  p.data = std::move(data);
  Seal(p, kDefaultChecksum);
  return p;
}

TEST(StackshotTyped, PingAtTableIdIsAnOption) {
  const Packet p = HostPacket(kPingTableId, 0, {0x12});
  auto as_ping = DecodeHostPacket(p);
  ASSERT_TRUE(as_ping.ok());
  EXPECT_EQ(as_ping->payload, Payload{PingRequest{0x12}});
  auto as_nor = DecodeHostPacket(p, DecodeOptions{.ping_at_table_id = false});
  ASSERT_TRUE(as_nor.ok());
  EXPECT_EQ(as_nor->payload, Payload(Raw{Bytes{0x12}}));
  EXPECT_EQ(PingAnswer(0x12), (PingReply{0xED, 0}));
}

TEST(StackshotTyped, BoolAcceptsAnyNonZeroByte) {
  auto c = DecodeHostPacket(HostPacket(Id(Command::kRailConfigPolarity), 1, {0x02}));
  ASSERT_TRUE(c.ok());
  EXPECT_EQ(c->payload, Payload{BoolValue{true}});
}

TEST(StackshotTyped, UnknownIdNeverFails) {
  for (uint8_t action = 0; action < 16; ++action) {
    auto c = DecodeHostPacket(HostPacket(0x7777, action, {1, 2, 3}));
    ASSERT_TRUE(c.ok());
    EXPECT_EQ(c->payload, Payload(Unknown{Bytes{1, 2, 3}}));
  }
}

TEST(StackshotTyped, ErrorReplyStatusMapping) {
  auto bad_action = DecodeHostPacket(HostPacket(Id(Command::kRailMove), 0, {}));
  ASSERT_FALSE(bad_action.ok());
  EXPECT_EQ(ErrorReplyStatus(bad_action.error()), Action::kUnsupportedAction);
  auto bad_len = DecodeHostPacket(HostPacket(Id(Command::kRailMove), 1, {0}));
  ASSERT_FALSE(bad_len.ok());
  EXPECT_EQ(ErrorReplyStatus(bad_len.error()), Action::kBadParam);
}

TEST(StackshotTyped, NoDataReplyInfersWriteAckAndDataInfersReadResponse) {
  Packet p;
  p.from_device = true;
  p.command = Id(Command::kRailConfigBacklight);
  p.action = 2;
  auto ack = DecodeDevicePacket(p);
  ASSERT_TRUE(ack.ok());
  EXPECT_EQ(ack->kind, ReplyKind::kWriteAck);
  p.data = {4};
  auto rsp = DecodeDevicePacket(p);
  ASSERT_TRUE(rsp.ok());
  EXPECT_EQ(rsp->kind, ReplyKind::kReadResponse);
  EXPECT_EQ(rsp->payload, Payload{U8Value{4}});
  // With context saying it answered a read, an empty reply is a length error.
  p.data.clear();
  auto short_read = DecodeDevicePacket(p, ReplyContext{Action::kRead});
  ASSERT_FALSE(short_read.ok());
  EXPECT_EQ(short_read.error().kind, DecodeError::Kind::kBadLength);
}

TEST(StackshotTyped, FormatF32IsShortestAndExact) {
  EXPECT_EQ(FormatF32(0.1f), "0.1");
  EXPECT_EQ(FormatF32(-0.0f), "-0");
  EXPECT_EQ(FormatF32(12345678.0f), "12345678");
  EXPECT_EQ(FormatF32(1.8f), "1.8");
}

// ---------------------------------------------------------------------------
// CC_MOTION_CONFIG layout and validation
// ---------------------------------------------------------------------------
MotionConfig TwoCurves() {
  MotionConfig m;
  m.axis_type = AxisType::kRail;
  m.curves[0].p = {BezierPoint{0, 0}, {1, 0}, {2, 100}, {3, 100}};
  m.curves[1].p = {BezierPoint{3, 100}, {4, 100}, {5, -50}, {6, -50}};
  return m;
}

TEST(StackshotMotion, PointOffsetsFollowErrata35) {
  MotionConfig m;
  for (size_t c = 0; c < kBezierCurves; ++c) {
    for (size_t p = 0; p < kBezierPoints; ++p) {
      m.curves[c].p[p].x = static_cast<float>(c * 10 + p);
      m.curves[c].p[p].y = -static_cast<float>(c * 10 + p);
    }
  }
  const Bytes data = EncodePayload(m);
  ASSERT_EQ(data.size(), 132u);
  for (size_t c = 0; c < kBezierCurves; ++c) {
    for (size_t p = 0; p < kBezierPoints; ++p) {
      float x = 0;
      float y = 0;
      std::memcpy(&x, data.data() + 4 + 32 * c + 8 * p, 4);  // host is little-endian
      std::memcpy(&y, data.data() + 4 + 32 * c + 8 * p + 4, 4);
      EXPECT_EQ(x, static_cast<float>(c * 10 + p));
      EXPECT_EQ(y, -static_cast<float>(c * 10 + p));
    }
  }
}

TEST(StackshotMotion, ValidConfigPasses) {
  EXPECT_TRUE(ValidateMotionConfig(TwoCurves()).ok());
  EXPECT_EQ(UsedCurves(TwoCurves()), 2);
  EXPECT_TRUE(ValidateMotionConfig(MotionConfig{}).ok());  // one degenerate curve at t=0
}

TEST(StackshotMotion, EachRuleIsReported) {
  struct Case {
    const char* name;
    void (*mutate)(MotionConfig&);
    MotionCheck want;
  };
  const Case cases[] = {
      {"curve 0 starts late",
       [](MotionConfig& m) { m.curves[0].p[0].x = 0.5f; },
       {MotionRule::kCurve0StartNotZero, 0}},
      {"gap between curves",
       [](MotionConfig& m) { m.curves[1].p[0].x = 3.5f; },
       {MotionRule::kContinuity, 1}},
      {"time runs backwards",
       [](MotionConfig& m) {
         m.curves[1].p[3].x = 2.0f;
         m.curves[1].p[1].x = 3.0f;
         m.curves[1].p[2].x = 2.0f;
       },
       {MotionRule::kTimeReversed, 1}},
      {"P1 before P0",
       [](MotionConfig& m) { m.curves[1].p[1].x = 2.5f; },
       {MotionRule::kP1BeforeP0, 1}},
      {"P2 after P3",
       [](MotionConfig& m) { m.curves[0].p[2].x = 3.5f; },
       {MotionRule::kP2AfterP3, 0}},
      {"P1 beyond P3",
       [](MotionConfig& m) { m.curves[0].p[1].x = 3.5f; },
       {MotionRule::kControlOutOfSpan, 0}},
      {"P2 before P0",
       [](MotionConfig& m) { m.curves[1].p[2].x = 2.0f; },
       {MotionRule::kControlOutOfSpan, 1}},
      {"NaN y",
       [](MotionConfig& m) { m.curves[1].p[2].y = std::numeric_limits<float>::quiet_NaN(); },
       {MotionRule::kNotFinite, 1}},
      {"curve after terminator",
       [](MotionConfig& m) { m.curves[3].p[0].x = 6.0f; },
       {MotionRule::kCurveAfterEnd, 3}},
  };
  for (const Case& c : cases) {
    MotionConfig m = TwoCurves();
    c.mutate(m);
    EXPECT_EQ(ValidateMotionConfig(m), c.want)
        << c.name << ": got " << MotionRuleName(ValidateMotionConfig(m).rule);
  }
}

// ---------------------------------------------------------------------------
// Wi-Fi batching
// ---------------------------------------------------------------------------
TEST(StackshotWifi, PacketsAreBatchedButNeverSplit) {
  Bytes stream;
  Packet big;
  big.data.assign(255, 0x55);
  Seal(big, kDefaultChecksum);
  for (int i = 0; i < 4; ++i) ASSERT_TRUE(EncodePacket(big, stream));  // 4 x 261 = 1044
  auto writes = SplitForWifi(stream);
  ASSERT_TRUE(writes.ok());
  ASSERT_EQ(writes->size(), 2u);
  EXPECT_EQ((*writes)[0].size(), 3 * kMaxPacketBytes);
  EXPECT_EQ((*writes)[1].size(), kMaxPacketBytes);
  EXPECT_EQ(SplitForWifi(stream, 200).error().kind, DecodeError::Kind::kBadLength);
  stream.pop_back();
  EXPECT_EQ(SplitForWifi(stream).error().kind, DecodeError::Kind::kTruncated);
  EXPECT_EQ(SplitForWifi(*FromHex("00")).error().kind, DecodeError::Kind::kBadValue);
}

// ---------------------------------------------------------------------------
// Generators
// ---------------------------------------------------------------------------
Bytes ArbitraryBytes(size_t max) {
  const auto n = *rc::gen::inRange<size_t>(0, max + 1);
  return *rc::gen::container<Bytes>(n, rc::gen::arbitrary<uint8_t>());
}

template <typename E>
E ArbitraryEnum() {
  return static_cast<E>(*rc::gen::arbitrary<uint8_t>());
}

F32 ArbitraryF32() { return F32::FromBits(*rc::gen::arbitrary<uint32_t>()); }

MotionConfig ArbitraryMotionConfig() {
  MotionConfig m;
  m.axis_type = static_cast<AxisType>(*rc::gen::arbitrary<uint32_t>());
  for (auto& c : m.curves) {
    for (auto& p : c.p) {
      p.x = ArbitraryF32();
      p.y = ArbitraryF32();
    }
  }
  return m;
}

// A payload of the given shape, drawn inside a property.
Payload ArbitraryPayload(Shape s) {
  switch (s) {
    case Shape::kNone:
    case Shape::kEmpty:
      return Empty{};
    case Shape::kUnitsQuery: {
      if (*rc::gen::arbitrary<bool>()) return UnitsQuery{};
      return UnitsQuery{ArbitraryEnum<Units>()};
    }
    case Shape::kU8:
      return U8Value{*rc::gen::arbitrary<uint8_t>()};
    case Shape::kBool:
      return BoolValue{*rc::gen::arbitrary<bool>()};
    case Shape::kU16:
      return U16Value{*rc::gen::arbitrary<uint16_t>()};
    case Shape::kU32:
      return U32Value{*rc::gen::arbitrary<uint32_t>()};
    case Shape::kF32:
      return F32Value{ArbitraryF32()};
    case Shape::kUnitsF32:
      return UnitsF32{ArbitraryEnum<Units>(), ArbitraryF32()};
    case Shape::kText: {
      const auto n = *rc::gen::inRange<size_t>(0, 200);
      std::string text = *rc::gen::container<std::string>(n, rc::gen::inRange<char>(1, 127));
      return Text{text, *rc::gen::arbitrary<bool>()};
    }
    case Shape::kUnits:
      return EnumValue<Units>{ArbitraryEnum<Units>()};
    case Shape::kRailMode:
      return EnumValue<RailMode>{ArbitraryEnum<RailMode>()};
    case Shape::kGlobalMode:
      return EnumValue<GlobalMode>{ArbitraryEnum<GlobalMode>()};
    case Shape::kShutterSetting:
      return EnumValue<ShutterSetting>{ArbitraryEnum<ShutterSetting>()};
    case Shape::kIoMode:
      return EnumValue<IoMode>{ArbitraryEnum<IoMode>()};
    case Shape::kDirection:
      return EnumValue<Direction>{ArbitraryEnum<Direction>()};
    case Shape::kRailMove:
      return RailMove{ArbitraryEnum<Direction>(), ArbitraryEnum<Units>(),
                      *rc::gen::arbitrary<bool>(), ArbitraryF32()};
    case Shape::kRailMoveAtSpeed:
      return RailMoveAtSpeed{ArbitraryEnum<Direction>(), ArbitraryEnum<Units>(), ArbitraryF32(),
                             ArbitraryF32()};
    case Shape::kShutterFire:
      return ShutterFire{*rc::gen::arbitrary<uint16_t>(), ArbitraryF32(), ArbitraryF32()};
    case Shape::kRailStack: {
      RailStack st;
      for (uint32_t* f :
           {&st.mode, &st.num_steps, &st.distance, &st.pano_start_steps, &st.pano_stop_steps,
            &st.x_start, &st.x_end, &st.y_start, &st.y_end, &st.z_start, &st.z_end}) {
        *f = *rc::gen::arbitrary<uint32_t>();
      }
      if (*rc::gen::arbitrary<bool>()) st.reserved = *rc::gen::arbitrary<uint32_t>();
      return st;
    }
    case Shape::kRailStatus:
      return RailStatus{*rc::gen::arbitrary<uint32_t>()};
    case Shape::kNvmRead:
      return NvmRead{*rc::gen::arbitrary<uint8_t>()};
    case Shape::kNvmWrite:
      return NvmWrite{*rc::gen::arbitrary<uint8_t>(), *rc::gen::arbitrary<uint32_t>()};
    case Shape::kPingRequest:
      return PingRequest{*rc::gen::arbitrary<uint8_t>()};
    case Shape::kPingReply:
      return PingReply{*rc::gen::arbitrary<uint8_t>(), *rc::gen::arbitrary<uint8_t>()};
    case Shape::kLogRequest:
      if (*rc::gen::arbitrary<bool>()) return LogRequest{*rc::gen::arbitrary<uint8_t>(), 1};
      return LogRequest{*rc::gen::arbitrary<uint32_t>(), 4};
    case Shape::kMotionConfig:
      return ArbitraryMotionConfig();
    case Shape::kMotionStart:
      return MotionStart{*rc::gen::arbitrary<bool>(), *rc::gen::arbitrary<bool>(),
                         *rc::gen::arbitrary<bool>()};
    case Shape::kRaw:
      return Raw{ArbitraryBytes(kMaxDataBytes)};
  }
  return Empty{};
}

uint16_t ArbitraryUnknownId() {
  return *rc::gen::suchThat(rc::gen::arbitrary<uint16_t>(),
                            [](uint16_t id) { return FindCommand(id) == nullptr; });
}

const CommandInfo& ArbitraryCommand() {
  const auto all = AllCommands();
  return all[*rc::gen::inRange<size_t>(0, all.size())];
}

void ArbitraryHeaderBits(uint8_t& axis, bool& sub_item, bool& bit6) {
  axis = *rc::gen::inRange<uint8_t>(0, 4);
  sub_item = *rc::gen::arbitrary<bool>();
  bit6 = *rc::gen::arbitrary<bool>();
}

HostCommand ArbitraryHostCommand() {
  HostCommand c;
  ArbitraryHeaderBits(c.axis, c.sub_item, c.reserved_bit6);
  if (*rc::gen::inRange(0, 10) == 0) {
    c.command = ArbitraryUnknownId();
    c.action = static_cast<Action>(*rc::gen::inRange<uint8_t>(0, 16));
    c.payload = Unknown{ArbitraryBytes(kMaxDataBytes)};
    return c;
  }
  const CommandInfo& info = ArbitraryCommand();
  c.command = info.id;
  std::vector<Action> allowed;
  if (info.read_request != Shape::kNone) allowed.push_back(Action::kRead);
  if (info.write_request != Shape::kNone) allowed.push_back(Action::kWrite);
  c.action = *rc::gen::elementOf(allowed);
  c.payload = ArbitraryPayload(c.action == Action::kRead ? info.read_request : info.write_request);
  // A one-byte READ of 0x110A is a ping by default (DecodeOptions).
  if (c.command == kPingTableId && c.action == Action::kRead) {
    c.payload = PingRequest{*rc::gen::arbitrary<uint8_t>()};
  }
  return c;
}

struct ReplyCase {
  DeviceReply reply;
  ReplyContext context;
};

ReplyCase ArbitraryDeviceReply() {
  ReplyCase rc_case;
  DeviceReply& r = rc_case.reply;
  ArbitraryHeaderBits(r.axis, r.sub_item, r.reserved_bit6);
  const int pick = *rc::gen::inRange(0, 10);
  if (pick == 0) {  // error status
    r.command = *rc::gen::arbitrary<uint16_t>();
    r.status = static_cast<Action>(
        *rc::gen::suchThat(rc::gen::inRange<uint8_t>(0, 16), [](uint8_t a) { return a != 2; }));
    r.kind = ReplyKind::kError;
    r.payload = Raw{ArbitraryBytes(16)};
    return rc_case;
  }
  r.status = Action::kRspOk;
  if (pick == 1) {  // unknown id
    r.command = ArbitraryUnknownId();
    r.kind = ReplyKind::kOpaque;
    r.payload = Unknown{ArbitraryBytes(kMaxDataBytes)};
    return rc_case;
  }
  const CommandInfo& info = ArbitraryCommand();
  r.command = info.id;
  if (info.read_response == Shape::kRaw) {
    r.kind = ReplyKind::kOpaque;
    Bytes data = ArbitraryBytes(kMaxDataBytes);
    if (r.command == kPingTableId && data.size() == 2) data.push_back(0);  // would read as ping
    r.payload = Raw{data};
    return rc_case;
  }
  const bool can_read = info.read_response != Shape::kNone;
  const bool can_write = info.write_request != Shape::kNone;
  const bool read = can_read && (!can_write || *rc::gen::arbitrary<bool>());
  if (read) {
    r.kind = ReplyKind::kReadResponse;
    r.payload = ArbitraryPayload(info.read_response);
    rc_case.context.request_action = Action::kRead;
  } else {
    r.kind = ReplyKind::kWriteAck;
    r.payload = Empty{};
    rc_case.context.request_action = Action::kWrite;
  }
  return rc_case;
}

// ---------------------------------------------------------------------------
// Round-trip laws
// ---------------------------------------------------------------------------
RC_GTEST_PROP(StackshotProps, HostCommandRoundTrips, ()) {
  const HostCommand c = ArbitraryHostCommand();
  const ChecksumAlgorithm algo =
      *rc::gen::element(ChecksumAlgorithm::kNegatedSum, ChecksumAlgorithm::kConstant69,
                        ChecksumAlgorithm::kConstant00);
  Bytes bytes;
  RC_ASSERT(EncodeHostCommand(c, bytes, algo));
  auto packet = DecodePacket(bytes);
  RC_ASSERT(packet.ok());
  RC_ASSERT(ChecksumMatches(*packet, algo));
  auto back = DecodeHostPacket(*packet);
  RC_ASSERT(back.ok());
  RC_ASSERT(*back == c);
  RC_ASSERT(!Describe(*back).empty());
}

RC_GTEST_PROP(StackshotProps, DeviceReplyRoundTrips, ()) {
  const ReplyCase rcase = ArbitraryDeviceReply();
  Bytes bytes;
  RC_ASSERT(EncodeDeviceReply(rcase.reply, bytes));
  auto packet = DecodePacket(bytes);
  RC_ASSERT(packet.ok());
  RC_ASSERT(packet->from_device);
  auto back = DecodeDevicePacket(*packet, rcase.context);
  RC_ASSERT(back.ok());
  RC_ASSERT(*back == rcase.reply);
  RC_ASSERT(!Describe(*back).empty());
}

RC_GTEST_PROP(StackshotProps, MotionConfigKeepsEveryF32BitExact, ()) {
  HostCommand c;
  c.command = Id(Command::kMotionConfig);
  c.action = Action::kWrite;
  c.axis = *rc::gen::inRange<uint8_t>(0, 3);
  MotionConfig m = ArbitraryMotionConfig();
  // Always include negative values and a negative zero somewhere.
  m.curves[0].p[1].y = -std::abs(m.curves[0].p[1].y.value());
  m.curves[2].p[3].x = -0.0f;
  c.payload = m;
  Bytes bytes;
  RC_ASSERT(EncodeHostCommand(c, bytes));
  RC_ASSERT(bytes.size() == kMinPacketBytes + kMotionConfigBytes);
  auto back = DecodeHostPacket(*DecodePacket(bytes));
  RC_ASSERT(back.ok());
  const auto& got = std::get<MotionConfig>(back->payload);
  for (size_t ci = 0; ci < kBezierCurves; ++ci) {
    for (size_t pi = 0; pi < kBezierPoints; ++pi) {
      RC_ASSERT(got.curves[ci].p[pi].x.bits() == m.curves[ci].p[pi].x.bits());
      RC_ASSERT(got.curves[ci].p[pi].y.bits() == m.curves[ci].p[pi].y.bits());
    }
  }
  RC_ASSERT(got == m);
}

// ---------------------------------------------------------------------------
// Streaming laws
// ---------------------------------------------------------------------------
std::vector<Packet> ArbitraryPackets(bool from_device) {
  const auto n = *rc::gen::inRange<size_t>(0, 8);
  std::vector<Packet> packets;
  for (size_t i = 0; i < n; ++i) {
    Packet p;
    p.from_device = from_device;
    p.command = *rc::gen::arbitrary<uint16_t>();
    p.action = *rc::gen::inRange<uint8_t>(0, 16);
    ArbitraryHeaderBits(p.axis, p.sub_item, p.reserved_bit6);
    p.data = ArbitraryBytes(kMaxDataBytes);
    p.checksum = *rc::gen::arbitrary<uint8_t>();
    packets.push_back(std::move(p));
  }
  return packets;
}

Bytes Concat(const std::vector<Packet>& packets) {
  Bytes out;
  for (const auto& p : packets) EncodePacket(p, out);
  return out;
}

RC_GTEST_PROP(StackshotProps, AnyChunkingYieldsTheSamePackets, ()) {
  const bool from_device = *rc::gen::arbitrary<bool>();
  const auto packets = ArbitraryPackets(from_device);
  const Bytes stream = Concat(packets);
  PacketDecoder decoder(from_device);
  std::vector<DecodedPacket> got;
  size_t pos = 0;
  while (pos < stream.size()) {
    const size_t n = *rc::gen::inRange<size_t>(1, std::min<size_t>(stream.size() - pos, 300) + 1);
    decoder.Feed(ByteView(stream).subspan(pos, n), got);
    RC_ASSERT(decoder.pending_bytes() < kMaxPacketBytes);
    pos += n;
  }
  RC_ASSERT(got.size() == packets.size());
  for (size_t i = 0; i < got.size(); ++i) {
    RC_ASSERT(got[i].packet == packets[i]);
    RC_ASSERT(got[i].skipped_before == 0u);
  }
  RC_ASSERT(decoder.skipped_total() == 0u);
}

RC_GTEST_PROP(StackshotProps, GarbagePrefixIsSkippedAndReported, ()) {
  const bool from_device = *rc::gen::arbitrary<bool>();
  const uint8_t sync = from_device ? kSyncDevice : kSyncHost;
  const auto n = *rc::gen::inRange<size_t>(0, 600);
  const Bytes garbage = *rc::gen::container<Bytes>(
      n, rc::gen::suchThat(rc::gen::arbitrary<uint8_t>(), [sync](uint8_t b) { return b != sync; }));
  auto packets = ArbitraryPackets(from_device);
  if (packets.empty()) {
    Packet p;
    p.from_device = from_device;
    packets.push_back(p);
  }
  Bytes stream = garbage;
  const Bytes body = Concat(packets);
  stream.insert(stream.end(), body.begin(), body.end());
  PacketDecoder decoder(from_device);
  std::vector<DecodedPacket> got;
  decoder.Feed(stream, got);
  RC_ASSERT(got.size() == packets.size());
  RC_ASSERT(got[0].packet == packets[0]);
  RC_ASSERT(got[0].skipped_before == garbage.size());
  RC_ASSERT(decoder.skipped_total() == garbage.size());
}

RC_GTEST_PROP(StackshotProps, ChecksumMismatchIsReportedNeverRejected, ()) {
  const bool from_device = *rc::gen::arbitrary<bool>();
  const auto algo =
      *rc::gen::element(ChecksumAlgorithm::kNegatedSum, ChecksumAlgorithm::kConstant69,
                        ChecksumAlgorithm::kConstant00);
  auto packets = ArbitraryPackets(from_device);
  PacketDecoder decoder(from_device, algo);
  std::vector<DecodedPacket> got;
  decoder.Feed(Concat(packets), got);
  RC_ASSERT(got.size() == packets.size());
  for (size_t i = 0; i < got.size(); ++i) {
    RC_ASSERT(got[i].packet == packets[i]);
    RC_ASSERT(got[i].checksum_ok == (packets[i].checksum == ComputeChecksum(algo, packets[i])));
    RC_ASSERT(got[i].expected_checksum == ComputeChecksum(algo, packets[i]));
  }
}

RC_GTEST_PROP(StackshotProps, FlushAfterAFalseSyncRecoversTheNextPacket, ()) {
  // A sync byte inside garbage starts a false packet; the inter-frame gap
  // (Flush) drops it and the next packet decodes.
  const Bytes partial = {kSyncHost, 0x10, 0x05, 0x00, 0x40};  // announces 64 data bytes
  Packet p;
  p.command = *rc::gen::arbitrary<uint16_t>();
  p.data = ArbitraryBytes(32);
  Seal(p, kDefaultChecksum);
  Bytes next;
  EncodePacket(p, next);
  PacketDecoder decoder(false);
  std::vector<DecodedPacket> got;
  decoder.Feed(partial, got);
  RC_ASSERT(got.empty());
  RC_ASSERT(decoder.Flush() == partial.size());
  decoder.Feed(next, got);
  RC_ASSERT(got.size() == 1u);
  RC_ASSERT(got[0].packet == p);
  RC_ASSERT(got[0].checksum_ok);
  RC_ASSERT(got[0].skipped_before == partial.size());
}

RC_GTEST_PROP(StackshotProps, DecoderNeverHoldsMoreThanOnePacket,
              (const std::vector<uint8_t>& junk)) {
  PacketDecoder decoder(*rc::gen::arbitrary<bool>());
  std::vector<DecodedPacket> got;
  for (uint8_t b : junk) {
    decoder.Feed(ByteView(&b, 1), got);
    RC_ASSERT(decoder.pending_bytes() < kMaxPacketBytes);
  }
  uint64_t in_packets = 0;
  for (const auto& d : got) in_packets += kMinPacketBytes + d.packet.data.size();
  RC_ASSERT(in_packets + decoder.skipped_total() + decoder.pending_bytes() == junk.size());
}

RC_GTEST_PROP(StackshotProps, WifiWritesConcatenateToTheStream, ()) {
  const auto packets = ArbitraryPackets(*rc::gen::arbitrary<bool>());
  const Bytes stream = Concat(packets);
  const auto limit = *rc::gen::inRange<size_t>(kMaxPacketBytes, 2 * kWifiMaxPacketBytes);
  auto writes = SplitForWifi(stream, limit);
  RC_ASSERT(writes.ok());
  Bytes joined;
  for (const auto& w : *writes) {
    RC_ASSERT(!w.empty());
    RC_ASSERT(w.size() <= limit);
    // Each write holds whole packets only.
    PacketDecoder d(w[0] == kSyncDevice);
    std::vector<DecodedPacket> got;
    d.Feed(w, got);
    RC_ASSERT(d.pending_bytes() == 0u);
    RC_ASSERT(d.skipped_total() == 0u);
    joined.insert(joined.end(), w.begin(), w.end());
  }
  RC_ASSERT(joined == stream);
}

}  // namespace
}  // namespace moco::stackshot
