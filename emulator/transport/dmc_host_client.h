// A blocking DMC v2 host over a file descriptor (a PTY opened by path, a TCP
// socket), for benchmarks, the soak run and end-to-end tests of served
// devices. Not used by mocosim itself.
#ifndef MOCO_TRANSPORT_DMC_HOST_CLIENT_H_
#define MOCO_TRANSPORT_DMC_HOST_CLIENT_H_

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <termios.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "wire/dmc.h"

namespace moco::transport::testing {

// Opens the host end of a PTY in raw mode; -1 on failure.
inline int OpenPtyHost(const std::string& path) {
  const int fd = open(path.c_str(), O_RDWR | O_NOCTTY | O_CLOEXEC);
  if (fd < 0) return fd;
  termios t{};
  tcgetattr(fd, &t);
  cfmakeraw(&t);
  tcsetattr(fd, TCSANOW, &t);
  return fd;
}

// Connects to 127.0.0.1:port with TCP_NODELAY; -1 on failure.
inline int ConnectTcp(uint16_t port) {
  const int fd = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return -1;
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(port);
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof(a)) != 0) {
    close(fd);
    return -1;
  }
  const int one = 1;
  setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof(one));
  return fd;
}

inline bool WriteAll(int fd, const uint8_t* p, size_t n) {
  while (n > 0) {
    const ssize_t w = write(fd, p, n);
    if (w <= 0) return false;
    p += w;
    n -= static_cast<size_t>(w);
  }
  return true;
}

// One decoded device frame.
struct DeviceFrame {
  uint32_t id = 0;
  uint16_t type = 0;
  dmc::DeviceMessage msg;
};

// Reads device frames from fd (owned by the caller).
class DmcHostClient {
 public:
  explicit DmcHostClient(int fd) : fd_(fd) {}

  bool Send(uint32_t id, const dmc::HostMessage& m) {
    tx_.clear();
    dmc::Encode(id, m, tx_);
    return WriteAll(fd_, tx_.data(), tx_.size());
  }

  // Next frame within timeout_ms (nullopt on timeout, EOF or error). Frames
  // that fail to decode are counted in bad_frames() and skipped.
  std::optional<DeviceFrame> Next(int timeout_ms) {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
    while (queue_.empty()) {
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
                            deadline - std::chrono::steady_clock::now())
                            .count();
      if (left <= 0) return std::nullopt;
      pollfd p{fd_, POLLIN, 0};
      if (poll(&p, 1, static_cast<int>(left)) <= 0) continue;
      uint8_t buf[4096];
      const ssize_t r = read(fd_, buf, sizeof buf);
      if (r <= 0) return std::nullopt;
      decoder_.Feed(wire::ByteView(buf, static_cast<size_t>(r)), [&](const dmc::FrameEvent& e) {
        const auto* f = std::get_if<dmc::FrameRef>(&e);
        if (f == nullptr) {
          ++bad_frames_;
          return;
        }
        auto m = dmc::DecodeDeviceMessage(f->type, f->data);
        if (!m.ok()) {
          ++bad_frames_;
          return;
        }
        queue_.push_back(DeviceFrame{f->id, f->type, m.value()});
      });
    }
    DeviceFrame f = std::move(queue_.front());
    queue_.erase(queue_.begin());
    return f;
  }

  // The reply to `id`, skipping frames with other IDs (unsolicited ones).
  std::optional<DeviceFrame> ReplyTo(uint32_t id, int timeout_ms) {
    while (auto f = Next(timeout_ms)) {
      if (f->id == id) return f;
      ++skipped_;
    }
    return std::nullopt;
  }

  uint64_t bad_frames() const { return bad_frames_; }
  uint64_t skipped() const { return skipped_; }

 private:
  int fd_;
  dmc::FrameDecoder decoder_;
  std::vector<DeviceFrame> queue_;
  wire::Bytes tx_;
  uint64_t bad_frames_ = 0;
  uint64_t skipped_ = 0;
};

}  // namespace moco::transport::testing

#endif  // MOCO_TRANSPORT_DMC_HOST_CLIENT_H_
