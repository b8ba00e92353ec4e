// A device served on a pseudo-terminal (ARCHITECTURE house style 9, like
// Klipper's src/linux/console.c and socat's link=): openpty, raw mode, the
// non-blocking master in an Asio posix::stream_descriptor, and a stable
// symlink to the slave at a path the user chose.
#ifndef MOCO_TRANSPORT_PTY_PORT_H_
#define MOCO_TRANSPORT_PTY_PORT_H_

#include <array>
#include <chrono>
#include <cstdint>
#include <memory>
#include <string>

#include "transport/asio.h"
#include "transport/link.h"

namespace moco::transport {

// Serves a Link on a PTY.
//
// Host open/close: the port keeps its own descriptor of the slave open, so
// the master never sees a hang-up (EIO) when the host closes, and the kernel
// keeps the slave's input buffer across a reopen. It watches the slave device
// node with inotify (IN_OPEN / IN_CLOSE) to count the host's descriptors; the
// Link writes only while a host has the port open, so device output written
// while it is closed waits in the Link's queue (bounded by
// LinkOptions::max_queue_bytes) and is delivered after the reopen. When the
// host closes, bytes it left unread in the kernel buffer are read back
// through the port's own slave descriptor and re-queued ahead of newer
// output: each byte reaches the host exactly once, in order (exact when the
// host used the port in raw, non-canonical mode; a canonical-mode host's
// partial line is discarded by the kernel's line discipline). Without inotify
// the host is assumed present and nothing is reported to the device.
//
// The symlink: every `link_check_period` the port checks (lstat) that the
// path still exists; when it is gone (deleted while serving) the port logs it
// and creates the symlink again. Whatever else appeared at the path (a file,
// another symlink) is logged once and left alone, never replaced.
//
// The Link must outlive the port.
class PtyPort {
 public:
  static constexpr std::chrono::milliseconds kDefaultLinkCheckPeriod{1000};

  // Opens the PTY, sets raw mode and slave mode 0600, and creates the symlink
  // `link_path` -> the slave. A symlink already at link_path is replaced when
  // dangling (left by an earlier run); anything else there is refused.
  // Throws std::runtime_error with a message a user can act on (path exists,
  // directory missing or not writable, no PTYs available).
  PtyPort(Link& link, std::string link_path,
          std::chrono::nanoseconds link_check_period = kDefaultLinkCheckPeriod);
  ~PtyPort();
  PtyPort(const PtyPort&) = delete;
  PtyPort& operator=(const PtyPort&) = delete;

  // Attaches the master to the link and starts watching the host.
  void Start();
  // Closes the PTY and removes the symlink (if it still points at this PTY).
  // Idempotent; called by the destructor.
  void Stop();

  const std::string& link_path() const { return link_path_; }
  const std::string& slave_name() const { return slave_name_; }  // "/dev/pts/N"
  // Whether host open/close is detected (inotify available).
  bool detects_host() const { return inotify_fd_ >= 0; }
  // Host descriptors currently open on the slave (0 when !detects_host()).
  int host_opens() const { return host_opens_; }
  // The line speed set on the PTY (the host's tcsetattr, or SetLineBaud), in
  // baud; 0 when it cannot be read or is not a standard rate. A PTY moves
  // bytes at any speed: the setting is what the host asked of its "port".
  uint32_t LineBaud() const;
  // Sets the PTY's line speed as a serial port's would read back. False when
  // `baud` is not a standard rate or the PTY is closed.
  bool SetLineBaud(uint32_t baud);

 private:
  class MasterStream;
  void CreateLink();
  void WatchHost();
  void OnInotify(const ErrorCode& ec, size_t n);
  void ScheduleLinkCheck();
  void CheckLink();

  Link& link_;
  std::string link_path_;
  std::string slave_name_;
  int master_fd_ = -1;  // owned by the MasterStream once Start()ed
  int slave_fd_ = -1;
  int inotify_fd_ = -1;  // owned by inotify_ once Start()ed
  bool link_created_ = false;
  bool link_foreign_ = false;  // something else took the path; reported once
  std::chrono::nanoseconds link_check_period_;
  std::unique_ptr<asio::steady_timer> link_timer_;
  bool started_ = false;
  bool stopped_ = false;
  int host_opens_ = 0;
  std::unique_ptr<asio::posix::stream_descriptor> inotify_;
  std::array<char, 4096> inotify_buf_{};
  std::shared_ptr<bool> alive_ = std::make_shared<bool>(true);
};

}  // namespace moco::transport

#endif  // MOCO_TRANSPORT_PTY_PORT_H_
