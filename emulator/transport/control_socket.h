// The control socket (docs/control.md "The control socket"): a unix-domain
// stream socket serving JSON Lines, one reply line per request line, on the
// io thread that drives the one clock.
#ifndef MOCO_TRANSPORT_CONTROL_SOCKET_H_
#define MOCO_TRANSPORT_CONTROL_SOCKET_H_

#include <sys/types.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "transport/asio.h"
#include "transport/link.h"
#include "transport/realtime_driver.h"

namespace moco::transport {

struct ControlSocketOptions {
  // The longest request line accepted, without its '\n'. A longer one gets an
  // error reply and the client is closed.
  size_t max_line_bytes = 64 * 1024;
  // Clients served at once; one more gets an error reply and is closed.
  size_t max_clients = 16;
  // A client's replies waiting to be written; above this, its requests are
  // not read until it reads its replies (the kernel then holds it back).
  size_t max_pending_reply_bytes = 1024 * 1024;
  LogFn log = LogToStderr;
};

// Serves JSON Lines on a unix socket at `path`. Each request line (up to
// '\n'; a trailing '\r' is kept for the handler, which may strip it) is
// passed to the handler without its '\n'; the handler's return value is
// written back followed by '\n', in request order, per client. A last line
// without '\n' before the client half-closes is handled too. Several clients
// are served at once, each independently.
//
// The handler runs on the io thread with the scheduler synced to the wall
// clock (RealtimeDriver::Sync) and the driver is kicked after it, so it may
// act on devices and schedule timers. It must not destroy the socket.
// Newlines in its reply are replaced by spaces (one reply = one line).
//
// The socket file has mode 0600. A stale socket file at `path` (nobody
// listening) is replaced; a live one, or any other kind of file, is refused.
// The file is removed by Stop() and the destructor (if it is still ours).
// The driver must outlive the socket; single-threaded (the io thread).
class ControlSocket {
 public:
  using LineHandler = std::function<std::string(std::string_view line)>;

  // Binds and listens at once, and accepts clients as the io_context runs.
  // Throws std::runtime_error with a message a user can act on: a path too
  // long for a unix socket, a path that exists and is not a socket, a socket
  // another process still serves, a directory that does not exist.
  ControlSocket(RealtimeDriver& driver, std::string path, LineHandler handler,
                ControlSocketOptions options = {});
  ~ControlSocket();
  ControlSocket(const ControlSocket&) = delete;
  ControlSocket& operator=(const ControlSocket&) = delete;

  // Closes every client and the listening socket, removes the socket file.
  // Idempotent.
  void Stop();

  const std::string& path() const { return path_; }
  size_t client_count() const { return clients_.size(); }
  uint64_t lines_handled() const { return lines_handled_; }

 private:
  using Socket = asio::local::stream_protocol::socket;
  struct Client {
    explicit Client(Socket s) : socket(std::move(s)) {}
    Socket socket;
    std::array<char, 4096> read_buf{};
    std::string inbox;    // bytes read, not yet handled (no complete line, unless held back)
    std::string out;      // replies waiting to be written
    std::string writing;  // the replies being written
    bool reading = false;
    bool write_pending = false;
    bool eof = false;      // the client half-closed
    bool closing = false;  // close once `out` and `writing` are written
    bool closed = false;
    size_t Pending() const { return out.size() + writing.size(); }
  };
  using ClientPtr = std::shared_ptr<Client>;

  void Accept();
  void StartRead(const ClientPtr& c);
  void OnRead(const ClientPtr& c, const ErrorCode& ec, size_t n);
  // Handles the complete lines in the inbox while the client's pending
  // replies allow, then writes and reads on.
  void Process(const ClientPtr& c);
  void HandleLine(const ClientPtr& c, std::string_view line);
  void RefuseLongLine(const ClientPtr& c);
  void PumpWrite(const ClientPtr& c);
  void Close(const ClientPtr& c);
  void Log(const std::string& line) const;

  RealtimeDriver& driver_;
  std::string path_;
  LineHandler handler_;
  ControlSocketOptions options_;
  asio::local::stream_protocol::acceptor acceptor_;
  std::vector<ClientPtr> clients_;
  dev_t file_dev_ = 0;  // identity of the socket file we created
  ino_t file_ino_ = 0;
  bool stopped_ = false;
  uint64_t lines_handled_ = 0;
  std::shared_ptr<bool> alive_ = std::make_shared<bool>(true);
};

}  // namespace moco::transport

#endif  // MOCO_TRANSPORT_CONTROL_SOCKET_H_
