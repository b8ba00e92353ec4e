// Tests for the control socket (control_socket.h) over real unix sockets in a
// temporary directory: one reply line per request line in order, any
// chunking, several clients, the line bound, the file's mode and lifetime,
// stale and foreign files at the path.
#include "transport/control_socket.h"

#include <fcntl.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>

#include <atomic>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "transport/test_support.h"

namespace moco::transport {
namespace {

namespace fs = std::filesystem;
using testing::RunUntil;

// A fresh directory per test, removed afterwards.
fs::path TempDir() {
  static std::atomic<int> counter{0};
  const fs::path dir = fs::temp_directory_path() /
                       ("moco_ctl_" + std::to_string(getpid()) + "_" + std::to_string(counter++));
  fs::create_directories(dir);
  return dir;
}

// A blocking-free client: connects, writes, and reads what has arrived.
class Client {
 public:
  explicit Client(const fs::path& path) {
    fd_ = ::socket(AF_UNIX, SOCK_STREAM, 0);
    sockaddr_un addr{};
    addr.sun_family = AF_UNIX;
    std::strncpy(addr.sun_path, path.c_str(), sizeof(addr.sun_path) - 1);
    connected_ = ::connect(fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr) == 0;
    ::fcntl(fd_, F_SETFL, O_NONBLOCK);
  }
  ~Client() {
    if (fd_ >= 0) ::close(fd_);
  }
  bool connected() const { return connected_; }
  void Send(std::string_view s) {
    while (!s.empty()) {
      const ssize_t n = ::send(fd_, s.data(), s.size(), MSG_NOSIGNAL);
      if (n <= 0) return;
      s.remove_prefix(static_cast<size_t>(n));
    }
  }
  void ShutdownWrite() { ::shutdown(fd_, SHUT_WR); }
  // Reads what is there; sets eof() when the server closed.
  void Poll() {
    char buf[4096];
    for (;;) {
      const ssize_t n = ::recv(fd_, buf, sizeof buf, MSG_DONTWAIT);
      if (n > 0) {
        received_.append(buf, static_cast<size_t>(n));
        lines_ += static_cast<size_t>(std::count(buf, buf + n, '\n'));
        continue;
      }
      if (n == 0) eof_ = true;
      return;
    }
  }
  // Counted as they arrive: a test polls this in a loop while megabytes come in.
  size_t Lines() {
    Poll();
    return lines_;
  }
  bool eof() {
    Poll();
    return eof_;
  }
  const std::string& received() const { return received_; }
  std::vector<std::string> SplitLines() const {
    std::vector<std::string> out;
    size_t pos = 0;
    for (size_t nl; (nl = received_.find('\n', pos)) != std::string::npos; pos = nl + 1) {
      out.push_back(received_.substr(pos, nl - pos));
    }
    return out;
  }

 private:
  int fd_ = -1;
  bool connected_ = false;
  bool eof_ = false;
  std::string received_;
  size_t lines_ = 0;
};

class ControlSocketTest : public ::testing::Test {
 protected:
  ControlSocketTest() : dir_(TempDir()), path_(dir_ / "ctl.sock") {}
  ~ControlSocketTest() override { fs::remove_all(dir_); }

  std::unique_ptr<ControlSocket> Open(ControlSocketOptions options = {}) {
    options.log = [this](std::string_view l) { logs_.emplace_back(l); };
    return std::make_unique<ControlSocket>(
        driver_, path_.string(),
        [this](std::string_view line) {
          seen_.emplace_back(line);
          return "{\"echo\":" + std::to_string(line.size()) + "}";
        },
        options);
  }
  bool Run(const std::function<bool()>& done) { return RunUntil(io_, done); }

  fs::path dir_;
  fs::path path_;
  asio::io_context io_;
  sim::Scheduler scheduler_;
  RealtimeDriver driver_{io_, scheduler_};
  std::vector<std::string> seen_;
  std::vector<std::string> logs_;
};

TEST_F(ControlSocketTest, EachRequestLineGetsOneReplyLineInOrder) {
  auto sock = Open();
  Client c(path_);
  ASSERT_TRUE(c.connected());
  c.Send("a\nbcd\n\nxy\r\n");
  ASSERT_TRUE(Run([&] { return c.Lines() == 4; }));
  EXPECT_EQ(c.SplitLines(), (std::vector<std::string>{"{\"echo\":1}", "{\"echo\":3}",
                                                      "{\"echo\":0}", "{\"echo\":3}"}));
  EXPECT_EQ(seen_, (std::vector<std::string>{"a", "bcd", "", "xy\r"}));
  EXPECT_EQ(sock->lines_handled(), 4u);
}

TEST_F(ControlSocketTest, ALineSentByteByByteIsOneRequest) {
  auto sock = Open();
  Client c(path_);
  for (char ch : std::string("{\"cmd\":\"state\"}\n")) {
    c.Send(std::string_view(&ch, 1));
    io_.restart();
    io_.poll();
  }
  ASSERT_TRUE(Run([&] { return c.Lines() == 1; }));
  EXPECT_EQ(seen_, std::vector<std::string>{"{\"cmd\":\"state\"}"});
}

TEST_F(ControlSocketTest, SeveralClientsAreServedIndependently) {
  auto sock = Open();
  Client a(path_);
  Client b(path_);
  a.Send("1\n");
  b.Send("22\n333\n");
  a.Send("4444\n");
  ASSERT_TRUE(Run([&] { return a.Lines() == 2 && b.Lines() == 2; }));
  EXPECT_EQ(a.SplitLines(), (std::vector<std::string>{"{\"echo\":1}", "{\"echo\":4}"}));
  EXPECT_EQ(b.SplitLines(), (std::vector<std::string>{"{\"echo\":2}", "{\"echo\":3}"}));
  EXPECT_EQ(sock->client_count(), 2u);
}

TEST_F(ControlSocketTest, ALastLineWithoutNewlineIsAnsweredAtHalfClose) {
  auto sock = Open();
  Client c(path_);
  c.Send("abc\nde");
  c.ShutdownWrite();
  ASSERT_TRUE(Run([&] { return c.eof(); }));
  EXPECT_EQ(c.SplitLines(), (std::vector<std::string>{"{\"echo\":3}", "{\"echo\":2}"}));
  ASSERT_TRUE(Run([&] { return sock->client_count() == 0; }));
}

TEST_F(ControlSocketTest, TheLineBoundIsInclusiveAndALongerLineClosesTheClient) {
  ControlSocketOptions opts;
  opts.max_line_bytes = 100;
  auto sock = Open(opts);
  Client ok(path_);
  ok.Send(std::string(100, 'x') + "\n");
  ASSERT_TRUE(Run([&] { return ok.Lines() == 1; }));
  EXPECT_EQ(ok.SplitLines()[0], "{\"echo\":100}");

  Client bad(path_);
  bad.Send("short\n" + std::string(101, 'y') + "\nnever\n");
  ASSERT_TRUE(Run([&] { return bad.eof(); }));
  const auto lines = bad.SplitLines();
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_EQ(lines[0], "{\"echo\":5}");
  EXPECT_NE(lines[1].find("\"ok\":false"), std::string::npos) << lines[1];
  EXPECT_NE(lines[1].find("longer than 100 bytes"), std::string::npos) << lines[1];
  EXPECT_EQ(std::count(seen_.begin(), seen_.end(), "never"), 0);
  // The other client is still served.
  ok.Send("z\n");
  ASSERT_TRUE(Run([&] { return ok.Lines() == 2; }));
}

TEST_F(ControlSocketTest, TheDefaultBoundIs64KiB) {
  auto sock = Open();
  Client c(path_);
  c.Send(std::string(64 * 1024, 'a') + "\n" + std::string(64 * 1024 + 1, 'b'));
  ASSERT_TRUE(Run([&] { return c.eof(); }));
  const auto lines = c.SplitLines();
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_EQ(lines[0], "{\"echo\":65536}");
  EXPECT_NE(lines[1].find("longer than 65536 bytes"), std::string::npos);
}

TEST_F(ControlSocketTest, ClientsBeyondTheLimitGetAnErrorAndAreClosed) {
  ControlSocketOptions opts;
  opts.max_clients = 1;
  auto sock = Open(opts);
  Client a(path_);
  a.Send("1\n");
  ASSERT_TRUE(Run([&] { return a.Lines() == 1; }));
  Client b(path_);
  ASSERT_TRUE(Run([&] { return b.eof(); }));
  EXPECT_NE(b.received().find("too many control clients"), std::string::npos) << b.received();
  a.Send("2\n");
  ASSERT_TRUE(Run([&] { return a.Lines() == 2; }));
}

TEST_F(ControlSocketTest, AClientThatDoesNotReadIsHeldBackNotBuffered) {
  ControlSocketOptions opts;
  opts.max_pending_reply_bytes = 4096;
  size_t handled = 0;
  ControlSocket sock(
      driver_, path_.string(),
      [&](std::string_view) {
        ++handled;
        return std::string(10000, 'r');
      },
      opts);
  Client c(path_);
  // 200 replies of 10 kB: far more than the kernel's socket buffers hold.
  std::string requests;
  for (int i = 0; i < 200; ++i) requests += "q\n";
  c.Send(requests);
  RunUntil(
      io_, [] { return false; }, std::chrono::milliseconds(200));
  // Held back: the server stopped handling once replies were pending.
  EXPECT_LT(handled, 200u);
  EXPECT_GT(handled, 0u);
  // Reading the replies lets it go on; every request is answered once.
  ASSERT_TRUE(Run([&] { return c.Lines() == 200; }));
  EXPECT_EQ(handled, 200u);
  EXPECT_EQ(c.received().size(), 200u * 10001u);
}

TEST_F(ControlSocketTest, TheSocketFileIsOwnerOnlyAndRemovedOnStop) {
  auto sock = Open();
  struct stat st {};
  ASSERT_EQ(::lstat(path_.c_str(), &st), 0);
  EXPECT_TRUE(S_ISSOCK(st.st_mode));
  EXPECT_EQ(st.st_mode & 0777, 0600u);
  sock->Stop();
  EXPECT_FALSE(fs::exists(fs::symlink_status(path_)));
  sock->Stop();  // idempotent
  Client late(path_);
  EXPECT_FALSE(late.connected());
}

TEST_F(ControlSocketTest, TheDestructorRemovesTheFileAndClosesClients) {
  auto sock = Open();
  Client c(path_);
  c.Send("a\n");
  ASSERT_TRUE(Run([&] { return c.Lines() == 1; }));
  sock.reset();
  EXPECT_FALSE(fs::exists(fs::symlink_status(path_)));
  io_.restart();
  io_.poll();
  EXPECT_TRUE(c.eof());
}

TEST_F(ControlSocketTest, AStaleSocketFileIsReplaced) {
  {
    // A socket file whose owner is gone: bound, never listening, closed.
    const int fd = ::socket(AF_UNIX, SOCK_STREAM, 0);
    sockaddr_un addr{};
    addr.sun_family = AF_UNIX;
    std::strncpy(addr.sun_path, path_.c_str(), sizeof(addr.sun_path) - 1);
    ASSERT_EQ(::bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr), 0);
    ::close(fd);
  }
  ASSERT_TRUE(fs::is_socket(path_));
  auto sock = Open();
  Client c(path_);
  c.Send("x\n");
  ASSERT_TRUE(Run([&] { return c.Lines() == 1; }));
}

TEST_F(ControlSocketTest, ALiveSocketAtThePathIsRefused) {
  auto first = Open();
  try {
    Open();
    ADD_FAILURE() << "a second server on the same path";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("another process is serving it"), std::string::npos)
        << e.what();
  }
  // The first one still works and keeps its file.
  Client c(path_);
  c.Send("x\n");
  ASSERT_TRUE(Run([&] { return c.Lines() == 1; }));
}

TEST_F(ControlSocketTest, APathThatIsNotASocketIsRefusedAndLeftAlone) {
  std::ofstream(path_) << "keep me";
  try {
    Open();
    ADD_FAILURE() << "a regular file was replaced";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("is a regular file"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("choose another path"), std::string::npos) << e.what();
  }
  std::ifstream in(path_);
  std::string content;
  std::getline(in, content);
  EXPECT_EQ(content, "keep me");
}

TEST_F(ControlSocketTest, BadPathsAreClearStartUpErrors) {
  const auto error_of = [this](const std::string& p) {
    try {
      ControlSocket s(driver_, p, [](std::string_view) { return std::string(); });
    } catch (const std::runtime_error& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(error_of("/tmp/" + std::string(200, 'x')).find("longer than the 107"),
            std::string::npos);
  EXPECT_NE(error_of((dir_ / "no_such_dir" / "ctl.sock").string()).find("directory does not"),
            std::string::npos);
  EXPECT_NE(error_of("").find("empty"), std::string::npos);
}

TEST_F(ControlSocketTest, AThrowingHandlerStillAnswersTheLine) {
  ControlSocketOptions opts;
  opts.log = [](std::string_view) {};
  ControlSocket sock(
      driver_, path_.string(),
      [](std::string_view line) -> std::string {
        if (line == "boom") throw std::runtime_error("boom");
        return "multi\nline";
      },
      opts);
  Client c(path_);
  c.Send("boom\nfine\n");
  ASSERT_TRUE(Run([&] { return c.Lines() == 2; }));
  EXPECT_NE(c.SplitLines()[0].find("internal error"), std::string::npos);
  EXPECT_EQ(c.SplitLines()[1], "multi line");
}

// Law: whatever the lines and however they are chunked, each line gets
// exactly one reply, in order.
RC_GTEST_PROP(ControlSocketLaw, AnyChunkingGivesOneReplyPerLineInOrder, ()) {
  const fs::path dir = TempDir();
  asio::io_context io;
  sim::Scheduler scheduler;
  RealtimeDriver driver(io, scheduler);
  std::vector<std::string> seen;
  ControlSocketOptions opts;
  opts.log = [](std::string_view) {};
  ControlSocket sock(
      driver, (dir / "s").string(),
      [&](std::string_view line) {
        seen.emplace_back(line);
        return std::to_string(seen.size()) + ":" + std::to_string(line.size());
      },
      opts);
  const auto lines = *rc::gen::container<std::vector<std::string>>(rc::gen::container<std::string>(
      rc::gen::suchThat(rc::gen::arbitrary<char>(), [](char ch) { return ch != '\n'; })));
  std::string stream;
  for (const std::string& l : lines) stream += l + "\n";
  Client c(dir / "s");
  RC_ASSERT(c.connected());
  size_t pos = 0;
  while (pos < stream.size()) {
    const size_t k = *rc::gen::inRange<size_t>(1, stream.size() - pos + 1);
    c.Send(std::string_view(stream).substr(pos, k));
    pos += k;
    io.restart();
    io.poll();
  }
  RC_ASSERT(RunUntil(io, [&] { return c.Lines() == lines.size(); }));
  std::vector<std::string> expected;
  for (size_t i = 0; i < lines.size(); ++i) {
    expected.push_back(std::to_string(i + 1) + ":" + std::to_string(lines[i].size()));
  }
  RC_ASSERT(c.SplitLines() == expected);
  RC_ASSERT(seen == lines);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace moco::transport
