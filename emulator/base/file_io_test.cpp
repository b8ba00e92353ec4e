// Tests for the output policy and bounded reads (file_io.h): regular files are
// replaced atomically, FIFOs written in place and left FIFOs, directories and
// sockets refused naming the path, symlinks followed to their final target,
// nothing planted at a temporary name followed, reads bounded.
#include "base/file_io.h"

#include <fcntl.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>

#include <algorithm>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <string>
#include <thread>
#include <vector>

namespace moco::base {
namespace {

namespace fs = std::filesystem;

// A fresh empty directory, removed with everything in it at the end.
class TempDir {
 public:
  TempDir() {
    static int counter = 0;
    path_ = fs::temp_directory_path() /
            ("moco_file_io_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  const fs::path& path() const { return path_; }
  std::vector<std::string> Names() const {
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(path_)) names.push_back(e.path().filename());
    std::sort(names.begin(), names.end());
    return names;
  }

 private:
  fs::path path_;
};

std::string Read(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void Put(const fs::path& p, const std::string& text) { std::ofstream(p, std::ios::binary) << text; }

// Reads a FIFO to its end on a thread (opening it blocks until a writer comes).
class FifoReader {
 public:
  explicit FifoReader(const fs::path& fifo)
      : thread_([this, fifo] {
          std::ifstream in(fifo, std::ios::binary);
          bytes_.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
        }) {}
  std::string Join() {
    thread_.join();
    return bytes_;
  }

 private:
  std::string bytes_;
  std::thread thread_;
};

fs::path MakeFifo(const fs::path& p) {
  EXPECT_EQ(::mkfifo(p.c_str(), 0600), 0) << std::strerror(errno);
  return p;
}

bool IsFifo(const fs::path& p) { return fs::is_fifo(fs::symlink_status(p)); }

TEST(WriteFile, WritesExactlyTheTextAndLeavesNoTemporaryFile) {
  TempDir dir;
  const fs::path p = dir.path() / "plot.svg";
  const WriteOutcome w = WriteFile(p.string(), "<svg/>\n");
  EXPECT_EQ(w.error, std::nullopt);
  EXPECT_FALSE(w.replaced);
  EXPECT_EQ(Read(p), "<svg/>\n");
  EXPECT_EQ(dir.Names(), std::vector<std::string>{"plot.svg"});
}

TEST(WriteFile, ReplacingAnExistingFileIsReportedAndKeepsItsPermissions) {
  TempDir dir;
  const fs::path p = dir.path() / "report.xml";
  Put(p, "a much longer first version\n");
  fs::permissions(p, fs::perms::owner_read | fs::perms::owner_write);
  const WriteOutcome w = WriteFile(p.string(), "v2", /*sync=*/true);
  EXPECT_EQ(w.error, std::nullopt);
  EXPECT_TRUE(w.replaced);
  EXPECT_EQ(Read(p), "v2");
  EXPECT_EQ(fs::status(p).permissions() & fs::perms::all,
            fs::perms::owner_read | fs::perms::owner_write);
  EXPECT_EQ(dir.Names(), std::vector<std::string>{"report.xml"});
}

TEST(WriteFile, AFifoIsWrittenInPlaceAndStaysAFifo) {
  TempDir dir;
  const fs::path fifo = MakeFifo(dir.path() / "junit.fifo");
  FifoReader reader(fifo);
  const WriteOutcome w = WriteFile(fifo.string(), "<testsuites/>\n");
  EXPECT_EQ(w.error, std::nullopt);
  EXPECT_FALSE(w.replaced);
  EXPECT_EQ(reader.Join(), "<testsuites/>\n");
  EXPECT_TRUE(IsFifo(fifo));
  EXPECT_EQ(dir.Names(), std::vector<std::string>{"junit.fifo"});
}

TEST(WriteFile, AFifoWhoseReaderLeftFailsWithAMessageInsteadOfEndingTheProgram) {
  TempDir dir;
  const fs::path fifo = MakeFifo(dir.path() / "f");
  std::thread reader([&] {
    const int fd = ::open(fifo.c_str(), O_RDONLY);
    ::close(fd);  // gone before anything is read
  });
  OutputFile out;
  ASSERT_EQ(out.Open(fifo.string()), std::nullopt);
  reader.join();
  const auto error = out.Write(std::string(1 << 16, 'x'));
  ASSERT_TRUE(error.has_value());
  EXPECT_NE(error->find(fifo.string()), std::string::npos) << *error;
  EXPECT_TRUE(IsFifo(fifo));
}

TEST(ResolveOutput, DeviceNodesAreWrittenInPlaceNeverReplaced) {
  // Only classified here: writing /dev/null for the test would put the node at
  // risk if atomic replacement ever applied to it again; the FIFO tests above
  // prove the in-place path.
  OutputTarget t;
  ASSERT_EQ(ResolveOutput("/dev/null", &t), std::nullopt);
  EXPECT_EQ(t.kind, PathKind::kCharDevice);
  EXPECT_EQ(t.path, "/dev/null");
}

TEST(WriteFile, ADirectoryIsRefusedNamingThePathAndTheFixAndIsLeftAlone) {
  TempDir dir;
  const fs::path d = dir.path() / "out";
  fs::create_directory(d);
  const auto error = WriteFileAtomically(d.string(), "x");
  ASSERT_TRUE(error.has_value());
  EXPECT_NE(error->find(d.string()), std::string::npos) << *error;
  EXPECT_NE(error->find("is a directory"), std::string::npos) << *error;
  EXPECT_TRUE(fs::is_directory(d));
  EXPECT_EQ(dir.Names(), std::vector<std::string>{"out"});
  const auto check = CheckOutputPath(d.string(), "--junit");
  ASSERT_TRUE(check.has_value());
  EXPECT_EQ(check->rfind("--junit " + d.string(), 0), 0u) << *check;
}

TEST(WriteFile, ASocketIsRefused) {
  TempDir dir;
  const fs::path s = dir.path() / "sock";
  const int fd = ::socket(AF_UNIX, SOCK_STREAM, 0);
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  std::snprintf(addr.sun_path, sizeof addr.sun_path, "%s", s.c_str());
  ASSERT_EQ(::bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr), 0);
  const auto error = WriteFileAtomically(s.string(), "x");
  ::close(fd);
  ASSERT_TRUE(error.has_value());
  EXPECT_NE(error->find("socket"), std::string::npos) << *error;
  EXPECT_TRUE(fs::is_socket(s));
}

TEST(WriteFile, AMissingDirectoryIsReportedWithThePath) {
  TempDir dir;
  const fs::path p = dir.path() / "no" / "such" / "plot.svg";
  const auto error = WriteFileAtomically(p.string(), "x");
  ASSERT_TRUE(error.has_value());
  EXPECT_NE(error->find((dir.path() / "no" / "such").string()), std::string::npos) << *error;
  EXPECT_NE(error->find("does not exist"), std::string::npos) << *error;
}

TEST(WriteFile, ASymlinkStaysASymlinkAndItsTargetIsReplaced) {
  TempDir dir;
  fs::create_directory(dir.path() / "real");
  const fs::path target = dir.path() / "real" / "state.json";
  Put(target, "old");
  const fs::path link = dir.path() / "state.json";
  fs::create_symlink("real/state.json", link);
  const WriteOutcome w = WriteFile(link.string(), "new");
  EXPECT_EQ(w.error, std::nullopt);
  EXPECT_TRUE(w.replaced);
  EXPECT_EQ(w.target, target.string());
  EXPECT_TRUE(fs::is_symlink(link));
  EXPECT_EQ(Read(target), "new");
}

TEST(WriteFile, ADanglingSymlinkCreatesTheFileItNames) {
  TempDir dir;
  const fs::path link = dir.path() / "out.jsonl";
  fs::create_symlink(dir.path() / "made.jsonl", link);
  EXPECT_EQ(WriteFileAtomically(link.string(), "x"), std::nullopt);
  EXPECT_TRUE(fs::is_symlink(link));
  EXPECT_EQ(Read(dir.path() / "made.jsonl"), "x");
}

TEST(WriteFile, ASymlinkLoopIsRefused) {
  TempDir dir;
  fs::create_symlink(dir.path() / "b", dir.path() / "a");
  fs::create_symlink(dir.path() / "a", dir.path() / "b");
  const auto error = WriteFileAtomically((dir.path() / "a").string(), "x");
  ASSERT_TRUE(error.has_value());
  EXPECT_NE(error->find("symlinks"), std::string::npos) << *error;
}

TEST(WriteFile, ASymlinkPlantedAtTheTemporaryNameIsSkippedNotFollowed) {
  TempDir dir;
  const fs::path victim = dir.path() / "victim";
  Put(victim, "precious");
  const fs::path p = dir.path() / "rec.jsonl";
  const uint64_t next = internal::NextTemporaryNumber();
  for (uint64_t n = next; n < next + 5; ++n) {
    fs::create_symlink(
        victim, p.string() + ".partial-" + std::to_string(::getpid()) + "-" + std::to_string(n));
  }
  EXPECT_EQ(WriteFileAtomically(p.string(), "recording"), std::nullopt);
  EXPECT_EQ(Read(victim), "precious");
  EXPECT_EQ(Read(p), "recording");
}

TEST(OutputFile, AnAbandonedWriteLeavesThePreviousFileAndNoTemporaryFile) {
  TempDir dir;
  const fs::path p = dir.path() / "r.jsonl";
  Put(p, "previous");
  {
    OutputFile out;
    ASSERT_EQ(out.Open(p.string()), std::nullopt);
    EXPECT_TRUE(out.replaces_existing());
    ASSERT_EQ(out.Write("half"), std::nullopt);
    EXPECT_TRUE(fs::exists(out.temporary_path()));
  }
  EXPECT_EQ(Read(p), "previous");
  EXPECT_EQ(dir.Names(), std::vector<std::string>{"r.jsonl"});
}

RC_GTEST_PROP(WriteFile, TheFileHoldsExactlyTheLastTextWritten,
              (const std::string& first, const std::string& second)) {
  TempDir dir;
  const fs::path p = dir.path() / "f";
  RC_ASSERT(WriteFileAtomically(p.string(), first) == std::nullopt);
  RC_ASSERT(Read(p) == first);
  RC_ASSERT(WriteFileAtomically(p.string(), second) == std::nullopt);
  RC_ASSERT(Read(p) == second);
  RC_ASSERT(dir.Names() == std::vector<std::string>{"f"});
}

// --- reading ------------------------------------------------------------------------------------

TEST(ReadFileBounded, ReadsAWholeFile) {
  TempDir dir;
  Put(dir.path() / "p.json", "{}\n");
  std::string text;
  EXPECT_EQ(ReadFileBounded((dir.path() / "p.json").string(), &text), std::nullopt);
  EXPECT_EQ(text, "{}\n");
  Put(dir.path() / "empty", "");
  EXPECT_EQ(ReadFileBounded((dir.path() / "empty").string(), &text), std::nullopt);
  EXPECT_EQ(text, "");
}

TEST(ReadFileBounded, MissingDirectoryAndDeviceAreRefusedWithAReason) {
  TempDir dir;
  std::string text;
  EXPECT_NE(
      ReadFileBounded((dir.path() / "none").string(), &text).value_or("").find("does not exist"),
      std::string::npos);
  EXPECT_NE(ReadFileBounded(dir.path().string(), &text).value_or("").find("is a directory"),
            std::string::npos);
  // /dev/zero never ends: it is refused before a byte is read.
  EXPECT_NE(ReadFileBounded("/dev/zero", &text).value_or("").find("character device"),
            std::string::npos);
  EXPECT_TRUE(text.empty());
}

TEST(ReadFileBounded, AFileOverTheLimitIsRefusedNamingTheLimit) {
  TempDir dir;
  Put(dir.path() / "big", std::string(2048, 'x'));
  std::string text;
  const auto error = ReadFileBounded((dir.path() / "big").string(), &text, {.max_bytes = 1024});
  ASSERT_TRUE(error.has_value());
  EXPECT_NE(error->find("1 KiB"), std::string::npos) << *error;
  EXPECT_TRUE(text.empty());
}

TEST(ReadFileBounded, AnEndlessFifoStopsAtTheLimit) {
  TempDir dir;
  const fs::path fifo = MakeFifo(dir.path() / "zero");
  std::thread writer([&] {
    const int fd = ::open(fifo.c_str(), O_WRONLY);
    const std::string block(4096, '\0');
    // Writes until the reader closes (EPIPE; SIGPIPE is held back by the test's mask).
    sigset_t set;
    sigemptyset(&set);
    sigaddset(&set, SIGPIPE);
    pthread_sigmask(SIG_BLOCK, &set, nullptr);
    while (::write(fd, block.data(), block.size()) > 0) {
    }
    ::close(fd);
  });
  std::string text;
  const auto error = ReadFileBounded(fifo.string(), &text, {.max_bytes = 64 * 1024});
  writer.join();
  ASSERT_TRUE(error.has_value());
  EXPECT_NE(error->find("64 KiB"), std::string::npos) << *error;
}

TEST(ReadFileBounded, ALineOverItsLimitIsRefusedNamingTheLine) {
  TempDir dir;
  Put(dir.path() / "s.jsonl", "{}\n{}\n" + std::string(300, 'x') + "\n");
  std::string text;
  const auto error = ReadFileBounded((dir.path() / "s.jsonl").string(), &text,
                                     {.max_bytes = 0, .max_line_bytes = 256});
  ASSERT_TRUE(error.has_value());
  EXPECT_NE(error->find("line 3"), std::string::npos) << *error;
}

// --- identity, copies, locks
// ----------------------------------------------------------------------

TEST(SameFile, TheSameInodeByAnyNameAndTheSameNewPath) {
  TempDir dir;
  const fs::path a = dir.path() / "a.json";
  Put(a, "{}");
  fs::create_symlink(a, dir.path() / "link");
  fs::create_hard_link(a, dir.path() / "hard");
  EXPECT_TRUE(SameFile(a.string(), (dir.path() / "link").string()));
  EXPECT_TRUE(SameFile(a.string(), (dir.path() / "hard").string()));
  EXPECT_TRUE(SameFile((dir.path() / "new").string(), (dir.path() / "." / "new").string()));
  EXPECT_FALSE(SameFile(a.string(), (dir.path() / "new").string()));
  Put(dir.path() / "b.json", "{}");
  EXPECT_FALSE(SameFile(a.string(), (dir.path() / "b.json").string()));
}

// An output against a path made later (a PTY's link) or reached by another
// spelling: the same place either way.
TEST(SamePath, OtherSpellingsSymlinksAndPathsNotYetMade) {
  TempDir dir;
  fs::create_directory(dir.path() / "d");
  fs::create_directory_symlink(dir.path() / "d", dir.path() / "dlink");
  const std::string pty = (dir.path() / "d" / "pty").string();
  EXPECT_TRUE(SamePath(pty, (dir.path() / "d" / ".." / "d" / "pty").string()));
  EXPECT_TRUE(SamePath(pty, (dir.path() / "dlink" / "pty").string()));
  // A stale link where the PTY's link will be, and where it points.
  fs::create_symlink(dir.path() / "gone", pty);
  EXPECT_TRUE(SamePath(pty, (dir.path() / "dlink" / "pty").string()));
  // A symlink to an existing node and the node itself.
  Put(dir.path() / "node", "");
  fs::create_symlink(dir.path() / "node", dir.path() / "to-node");
  EXPECT_TRUE(SamePath((dir.path() / "to-node").string(), (dir.path() / "node").string()));
  EXPECT_FALSE(SamePath(pty, (dir.path() / "d" / "other").string()));
  EXPECT_FALSE(SamePath(pty, ""));
}

TEST(MoveAsideNumbered, EveryCopyIsKeptNoneOverwritten) {
  TempDir dir;
  const fs::path p = dir.path() / "s.json";
  std::vector<std::string> moved;
  for (const char* text : {"one", "two", "three"}) {
    Put(p, text);
    std::string to;
    ASSERT_EQ(MoveAsideNumbered(p.string(), ".corrupt", &to), std::nullopt);
    moved.push_back(to);
  }
  EXPECT_EQ(moved, (std::vector<std::string>{p.string() + ".corrupt", p.string() + ".corrupt.1",
                                             p.string() + ".corrupt.2"}));
  EXPECT_EQ(Read(moved[0]), "one");
  EXPECT_EQ(Read(moved[1]), "two");
  EXPECT_EQ(Read(moved[2]), "three");
  EXPECT_FALSE(fs::exists(p));
}

TEST(FileLock, ASecondHolderIsRefusedUntilTheFirstLetsGo) {
  TempDir dir;
  const std::string lock = (dir.path() / "s.json.lock").string();
  auto first = std::make_unique<FileLock>();
  ASSERT_EQ(first->Acquire(lock), std::nullopt);
  FileLock second;
  const auto error = second.Acquire(lock);
  ASSERT_TRUE(error.has_value());
  EXPECT_NE(error->find(lock), std::string::npos);
  EXPECT_FALSE(second.held());
  first.reset();
  EXPECT_EQ(second.Acquire(lock), std::nullopt);
}

}  // namespace
}  // namespace moco::base
