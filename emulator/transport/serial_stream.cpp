// The device end of a recording tap: a serial port or a TCP connection (see serial_stream.h).
#include "transport/serial_stream.h"

#include <fcntl.h>
#include <linux/serial.h>
#include <sys/ioctl.h>
#include <sys/stat.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

#include "base/termios_speed.h"
#include "wire/protocol.h"

namespace moco::transport {
namespace {

// That `baud` cannot be set, the rates that can, and the protocols' lines.
std::string BaudHint(uint32_t baud) {
  return base::NonStandardBaudHint(baud, "the protocols' lines: " + wire::DefaultBaudList());
}

std::optional<std::string> Apply(int fd, uint32_t baud, bool rtscts) {
  const std::optional<speed_t> speed = base::TermiosSpeed(baud);
  if (!speed) return BaudHint(baud);
  termios t{};
  if (tcgetattr(fd, &t) != 0) return std::string("tcgetattr: ") + std::strerror(errno);
  cfmakeraw(&t);
  t.c_cflag &= ~static_cast<tcflag_t>(CSIZE | PARENB | CSTOPB | CRTSCTS);
  t.c_cflag |= CS8 | CLOCAL | CREAD;
  if (rtscts) t.c_cflag |= CRTSCTS;
  t.c_iflag &= ~static_cast<tcflag_t>(IXON | IXOFF | IXANY);
  t.c_cc[VMIN] = 1;
  t.c_cc[VTIME] = 0;
  cfsetispeed(&t, *speed);
  cfsetospeed(&t, *speed);
  if (tcsetattr(fd, TCSANOW, &t) != 0) return std::string("tcsetattr: ") + std::strerror(errno);
  return std::nullopt;
}

// Asks the driver to pass received bytes on at once (ASYNC_LOW_LATENCY, a
// flag an unprivileged user may set). Best effort: a PTY or a driver without
// serial_struct refuses it, and the port works as it is.
bool SetLowLatency(int fd) {
  serial_struct s{};
  if (ioctl(fd, TIOCGSERIAL, &s) != 0) return false;
  if ((s.flags & ASYNC_LOW_LATENCY) != 0) return true;
  s.flags |= ASYNC_LOW_LATENCY;
  if (ioctl(fd, TIOCSSERIAL, &s) != 0) return false;
  return ioctl(fd, TIOCGSERIAL, &s) == 0 && (s.flags & ASYNC_LOW_LATENCY) != 0;
}

}  // namespace

bool IsStandardBaud(uint32_t baud) { return base::TermiosSpeed(baud).has_value(); }

std::unique_ptr<SerialStream> SerialStream::Open(asio::io_context& io, const std::string& path,
                                                 const SerialSettings& settings) {
  if (!IsStandardBaud(settings.baud)) {
    throw std::runtime_error("serial port " + path + ": " + BaudHint(settings.baud));
  }
  const int fd = open(path.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) {
    const int err = errno;
    std::string hint;
    if (err == ENOENT) hint = " (is the device plugged in? give its path, e.g. /dev/ttyUSB0)";
    if (err == EACCES || err == EPERM) {
      hint = " (add yourself to the group owning it, e.g. `sudo usermod -aG dialout $USER`)";
    }
    if (err == EBUSY) hint = " (another program has it open)";
    throw std::runtime_error("cannot open serial port " + path + ": " + std::strerror(err) + hint);
  }
  struct stat st {};
  if (fstat(fd, &st) != 0 || !S_ISCHR(st.st_mode) || !isatty(fd)) {
    close(fd);
    throw std::runtime_error(path +
                             " is not a serial port (not a terminal device): give the device's "
                             "port, e.g. serial:/dev/ttyUSB0, or tcp:HOST:PORT");
  }
  if (auto error = Apply(fd, settings.baud, settings.rtscts)) {
    close(fd);
    throw std::runtime_error("cannot set up serial port " + path + ": " + *error);
  }
  const bool low_latency = SetLowLatency(fd);
  return std::unique_ptr<SerialStream>(
      new SerialStream(asio::posix::stream_descriptor(io, fd), path, settings.baud, low_latency));
}

std::optional<std::string> SerialStream::SetBaud(uint32_t baud) {
  const std::optional<speed_t> speed = base::TermiosSpeed(baud);
  if (!speed) return BaudHint(baud);
  const int fd = stream().native_handle();
  termios t{};
  if (tcgetattr(fd, &t) != 0) return std::string("tcgetattr: ") + std::strerror(errno);
  cfsetispeed(&t, *speed);
  cfsetospeed(&t, *speed);
  // TCSADRAIN: bytes already written leave at the old speed.
  if (tcsetattr(fd, TCSADRAIN, &t) != 0) return std::string("tcsetattr: ") + std::strerror(errno);
  baud_ = baud;
  return std::nullopt;
}

std::unique_ptr<ByteStream> ConnectTcpStream(asio::io_context& io, const std::string& host,
                                             uint16_t port) {
  const std::string where = host + ":" + std::to_string(port);
  ErrorCode ec;
  asio::ip::tcp::resolver resolver(io);
  const auto endpoints = resolver.resolve(host, std::to_string(port), ec);
  if (ec) {
    throw std::runtime_error("cannot resolve the device address " + where + ": " + ec.message() +
                             " (give tcp:HOST:PORT, e.g. tcp:192.168.1.20:5000)");
  }
  asio::ip::tcp::socket socket(io);
  asio::connect(socket, endpoints, ec);
  if (ec) {
    throw std::runtime_error("cannot connect to the device at " + where + ": " + ec.message() +
                             " (is it listening there?)");
  }
  socket.set_option(asio::ip::tcp::no_delay(true), ec);
  return std::make_unique<AsioByteStream<asio::ip::tcp::socket>>(std::move(socket), where);
}

}  // namespace moco::transport
