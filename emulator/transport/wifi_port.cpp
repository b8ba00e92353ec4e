// A StackShot 3X on Wi-Fi: UDP discovery, TCP client (see wifi_port.h).
#include "transport/wifi_port.h"

#include <netinet/in.h>
#include <netinet/tcp.h>
#include <sys/socket.h>

#include <stdexcept>
#include <string_view>

namespace moco::transport {

using asio::ip::tcp;
using asio::ip::udp;

WifiPort::WifiPort(Link& link, const std::string& address, uint16_t udp_port,
                   uint16_t host_tcp_port, WifiOptions options)
    : link_(link),
      options_(options),
      udp_(link.driver().io()),
      connect_timer_(link.driver().io()),
      address_(address),
      host_tcp_port_(host_tcp_port) {
  ErrorCode ec;
  const asio::ip::address addr = asio::ip::make_address(address, ec);
  if (ec) {
    throw std::runtime_error("cannot listen for FINDSTACK on \"" + address +
                             "\": not an IP address (use 0.0.0.0 for every network, or "
                             "127.0.0.1 for this machine only)");
  }
  const udp::endpoint endpoint(addr, udp_port);
  udp_.open(endpoint.protocol(), ec);
  if (!ec) udp_.set_option(udp::socket::reuse_address(true), ec);
  if (!ec) udp_.set_option(asio::socket_base::broadcast(true), ec);
  if (!ec) udp_.bind(endpoint, ec);
  if (ec) {
    throw std::runtime_error("cannot listen for FINDSTACK on udp " + address + ":" +
                             std::to_string(udp_port) + ": " + ec.message() +
                             " (another program may hold the port; choose another with "
                             "wifi:<address>:<udp port>)");
  }
  udp_port_ = udp_.local_endpoint().port();
}

WifiPort::~WifiPort() {
  Stop();
  alive_.reset();
}

std::string WifiPort::Where() const {
  return "wifi udp " + address_ + ":" + std::to_string(udp_port_) +
         " -> host tcp :" + std::to_string(host_tcp_port_);
}

void WifiPort::Start() {
  if (stopped_) return;
  Receive();
}

void WifiPort::Receive() {
  udp_.async_receive_from(
      asio::buffer(buf_), sender_,
      [this, weak = std::weak_ptr<bool>(alive_)](const ErrorCode& ec, size_t n) {
        if (weak.expired() || stopped_) return;
        OnDatagram(ec, n);
      });
}

void WifiPort::OnDatagram(const ErrorCode& ec, size_t n) {
  if (ec) {
    if (ec == asio::error::operation_aborted) return;
    link_.Log("udp receive failed: " + ec.message());
    Receive();
    return;
  }
  std::string_view msg(buf_.data(), n);
  while (!msg.empty() && (msg.back() == '\n' || msg.back() == '\r' || msg.back() == '\0')) {
    msg.remove_suffix(1);
  }
  if (msg == kFindStackMessage && !connecting_) {
    const asio::ip::address from = sender_.address();
    if (!link_.attached()) {
      ++discoveries_;
      Connect(from);
    } else if (host_ && *host_ == from &&
               std::chrono::steady_clock::now() - connected_at_ >= options_.reconnect_grace) {
      // Section 4.1: the host broadcasts again when it believes the link is
      // lost. Whatever this end thinks of the connection, the host no longer
      // uses it (a half-open socket after the host slept or changed network):
      // close it and connect anew.
      ++discoveries_;
      ++replaced_;
      link_.Log("FINDSTACK from the connected host " + from.to_string() +
                ": it has lost the link; closing it and connecting again");
      host_.reset();
      link_.Detach();
      Connect(from);
    }
    // Another host's broadcast while connected is not ours to answer ("once a
    // connection is established, these broadcast messages should stop").
  }
  Receive();
}

void WifiPort::ApplyKeepalive(tcp::socket& socket) {
  const int fd = socket.native_handle();
  const int on = 1;
  const int idle = static_cast<int>(options_.keepalive_idle.count());
  const int interval = static_cast<int>(options_.keepalive_interval.count());
  const int count = options_.keepalive_count;
  const auto user = static_cast<unsigned int>(options_.unacked_timeout.count());
  bool ok = setsockopt(fd, SOL_SOCKET, SO_KEEPALIVE, &on, sizeof on) == 0;
  if (idle > 0) ok = setsockopt(fd, IPPROTO_TCP, TCP_KEEPIDLE, &idle, sizeof idle) == 0 && ok;
  if (interval > 0) {
    ok = setsockopt(fd, IPPROTO_TCP, TCP_KEEPINTVL, &interval, sizeof interval) == 0 && ok;
  }
  if (count > 0) ok = setsockopt(fd, IPPROTO_TCP, TCP_KEEPCNT, &count, sizeof count) == 0 && ok;
  ok = setsockopt(fd, IPPROTO_TCP, TCP_USER_TIMEOUT, &user, sizeof user) == 0 && ok;
  if (!ok)
    link_.Log(
        "could not set keepalive on the connection; a vanished host is found by "
        "its next FINDSTACK only");
  WifiKeepalive k;
  socklen_t len = sizeof(int);
  int value = 0;
  if (getsockopt(fd, SOL_SOCKET, SO_KEEPALIVE, &value, &len) == 0) k.enabled = value != 0;
  len = sizeof(int);
  if (getsockopt(fd, IPPROTO_TCP, TCP_KEEPIDLE, &k.idle_s, &len) != 0) k.idle_s = 0;
  len = sizeof(int);
  if (getsockopt(fd, IPPROTO_TCP, TCP_KEEPINTVL, &k.interval_s, &len) != 0) k.interval_s = 0;
  len = sizeof(int);
  if (getsockopt(fd, IPPROTO_TCP, TCP_KEEPCNT, &k.count, &len) != 0) k.count = 0;
  unsigned int user_read = 0;
  len = sizeof user_read;
  if (getsockopt(fd, IPPROTO_TCP, TCP_USER_TIMEOUT, &user_read, &len) == 0) {
    k.user_timeout_ms = static_cast<int>(user_read);
  }
  last_keepalive_ = k;
}

void WifiPort::Connect(const asio::ip::address& host) {
  connecting_ = true;
  const uint64_t attempt = ++connect_gen_;
  const tcp::endpoint target(host, host_tcp_port_);
  const std::string peer = host.to_string() + ":" + std::to_string(host_tcp_port_);
  link_.Log("FINDSTACK from " + host.to_string() + ": connecting to " + peer);
  pending_ = std::make_unique<tcp::socket>(link_.driver().io());
  // A connect that hangs (SYNs unanswered) would keep every later FINDSTACK
  // unheard: it is abandoned after connect_timeout.
  connect_timer_.expires_after(options_.connect_timeout);
  connect_timer_.async_wait(
      [this, weak = std::weak_ptr<bool>(alive_), attempt, peer](const ErrorCode& ec) {
        if (weak.expired() || ec || attempt != connect_gen_ || !connecting_) return;
        ++connect_timeouts_;
        link_.Log("connecting to " + peer + " timed out after " +
                  std::to_string(options_.connect_timeout.count()) +
                  " ms; waiting for the next FINDSTACK");
        connecting_ = false;
        ++connect_gen_;    // the aborted connect's handler is stale
        pending_.reset();  // closes the socket: the connect ends with operation_aborted
      });
  pending_->async_connect(
      target, [this, weak = std::weak_ptr<bool>(alive_), attempt, host, peer](const ErrorCode& ec) {
        if (weak.expired() || attempt != connect_gen_) return;
        connecting_ = false;
        connect_timer_.cancel();
        std::unique_ptr<tcp::socket> socket = std::move(pending_);
        if (stopped_) return;
        if (ec) {
          // The host will broadcast again: the next FINDSTACK retries.
          link_.Log("connecting to " + peer + " failed: " + ec.message());
          return;
        }
        ErrorCode ignored;
        socket->set_option(tcp::no_delay(true), ignored);
        ApplyKeepalive(*socket);
        link_.Log("connected to host " + peer);
        host_ = host;
        connected_at_ = std::chrono::steady_clock::now();
        link_.Attach(std::make_unique<AsioByteStream<tcp::socket>>(std::move(*socket), peer),
                     [this, weak2 = std::weak_ptr<bool>(alive_), peer](const std::string& reason) {
                       if (weak2.expired()) return;
                       host_.reset();
                       // Back to listening for FINDSTACK (the UDP receive never stopped).
                       link_.Log("host " + peer + " gone (" + reason + "); waiting for FINDSTACK");
                     });
      });
}

void WifiPort::Stop() {
  if (stopped_) return;
  stopped_ = true;
  ErrorCode ignored;
  udp_.close(ignored);
  connect_timer_.cancel();
  ++connect_gen_;
  connecting_ = false;
  if (pending_) pending_->close(ignored);
  host_.reset();
  link_.Detach();
}

}  // namespace moco::transport
