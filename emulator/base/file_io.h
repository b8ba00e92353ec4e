// Every file the programs read whole or write (docs/files.md): one policy for
// outputs (a regular file is replaced atomically, a character device or FIFO
// is written in place, anything else is refused), bounded whole-file reads,
// exclusive temporary files, numbered copies and lock files.
#ifndef MOCO_BASE_FILE_IO_H_
#define MOCO_BASE_FILE_IO_H_

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace moco::base {

// What a path names once every symlink on it is followed.
enum class PathKind : uint8_t {
  kMissing,     // nothing there yet (a dangling symlink: where it points)
  kRegular,     // a regular file
  kDirectory,   // a directory
  kCharDevice,  // /dev/null, /dev/full, a tty
  kFifo,        // a named pipe
  kOther,       // a socket or a block device
};

// "a directory", "a character device", ... for messages.
std::string_view PathKindName(PathKind kind);

// An output path after its symlinks are followed.
struct OutputTarget {
  std::string path;  // the file that is written: the final target of every symlink
  PathKind kind = PathKind::kMissing;
};

// Follows `path` through every symlink (relative links from the link's
// directory; a dangling link resolves to the path it names) and says what is
// there. Returns a message naming `path`, what is wrong and the fix when the
// path cannot be an output: a directory, a socket or block device, a symlink
// loop, a new file in a directory that does not exist. Never throws.
std::optional<std::string> ResolveOutput(const std::string& path, OutputTarget* out);

// ResolveOutput without the result, and the write permission it needs (the
// target's directory for a file, the target itself for a device or FIFO):
// the check every program makes at start,
// before any run, for each file it will write (`what`: "--junit", ...).
std::optional<std::string> CheckOutputPath(const std::string& path, std::string_view what);

// A file being written, to be committed in one step:
// - a new path or a regular file (also through symlinks): the text goes to an
//   exclusively created "<target>.partial-<pid>-<n>" beside the final target
//   (O_CREAT|O_EXCL|O_NOFOLLOW, so nothing planted there is followed or
//   overwritten), and Commit() renames it over the target, which keeps its
//   permission bits; the symlinks stay and point at the new file;
// - a character device or FIFO: written in place (opened without O_TRUNC or
//   O_CREAT; a FIFO's open waits for its reader); Commit() closes it;
// - anything else: Open fails with a message naming the path and the fix.
// Destroying an uncommitted OutputFile removes its temporary file.
class OutputFile {
 public:
  OutputFile() = default;
  ~OutputFile();
  OutputFile(OutputFile&& other) noexcept;
  OutputFile& operator=(OutputFile&& other) noexcept;
  OutputFile(const OutputFile&) = delete;
  OutputFile& operator=(const OutputFile&) = delete;

  // Opens `path` for writing; returns a message naming it on failure.
  std::optional<std::string> Open(const std::string& path);
  // Appends `bytes` (written through at once, no user-space buffer). Returns
  // a message on failure; the failure is also remembered for Commit().
  std::optional<std::string> Write(std::string_view bytes);
  // Makes the written text the file: `sync` flushes it to the disk first
  // (fsync of the temporary file, then of its directory after the rename).
  // Returns a message on failure; then the previous file is untouched and no
  // temporary file is left.
  std::optional<std::string> Commit(bool sync = false);
  // Drops what was written (removes the temporary file).
  void Abandon();

  bool is_open() const { return fd_ >= 0; }
  const std::string& path() const { return path_; }                 // as given
  const std::string& target() const { return target_.path; }        // symlinks followed
  const std::string& temporary_path() const { return temporary_; }  // empty: in place
  bool in_place() const { return is_open() && temporary_.empty(); }
  // An existing regular file is (or was, once committed) replaced.
  bool replaces_existing() const { return replaces_; }

 private:
  void Close();
  std::string path_;
  OutputTarget target_;
  std::string temporary_;
  int fd_ = -1;
  int mode_ = 0;
  bool replaces_ = false;
  std::string error_;
};

// The result of a whole-file write.
struct WriteOutcome {
  std::optional<std::string> error;  // names the path and the reason
  bool replaced = false;             // an existing regular file was replaced
  std::string target;                // the file written (symlinks followed)
};

// Writes `text` as the whole file at `path` through OutputFile (atomic
// replacement, or in place for a device or FIFO). Never throws.
WriteOutcome WriteFile(const std::string& path, std::string_view text, bool sync = false);

// WriteFile, reporting only an error.
std::optional<std::string> WriteFileAtomically(const std::string& path, std::string_view text,
                                               bool sync = false);

// Bounds of a whole-file read.
inline constexpr size_t kMaxInputFileBytes = size_t{4} << 20;  // profiles, run files, ...
struct ReadLimits {
  size_t max_bytes = kMaxInputFileBytes;  // 0: no bound on the whole file
  size_t max_line_bytes = 0;              // 0: no bound on a line
};

// Reads the whole of a regular file or FIFO into `text`. Returns the reason
// it could not, without the path (the caller's message names the file, e.g.
// "profile p.json: " + reason): missing, a directory, a device or other
// special file, unreadable, longer than the limit (the limit is named), or a
// line longer than its limit. Never reads more than a bound past the limit.
std::optional<std::string> ReadFileBounded(const std::string& path, std::string* text,
                                           const ReadLimits& limits = {});

// "4 MiB", "512 KiB", "100 bytes".
std::string FormatByteSize(size_t bytes);

// True when `a` and `b` are the same file: the same inode when both exist,
// else the same absolute path once symlinks are followed.
bool SameFile(const std::string& a, const std::string& b);

// True when `a` and `b` name one place, also before it exists: SameFile, or
// the same absolute path once std::filesystem::weakly_canonical has followed
// the symlinks of its directories (the last name followed or not). An output
// checked against a path a program will create (a PTY's symlink) or against
// an input reached by another spelling (./x, a/../x, a symlink to x, the
// device node a symlink points to).
bool SamePath(const std::string& a, const std::string& b);

// Moves `path` to the first of "<path><suffix>", "<path><suffix>.1", ...
// that does not exist, never replacing one (rename with RENAME_NOREPLACE, or
// link + unlink). Returns the new path in `moved_to`, or a message.
std::optional<std::string> MoveAsideNumbered(const std::string& path, const std::string& suffix,
                                             std::string* moved_to);

// An exclusive advisory lock (flock) on a lock file, held until destroyed.
// The lock file is created when missing and never removed (removing it would
// let two holders lock two different files).
class FileLock {
 public:
  FileLock() = default;
  ~FileLock();
  FileLock(FileLock&& other) noexcept;
  FileLock& operator=(FileLock&& other) noexcept;
  FileLock(const FileLock&) = delete;
  FileLock& operator=(const FileLock&) = delete;

  // Takes the lock without waiting. Returns a message when another holder
  // (another process, or another FileLock in this one) has it, or the file
  // cannot be opened.
  std::optional<std::string> Acquire(const std::string& lock_path);
  bool held() const { return fd_ >= 0; }
  const std::string& path() const { return path_; }

 private:
  int fd_ = -1;
  std::string path_;
};

namespace internal {
// The <n> of the next temporary name this process makes (tests plant files
// there to prove they are skipped, never followed).
uint64_t NextTemporaryNumber();
}  // namespace internal

}  // namespace moco::base

#endif  // MOCO_BASE_FILE_IO_H_
