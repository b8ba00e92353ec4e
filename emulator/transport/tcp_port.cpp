// A device served on a TCP port, one host at a time (see tcp_port.h).
#include "transport/tcp_port.h"

#include <stdexcept>

namespace moco::transport {
namespace {

using asio::ip::tcp;

std::string EndpointText(const tcp::endpoint& ep) {
  const std::string addr = ep.address().to_string();
  return (ep.address().is_v6() ? "[" + addr + "]" : addr) + ":" + std::to_string(ep.port());
}

}  // namespace

TcpPort::TcpPort(Link& link, const std::string& address, uint16_t port)
    : link_(link), acceptor_(link.driver().io()), address_(address) {
  ErrorCode ec;
  const asio::ip::address addr = asio::ip::make_address(address, ec);
  if (ec) {
    throw std::runtime_error("cannot listen on \"" + address +
                             "\": not an IP address (use e.g. 127.0.0.1, or 0.0.0.0 for all "
                             "interfaces)");
  }
  const tcp::endpoint endpoint(addr, port);
  const std::string where = EndpointText(endpoint);
  acceptor_.open(endpoint.protocol(), ec);
  if (!ec) acceptor_.set_option(tcp::acceptor::reuse_address(true), ec);
  if (!ec) acceptor_.bind(endpoint, ec);
  if (ec == asio::error::address_in_use) {
    throw std::runtime_error("cannot listen on " + where + ": port " + std::to_string(port) +
                             " is already in use; choose another port, or use --tcp " +
                             (addr.is_v6() ? "[" + address + "]" : address) + ":0 for a free one");
  }
  if (ec == boost::system::errc::address_not_available) {
    throw std::runtime_error("cannot listen on " + where + ": " + address +
                             " is not an address of this machine");
  }
  if (ec == asio::error::access_denied) {
    throw std::runtime_error("cannot listen on " + where +
                             ": permission denied (ports below 1024 "
                             "need privileges; choose a port above 1023)");
  }
  if (!ec) acceptor_.listen(asio::socket_base::max_listen_connections, ec);
  if (ec) throw std::runtime_error("cannot listen on " + where + ": " + ec.message());
  port_ = acceptor_.local_endpoint().port();
}

TcpPort::~TcpPort() {
  Stop();
  alive_.reset();
}

std::string TcpPort::Where() const {
  const bool v6 = address_.find(':') != std::string::npos;
  return (v6 ? "[" + address_ + "]" : address_) + ":" + std::to_string(port_);
}

void TcpPort::Start() {
  if (stopped_) return;
  Accept();
}

void TcpPort::Accept() {
  acceptor_.async_accept(
      [this, weak = std::weak_ptr<bool>(alive_)](const ErrorCode& ec, tcp::socket socket) {
        if (weak.expired() || stopped_) return;
        if (ec) {
          if (ec == asio::error::operation_aborted) return;
          // Transient (e.g. out of descriptors): keep listening.
          link_.Log("accept failed: " + ec.message());
          Accept();
          return;
        }
        ErrorCode peer_ec;
        const tcp::endpoint peer = socket.remote_endpoint(peer_ec);
        const std::string peer_text = peer_ec ? std::string("unknown peer") : EndpointText(peer);
        if (link_.attached()) {
          ++refused_;
          link_.Log("refused connection from " + peer_text +
                    ": the device already has a host connected; one host at a time");
          ErrorCode ignored;
          socket.shutdown(tcp::socket::shutdown_both, ignored);
          socket.close(ignored);
        } else {
          ErrorCode ignored;
          socket.set_option(tcp::no_delay(true), ignored);
          link_.Log("host connected from " + peer_text);
          link_.Attach(
              std::make_unique<AsioByteStream<tcp::socket>>(std::move(socket), peer_text),
              [this, weak2 = std::weak_ptr<bool>(alive_), peer_text](const std::string& reason) {
                if (weak2.expired()) return;
                link_.Log("host " + peer_text + " disconnected (" + reason + ")");
              });
        }
        Accept();
      });
}

void TcpPort::Stop() {
  if (stopped_) return;
  stopped_ = true;
  ErrorCode ignored;
  acceptor_.close(ignored);
  link_.Detach();
}

}  // namespace moco::transport
