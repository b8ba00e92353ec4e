// mocosim tap: following a StackShot's switch to its DfMoco dialect from the
// traffic (stackshot-protocol.txt 1.1.17 CC_RAIL_CONFIG_GLOBAL_MODE, section
// 3; ERRATA 3.7) and the device-side specs it takes.
#include <gtest/gtest.h>
#include <poll.h>
#include <unistd.h>

#include <filesystem>
#include <string>
#include <thread>
#include <variant>

#include "serve/tap.h"
#include "serve/tap_line_rate.h"
#include "session/session.h"
#include "transport/device_server.h"
#include "transport/dmc_host_client.h"
#include "transport/test_support.h"
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

// The recording is written off the forwarding path in batches; a tap stopped
// right after the last chunk crossed (well inside a batch's window) still
// records every chunk, in order, both ways.
TEST(TapRecording, StopRightAfterTheLastChunkRecordsEveryChunkInOrder) {
  namespace asio = transport::asio;
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("tap_test." + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  // An echo device on a PTY, on its own io thread.
  asio::io_context device_io;
  sim::Scheduler device_scheduler;
  transport::RealtimeDriver device_driver(device_io, device_scheduler);
  transport::ServeOptions opts;
  opts.no_pacing = true;
  opts.log = [](std::string_view) {};
  transport::DeviceServer device_server(device_driver, "pty:" + (dir / "device").string(), opts);
  transport::testing::EchoDevice echo(device_server.sink());
  device_server.Serve(echo);
  echo.PowerOn();
  device_driver.Start();
  std::thread device_thread([&] { device_io.run(); });
  // The tap in front of it, on its own.
  asio::io_context tap_io;
  sim::Scheduler tap_scheduler;
  transport::RealtimeDriver tap_driver(tap_io, tap_scheduler);
  TapConfig config;
  config.protocol = wire::Protocol::kDmc;
  config.device = "serial:" + (dir / "device").string();
  config.host = "pty:" + (dir / "host").string();
  config.record_path = (dir / "tapped.jsonl").string();
  Tap tap(tap_driver, config, [](std::string_view) {});
  tap.Start();
  tap_driver.Start();
  std::thread tap_thread([&] { tap_io.run(); });

  const int fd = transport::testing::OpenPtyHost((dir / "host").string());
  ASSERT_GE(fd, 0);
  wire::Bytes sent;
  wire::Bytes back;
  for (int i = 0; i < 50; ++i) {
    const wire::Bytes chunk(static_cast<size_t>(1 + i % 7), static_cast<uint8_t>(i));
    ASSERT_TRUE(transport::testing::WriteAll(fd, chunk.data(), chunk.size()));
    sent.insert(sent.end(), chunk.begin(), chunk.end());
    while (back.size() < sent.size()) {
      pollfd p{fd, POLLIN, 0};
      ASSERT_GT(poll(&p, 1, 5000), 0) << "no echo";
      uint8_t buf[256];
      const ssize_t n = read(fd, buf, sizeof buf);
      ASSERT_GT(n, 0);
      back.insert(back.end(), buf, buf + n);
    }
  }
  EXPECT_EQ(back, sent);
  bool stopped = false;
  asio::post(tap_io, [&] {
    stopped = tap.Stop();
    tap_driver.Stop();
    tap_io.stop();
  });
  tap_thread.join();
  close(fd);
  asio::post(device_io, [&] {
    device_server.Stop();
    device_driver.Stop();
    device_io.stop();
  });
  device_thread.join();
  EXPECT_TRUE(stopped);

  auto loaded = session::LoadSession(dir / "tapped.jsonl");
  ASSERT_TRUE(std::holds_alternative<session::Session>(loaded));
  const session::Session& s = std::get<session::Session>(loaded);
  EXPECT_EQ(s.cut_line, 0u);
  wire::Bytes host_bytes;
  wire::Bytes device_bytes;
  int64_t last_t_ns = 0;
  for (const session::SessionEntry& e : s.entries) {
    EXPECT_GE(e.t_ns, last_t_ns);
    last_t_ns = e.t_ns;
    if (e.is_event) continue;
    wire::Bytes& to = e.from == session::Origin::kHost ? host_bytes : device_bytes;
    to.insert(to.end(), e.bytes.begin(), e.bytes.end());
    // Each echo follows its request: the device never leads the host.
    EXPECT_LE(device_bytes.size(), host_bytes.size());
  }
  EXPECT_EQ(host_bytes, sent);
  EXPECT_EQ(device_bytes, sent);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace moco::serve
