// The control socket: a unix-domain JSON Lines server (see control_socket.h).
#include "transport/control_socket.h"

#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <exception>
#include <stdexcept>

namespace moco::transport {
namespace {

using Protocol = asio::local::stream_protocol;

constexpr std::string_view kInternalError =
    R"({"ok":false,"error":"internal error while handling the request"})";
constexpr std::string_view kTooManyClients =
    R"({"ok":false,"error":"too many control clients are connected: close one and retry"})";

std::string KindOfFile(mode_t mode) {
  if (S_ISDIR(mode)) return "a directory";
  if (S_ISREG(mode)) return "a regular file";
  if (S_ISLNK(mode)) return "a symbolic link";
  if (S_ISFIFO(mode)) return "a FIFO";
  if (S_ISCHR(mode) || S_ISBLK(mode)) return "a device file";
  return "not a socket";
}

// Whether a process accepts connections on the unix socket at `path`.
bool SomeoneListens(asio::io_context& io, const std::string& path) {
  Protocol::socket probe(io);
  ErrorCode ec;
  probe.connect(Protocol::endpoint(path), ec);
  return !ec;
}

// Makes the path free for a new socket, or throws saying why it cannot be.
void ClearPath(asio::io_context& io, const std::string& path) {
  struct stat st {};
  if (::lstat(path.c_str(), &st) != 0) {
    if (errno == ENOENT) return;
    throw std::runtime_error("control socket " + path + ": " + std::strerror(errno));
  }
  if (!S_ISSOCK(st.st_mode)) {
    throw std::runtime_error("control socket " + path + ": the path exists and is " +
                             KindOfFile(st.st_mode) +
                             "; remove it or choose another path for the control socket");
  }
  if (SomeoneListens(io, path)) {
    throw std::runtime_error("control socket " + path +
                             ": another process is serving it; stop that process or choose "
                             "another path");
  }
  // A stale socket left by a process that ended without removing it.
  if (::unlink(path.c_str()) != 0 && errno != ENOENT) {
    throw std::runtime_error("control socket " + path + ": cannot remove the stale socket (" +
                             std::strerror(errno) + ")");
  }
}

}  // namespace

ControlSocket::ControlSocket(RealtimeDriver& driver, std::string path, LineHandler handler,
                             ControlSocketOptions options)
    : driver_(driver),
      path_(std::move(path)),
      handler_(std::move(handler)),
      options_(std::move(options)),
      acceptor_(driver.io()) {
  if (!options_.log) options_.log = LogToStderr;
  if (options_.max_line_bytes == 0) options_.max_line_bytes = 1;
  if (options_.max_clients == 0) options_.max_clients = 1;
  constexpr size_t kMaxPath = sizeof(sockaddr_un::sun_path) - 1;
  if (path_.empty()) throw std::runtime_error("control socket: the path is empty");
  if (path_.size() > kMaxPath) {
    throw std::runtime_error("control socket " + path_ + ": the path is " +
                             std::to_string(path_.size()) + " bytes, longer than the " +
                             std::to_string(kMaxPath) +
                             " a unix socket allows; choose a shorter path (e.g. under /tmp)");
  }
  ClearPath(driver_.io(), path_);

  const Protocol::endpoint endpoint(path_);
  ErrorCode ec;
  acceptor_.open(endpoint.protocol(), ec);
  if (!ec) acceptor_.bind(endpoint, ec);
  if (ec) {
    const std::string why = ec == boost::system::errc::no_such_file_or_directory
                                ? "its directory does not exist; create it or choose another path"
                                : ec.message();
    throw std::runtime_error("control socket " + path_ + ": cannot bind: " + why);
  }
  // Owner only, set before listen(): nobody can connect until then.
  struct stat st {};
  if (::chmod(path_.c_str(), 0600) != 0 || ::lstat(path_.c_str(), &st) != 0) {
    const std::string why = std::strerror(errno);
    ::unlink(path_.c_str());
    throw std::runtime_error("control socket " + path_ + ": cannot set mode 0600: " + why);
  }
  file_dev_ = st.st_dev;
  file_ino_ = st.st_ino;
  acceptor_.listen(asio::socket_base::max_listen_connections, ec);
  if (ec) {
    ::unlink(path_.c_str());
    throw std::runtime_error("control socket " + path_ + ": cannot listen: " + ec.message());
  }
  Accept();
}

ControlSocket::~ControlSocket() {
  Stop();
  alive_.reset();
}

void ControlSocket::Log(const std::string& line) const { options_.log("control " + line); }

void ControlSocket::Stop() {
  if (stopped_) return;
  stopped_ = true;
  ErrorCode ignored;
  acceptor_.close(ignored);
  for (const ClientPtr& c : clients_) {
    c->closed = true;
    c->socket.close(ignored);
  }
  clients_.clear();
  // Only our own file: another process may have replaced it meanwhile.
  struct stat st {};
  if (::lstat(path_.c_str(), &st) == 0 && S_ISSOCK(st.st_mode) && st.st_dev == file_dev_ &&
      st.st_ino == file_ino_) {
    ::unlink(path_.c_str());
  }
}

void ControlSocket::Accept() {
  acceptor_.async_accept(
      [this, weak = std::weak_ptr<bool>(alive_)](const ErrorCode& ec, Socket socket) {
        if (weak.expired() || stopped_) return;
        if (ec) {
          if (ec == asio::error::operation_aborted) return;
          Log("accept failed: " + ec.message());
          Accept();
          return;
        }
        auto c = std::make_shared<Client>(std::move(socket));
        clients_.push_back(c);
        if (clients_.size() > options_.max_clients) {
          Log(path_ + ": refused a client: " + std::to_string(options_.max_clients) +
              " already connected");
          c->out.append(kTooManyClients);
          c->out.push_back('\n');
          c->closing = true;
          PumpWrite(c);
        } else {
          StartRead(c);
        }
        Accept();
      });
}

void ControlSocket::StartRead(const ClientPtr& c) {
  if (stopped_ || c->closed || c->closing || c->eof || c->reading) return;
  if (c->Pending() > options_.max_pending_reply_bytes) return;
  if (c->inbox.find('\n') != std::string::npos) return;  // held back: lines still to handle
  c->reading = true;
  c->socket.async_read_some(asio::buffer(c->read_buf), [this, weak = std::weak_ptr<bool>(alive_),
                                                        c](const ErrorCode& ec, size_t n) {
    if (weak.expired()) return;
    c->reading = false;
    OnRead(c, ec, n);
  });
}

void ControlSocket::OnRead(const ClientPtr& c, const ErrorCode& ec, size_t n) {
  if (stopped_ || c->closed) return;
  if (ec == asio::error::eof) {
    c->eof = true;
  } else if (ec) {
    Close(c);
    return;
  } else {
    c->inbox.append(c->read_buf.data(), n);
  }
  Process(c);
}

void ControlSocket::RefuseLongLine(const ClientPtr& c) {
  Log(path_ + ": a request line exceeded " + std::to_string(options_.max_line_bytes) +
      " bytes; closing that client");
  c->inbox.clear();
  c->out += R"({"ok":false,"error":"request line longer than )" +
            std::to_string(options_.max_line_bytes) +
            R"( bytes: send one JSON object per line, each shorter; closing"})";
  c->out.push_back('\n');
  c->closing = true;
}

void ControlSocket::Process(const ClientPtr& c) {
  size_t start = 0;
  while (!stopped_ && !c->closed && !c->closing &&
         c->Pending() <= options_.max_pending_reply_bytes) {
    const size_t nl = c->inbox.find('\n', start);
    const size_t length = (nl == std::string::npos ? c->inbox.size() : nl) - start;
    if (length > options_.max_line_bytes) {
      RefuseLongLine(c);
      start = 0;
      break;
    }
    if (nl == std::string::npos) {
      // Half-closed: a last line without '\n' is still a request.
      if (c->eof) {
        if (length > 0) HandleLine(c, std::string_view(c->inbox).substr(start, length));
        start = c->inbox.size();
        c->closing = true;
      }
      break;
    }
    HandleLine(c, std::string_view(c->inbox).substr(start, length));
    start = nl + 1;
  }
  if (stopped_ || c->closed) return;
  c->inbox.erase(0, start);
  PumpWrite(c);
  StartRead(c);
}

void ControlSocket::HandleLine(const ClientPtr& c, std::string_view line) {
  ++lines_handled_;
  std::string reply;
  driver_.Sync();
  try {
    reply = handler_(line);
  } catch (const std::exception& e) {
    Log(path_ + ": the request handler failed: " + e.what());
    reply = kInternalError;
  }
  driver_.Kick();
  std::replace(reply.begin(), reply.end(), '\n', ' ');
  c->out += reply;
  c->out.push_back('\n');
}

void ControlSocket::PumpWrite(const ClientPtr& c) {
  if (stopped_ || c->closed || c->write_pending) return;
  if (c->out.empty()) {
    if (c->closing) Close(c);
    return;
  }
  c->writing.clear();
  c->writing.swap(c->out);
  c->write_pending = true;
  asio::async_write(c->socket, asio::buffer(c->writing),
                    [this, weak = std::weak_ptr<bool>(alive_), c](const ErrorCode& ec, size_t) {
                      if (weak.expired()) return;
                      c->write_pending = false;
                      if (stopped_ || c->closed) return;
                      if (ec) {
                        Close(c);
                        return;
                      }
                      c->writing.clear();
                      Process(c);  // resumes a client held back by its unread replies
                    });
}

void ControlSocket::Close(const ClientPtr& c) {
  if (c->closed) return;
  c->closed = true;
  ErrorCode ignored;
  c->socket.shutdown(Protocol::socket::shutdown_both, ignored);
  c->socket.close(ignored);
  clients_.erase(std::remove(clients_.begin(), clients_.end(), c), clients_.end());
}

}  // namespace moco::transport
