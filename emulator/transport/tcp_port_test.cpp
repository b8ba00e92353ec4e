// Tests for the TCP port (tcp_port.h): echo on 127.0.0.1 port 0, one host at
// a time, disconnect mid-stream then reconnect, and the port-in-use message.
#include "transport/tcp_port.h"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include "transport/test_support.h"

namespace moco::transport {
namespace {

using testing::EchoDevice;
using testing::RunUntil;

// A host connecting with plain sockets (not through the code under test).
class Client {
 public:
  explicit Client(uint16_t port) {
    fd_ = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(port);
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    connected_ = connect(fd_, reinterpret_cast<sockaddr*>(&a), sizeof(a)) == 0;
    fcntl(fd_, F_SETFL, fcntl(fd_, F_GETFL) | O_NONBLOCK);
  }
  ~Client() { Close(); }
  bool connected() const { return connected_; }
  void Close() {
    if (fd_ >= 0) close(fd_);
    fd_ = -1;
  }
  void Write(std::string_view s) {
    ASSERT_EQ(send(fd_, s.data(), s.size(), MSG_NOSIGNAL), static_cast<ssize_t>(s.size()));
  }
  void Poll() {
    char buf[4096];
    while (fd_ >= 0) {
      const ssize_t n = read(fd_, buf, sizeof(buf));
      if (n == 0) eof = true;
      if (n < 0 && errno != EAGAIN) eof = true;
      if (n <= 0) break;
      got.append(buf, static_cast<size_t>(n));
    }
  }
  std::string got;
  bool eof = false;

 private:
  int fd_ = -1;
  bool connected_ = false;
};

class TcpPortTest : public ::testing::Test {
 protected:
  void Serve() {
    LinkOptions o;
    o.hold_while_closed = false;
    o.log = [this](std::string_view l) { log_ += std::string(l) + "\n"; };
    link_ = std::make_unique<Link>(driver_, o);
    device_ = std::make_unique<EchoDevice>(*link_);
    device_->PowerOn();
    link_->SetDevice(device_.get());
    port_ = std::make_unique<TcpPort>(*link_, "127.0.0.1", 0);
    port_->Start();
    driver_.Start();
  }
  bool Echo(Client& c, const std::string& s) {
    const size_t before = c.got.size();
    c.Write(s);
    return RunUntil(io_,
                    [&] {
                      c.Poll();
                      return c.got.size() >= before + s.size();
                    }) &&
           c.got.substr(before) == s;
  }

  asio::io_context io_;
  sim::Scheduler scheduler_;
  RealtimeDriver driver_{io_, scheduler_};
  std::unique_ptr<Link> link_;
  std::unique_ptr<EchoDevice> device_;
  std::unique_ptr<TcpPort> port_;
  std::string log_;
};

TEST_F(TcpPortTest, EchoesOnAnEphemeralPort) {
  Serve();
  ASSERT_NE(port_->port(), 0);
  EXPECT_EQ(port_->Where(), "127.0.0.1:" + std::to_string(port_->port()));
  Client c(port_->port());
  ASSERT_TRUE(c.connected());
  EXPECT_TRUE(Echo(c, "hi 2 4 2.0.0\r\n"));
  EXPECT_EQ(device_->received, "hi 2 4 2.0.0\r\n");
}

TEST_F(TcpPortTest, RefusesASecondConnection) {
  Serve();
  Client first(port_->port());
  ASSERT_TRUE(RunUntil(io_, [&] { return link_->attached(); }));
  Client second(port_->port());
  ASSERT_TRUE(RunUntil(io_, [&] {
    second.Poll();
    return second.eof;
  }));
  EXPECT_EQ(port_->refused(), 1u);
  EXPECT_NE(log_.find("refused connection from 127.0.0.1:"), std::string::npos) << log_;
  EXPECT_NE(log_.find("already has a host"), std::string::npos) << log_;
  // The first host is unaffected.
  EXPECT_TRUE(Echo(first, "still here"));
  EXPECT_TRUE(second.got.empty());
}

TEST_F(TcpPortTest, DisconnectMidFrameThenReconnect) {
  Serve();
  {
    Client c(port_->port());
    EXPECT_TRUE(Echo(c, "ab"));
    c.Write("cde");  // half a frame, then the host goes away
    ASSERT_TRUE(RunUntil(io_, [&] { return device_->received.size() == 5; }));
  }
  ASSERT_TRUE(RunUntil(io_, [&] { return device_->link_events.size() == 2; }));
  EXPECT_EQ(device_->link_events, (std::vector<bool>{true, false}));
  EXPECT_EQ(device_->received, "abcde");
  EXPECT_FALSE(link_->attached());
  // Output with no host connected is not kept for the next one.
  const uint64_t discarded_before = link_->stats().discarded;
  device_->Send("stale");
  EXPECT_EQ(link_->queued_bytes(), 0u);
  EXPECT_EQ(link_->stats().discarded - discarded_before, 5u);

  Client again(port_->port());
  ASSERT_TRUE(again.connected());
  EXPECT_TRUE(Echo(again, "fgh"));
  EXPECT_EQ(again.got, "fgh");
  EXPECT_EQ(device_->link_events, (std::vector<bool>{true, false, true}));
  EXPECT_NE(log_.find("disconnected"), std::string::npos) << log_;
}

TEST_F(TcpPortTest, DisconnectWhileTheDeviceIsWritingKeepsServing) {
  Serve();
  {
    Client c(port_->port());
    ASSERT_TRUE(RunUntil(io_, [&] { return link_->attached(); }));
    device_->Send(std::string(200000, 'x'));  // more than the socket buffers take at once
  }
  ASSERT_TRUE(RunUntil(io_, [&] { return !link_->attached(); }));
  Client again(port_->port());
  EXPECT_TRUE(Echo(again, "ok"));
  EXPECT_EQ(again.got, "ok");
}

TEST_F(TcpPortTest, PortInUseNamesThePortAndSuggestsPortZero) {
  Serve();
  const uint16_t busy = port_->port();
  LinkOptions o;
  Link other(driver_, o);
  try {
    TcpPort clash(other, "127.0.0.1", busy);
    FAIL() << "bound a port already in use";
  } catch (const std::runtime_error& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("port " + std::to_string(busy) + " is already in use"), std::string::npos)
        << m;
    EXPECT_NE(m.find("--tcp 127.0.0.1:0"), std::string::npos) << m;
  }
}

TEST_F(TcpPortTest, BadAddressIsNamed) {
  LinkOptions o;
  Link link(driver_, o);
  try {
    TcpPort port(link, "localhost-ish", 0);
    FAIL() << "accepted a bad address";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("\"localhost-ish\": not an IP address"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace moco::transport
