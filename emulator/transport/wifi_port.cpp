// A StackShot 3X on Wi-Fi: UDP discovery, TCP client (see wifi_port.h).
#include "transport/wifi_port.h"

#include <stdexcept>
#include <string_view>

namespace moco::transport {

using asio::ip::tcp;
using asio::ip::udp;

WifiPort::WifiPort(Link& link, const std::string& address, uint16_t udp_port,
                   uint16_t host_tcp_port)
    : link_(link), udp_(link.driver().io()), address_(address), host_tcp_port_(host_tcp_port) {
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
  // Broadcasts are ignored while a host is connected ("once a connection is
  // established, these broadcast messages should stop").
  if (msg == kFindStackMessage && !link_.attached() && !connecting_) {
    ++discoveries_;
    Connect(sender_.address());
  }
  Receive();
}

void WifiPort::Connect(const asio::ip::address& host) {
  connecting_ = true;
  const tcp::endpoint target(host, host_tcp_port_);
  const std::string peer = host.to_string() + ":" + std::to_string(host_tcp_port_);
  link_.Log("FINDSTACK from " + host.to_string() + ": connecting to " + peer);
  pending_ = std::make_unique<tcp::socket>(link_.driver().io());
  pending_->async_connect(
      target, [this, weak = std::weak_ptr<bool>(alive_), peer](const ErrorCode& ec) {
        if (weak.expired()) return;
        connecting_ = false;
        std::unique_ptr<tcp::socket> socket = std::move(pending_);
        if (stopped_) return;
        if (ec) {
          // The host will broadcast again: the next FINDSTACK retries.
          link_.Log("connecting to " + peer + " failed: " + ec.message());
          return;
        }
        ErrorCode ignored;
        socket->set_option(tcp::no_delay(true), ignored);
        link_.Log("connected to host " + peer);
        link_.Attach(std::make_unique<AsioByteStream<tcp::socket>>(std::move(*socket), peer),
                     [this, weak2 = std::weak_ptr<bool>(alive_), peer](const std::string& reason) {
                       if (weak2.expired()) return;
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
  if (pending_) pending_->close(ignored);
  link_.Detach();
}

}  // namespace moco::transport
