// Serving one emulated device on one endpoint ("pty:/tmp/dmc16",
// "tcp:127.0.0.1:5000"): the Link session plus the PTY or TCP port, built
// from a spec string (ARCHITECTURE "transport").
#ifndef MOCO_TRANSPORT_DEVICE_SERVER_H_
#define MOCO_TRANSPORT_DEVICE_SERVER_H_

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <variant>

#include "devices/device.h"
#include "transport/link.h"
#include "transport/link_faults.h"
#include "transport/pty_port.h"
#include "transport/realtime_driver.h"
#include "transport/tcp_port.h"
#include "transport/traffic.h"
#include "transport/wifi_port.h"

namespace moco::transport {

// A parsed endpoint spec.
//   pty:<path>              a PTY with a symlink at <path>
//   tcp:<port>              TCP on the bind address (default 127.0.0.1)
//   tcp:<address>:<port>    TCP on <address>; IPv6 as tcp:[::1]:5000
//   wifi:[<address>[:<udp port>[:<host tcp port>]]]
//                           a StackShot on Wi-Fi: hears FINDSTACK on UDP
//                           (default 127.0.0.1:24869, the bind address), connects to the host's
//                           TCP port (default 24870)
// Port 0 asks for an ephemeral port.
struct EndpointSpec {
  enum class Kind { kPty, kTcp, kWifi };
  Kind kind = Kind::kPty;
  std::string path;                    // kPty
  std::optional<std::string> address;  // kTcp, when given in the spec
  uint16_t port = 0;                   // kTcp; kWifi: the UDP port
  uint16_t host_tcp_port = 0;          // kWifi
};

// Parses a spec; on failure returns a message naming the problem and the forms
// accepted.
std::variant<EndpointSpec, std::string> ParseEndpointSpec(std::string_view spec);

struct ServeOptions {
  bool no_pacing = false;
  // TCP bind address when the spec gives none.
  std::string bind_address = "127.0.0.1";
  size_t max_queue_bytes = 256 * 1024;
  FaultConfig faults;                   // off by default
  TrafficObserver* observer = nullptr;  // not owned; must outlive the server
  std::function<void()> on_drain;       // LinkOptions::on_drain
  LogFn log = LogToStderr;
};

// One device on one endpoint. Typical use:
//   DeviceServer server(driver, "pty:/tmp/dmc16", options);   // throws on bad spec / busy port
//   Dmc16 device(scheduler, server.sink());
//   server.Serve(device);              // device.PowerOn() and driver.Start() are the caller's
//   std::cout << server.Where();
// The driver must outlive the server; the device must outlive the server or
// be withdrawn first (Stop()).
class DeviceServer {
 public:
  // Opens the endpoint (creates the PTY and its link, or binds the TCP port).
  // Throws std::runtime_error with a user-facing message on a bad spec, a bad
  // fault config, a PTY path that cannot be used or a TCP port in use.
  DeviceServer(RealtimeDriver& driver, std::string_view spec, ServeOptions options);
  ~DeviceServer();
  DeviceServer(const DeviceServer&) = delete;
  DeviceServer& operator=(const DeviceServer&) = delete;

  // Where the device writes its output.
  devices::ByteSink& sink() { return *link_; }
  // Starts serving `device` (must be the device writing to sink()).
  void Serve(devices::Device& device);
  // Closes the endpoint, removes the PTY symlink. Idempotent.
  void Stop();

  const EndpointSpec& spec() const { return spec_; }
  // "pty /tmp/dmc16 -> /dev/pts/4" or "tcp 127.0.0.1:5000".
  std::string Where() const;
  // PTY: the symlink path and the slave device; empty for TCP.
  std::string pty_path() const { return pty_ ? pty_->link_path() : std::string(); }
  std::string pty_slave() const { return pty_ ? pty_->slave_name() : std::string(); }
  // TCP: the bound port (the actual one for port 0); 0 for a PTY.
  uint16_t tcp_port() const { return tcp_ ? tcp_->port() : 0; }

  Link& link() { return *link_; }
  PtyPort* pty() { return pty_.get(); }
  TcpPort* tcp() { return tcp_.get(); }
  WifiPort* wifi() { return wifi_.get(); }

  // Faults on demand (e.g. from the control channel): cut the link for
  // duration_ns (TCP: the connection is closed too), power-cycle the device.
  void CutLink(sim::TimeNs duration_ns);
  void PowerCycle(sim::TimeNs off_ns) { link_->PowerCycle(off_ns); }

 private:
  EndpointSpec spec_;
  std::unique_ptr<Link> link_;
  std::unique_ptr<PtyPort> pty_;
  std::unique_ptr<TcpPort> tcp_;
  std::unique_ptr<WifiPort> wifi_;
  bool serving_ = false;
};

}  // namespace moco::transport

#endif  // MOCO_TRANSPORT_DEVICE_SERVER_H_
