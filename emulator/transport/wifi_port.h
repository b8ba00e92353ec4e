// A StackShot 3X on Wi-Fi (stackshot-protocol.txt section 4 "Wifi
// Communication"; ERRATA 3.8: discovery is inverted): the controller listens
// for the host's "FINDSTACK" broadcast on UDP 24869, then connects as a TCP
// client to the host's port 24870 and speaks the binary protocol there. When
// the connection ends it listens for the broadcast again.
#ifndef MOCO_TRANSPORT_WIFI_PORT_H_
#define MOCO_TRANSPORT_WIFI_PORT_H_

#include <array>
#include <cstdint>
#include <memory>
#include <string>

#include "transport/asio.h"
#include "transport/link.h"

namespace moco::transport {

inline constexpr uint16_t kFindStackUdpPort = 24869;
inline constexpr uint16_t kStackHostTcpPort = 24870;
inline constexpr std::string_view kFindStackMessage = "FINDSTACK";

class WifiPort {
 public:
  // Binds UDP `address`:`udp_port` (0: ephemeral, see udp_port()) with
  // address reuse and broadcast reception. Throws std::runtime_error with a
  // message naming the address and the fix.
  WifiPort(Link& link, const std::string& address, uint16_t udp_port,
           uint16_t host_tcp_port = kStackHostTcpPort);
  ~WifiPort();
  WifiPort(const WifiPort&) = delete;
  WifiPort& operator=(const WifiPort&) = delete;

  void Start();
  // Closes the UDP socket and the connection. Idempotent.
  void Stop();

  uint16_t udp_port() const { return udp_port_; }
  uint16_t host_tcp_port() const { return host_tcp_port_; }
  bool connected() const { return link_.attached(); }
  // "udp 0.0.0.0:24869 -> host tcp :24870".
  std::string Where() const;
  uint64_t discoveries() const { return discoveries_; }

 private:
  void Receive();
  void OnDatagram(const ErrorCode& ec, size_t n);
  void Connect(const asio::ip::address& host);

  Link& link_;
  asio::ip::udp::socket udp_;
  std::string address_;
  uint16_t udp_port_ = 0;
  uint16_t host_tcp_port_;
  std::array<char, 512> buf_{};
  asio::ip::udp::endpoint sender_;
  bool connecting_ = false;
  bool stopped_ = false;
  uint64_t discoveries_ = 0;
  std::unique_ptr<asio::ip::tcp::socket> pending_;
  std::shared_ptr<bool> alive_ = std::make_shared<bool>(true);
};

}  // namespace moco::transport

#endif  // MOCO_TRANSPORT_WIFI_PORT_H_
