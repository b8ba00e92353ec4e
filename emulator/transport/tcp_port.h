// A device served on a TCP port (ARCHITECTURE house style 9): an acceptor on
// 127.0.0.1 by default, one host connection at a time, each connection fed to
// the shared Link session.
#ifndef MOCO_TRANSPORT_TCP_PORT_H_
#define MOCO_TRANSPORT_TCP_PORT_H_

#include <cstdint>
#include <memory>
#include <string>

#include "transport/asio.h"
#include "transport/link.h"

namespace moco::transport {

// Serves a Link on TCP. A second connection while a host is connected is
// accepted and closed at once, with a log line naming both peers. When the
// host disconnects (even mid-frame) the device just stops getting bytes and
// is told OnHostLink(false); the next connection starts a fresh session
// (device output written while no host is connected is discarded, as the
// Link is built with hold_while_closed = false for TCP).
//
// The Link must outlive the port.
class TcpPort {
 public:
  // Binds and listens on address:port (port 0: an ephemeral port, see
  // port()). Throws std::runtime_error with a message a user can act on: a
  // port in use names the port and suggests another or `--tcp 127.0.0.1:0`;
  // a bad address names it.
  TcpPort(Link& link, const std::string& address, uint16_t port);
  ~TcpPort();
  TcpPort(const TcpPort&) = delete;
  TcpPort& operator=(const TcpPort&) = delete;

  // Starts accepting.
  void Start();
  // Closes the acceptor and the current connection. Idempotent.
  void Stop();

  // The port actually bound (the ephemeral one when 0 was asked).
  uint16_t port() const { return port_; }
  const std::string& address() const { return address_; }
  // "127.0.0.1:5000".
  std::string Where() const;
  uint64_t refused() const { return refused_; }

 private:
  void Accept();

  Link& link_;
  asio::ip::tcp::acceptor acceptor_;
  std::string address_;
  uint16_t port_ = 0;
  bool stopped_ = false;
  uint64_t refused_ = 0;
  std::shared_ptr<bool> alive_ = std::make_shared<bool>(true);
};

}  // namespace moco::transport

#endif  // MOCO_TRANSPORT_TCP_PORT_H_
