// mocosim tap: following a StackShot's switch to its DfMoco dialect from the
// traffic (stackshot-protocol.txt 1.1.17 CC_RAIL_CONFIG_GLOBAL_MODE, section
// 3; ERRATA 3.7) and the device-side specs it takes.
#include <gtest/gtest.h>

#include <string>
#include <variant>

#include "serve/tap.h"
#include "serve/tap_line_rate.h"
#include "wire/stackshot.h"
#include "wire/stackshot_constants.h"

namespace moco::serve {
namespace {

using stackshot::Action;
using stackshot::Command;
using stackshot::GlobalMode;

wire::Bytes ModeWrite(GlobalMode mode) {
  stackshot::HostCommand c;
  c.command = static_cast<uint16_t>(Command::kRailConfigGlobalMode);
  c.action = Action::kWrite;
  c.payload = stackshot::EnumValue<GlobalMode>{mode};
  wire::Bytes out;
  EXPECT_TRUE(stackshot::EncodeHostCommand(c, out));
  return out;
}

wire::Bytes ModeAnswer(Action status) {
  stackshot::DeviceReply r;
  r.command = static_cast<uint16_t>(Command::kRailConfigGlobalMode);
  r.status = status;
  r.kind =
      status == Action::kRspOk ? stackshot::ReplyKind::kWriteAck : stackshot::ReplyKind::kError;
  r.payload = stackshot::Empty{};
  wire::Bytes out;
  EXPECT_TRUE(stackshot::EncodeDeviceReply(r, out));
  return out;
}

TEST(LineRateFollower, AcknowledgedDfmocoModeSwitchesTo57600AfterTheAck) {
  LineRateFollower f(wire::Protocol::kStackshot);
  f.OnHostBytes(ModeWrite(GlobalMode::kMotionDfMoco));
  // The request alone switches nothing: the device answers at the old rate.
  EXPECT_EQ(f.dialect(), wire::Protocol::kStackshot);
  const auto change = f.OnDeviceBytes(ModeAnswer(Action::kRspOk));
  ASSERT_TRUE(change.has_value());
  EXPECT_EQ(change->baud, 57600u);
  EXPECT_EQ(change->dialect, wire::Protocol::kStackshotDfmoco);
  EXPECT_EQ(f.dialect(), wire::Protocol::kStackshotDfmoco);
  // DfMoco text from then on is not read as packets.
  EXPECT_FALSE(f.OnDeviceBytes(ModeAnswer(Action::kRspOk)).has_value());
}

TEST(LineRateFollower, SwitchIsFoundInAnyChunking) {
  const wire::Bytes req = ModeWrite(GlobalMode::kMotionDfMoco);
  const wire::Bytes ack = ModeAnswer(Action::kRspOk);
  for (size_t cut = 0; cut <= ack.size(); ++cut) {
    LineRateFollower f(wire::Protocol::kStackshot);
    for (uint8_t b : req) f.OnHostBytes(wire::ByteView(&b, 1));
    const auto first = f.OnDeviceBytes(wire::ByteView(ack.data(), cut));
    const auto second = f.OnDeviceBytes(wire::ByteView(ack.data() + cut, ack.size() - cut));
    EXPECT_EQ(first.has_value(), cut == ack.size()) << "cut " << cut;
    EXPECT_EQ(second.has_value(), cut < ack.size()) << "cut " << cut;
  }
}

TEST(LineRateFollower, RefusedSwitchKeepsTheBinaryLine) {
  LineRateFollower f(wire::Protocol::kStackshot);
  f.OnHostBytes(ModeWrite(GlobalMode::kMotionDfMoco));
  EXPECT_FALSE(f.OnDeviceBytes(ModeAnswer(Action::kBusy)).has_value());
  // The request was answered: a later acknowledgement belongs to another one.
  EXPECT_FALSE(f.OnDeviceBytes(ModeAnswer(Action::kRspOk)).has_value());
  EXPECT_EQ(f.dialect(), wire::Protocol::kStackshot);
}

TEST(LineRateFollower, AnotherModeOrNoRequestSwitchesNothing) {
  LineRateFollower f(wire::Protocol::kStackshot);
  EXPECT_FALSE(f.OnDeviceBytes(ModeAnswer(Action::kRspOk)).has_value());
  f.OnHostBytes(ModeWrite(GlobalMode::kAdvanced));
  EXPECT_FALSE(f.OnDeviceBytes(ModeAnswer(Action::kRspOk)).has_value());
  // The latest write decides.
  f.OnHostBytes(ModeWrite(GlobalMode::kMotionDfMoco));
  f.OnHostBytes(ModeWrite(GlobalMode::kAdvanced));
  EXPECT_FALSE(f.OnDeviceBytes(ModeAnswer(Action::kRspOk)).has_value());
}

TEST(LineRateFollower, FixedLineProtocolsNeverChange) {
  for (wire::Protocol p : {wire::Protocol::kDmc, wire::Protocol::kDfmoco}) {
    LineRateFollower f(p);
    f.OnHostBytes(ModeWrite(GlobalMode::kMotionDfMoco));
    EXPECT_FALSE(f.OnDeviceBytes(ModeAnswer(Action::kRspOk)).has_value());
    EXPECT_EQ(f.dialect(), p);
  }
}

TEST(TapDeviceSpec, SerialTcpAndBarePathsAreTakenAndOthersNamed) {
  auto s = ParseDeviceSpec("serial:/dev/ttyUSB0");
  ASSERT_TRUE(std::holds_alternative<DeviceSpec>(s));
  EXPECT_FALSE(std::get<DeviceSpec>(s).tcp);
  EXPECT_EQ(std::get<DeviceSpec>(s).path, "/dev/ttyUSB0");
  s = ParseDeviceSpec("/dev/ttyACM0");
  ASSERT_TRUE(std::holds_alternative<DeviceSpec>(s));
  EXPECT_EQ(std::get<DeviceSpec>(s).path, "/dev/ttyACM0");
  s = ParseDeviceSpec("tcp:192.168.1.20:5000");
  ASSERT_TRUE(std::holds_alternative<DeviceSpec>(s));
  EXPECT_TRUE(std::get<DeviceSpec>(s).tcp);
  EXPECT_EQ(std::get<DeviceSpec>(s).host, "192.168.1.20");
  EXPECT_EQ(std::get<DeviceSpec>(s).port, 5000);
  s = ParseDeviceSpec("tcp:[::1]:7");
  ASSERT_TRUE(std::holds_alternative<DeviceSpec>(s));
  EXPECT_EQ(std::get<DeviceSpec>(s).host, "::1");
  for (const char* bad :
       {"", "serial:", "tcp:5000", "tcp:host:0", "tcp:host:70000", "tcp:host:12x", "udp:host:5"}) {
    const auto r = ParseDeviceSpec(bad);
    ASSERT_TRUE(std::holds_alternative<std::string>(r)) << bad;
    EXPECT_NE(std::get<std::string>(r).find("serial:PATH"), std::string::npos) << bad;
  }
}

TEST(TapDeviceSpec, DefaultModelPerProtocolIsTheEmulatedOne) {
  EXPECT_EQ(DefaultTapDevice(wire::Protocol::kDmc), "dmc16");
  EXPECT_EQ(DefaultTapDevice(wire::Protocol::kDfmoco), "dfmoco");
  EXPECT_EQ(DefaultTapDevice(wire::Protocol::kStackshot), "stackshot3x");
}

// emulator/serve/tap_cli_test.sh sends these bytes to switch a StackShot.
TEST(LineRateFollower, DfmocoModeWriteIsTheOneTheCommandLineTestSends) {
  EXPECT_EQ(wire::ToHex(ModeWrite(GlobalMode::kMotionDfMoco)), "55109e01010848");
}

}  // namespace
}  // namespace moco::serve
