// Output policy, bounded reads, numbered copies and locks (see file_io.h).
#include "base/file_io.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <utility>

namespace moco::base {
namespace {

namespace fs = std::filesystem;

std::string Errno(int e) { return std::strerror(e); }

std::string ParentOf(const std::string& path) {
  const std::string parent = fs::path(path).parent_path().string();
  return parent.empty() ? "." : parent;
}

PathKind KindOf(mode_t mode) {
  if (S_ISREG(mode)) return PathKind::kRegular;
  if (S_ISDIR(mode)) return PathKind::kDirectory;
  if (S_ISCHR(mode)) return PathKind::kCharDevice;
  if (S_ISFIFO(mode)) return PathKind::kFifo;
  return PathKind::kOther;
}

std::string KindOfMode(mode_t mode) {
  if (S_ISSOCK(mode)) return "a socket";
  if (S_ISBLK(mode)) return "a block device";
  return std::string(PathKindName(KindOf(mode)));
}

// Writes all of `bytes` to `fd`. A FIFO whose reader has gone raises SIGPIPE,
// which would end the program: it is held back for the write and dropped, so
// the write fails with EPIPE instead. Returns 0 or an errno.
int WriteAll(int fd, std::string_view bytes) {
  sigset_t pipe_set, old_set;
  sigemptyset(&pipe_set);
  sigaddset(&pipe_set, SIGPIPE);
  sigset_t pending;
  sigemptyset(&pending);
  sigpending(&pending);
  const bool was_pending = sigismember(&pending, SIGPIPE) == 1;
  pthread_sigmask(SIG_BLOCK, &pipe_set, &old_set);
  int error = 0;
  while (!bytes.empty()) {
    const ssize_t n = ::write(fd, bytes.data(), bytes.size());
    if (n < 0) {
      if (errno == EINTR) continue;
      error = errno;
      break;
    }
    bytes.remove_prefix(static_cast<size_t>(n));
  }
  if (error == EPIPE && !was_pending) {
    const timespec zero{0, 0};
    while (sigtimedwait(&pipe_set, nullptr, &zero) < 0 && errno == EINTR) {
    }
  }
  pthread_sigmask(SIG_SETMASK, &old_set, nullptr);
  return error;
}

std::atomic<uint64_t> temporary_counter{0};

}  // namespace

namespace internal {
uint64_t NextTemporaryNumber() { return temporary_counter.load(); }
}  // namespace internal

std::string_view PathKindName(PathKind kind) {
  switch (kind) {
    case PathKind::kMissing:
      return "missing";
    case PathKind::kRegular:
      return "a regular file";
    case PathKind::kDirectory:
      return "a directory";
    case PathKind::kCharDevice:
      return "a character device";
    case PathKind::kFifo:
      return "a FIFO";
    case PathKind::kOther:
      return "a special file";
  }
  return "a special file";
}

std::optional<std::string> ResolveOutput(const std::string& path, OutputTarget* out) {
  if (path.empty()) return std::string("an empty path; give a file name");
  std::string current = path;
  for (int hops = 0; hops < 40; ++hops) {
    struct stat st {};
    if (::lstat(current.c_str(), &st) != 0) {
      const int e = errno;
      if (e != ENOENT) return path + ": " + Errno(e) + "; check the path";
      // A new file: its directory must exist.
      const std::string dir = ParentOf(current);
      struct stat dst {};
      if (::stat(dir.c_str(), &dst) != 0 || !S_ISDIR(dst.st_mode)) {
        return path + ": the directory " + dir +
               " does not exist; create it first or choose another path";
      }
      out->path = current;
      out->kind = PathKind::kMissing;
      return std::nullopt;
    }
    if (S_ISLNK(st.st_mode)) {
      char buffer[4096];
      const ssize_t n = ::readlink(current.c_str(), buffer, sizeof buffer - 1);
      if (n < 0) return path + ": cannot read the symlink " + current + ": " + Errno(errno);
      const fs::path link(std::string(buffer, static_cast<size_t>(n)));
      current = link.is_absolute() ? link.string() : (fs::path(ParentOf(current)) / link).string();
      continue;
    }
    out->path = current;
    out->kind = KindOf(st.st_mode);
    if (out->kind == PathKind::kDirectory) {
      return path + ": is a directory; give a file path inside it (e.g. " +
             (fs::path(path) / "out.txt").string() + ")";
    }
    if (out->kind == PathKind::kOther) {
      return path + ": is " + KindOfMode(st.st_mode) +
             "; give a regular file, a FIFO or a character device such as /dev/null";
    }
    return std::nullopt;
  }
  return path + ": too many levels of symlinks (a loop?); point it at a file";
}

std::optional<std::string> CheckOutputPath(const std::string& path, std::string_view what) {
  const std::string prefix = std::string(what) + (what.empty() ? "" : " ");
  OutputTarget target;
  if (auto error = ResolveOutput(path, &target)) return prefix + *error;
  // A device or FIFO is written in place; a file is made beside its target.
  const bool in_place = target.kind == PathKind::kCharDevice || target.kind == PathKind::kFifo;
  const std::string need = in_place ? target.path : ParentOf(target.path);
  if (::access(need.c_str(), in_place ? W_OK : W_OK | X_OK) != 0) {
    const int e = errno;
    return prefix + path + ": " + (in_place ? "" : "the directory ") + need + " is not writable (" +
           Errno(e) + "); give a path " + (in_place ? "you can write" : "in a writable directory");
  }
  return std::nullopt;
}

// --- OutputFile -------------------------------------------------------------------------------

OutputFile::~OutputFile() { Abandon(); }

OutputFile::OutputFile(OutputFile&& other) noexcept { *this = std::move(other); }

OutputFile& OutputFile::operator=(OutputFile&& other) noexcept {
  if (this != &other) {
    Abandon();
    path_ = std::move(other.path_);
    target_ = std::move(other.target_);
    temporary_ = std::move(other.temporary_);
    fd_ = std::exchange(other.fd_, -1);
    mode_ = other.mode_;
    replaces_ = other.replaces_;
    error_ = std::move(other.error_);
    other.temporary_.clear();
  }
  return *this;
}

std::optional<std::string> OutputFile::Open(const std::string& path) {
  Abandon();
  path_ = path;
  error_.clear();
  replaces_ = false;
  if (auto error = ResolveOutput(path, &target_)) return "cannot write " + *error;
  if (target_.kind == PathKind::kCharDevice || target_.kind == PathKind::kFifo) {
    // In place: replacing a device node or a FIFO by a regular file would
    // destroy it (as root, /dev/null itself).
    fd_ = ::open(target_.path.c_str(), O_WRONLY | O_NOCTTY | O_CLOEXEC);
    if (fd_ < 0) return "cannot write " + path + ": " + Errno(errno);
    return std::nullopt;
  }
  if (target_.kind == PathKind::kRegular) {
    struct stat st {};
    if (::stat(target_.path.c_str(), &st) == 0) {
      replaces_ = true;
      mode_ = static_cast<int>(st.st_mode & 07777);
    }
  }
  // Exclusive creation: a file or symlink already at the name is never
  // followed or reused, only skipped.
  for (int attempt = 0; attempt < 100; ++attempt) {
    const std::string name = target_.path + ".partial-" + std::to_string(::getpid()) + "-" +
                             std::to_string(temporary_counter.fetch_add(1));
    const int fd = ::open(name.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0666);
    if (fd < 0) {
      if (errno == EEXIST) continue;
      return "cannot write " + path + ": " + Errno(errno) + " (creating " + name + ")";
    }
    fd_ = fd;
    temporary_ = name;
    if (replaces_) (void)::fchmod(fd_, static_cast<mode_t>(mode_));
    return std::nullopt;
  }
  return "cannot write " + path + ": no free temporary name beside it (" + target_.path +
         ".partial-*); remove the old ones";
}

std::optional<std::string> OutputFile::Write(std::string_view bytes) {
  if (!error_.empty()) return error_;
  if (fd_ < 0) return error_ = "cannot write " + path_ + ": not open";
  if (const int e = WriteAll(fd_, bytes); e != 0) {
    error_ = "cannot write " + path_ + ": " + Errno(e) +
             (temporary_.empty() ? "" : " (writing " + temporary_ + ")");
    return error_;
  }
  return std::nullopt;
}

void OutputFile::Close() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

std::optional<std::string> OutputFile::Commit(bool sync) {
  if (fd_ < 0) return error_.empty() ? std::optional<std::string>() : error_;
  if (!error_.empty()) {
    const std::string error = error_;
    Abandon();
    return error;
  }
  if (temporary_.empty()) {
    const int rc = ::close(std::exchange(fd_, -1));
    if (rc != 0) return error_ = "cannot write " + path_ + ": " + Errno(errno);
    return std::nullopt;
  }
  if (sync && ::fsync(fd_) != 0) {
    error_ = "cannot write " + path_ + ": " + Errno(errno) + " (flushing " + temporary_ + ")";
    const std::string error = error_;
    Abandon();
    return error;
  }
  if (::close(std::exchange(fd_, -1)) != 0) {
    error_ = "cannot write " + path_ + ": " + Errno(errno) + " (closing " + temporary_ + ")";
    const std::string error = error_;
    Abandon();
    return error;
  }
  if (::rename(temporary_.c_str(), target_.path.c_str()) != 0) {
    error_ = "cannot write " + path_ + ": " + Errno(errno) + " (renaming " + temporary_ + " to " +
             target_.path + ")";
    const std::string error = error_;
    Abandon();
    return error;
  }
  temporary_.clear();
  if (sync) {
    const int dir = ::open(ParentOf(target_.path).c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (dir >= 0) {
      (void)::fsync(dir);
      ::close(dir);
    }
  }
  return std::nullopt;
}

void OutputFile::Abandon() {
  Close();
  if (!temporary_.empty()) ::unlink(temporary_.c_str());
  temporary_.clear();
}

WriteOutcome WriteFile(const std::string& path, std::string_view text, bool sync) {
  WriteOutcome outcome;
  OutputFile file;
  if ((outcome.error = file.Open(path))) return outcome;
  outcome.target = file.target();
  if ((outcome.error = file.Write(text))) return outcome;
  if ((outcome.error = file.Commit(sync))) return outcome;
  outcome.replaced = file.replaces_existing();
  return outcome;
}

std::optional<std::string> WriteFileAtomically(const std::string& path, std::string_view text,
                                               bool sync) {
  return WriteFile(path, text, sync).error;
}

// --- reading ----------------------------------------------------------------------------------

std::string FormatByteSize(size_t bytes) {
  if (bytes >= (size_t{1} << 20) && bytes % (size_t{1} << 20) == 0) {
    return std::to_string(bytes >> 20) + " MiB";
  }
  if (bytes >= 1024 && bytes % 1024 == 0) return std::to_string(bytes >> 10) + " KiB";
  return std::to_string(bytes) + " bytes";
}

std::optional<std::string> ReadFileBounded(const std::string& path, std::string* text,
                                           const ReadLimits& limits) {
  text->clear();
  if (path.empty()) return std::string("no path given");
  const auto refuse = [](const struct stat& st) -> std::optional<std::string> {
    if (S_ISDIR(st.st_mode)) return std::string("is a directory, not a file; give the file's path");
    if (!S_ISREG(st.st_mode) && !S_ISFIFO(st.st_mode)) {
      return "is " + KindOfMode(st.st_mode) + ", not a file; give a regular file";
    }
    return std::nullopt;
  };
  const auto too_long = [&limits]() {
    return "is longer than " + FormatByteSize(limits.max_bytes) +
           ", the limit for this kind of file; is it the right file?";
  };
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    const int e = errno;
    if (e == ENOENT) return std::string("does not exist; check the path");
    return "cannot be read: " + Errno(e) + "; check the path and its permissions";
  }
  if (auto r = refuse(st)) return r;
  if (limits.max_bytes != 0 && S_ISREG(st.st_mode) &&
      static_cast<uint64_t>(st.st_size) > limits.max_bytes) {
    return too_long();
  }
  const int fd = ::open(path.c_str(), O_RDONLY | O_NOCTTY | O_CLOEXEC);
  if (fd < 0) return "cannot be read: " + Errno(errno) + "; check the path and its permissions";
  // What was opened may not be what was checked (the path may have changed).
  if (::fstat(fd, &st) != 0) {
    const int e = errno;
    ::close(fd);
    return "cannot be read: " + Errno(e);
  }
  if (auto r = refuse(st)) {
    ::close(fd);
    return r;
  }
  size_t line_length = 0;
  size_t line_number = 1;
  char buffer[65536];
  for (;;) {
    const ssize_t n = ::read(fd, buffer, sizeof buffer);
    if (n < 0) {
      if (errno == EINTR) continue;
      const int e = errno;
      ::close(fd);
      text->clear();
      return "cannot be read: " + Errno(e);
    }
    if (n == 0) break;
    const std::string_view chunk(buffer, static_cast<size_t>(n));
    if (limits.max_line_bytes != 0) {
      for (const char c : chunk) {
        if (c == '\n') {
          ++line_number;
          line_length = 0;
        } else if (++line_length > limits.max_line_bytes) {
          ::close(fd);
          text->clear();
          return "line " + std::to_string(line_number) + " is longer than " +
                 FormatByteSize(limits.max_line_bytes) +
                 ", the limit for a line of this kind of file; is it the right file?";
        }
      }
    }
    if (limits.max_bytes != 0 && text->size() + chunk.size() > limits.max_bytes) {
      ::close(fd);
      text->clear();
      return too_long();
    }
    text->append(chunk);
  }
  ::close(fd);
  return std::nullopt;
}

// --- identity, copies, locks -------------------------------------------------------------------

bool SameFile(const std::string& a, const std::string& b) {
  struct stat sa {
  }, sb{};
  const bool a_exists = ::stat(a.c_str(), &sa) == 0;
  const bool b_exists = ::stat(b.c_str(), &sb) == 0;
  if (a_exists && b_exists) return sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
  if (a_exists != b_exists) return false;
  const auto normal = [](const std::string& p) {
    OutputTarget t;
    const std::string resolved = ResolveOutput(p, &t) ? p : t.path;
    std::error_code ec;
    fs::path canonical = fs::weakly_canonical(fs::absolute(resolved, ec), ec);
    return ec ? fs::path(resolved).lexically_normal() : canonical;
  };
  return normal(a) == normal(b);
}

bool SamePath(const std::string& a, const std::string& b) {
  if (a.empty() || b.empty()) return false;
  if (SameFile(a, b)) return true;
  // Not following the last name: a dangling or stale symlink (a PTY's link
  // left by a crash) and the path that will replace it.
  const auto unfollowed = [](const std::string& p) {
    std::error_code ec;
    const fs::path abs = fs::absolute(p, ec).lexically_normal();
    if (ec) return fs::path(p).lexically_normal();
    const fs::path dir = fs::weakly_canonical(abs.parent_path(), ec);
    return ec ? abs : dir / abs.filename();
  };
  return unfollowed(a) == unfollowed(b);
}

std::optional<std::string> MoveAsideNumbered(const std::string& path, const std::string& suffix,
                                             std::string* moved_to) {
  for (int i = 0; i < 10000; ++i) {
    const std::string to = path + suffix + (i == 0 ? "" : "." + std::to_string(i));
    if (::renameat2(AT_FDCWD, path.c_str(), AT_FDCWD, to.c_str(), RENAME_NOREPLACE) == 0) {
      *moved_to = to;
      return std::nullopt;
    }
    if (errno == EEXIST) continue;
    if (errno != EINVAL && errno != ENOSYS) {
      return "cannot move " + path + " aside to " + to + ": " + Errno(errno);
    }
    // A file system without RENAME_NOREPLACE: link fails on an existing name too.
    if (::link(path.c_str(), to.c_str()) != 0) {
      if (errno == EEXIST) continue;
      return "cannot move " + path + " aside to " + to + ": " + Errno(errno);
    }
    ::unlink(path.c_str());
    *moved_to = to;
    return std::nullopt;
  }
  return "cannot move " + path + " aside: " + path + suffix +
         " .. .9999 all exist; remove the old copies";
}

FileLock::~FileLock() {
  if (fd_ >= 0) ::close(fd_);
}

FileLock::FileLock(FileLock&& other) noexcept { *this = std::move(other); }

FileLock& FileLock::operator=(FileLock&& other) noexcept {
  if (this != &other) {
    if (fd_ >= 0) ::close(fd_);
    fd_ = std::exchange(other.fd_, -1);
    path_ = std::move(other.path_);
  }
  return *this;
}

std::optional<std::string> FileLock::Acquire(const std::string& lock_path) {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
  path_ = lock_path;
  const int fd = ::open(lock_path.c_str(), O_RDWR | O_CREAT | O_NOFOLLOW | O_CLOEXEC, 0644);
  if (fd < 0) return "cannot open the lock file " + lock_path + ": " + Errno(errno);
  if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
    const int e = errno;
    ::close(fd);
    if (e == EWOULDBLOCK) return lock_path + " is locked by another user of the same file";
    return "cannot lock " + lock_path + ": " + Errno(e);
  }
  fd_ = fd;
  return std::nullopt;
}

}  // namespace moco::base
