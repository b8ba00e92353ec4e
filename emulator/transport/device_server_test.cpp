// Tests for the endpoint builder (device_server.h): spec parsing, serving a
// device on a PTY and on TCP, and recording a session through the tap.
#include "transport/device_server.h"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <termios.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <filesystem>

#include "serve/session_tap.h"
#include "session/session.h"
#include "transport/test_support.h"

namespace moco::transport {
namespace {

using testing::EchoDevice;
using testing::RunUntil;
namespace fs = std::filesystem;

EndpointSpec Parsed(std::string_view s) {
  auto r = ParseEndpointSpec(s);
  EXPECT_TRUE(std::holds_alternative<EndpointSpec>(r)) << std::get<std::string>(r);
  return std::holds_alternative<EndpointSpec>(r) ? std::get<EndpointSpec>(r) : EndpointSpec{};
}

std::string ParseError(std::string_view s) {
  auto r = ParseEndpointSpec(s);
  return std::holds_alternative<std::string>(r) ? std::get<std::string>(r) : std::string();
}

TEST(EndpointSpecTest, ParsesPtyAndTcpForms) {
  EXPECT_EQ(Parsed("pty:/tmp/dmc16").path, "/tmp/dmc16");
  EXPECT_EQ(Parsed("pty:/tmp/dmc16").kind, EndpointSpec::Kind::kPty);
  const auto t = Parsed("tcp:127.0.0.1:5000");
  EXPECT_EQ(t.kind, EndpointSpec::Kind::kTcp);
  EXPECT_EQ(t.address, "127.0.0.1");
  EXPECT_EQ(t.port, 5000);
  const auto bare = Parsed("tcp:0");
  EXPECT_FALSE(bare.address.has_value());
  EXPECT_EQ(bare.port, 0);
  const auto v6 = Parsed("tcp:[::1]:7");
  EXPECT_EQ(v6.address, "::1");
  EXPECT_EQ(v6.port, 7);
}

TEST(EndpointSpecTest, ParsesWifiFormsWithTheSpecDefaults) {
  const auto d = Parsed("wifi:");
  EXPECT_EQ(d.kind, EndpointSpec::Kind::kWifi);
  EXPECT_FALSE(d.address.has_value());
  EXPECT_EQ(d.port, 24869);  // FINDSTACK on UDP 24869
  EXPECT_EQ(d.host_tcp_port, 24870);
  const auto full = Parsed("wifi:127.0.0.1:0:5555");
  EXPECT_EQ(full.address, "127.0.0.1");
  EXPECT_EQ(full.port, 0);
  EXPECT_EQ(full.host_tcp_port, 5555);
  EXPECT_NE(ParseError("wifi:1.2.3.4:x").find("not a UDP port"), std::string::npos);
  EXPECT_NE(ParseError("wifi:1.2.3.4:1:0").find("not a host TCP port"), std::string::npos);
  EXPECT_NE(ParseError("wifi:a:1:2:3").find("too many parts"), std::string::npos);
}

TEST(EndpointSpecTest, RejectsBadSpecsWithTheAcceptedForms) {
  EXPECT_NE(ParseError("serial:/dev/ttyUSB0").find("pty:<path>"), std::string::npos);
  EXPECT_NE(ParseError("pty:").find("names no path"), std::string::npos);
  EXPECT_NE(ParseError("tcp:127.0.0.1:70000").find("not a port number"), std::string::npos);
  EXPECT_NE(ParseError("tcp:127.0.0.1:").find("not a port number"), std::string::npos);
  EXPECT_NE(ParseError("tcp:[::1]5000").find("[addr]:port"), std::string::npos);
}

class DeviceServerTest : public ::testing::Test {
 protected:
  asio::io_context io_;
  sim::Scheduler scheduler_;
  RealtimeDriver driver_{io_, scheduler_};
};

// A host that writes far more than it reads back: the link stops reading its
// requests while the answers wait (the host's writes then block in the
// kernel), so nothing is dropped and every byte comes back in order.
TEST_F(DeviceServerTest, HostThatDoesNotReadIsHeldBackNotAnsweredIntoTheVoid) {
  ServeOptions opts;
  opts.no_pacing = true;
  opts.max_queue_bytes = 4096;
  opts.log = [](std::string_view) {};
  DeviceServer server(driver_, "tcp:127.0.0.1:0", opts);
  EchoDevice device(server.sink());
  server.Serve(device);
  device.PowerOn();
  driver_.Start();
  const int fd = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(server.tcp_port());
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ASSERT_EQ(connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof(a)), 0);
  fcntl(fd, F_SETFL, fcntl(fd, F_GETFL) | O_NONBLOCK);
  // 16 MiB of patterned bytes: far beyond the queue and the socket buffers.
  constexpr size_t kTotal = 16u << 20;
  std::string sent(kTotal, '\0');
  for (size_t i = 0; i < kTotal; ++i) sent[i] = static_cast<char>((i * 131 + i / 251) & 0xff);
  std::string got;
  size_t written = 0;
  // First only write, for a while: a link that kept reading would have to
  // drop answers the host does not take.
  RunUntil(
      io_,
      [&] {
        const ssize_t w = send(fd, sent.data() + written, kTotal - written, MSG_NOSIGNAL);
        if (w > 0) written += static_cast<size_t>(w);
        return written == kTotal;
      },
      std::chrono::milliseconds(1500));
  EXPECT_LT(written, kTotal) << "the host's writes were held back";
  // Then read and write until everything came back.
  ASSERT_TRUE(RunUntil(
      io_,
      [&] {
        if (written < kTotal) {
          const ssize_t w = send(fd, sent.data() + written, kTotal - written, MSG_NOSIGNAL);
          if (w > 0) written += static_cast<size_t>(w);
        }
        char buf[65536];
        const ssize_t n = read(fd, buf, sizeof buf);
        if (n > 0) got.append(buf, static_cast<size_t>(n));
        return got.size() == kTotal;
      },
      std::chrono::milliseconds(60000)));
  EXPECT_EQ(server.link().stats().overflowed, 0u);
  EXPECT_TRUE(got == sent) << "every byte back, in order";
  close(fd);
  server.Stop();
}

TEST_F(DeviceServerTest, ServesOnTcpAndRecordsASession) {
  const fs::path file =
      fs::temp_directory_path() / ("moco_tap_" + std::to_string(getpid()) + ".jsonl");
  session::SessionHeader header;
  header.protocol = wire::Protocol::kDfmoco;
  header.device = "echo";
  {
    session::SessionWriter writer(file, header);
    serve::SessionTap tap(writer);
    ServeOptions opts;
    opts.observer = &tap;
    opts.log = [](std::string_view) {};
    DeviceServer server(driver_, "tcp:127.0.0.1:0", opts);
    EchoDevice device(server.sink());
    server.Serve(device);
    device.PowerOn();
    driver_.Start();
    ASSERT_NE(server.tcp_port(), 0);
    EXPECT_EQ(server.Where(), "tcp 127.0.0.1:" + std::to_string(server.tcp_port()));
    EXPECT_TRUE(server.pty_path().empty());

    const int fd = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(server.tcp_port());
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    ASSERT_EQ(connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof(a)), 0);
    fcntl(fd, F_SETFL, fcntl(fd, F_GETFL) | O_NONBLOCK);
    ASSERT_EQ(send(fd, "ms\r\n", 4, MSG_NOSIGNAL), 4);
    std::string got;
    ASSERT_TRUE(RunUntil(io_, [&] {
      char buf[64];
      const ssize_t n = read(fd, buf, sizeof(buf));
      if (n > 0) got.append(buf, static_cast<size_t>(n));
      return got.size() >= 4;
    }));
    EXPECT_EQ(got, "ms\r\n");
    close(fd);
    ASSERT_TRUE(RunUntil(io_, [&] { return !server.link().attached(); }));
    server.Stop();
    ASSERT_TRUE(writer.Finish());
  }
  auto loaded = session::LoadSession(file);
  ASSERT_TRUE(std::holds_alternative<session::Session>(loaded))
      << std::get<session::SessionError>(loaded).message;
  const auto& s = std::get<session::Session>(loaded);
  std::string from_host;
  std::string from_device;
  std::vector<std::string> events;
  int64_t last_t = 0;
  for (const auto& e : s.entries) {
    EXPECT_GE(e.t_ns, last_t);
    last_t = e.t_ns;
    if (e.is_event) {
      events.push_back(e.event["event"].get<std::string>() + " " +
                       e.event["detail"].get<std::string>());
    } else if (e.from == session::Origin::kHost) {
      from_host.append(e.bytes.begin(), e.bytes.end());
    } else {
      from_device.append(e.bytes.begin(), e.bytes.end());
    }
  }
  EXPECT_EQ(from_host, "ms\r\n");
  EXPECT_EQ(from_device, "ms\r\n");
  EXPECT_EQ(events, (std::vector<std::string>{"host_link open", "host_link closed"}));
  fs::remove(file);
}

TEST_F(DeviceServerTest, ServesOnAPtyAndCleansUp) {
  const std::string path =
      (fs::temp_directory_path() / ("moco_srv_" + std::to_string(getpid()))).string();
  ServeOptions opts;
  opts.no_pacing = true;
  opts.log = [](std::string_view) {};
  {
    DeviceServer server(driver_, "pty:" + path, opts);
    EchoDevice device(server.sink());
    server.Serve(device);
    device.PowerOn();
    driver_.Start();
    EXPECT_EQ(server.pty_path(), path);
    EXPECT_TRUE(server.pty_slave().starts_with("/dev/pts/"));
    EXPECT_EQ(server.Where(), "pty " + path + " -> " + server.pty_slave());
    const int fd = open(path.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
    ASSERT_GE(fd, 0);
    termios t{};
    tcgetattr(fd, &t);
    cfmakeraw(&t);
    tcsetattr(fd, TCSANOW, &t);
    ASSERT_EQ(write(fd, "\x44\x46\x00", 3), 3);
    std::string got;
    ASSERT_TRUE(RunUntil(io_, [&] {
      char buf[64];
      const ssize_t n = read(fd, buf, sizeof(buf));
      if (n > 0) got.append(buf, static_cast<size_t>(n));
      return got.size() >= 3;
    }));
    EXPECT_EQ(got, std::string("\x44\x46\x00", 3));
    close(fd);
    server.Stop();
    EXPECT_FALSE(fs::exists(fs::symlink_status(path)));
  }
}

TEST_F(DeviceServerTest, BadFaultConfigIsAStartUpError) {
  ServeOptions opts;
  opts.faults.to_host.drop_rate = 2;
  try {
    DeviceServer server(driver_, "tcp:127.0.0.1:0", opts);
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("to-host drop rate"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace moco::transport
