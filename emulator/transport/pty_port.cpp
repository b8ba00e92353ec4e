// A device served on a pseudo-terminal with a stable symlink (see pty_port.h).
#include "transport/pty_port.h"

#include <fcntl.h>
#include <pty.h>
#include <sys/inotify.h>
#include <sys/stat.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

#include "base/termios_speed.h"

namespace moco::transport {
namespace {

std::string ErrnoText(int err) { return std::strerror(err); }

void SetNonBlocking(int fd) {
  const int flags = fcntl(fd, F_GETFL);
  if (flags < 0 || fcntl(fd, F_SETFL, flags | O_NONBLOCK) < 0) {
    throw std::runtime_error("cannot make the PTY non-blocking: " + ErrnoText(errno));
  }
}

void SetCloseOnExec(int fd) { (void)fcntl(fd, F_SETFD, FD_CLOEXEC); }

// Raw mode on the slave (cfmakeraw: no echo, no line editing, 8 bits, no
// CR/LF translation), as a serial device's bytes are binary.
bool MakeRaw(int slave_fd) {
  termios t{};
  if (tcgetattr(slave_fd, &t) != 0) return false;
  cfmakeraw(&t);
  t.c_cc[VMIN] = 1;
  t.c_cc[VTIME] = 0;
  return tcsetattr(slave_fd, TCSANOW, &t) == 0;
}

std::string ReadLinkText(const std::string& path) {
  std::string target(4096, '\0');
  const ssize_t n = readlink(path.c_str(), target.data(), target.size());
  if (n < 0) return {};
  target.resize(static_cast<size_t>(n));
  return target;
}

std::string LinkErrorHint(int err) {
  switch (err) {
    case ENOENT:
    case ENOTDIR:
      return " (its directory does not exist; create it or choose another path, e.g. /tmp/dmc16)";
    case EACCES:
    case EPERM:
    case EROFS:
      return " (the directory is not writable; choose a writable path, e.g. /tmp/dmc16)";
    default:
      return "";
  }
}

}  // namespace

// The PTY master as a ByteStream; Reclaim() reads back, through the port's
// own slave descriptor, what the departed host left unread.
class PtyPort::MasterStream final : public AsioByteStream<asio::posix::stream_descriptor> {
 public:
  MasterStream(asio::posix::stream_descriptor master, std::string slave_name, int slave_fd)
      : AsioByteStream(std::move(master), std::move(slave_name)), slave_fd_(slave_fd) {}

  wire::Bytes Reclaim() override {
    wire::Bytes out;
    // A host may have left the line in canonical mode; raw mode makes every
    // buffered byte readable at once.
    MakeRaw(slave_fd_);
    std::array<uint8_t, 4096> buf{};
    for (;;) {
      const ssize_t n = read(slave_fd_, buf.data(), buf.size());
      if (n <= 0) break;  // EAGAIN: nothing left
      out.insert(out.end(), buf.begin(), buf.begin() + n);
    }
    return out;
  }

 private:
  int slave_fd_;  // owned by the PtyPort
};

PtyPort::PtyPort(Link& link, std::string link_path, std::chrono::nanoseconds link_check_period)
    : link_(link), link_path_(std::move(link_path)), link_check_period_(link_check_period) {
  if (link_path_.empty())
    throw std::runtime_error("the PTY link path is empty: give a path such as /tmp/dmc16");
  char name[256] = {};
  if (openpty(&master_fd_, &slave_fd_, name, nullptr, nullptr) != 0) {
    throw std::runtime_error("cannot open a pseudo-terminal: " + ErrnoText(errno) +
                             " (is /dev/ptmx available?)");
  }
  slave_name_ = name;
  try {
    SetCloseOnExec(master_fd_);
    SetCloseOnExec(slave_fd_);
    SetNonBlocking(master_fd_);
    SetNonBlocking(slave_fd_);
    if (!MakeRaw(slave_fd_)) {
      throw std::runtime_error("cannot set raw mode on " + slave_name_ + ": " + ErrnoText(errno));
    }
    if (fchmod(slave_fd_, 0600) != 0) {
      throw std::runtime_error("cannot set mode 0600 on " + slave_name_ + ": " + ErrnoText(errno));
    }
    // Watch before the link exists, so no host can open the port unseen.
    inotify_fd_ = inotify_init1(IN_NONBLOCK | IN_CLOEXEC);
    if (inotify_fd_ >= 0 &&
        inotify_add_watch(inotify_fd_, slave_name_.c_str(), IN_OPEN | IN_CLOSE) < 0) {
      close(inotify_fd_);
      inotify_fd_ = -1;
    }
    CreateLink();
  } catch (...) {
    if (inotify_fd_ >= 0) close(inotify_fd_);
    close(master_fd_);
    close(slave_fd_);
    throw;
  }
}

PtyPort::~PtyPort() {
  Stop();
  alive_.reset();
}

void PtyPort::CreateLink() {
  struct stat st {};
  if (lstat(link_path_.c_str(), &st) == 0) {
    if (!S_ISLNK(st.st_mode)) {
      throw std::runtime_error(link_path_ +
                               " exists and is not a symlink: refusing to replace it; remove it "
                               "or choose another PTY path");
    }
    const std::string old_target = ReadLinkText(link_path_);
    struct stat target {};
    if (stat(link_path_.c_str(), &target) == 0) {
      throw std::runtime_error(link_path_ + " is a symlink to " + old_target +
                               ", which exists (another emulator may be serving it): remove " +
                               link_path_ + " or choose another PTY path");
    }
    link_.Log("replacing stale link " + link_path_ + " -> " + old_target);
  }
  // Create under a temporary name and rename over: the path never points
  // nowhere, and a stale link is replaced atomically.
  const std::string tmp = link_path_ + ".tmp." + std::to_string(getpid());
  unlink(tmp.c_str());
  if (symlink(slave_name_.c_str(), tmp.c_str()) != 0) {
    const int err = errno;
    throw std::runtime_error("cannot create the PTY link " + link_path_ + ": " + ErrnoText(err) +
                             LinkErrorHint(err));
  }
  if (rename(tmp.c_str(), link_path_.c_str()) != 0) {
    const int err = errno;
    unlink(tmp.c_str());
    throw std::runtime_error("cannot create the PTY link " + link_path_ + ": " + ErrnoText(err) +
                             LinkErrorHint(err));
  }
  link_created_ = true;
}

void PtyPort::Start() {
  if (started_ || stopped_) return;
  started_ = true;
  asio::io_context& io = link_.driver().io();
  auto stream = std::make_unique<MasterStream>(asio::posix::stream_descriptor(io, master_fd_),
                                               slave_name_, slave_fd_);
  master_fd_ = -1;
  // Until a host opens the slave, device output waits in the link's queue.
  link_.SetHostPresent(!detects_host());
  link_.Attach(std::move(stream),
               [this, weak = std::weak_ptr<bool>(alive_)](const std::string& reason) {
                 if (weak.expired()) return;
                 link_.Log("PTY " + slave_name_ + " failed: " + reason);
               });
  if (detects_host()) {
    inotify_ = std::make_unique<asio::posix::stream_descriptor>(io, inotify_fd_);
    WatchHost();
  }
  if (link_check_period_.count() > 0) {
    link_timer_ = std::make_unique<asio::steady_timer>(io);
    ScheduleLinkCheck();
  }
}

void PtyPort::ScheduleLinkCheck() {
  link_timer_->expires_after(link_check_period_);
  link_timer_->async_wait([this, weak = std::weak_ptr<bool>(alive_)](const ErrorCode& ec) {
    if (weak.expired() || ec || stopped_) return;
    CheckLink();
    ScheduleLinkCheck();
  });
}

void PtyPort::CheckLink() {
  struct stat st {};
  if (lstat(link_path_.c_str(), &st) == 0) {
    const bool ours = S_ISLNK(st.st_mode) && ReadLinkText(link_path_) == slave_name_;
    if (!ours && !link_foreign_) {
      link_.Log("the PTY link " + link_path_ +
                " was replaced by something else; leaving it alone (the PTY is still " +
                slave_name_ + ")");
    }
    link_foreign_ = !ours;
    return;
  }
  if (errno != ENOENT) return;
  // symlink() itself fails with EEXIST when something appeared meanwhile:
  // nothing is ever replaced here.
  if (symlink(slave_name_.c_str(), link_path_.c_str()) == 0) {
    link_created_ = true;
    link_foreign_ = false;
    link_.Log("the PTY link " + link_path_ + " was deleted; created it again -> " + slave_name_);
  } else if (errno != EEXIST) {
    link_.Log("the PTY link " + link_path_ + " was deleted and cannot be created again: " +
              ErrnoText(errno) + " (the PTY is still " + slave_name_ + ")");
    link_created_ = false;
  }
}

void PtyPort::WatchHost() {
  inotify_->async_read_some(asio::buffer(inotify_buf_), [this, weak = std::weak_ptr<bool>(alive_)](
                                                            const ErrorCode& ec, size_t n) {
    if (weak.expired()) return;
    OnInotify(ec, n);
  });
}

void PtyPort::OnInotify(const ErrorCode& ec, size_t n) {
  if (stopped_) return;
  if (ec) {
    link_.Log("host detection stopped (" + ec.message() + "); assuming a host is present");
    link_.SetHostPresent(true);
    return;
  }
  bool lost_track = false;
  size_t off = 0;
  while (off + sizeof(inotify_event) <= n) {
    inotify_event ev{};
    std::memcpy(&ev, inotify_buf_.data() + off, sizeof(ev));
    off += sizeof(inotify_event) + ev.len;
    if (ev.mask & IN_OPEN) ++host_opens_;
    if (ev.mask & IN_CLOSE) host_opens_ = std::max(0, host_opens_ - 1);
    if (ev.mask & (IN_Q_OVERFLOW | IN_IGNORED)) lost_track = true;
  }
  if (lost_track) {
    // Events were lost or the watch is gone: the count is no longer known.
    link_.Log("lost track of host open/close; assuming a host is present");
    host_opens_ = std::max(host_opens_, 1);
  }
  link_.SetHostPresent(host_opens_ > 0);
  WatchHost();
}

uint32_t PtyPort::LineBaud() const {
  termios t{};
  if (slave_fd_ < 0 || tcgetattr(slave_fd_, &t) != 0) return 0;
  return base::BaudOfTermiosSpeed(cfgetospeed(&t)).value_or(0);
}

bool PtyPort::SetLineBaud(uint32_t baud) {
  termios t{};
  if (slave_fd_ < 0 || tcgetattr(slave_fd_, &t) != 0) return false;
  const std::optional<speed_t> speed = base::TermiosSpeed(baud);
  if (!speed) return false;
  cfsetispeed(&t, *speed);
  cfsetospeed(&t, *speed);
  return tcsetattr(slave_fd_, TCSANOW, &t) == 0;
}

void PtyPort::Stop() {
  if (stopped_) return;
  stopped_ = true;
  if (inotify_) {
    ErrorCode ignored;
    inotify_->close(ignored);
  } else if (inotify_fd_ >= 0) {
    close(inotify_fd_);
  }
  inotify_fd_ = -1;
  if (link_timer_) link_timer_->cancel();
  if (link_created_ && ReadLinkText(link_path_) == slave_name_) unlink(link_path_.c_str());
  link_created_ = false;
  if (started_) {
    link_.Detach();
  } else if (master_fd_ >= 0) {
    close(master_fd_);
  }
  master_fd_ = -1;
  if (slave_fd_ >= 0) close(slave_fd_);
  slave_fd_ = -1;
}

}  // namespace moco::transport
