// Serving one emulated device on one endpoint spec (see device_server.h).
#include "transport/device_server.h"

#include <charconv>
#include <initializer_list>
#include <memory>
#include <stdexcept>
#include <vector>

namespace moco::transport {
namespace {

constexpr std::string_view kForms =
    "use pty:<path> (e.g. pty:/tmp/dmc16), tcp:<port> or tcp:<address>:<port> "
    "(e.g. tcp:127.0.0.1:5000, tcp:127.0.0.1:0 for a free port), or wifi: for a StackShot "
    "on Wi-Fi (wifi:[address[:udp port[:host tcp port]]], default 127.0.0.1:24869:24870; give "
    "0.0.0.0 to hear FINDSTACK from every network)";

// Concatenates pieces (also avoids g++ 12's false -Wrestrict on
// "literal" + std::string at -O2).
std::string Cat(std::initializer_list<std::string_view> parts) {
  std::string out;
  for (std::string_view p : parts) out.append(p);
  return out;
}

std::optional<uint16_t> ParsePort(std::string_view text) {
  unsigned v = 0;
  const auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (text.empty() || ec != std::errc() || ptr != text.data() + text.size() || v > 65535) {
    return std::nullopt;
  }
  return static_cast<uint16_t>(v);
}

}  // namespace

std::variant<EndpointSpec, std::string> ParseEndpointSpec(std::string_view spec) {
  EndpointSpec out;
  if (spec.starts_with("pty:")) {
    out.kind = EndpointSpec::Kind::kPty;
    out.path = std::string(spec.substr(4));
    if (out.path.empty()) return Cat({"\"", spec, "\" names no path: ", kForms});
    return out;
  }
  if (spec.starts_with("tcp:")) {
    out.kind = EndpointSpec::Kind::kTcp;
    std::string_view rest = spec.substr(4);
    std::string_view port_text = rest;
    if (!rest.empty() && rest.front() == '[') {
      const size_t close = rest.find(']');
      if (close == std::string_view::npos || close + 1 >= rest.size() || rest[close + 1] != ':') {
        return Cat({"\"", spec, "\": an IPv6 address is written [addr]:port"});
      }
      out.address = std::string(rest.substr(1, close - 1));
      port_text = rest.substr(close + 2);
    } else if (const size_t colon = rest.rfind(':'); colon != std::string_view::npos) {
      out.address = std::string(rest.substr(0, colon));
      port_text = rest.substr(colon + 1);
      if (out.address->empty()) return Cat({"\"", spec, "\" has an empty address: ", kForms});
    }
    const auto port = ParsePort(port_text);
    if (!port) {
      return Cat({"\"", port_text, "\" in \"", spec, "\" is not a port number 0..65535"});
    }
    out.port = *port;
    return out;
  }
  if (spec.starts_with("wifi:") || spec == "wifi") {
    out.kind = EndpointSpec::Kind::kWifi;
    out.port = kFindStackUdpPort;
    out.host_tcp_port = kStackHostTcpPort;
    std::string_view rest = spec.size() > 5 ? spec.substr(5) : std::string_view();
    std::vector<std::string_view> parts;
    while (!rest.empty()) {
      const size_t colon = rest.find(':');
      parts.push_back(rest.substr(0, colon));
      if (colon == std::string_view::npos) break;
      rest = rest.substr(colon + 1);
    }
    if (parts.size() > 3) return Cat({"\"", spec, "\" has too many parts: ", kForms});
    if (!parts.empty() && !parts[0].empty()) out.address = std::string(parts[0]);
    if (parts.size() > 1) {
      const auto p = ParsePort(parts[1]);
      if (!p) return Cat({"\"", parts[1], "\" in \"", spec, "\" is not a UDP port 0..65535"});
      out.port = *p;
    }
    if (parts.size() > 2) {
      const auto p = ParsePort(parts[2]);
      if (!p || *p == 0) {
        return Cat({"\"", parts[2], "\" in \"", spec, "\" is not a host TCP port 1..65535"});
      }
      out.host_tcp_port = *p;
    }
    return out;
  }
  return Cat({"unknown endpoint \"", spec, "\": ", kForms});
}

DeviceServer::DeviceServer(RealtimeDriver& driver, std::string_view spec, ServeOptions options) {
  auto parsed = ParseEndpointSpec(spec);
  if (auto* err = std::get_if<std::string>(&parsed)) throw std::runtime_error(*err);
  spec_ = std::get<EndpointSpec>(std::move(parsed));
  if (auto err = options.faults.Validate()) throw std::runtime_error("link faults: " + *err);

  LinkOptions lo;
  lo.pacing = !options.no_pacing;
  lo.max_queue_bytes = options.max_queue_bytes;
  lo.faults = options.faults;
  lo.observer = options.observer;
  lo.on_drain = options.on_drain;
  lo.log = options.log ? options.log : LogFn(LogToStderr);
  if (spec_.kind == EndpointSpec::Kind::kPty) {
    lo.hold_while_closed = true;
    lo.name = "pty " + spec_.path;
    link_ = std::make_unique<Link>(driver, std::move(lo));
    pty_ = std::make_unique<PtyPort>(*link_, spec_.path);
  } else if (spec_.kind == EndpointSpec::Kind::kWifi) {
    // No serial line on Wi-Fi: bytes are not paced; output with no host is dropped.
    lo.pacing = false;
    lo.hold_while_closed = false;
    lo.max_write_bytes = kWifiMaxPacketBytes;  // section 4.2
    // Loopback unless asked: on 0.0.0.0 any machine that sends FINDSTACK
    // makes the emulator connect out to it.
    const std::string address = spec_.address.value_or(options.bind_address);
    lo.name = "wifi " + address + ":" + std::to_string(spec_.port);
    link_ = std::make_unique<Link>(driver, std::move(lo));
    wifi_ = std::make_unique<WifiPort>(*link_, address, spec_.port, spec_.host_tcp_port);
  } else {
    lo.hold_while_closed = false;
    const std::string address = spec_.address.value_or(options.bind_address);
    lo.name = "tcp " + address + ":" + std::to_string(spec_.port);
    // The link's log lines name the endpoint actually bound: port 0 asks for
    // any free port, and "tcp 127.0.0.1:0" tells the reader nothing.
    const std::string asked = lo.name;
    auto bound = std::make_shared<std::string>(asked);
    lo.log = [asked, bound, inner = std::move(lo.log)](std::string_view line) {
      if (line.starts_with(asked)) {
        inner(*bound + std::string(line.substr(asked.size())));
      } else {
        inner(line);
      }
    };
    link_ = std::make_unique<Link>(driver, std::move(lo));
    tcp_ = std::make_unique<TcpPort>(*link_, address, spec_.port);
    *bound = "tcp " + tcp_->Where();
  }
}

DeviceServer::~DeviceServer() { Stop(); }

void DeviceServer::Serve(devices::Device& device) {
  if (serving_) return;
  serving_ = true;
  link_->SetDevice(&device);
  if (pty_) pty_->Start();
  if (tcp_) tcp_->Start();
  if (wifi_) wifi_->Start();
}

void DeviceServer::Stop() {
  // The link first: it then closes quietly, without calling the device.
  if (link_) link_->Stop();
  if (pty_) pty_->Stop();
  if (tcp_) tcp_->Stop();
  if (wifi_) wifi_->Stop();
}

std::string DeviceServer::Where() const {
  if (pty_) return "pty " + pty_->link_path() + " -> " + pty_->slave_name();
  if (tcp_) return "tcp " + tcp_->Where();
  if (wifi_) return wifi_->Where();
  return {};
}

void DeviceServer::CutLink(sim::TimeNs duration_ns) {
  link_->Cut(duration_ns, /*close_stream=*/tcp_ != nullptr || wifi_ != nullptr);
}

}  // namespace moco::transport
