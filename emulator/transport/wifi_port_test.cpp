// Tests for the StackShot 3X Wi-Fi port (wifi_port.h, stackshot-protocol.txt
// section 4): real loopback sockets, a host made of plain sockets (a TCP
// listener and FINDSTACK datagrams), and the emulated StackShot 3X behind the
// link. Waits are bounded (RunUntil's deadline) and driven by the port's
// short configured timeouts.
#include "transport/wifi_port.h"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include "devices/stackshot3x/stackshot3x.h"
#include "transport/test_support.h"
#include "wire/stackshot.h"

namespace moco::transport {
namespace {

using testing::RunUntil;

sockaddr_in Loopback(uint16_t port, const char* ip = "127.0.0.1") {
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(port);
  inet_pton(AF_INET, ip, &a.sin_addr);
  return a;
}

// The host of section 4.1: a TCP server the controller connects to, and
// FINDSTACK broadcasts (sent to the port's loopback address).
class Host {
 public:
  explicit Host(int backlog = 4) {
    listener_ = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0);
    sockaddr_in a = Loopback(0);
    EXPECT_EQ(bind(listener_, reinterpret_cast<sockaddr*>(&a), sizeof a), 0);
    EXPECT_EQ(listen(listener_, backlog), 0);
    socklen_t len = sizeof a;
    getsockname(listener_, reinterpret_cast<sockaddr*>(&a), &len);
    port_ = ntohs(a.sin_port);
  }
  ~Host() { close(listener_); }
  uint16_t port() const { return port_; }
  int listener() const { return listener_; }
  // A FINDSTACK datagram to `udp_port`, sent from `from_ip`.
  static void FindStack(uint16_t udp_port, const char* from_ip = "127.0.0.1") {
    const int udp = socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    sockaddr_in src = Loopback(0, from_ip);
    bind(udp, reinterpret_cast<sockaddr*>(&src), sizeof src);
    sockaddr_in to = Loopback(udp_port);
    sendto(udp, "FINDSTACK", 9, 0, reinterpret_cast<sockaddr*>(&to), sizeof to);
    close(udp);
  }
  // A connection the controller made, or -1.
  int TryAccept() {
    const int fd = accept4(listener_, nullptr, nullptr, SOCK_CLOEXEC | SOCK_NONBLOCK);
    return fd;
  }

 private:
  int listener_ = -1;
  uint16_t port_ = 0;
};

class WifiPortTest : public ::testing::Test {
 protected:
  void Serve(uint16_t host_port, WifiOptions options) {
    LinkOptions o;
    o.pacing = false;
    o.hold_while_closed = false;
    o.max_write_bytes = kWifiMaxPacketBytes;
    o.log = [this](std::string_view l) { log_ += std::string(l) + "\n"; };
    link_ = std::make_unique<Link>(driver_, o);
    device_ = std::make_unique<devices::Stackshot3x>(scheduler_, *link_);
    device_->SetHostLink(devices::Stackshot3x::HostLink::kWifi);
    device_->PowerOn();
    link_->SetDevice(device_.get());
    port_ = std::make_unique<WifiPort>(*link_, "127.0.0.1", 0, host_port, options);
    port_->Start();
    driver_.Start();
  }
  // Broadcasts FINDSTACK until the controller connects (as a host does,
  // "periodically"); the accepted socket or -1.
  int Discover(Host& host) {
    int fd = -1;
    for (int round = 0; round < 20 && fd < 0; ++round) {
      Host::FindStack(port_->udp_port());
      RunUntil(
          io_,
          [&] {
            fd = host.TryAccept();
            return fd >= 0;
          },
          std::chrono::milliseconds(250));
    }
    // The kernel accepts before the controller's connect handler has run.
    if (fd >= 0) RunUntil(io_, [&] { return port_->connected(); });
    return fd;
  }
  // CC_PING over `fd`: true when the answer (in ^ 0xFF) comes back.
  bool Ping(int fd, uint8_t value) {
    wire::Bytes req;
    stackshot::EncodeHostCommand(
        stackshot::HostCommand{stackshot::Id(stackshot::Command::kPing), stackshot::Action::kRead,
                               0, false, false, stackshot::PingRequest{value}},
        req);
    if (send(fd, req.data(), req.size(), MSG_NOSIGNAL) != static_cast<ssize_t>(req.size())) {
      return false;
    }
    wire::Bytes got;
    const bool answered = RunUntil(io_, [&] {
      uint8_t buf[256];
      const ssize_t n = read(fd, buf, sizeof buf);
      if (n > 0) got.insert(got.end(), buf, buf + n);
      return got.size() >= 8;
    });
    return answered && got.size() == 8 && got[5] == static_cast<uint8_t>(value ^ 0xFF);
  }
  // Whether the controller closed its end of `fd` (EOF or reset).
  bool ClosedByController(int fd) {
    return RunUntil(io_, [&] {
      uint8_t buf[256];
      const ssize_t n = read(fd, buf, sizeof buf);
      return n == 0 || (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK);
    });
  }

  WifiOptions Quick() {
    WifiOptions w;
    w.connect_timeout = std::chrono::milliseconds(150);
    w.keepalive_idle = std::chrono::seconds(1);
    w.keepalive_interval = std::chrono::seconds(1);
    w.keepalive_count = 2;
    w.unacked_timeout = std::chrono::milliseconds(1500);
    w.reconnect_grace = std::chrono::milliseconds(0);
    return w;
  }

  asio::io_context io_;
  sim::Scheduler scheduler_;
  RealtimeDriver driver_{io_, scheduler_};
  std::unique_ptr<Link> link_;
  std::unique_ptr<devices::Stackshot3x> device_;
  std::unique_ptr<WifiPort> port_;
  std::string log_;
};

TEST_F(WifiPortTest, AHostThatVanishedWithoutClosingGetsANewConnectionAtItsNextFindstack) {
  // Section 4.1: "If the TCP server detects the connection is lost ... the
  // UDP broadcasts should resume." A host that slept keeps no socket the
  // controller could see close: its next FINDSTACK must bring the unit back.
  Host host;
  Serve(host.port(), Quick());
  const int first = Discover(host);
  ASSERT_GE(first, 0) << log_;
  EXPECT_TRUE(Ping(first, 0x0F)) << log_;
  // The host vanishes: it never reads `first` again and never closes it (no
  // FIN, no reset reaches the controller), then broadcasts as after a wake-up.
  const int second = Discover(host);
  ASSERT_GE(second, 0) << "the controller ignored the host's FINDSTACK\n" << log_;
  EXPECT_TRUE(Ping(second, 0x3C)) << log_;
  EXPECT_EQ(port_->replaced(), 1u);
  EXPECT_TRUE(ClosedByController(first)) << "the half-open connection was left open";
  EXPECT_NE(log_.find("it has lost the link"), std::string::npos) << log_;
  close(first);
  close(second);
}

TEST_F(WifiPortTest, AFindstackStillInFlightAsTheConnectionIsMadeDoesNotTearItDown) {
  // Broadcasts sent before the host saw the connection (on several networks,
  // or a periodic one already queued) arrive just after it: within the grace
  // period they are the host's old search, not a lost link.
  Host host;
  WifiOptions w = Quick();
  w.reconnect_grace = std::chrono::seconds(30);
  Serve(host.port(), w);
  const int fd = Discover(host);
  ASSERT_GE(fd, 0) << log_;
  for (int i = 0; i < 3; ++i) Host::FindStack(port_->udp_port());
  RunUntil(
      io_, [] { return false; }, std::chrono::milliseconds(100));
  EXPECT_EQ(port_->replaced(), 0u);
  EXPECT_EQ(host.TryAccept(), -1);
  EXPECT_TRUE(Ping(fd, 0x42)) << log_;
  close(fd);
}

TEST_F(WifiPortTest, AnotherHostsFindstackWhileConnectedIsIgnored) {
  // "Once a connection is established, these broadcast messages should stop":
  // a broadcast from another machine does not take the unit away.
  Host host;
  Serve(host.port(), Quick());
  const int fd = Discover(host);
  ASSERT_GE(fd, 0) << log_;
  const uint64_t discoveries = port_->discoveries();
  Host::FindStack(port_->udp_port(), "127.0.0.2");
  RunUntil(
      io_, [] { return false; }, std::chrono::milliseconds(100));
  EXPECT_EQ(port_->discoveries(), discoveries);
  EXPECT_EQ(port_->replaced(), 0u);
  EXPECT_TRUE(port_->connected());
  EXPECT_TRUE(Ping(fd, 0x01)) << log_;
  close(fd);
}

TEST_F(WifiPortTest,
       AConnectThatHangsIsAbandonedAfterTheConnectTimeoutAndTheNextFindstackConnects) {
  // A host whose accept queue is full drops the controller's SYN: the connect
  // neither succeeds nor fails. Without a timeout every later FINDSTACK would
  // be ignored for good.
  Host host(/*backlog=*/0);
  const int filler = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  sockaddr_in a = Loopback(host.port());
  ASSERT_EQ(connect(filler, reinterpret_cast<sockaddr*>(&a), sizeof a), 0);
  Serve(host.port(), Quick());
  Host::FindStack(port_->udp_port());
  ASSERT_TRUE(RunUntil(io_, [&] { return port_->connecting(); }));
  ASSERT_TRUE(RunUntil(io_, [&] { return port_->connect_timeouts() == 1; })) << log_;
  EXPECT_FALSE(port_->connecting());
  EXPECT_FALSE(port_->connected());
  EXPECT_NE(log_.find("timed out after 150 ms"), std::string::npos) << log_;
  // The host frees its queue and broadcasts again: the unit connects.
  const int queued = host.TryAccept();
  ASSERT_GE(queued, 0);
  close(queued);
  close(filler);
  const int fd = Discover(host);
  ASSERT_GE(fd, 0) << log_;
  EXPECT_TRUE(Ping(fd, 0x55)) << log_;
  close(fd);
}

TEST_F(WifiPortTest, ConnectionsCarryTheConfiguredKeepaliveAndUnackedTimeout) {
  // A host that answers nothing at all (powered off, out of range) is found
  // by the kernel: keepalive probes on an idle link, TCP_USER_TIMEOUT on
  // unacknowledged replies.
  Host host;
  WifiOptions w = Quick();
  w.keepalive_idle = std::chrono::seconds(3);
  w.keepalive_interval = std::chrono::seconds(2);
  w.keepalive_count = 4;
  w.unacked_timeout = std::chrono::milliseconds(2500);
  Serve(host.port(), w);
  const int fd = Discover(host);
  ASSERT_GE(fd, 0) << log_;
  ASSERT_TRUE(port_->last_keepalive().has_value());
  const WifiKeepalive& k = *port_->last_keepalive();
  EXPECT_TRUE(k.enabled);
  EXPECT_EQ(k.idle_s, 3);
  EXPECT_EQ(k.interval_s, 2);
  EXPECT_EQ(k.count, 4);
  EXPECT_EQ(k.user_timeout_ms, 2500);
  close(fd);
}

TEST_F(WifiPortTest, AHostThatClosesIsFollowedByAReconnectAtTheNextFindstack) {
  Host host;
  Serve(host.port(), Quick());
  for (int round = 0; round < 2; ++round) {
    const int fd = Discover(host);
    ASSERT_GE(fd, 0) << "round " << round << "\n" << log_;
    EXPECT_TRUE(Ping(fd, static_cast<uint8_t>(round))) << log_;
    close(fd);
    ASSERT_TRUE(RunUntil(io_, [&] { return !port_->connected(); }));
  }
  EXPECT_EQ(port_->replaced(), 0u);
}

}  // namespace
}  // namespace moco::transport
