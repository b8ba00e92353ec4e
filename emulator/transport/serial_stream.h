// The device end of a recording tap (docs/tap.md): a serial port opened as a
// real device's line (termios: raw, 8N1, no flow control unless asked) or a
// TCP connection to a device, each as a ByteStream.
#ifndef MOCO_TRANSPORT_SERIAL_STREAM_H_
#define MOCO_TRANSPORT_SERIAL_STREAM_H_

#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "transport/asio.h"
#include "transport/link.h"

namespace moco::transport {

struct SerialSettings {
  uint32_t baud = 0;    // a standard rate (IsStandardBaud); the tap gives its line's
  bool rtscts = false;  // hardware flow control (CRTSCTS); off: none at all
};

// Whether `baud` is one termios can set (50 .. 4000000, the standard rates).
bool IsStandardBaud(uint32_t baud);

// A serial port (a USB adapter, a UART, or a PTY standing in for one) as a
// ByteStream. Raw mode: no echo, no line editing, no CR/LF translation, no
// software flow control, 8 data bits, no parity, 1 stop bit, CLOCAL|CREAD.
class SerialStream final : public AsioByteStream<asio::posix::stream_descriptor> {
 public:
  // Opens `path` (O_NOCTTY, non-blocking) and applies `settings`. Throws
  // std::runtime_error naming the path, the problem and the fix: missing,
  // not permitted (the dialout group), not a character device, not a
  // terminal, or a baud rate termios cannot set.
  static std::unique_ptr<SerialStream> Open(asio::io_context& io, const std::string& path,
                                            const SerialSettings& settings);
  // Changes the line's speed in both directions from the next byte on.
  // Returns an error message, or nullopt.
  std::optional<std::string> SetBaud(uint32_t baud);
  uint32_t baud() const { return baud_; }
  // Whether the driver took the low-latency flag (ASYNC_LOW_LATENCY, asked
  // for at open): a USB adapter then hands each received byte on at once
  // instead of holding it for its latency timer (an FTDI chip's is 16 ms by
  // default, which would add up to 16 ms to every reply). Ports without the
  // setting (a PTY, some adapters) say false and work as before.
  bool low_latency() const { return low_latency_; }

 private:
  SerialStream(asio::posix::stream_descriptor fd, std::string path, uint32_t baud, bool low_latency)
      : AsioByteStream(std::move(fd), std::move(path)), baud_(baud), low_latency_(low_latency) {}
  uint32_t baud_;
  bool low_latency_;
};

// Connects to a device listening on TCP (blocking, at start-up). Throws
// std::runtime_error naming the address and the fix.
std::unique_ptr<ByteStream> ConnectTcpStream(asio::io_context& io, const std::string& host,
                                             uint16_t port);

}  // namespace moco::transport

#endif  // MOCO_TRANSPORT_SERIAL_STREAM_H_
