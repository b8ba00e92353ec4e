// A StackShot 3X on Wi-Fi (stackshot-protocol.txt section 4 "Wifi
// Communication"; ERRATA 3.8: discovery is inverted): the controller listens
// for the host's "FINDSTACK" broadcast on UDP 24869, then connects as a TCP
// client to the host's port 24870 and speaks the binary protocol there. When
// the connection ends it listens for the broadcast again.
//
// A host that vanishes without closing (asleep, off the network) leaves a
// half-open connection. Three things end it, so the unit can be found again:
//  - a FINDSTACK from the connected host's address (after a short grace
//    period): section 4.1 has the host resume broadcasting "if the TCP server
//    detects the connection is lost", so the host no longer counts on this
//    connection: it is closed and the unit connects anew;
//  - TCP keepalive (idle, interval, count) and TCP_USER_TIMEOUT (data left
//    unacknowledged) on the connection: a peer that answers nothing at all;
//  - a connect that neither succeeds nor fails is given up after
//    connect_timeout, so the next FINDSTACK is heard.
// Device output is written at most 1000 bytes at a time (section 4.2: "The
// maximum size of a single packet is set to 1000 bytes").
#ifndef MOCO_TRANSPORT_WIFI_PORT_H_
#define MOCO_TRANSPORT_WIFI_PORT_H_

#include <array>
#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "transport/asio.h"
#include "transport/link.h"

namespace moco::transport {

inline constexpr uint16_t kFindStackUdpPort = 24869;
inline constexpr uint16_t kStackHostTcpPort = 24870;
inline constexpr std::string_view kFindStackMessage = "FINDSTACK";
// Section 4.2: "The maximum size of a single packet is set to 1000 bytes."
inline constexpr size_t kWifiMaxPacketBytes = 1000;

struct WifiOptions {
  // A connect still pending after this long is abandoned (section 4.1 calls
  // 5 s "more than suitable" for the host's own socket timeout).
  std::chrono::milliseconds connect_timeout{5000};
  // TCP keepalive on the connection: the first probe after keepalive_idle
  // without traffic, then one every keepalive_interval; keepalive_count
  // unanswered probes end the connection.
  std::chrono::seconds keepalive_idle{10};
  std::chrono::seconds keepalive_interval{2};
  int keepalive_count = 3;
  // Data written but not acknowledged for this long ends the connection
  // (TCP_USER_TIMEOUT; 0: the kernel's default of many minutes).
  std::chrono::milliseconds unacked_timeout{16000};
  // A FINDSTACK from the connected host this soon after the connection was
  // made is one the host sent before it saw the connection (broadcasts in
  // flight, several networks): ignored, so a fresh connection is not torn down.
  std::chrono::milliseconds reconnect_grace{1000};
};

// The socket options a connection was given, read back from the socket.
struct WifiKeepalive {
  bool enabled = false;
  int idle_s = 0;
  int interval_s = 0;
  int count = 0;
  int user_timeout_ms = 0;
};

class WifiPort {
 public:
  // Binds UDP `address`:`udp_port` (0: ephemeral, see udp_port()) with
  // address reuse and broadcast reception. Throws std::runtime_error with a
  // message naming the address and the fix. The link should have been made
  // with LinkOptions::max_write_bytes = kWifiMaxPacketBytes.
  WifiPort(Link& link, const std::string& address, uint16_t udp_port,
           uint16_t host_tcp_port = kStackHostTcpPort, WifiOptions options = {});
  ~WifiPort();
  WifiPort(const WifiPort&) = delete;
  WifiPort& operator=(const WifiPort&) = delete;

  void Start();
  // Closes the UDP socket and the connection. Idempotent.
  void Stop();

  uint16_t udp_port() const { return udp_port_; }
  uint16_t host_tcp_port() const { return host_tcp_port_; }
  bool connected() const { return link_.attached(); }
  bool connecting() const { return connecting_; }
  // "udp 0.0.0.0:24869 -> host tcp :24870".
  std::string Where() const;
  // FINDSTACKs that started a connect (a reconnect included).
  uint64_t discoveries() const { return discoveries_; }
  // Connections closed because their host broadcast FINDSTACK again.
  uint64_t replaced() const { return replaced_; }
  // Connects abandoned after connect_timeout.
  uint64_t connect_timeouts() const { return connect_timeouts_; }
  // The options of the last connection, as the socket reports them.
  const std::optional<WifiKeepalive>& last_keepalive() const { return last_keepalive_; }

 private:
  void Receive();
  void OnDatagram(const ErrorCode& ec, size_t n);
  void Connect(const asio::ip::address& host);
  void ApplyKeepalive(asio::ip::tcp::socket& socket);

  Link& link_;
  WifiOptions options_;
  asio::ip::udp::socket udp_;
  asio::steady_timer connect_timer_;
  std::string address_;
  uint16_t udp_port_ = 0;
  uint16_t host_tcp_port_;
  std::array<char, 512> buf_{};
  asio::ip::udp::endpoint sender_;
  bool connecting_ = false;
  bool stopped_ = false;
  uint64_t discoveries_ = 0;
  uint64_t replaced_ = 0;
  uint64_t connect_timeouts_ = 0;
  uint64_t connect_gen_ = 0;               // bumped per connect attempt; stale handlers do nothing
  std::optional<asio::ip::address> host_;  // the connected host, while attached
  std::chrono::steady_clock::time_point connected_at_{};
  std::optional<WifiKeepalive> last_keepalive_;
  std::unique_ptr<asio::ip::tcp::socket> pending_;
  std::shared_ptr<bool> alive_ = std::make_shared<bool>(true);
};

}  // namespace moco::transport

#endif  // MOCO_TRANSPORT_WIFI_PORT_H_
