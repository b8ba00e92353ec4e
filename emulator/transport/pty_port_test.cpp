// Tests for the PTY port (pty_port.h): a host opens the symlink as a serial
// port (termios raw), talks to an echo device, closes and reopens the port
// without losing or duplicating a byte; the symlink's life cycle and errors.
#include "transport/pty_port.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <termios.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <atomic>
#include <filesystem>
#include <fstream>

#include "transport/test_support.h"

namespace moco::transport {
namespace {

using testing::EchoDevice;
using testing::RunUntil;
namespace fs = std::filesystem;

// The host side: opens the link path the way a serial program does.
class Host {
 public:
  explicit Host(const std::string& path) { Open(path); }
  ~Host() { Close(); }
  void Open(const std::string& path) {
    fd_ = open(path.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
    if (fd_ < 0) return;
    termios t{};
    tcgetattr(fd_, &t);
    cfmakeraw(&t);
    cfsetspeed(&t, B115200);
    tcsetattr(fd_, TCSANOW, &t);
  }
  bool is_open() const { return fd_ >= 0; }
  void Close() {
    if (fd_ >= 0) close(fd_);
    fd_ = -1;
  }
  void Write(std::string_view s) {
    size_t off = 0;
    while (off < s.size()) {
      const ssize_t n = write(fd_, s.data() + off, s.size() - off);
      if (n > 0) off += static_cast<size_t>(n);
      if (n < 0 && errno != EAGAIN) FAIL() << "host write: " << std::strerror(errno);
    }
  }
  // Reads what is available, at most `limit` bytes in total held in got.
  void Poll(size_t limit = SIZE_MAX) {
    char buf[4096];
    while (fd_ >= 0 && got.size() < limit) {
      const ssize_t n = read(fd_, buf, std::min(sizeof(buf), limit - got.size()));
      if (n <= 0) break;
      got.append(buf, static_cast<size_t>(n));
    }
  }
  std::string got;

 private:
  int fd_ = -1;
};

std::string TempDir() {
  static std::atomic<int> counter{0};
  const fs::path dir = fs::temp_directory_path() / ("moco_pty_test_" + std::to_string(getpid()) +
                                                    "_" + std::to_string(counter++));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir.string();
}

std::string Pattern(size_t n, uint8_t salt) {
  std::string s(n, '\0');
  for (size_t i = 0; i < n; ++i) s[i] = static_cast<char>((i * 131 + salt) & 0xFF);
  return s;
}

class PtyPortTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = TempDir();
    path_ = dir_ + "/dmc16";
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Builds link, device, port; pacing as given.
  void Serve(bool pacing) {
    LinkOptions o;
    o.pacing = pacing;
    o.log = [this](std::string_view l) { log_ += std::string(l) + "\n"; };
    link_ = std::make_unique<Link>(driver_, o);
    device_ = std::make_unique<EchoDevice>(*link_);
    device_->PowerOn();
    link_->SetDevice(device_.get());
    port_ = std::make_unique<PtyPort>(*link_, path_, link_check_period_);
    port_->Start();
    driver_.Start();
  }

  asio::io_context io_;
  sim::Scheduler scheduler_;
  RealtimeDriver driver_{io_, scheduler_};
  std::unique_ptr<Link> link_;
  std::unique_ptr<EchoDevice> device_;
  std::unique_ptr<PtyPort> port_;
  std::string dir_;
  std::string path_;
  std::string log_;
  std::chrono::nanoseconds link_check_period_ = PtyPort::kDefaultLinkCheckPeriod;
};

TEST_F(PtyPortTest, EchoesThroughTheSymlink) {
  Serve(/*pacing=*/true);
  Host host(path_);
  ASSERT_TRUE(host.is_open());
  host.Write("hello\r\n");
  ASSERT_TRUE(RunUntil(io_, [&] {
    host.Poll();
    return host.got.size() >= 7;
  }));
  EXPECT_EQ(host.got, "hello\r\n");
  EXPECT_EQ(device_->received, "hello\r\n");
}

TEST_F(PtyPortTest, PacedEchoOfALongStreamArrivesIntactAndInOrder) {
  Serve(/*pacing=*/true);
  Host host(path_);
  const std::string data = Pattern(3000, 7);  // ~0.26 s each way at 11520 B/s
  for (size_t i = 0; i < data.size(); i += 64) host.Write(std::string_view(data).substr(i, 64));
  ASSERT_TRUE(RunUntil(io_, [&] {
    host.Poll();
    return host.got.size() >= data.size();
  }));
  EXPECT_EQ(host.got, data);
  EXPECT_EQ(device_->received, data);
}

TEST_F(PtyPortTest, SymlinkPointsAtASlaveOnlyTheUserCanOpen) {
  Serve(false);
  EXPECT_EQ(fs::read_symlink(path_).string(), port_->slave_name());
  struct stat st {};
  ASSERT_EQ(stat(port_->slave_name().c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0600u);
  EXPECT_TRUE(S_ISCHR(st.st_mode));
}

TEST_F(PtyPortTest, ReportsHostOpenAndClose) {
  Serve(false);
  ASSERT_TRUE(port_->detects_host());
  EXPECT_FALSE(link_->host_open());
  Host host(path_);
  ASSERT_TRUE(RunUntil(io_, [&] { return device_->link_events.size() == 1; }));
  EXPECT_TRUE(link_->host_open());
  host.Close();
  ASSERT_TRUE(RunUntil(io_, [&] { return device_->link_events.size() == 2; }));
  EXPECT_EQ(device_->link_events, (std::vector<bool>{true, false}));
  EXPECT_FALSE(link_->host_open());
}

// The host reads part of the output, closes the port with bytes still in the
// kernel's buffer and more in the link's queue, the device writes more while
// the port is closed, and the host reopens: every byte arrives exactly once,
// in order.
TEST_F(PtyPortTest, ReopenDeliversEveryByteExactlyOnceInOrder) {
  Serve(/*pacing=*/false);
  ASSERT_TRUE(port_->detects_host());
  const std::string a = Pattern(20000, 1);  // more than the kernel buffers
  const std::string b = Pattern(20000, 2);
  device_->echo = false;

  Host host(path_);
  ASSERT_TRUE(RunUntil(io_, [&] { return link_->host_open(); }));
  device_->Send(a);
  // Wait until the kernel holds some of `a` (the link wrote to the master).
  ASSERT_TRUE(RunUntil(io_, [&] { return link_->stats().bytes_to_host > 0; }));
  ASSERT_TRUE(RunUntil(io_, [&] {
    host.Poll(100);
    return host.got.size() == 100;
  }));
  host.Close();
  ASSERT_TRUE(RunUntil(io_, [&] { return !link_->host_open(); }));
  device_->Send(b);  // written while no host has the port open
  // Let the link reclaim what the kernel held for the closed port before the
  // host comes back (a reclaim pass runs on the link's own schedule, later on
  // a loaded machine, so wait for it rather than for a fixed time).
  driver_.Kick();
  ASSERT_TRUE(RunUntil(io_, [&] { return link_->stats().reclaimed > 0; }))
      << "the kernel-buffer path was not exercised";

  host.Open(path_);
  ASSERT_TRUE(host.is_open());
  ASSERT_TRUE(RunUntil(io_, [&] {
    host.Poll();
    return host.got.size() >= a.size() + b.size();
  }));
  // A marker written after the reopen: anything duplicated would precede it.
  device_->Send("Z");
  ASSERT_TRUE(RunUntil(io_, [&] {
    host.Poll();
    return !host.got.empty() && host.got.back() == 'Z';
  }));
  EXPECT_EQ(host.got.size(), a.size() + b.size() + 1);
  EXPECT_TRUE(host.got == a + b + "Z") << "bytes lost, duplicated or reordered across the reopen";
  EXPECT_EQ(device_->link_events, (std::vector<bool>{true, false, true}));
}

TEST_F(PtyPortTest, StopRemovesTheSymlink) {
  Serve(false);
  ASSERT_TRUE(fs::is_symlink(path_));
  port_->Stop();
  EXPECT_FALSE(fs::exists(fs::symlink_status(path_)));
}

TEST_F(PtyPortTest, ADeletedSymlinkIsLoggedAndCreatedAgain) {
  link_check_period_ = std::chrono::milliseconds(10);
  Serve(false);
  ASSERT_TRUE(fs::is_symlink(path_));
  fs::remove(path_);
  ASSERT_TRUE(RunUntil(io_, [&] { return fs::is_symlink(fs::symlink_status(path_)); }))
      << "the link was not created again; log:\n"
      << log_;
  EXPECT_EQ(fs::read_symlink(path_).string(), port_->slave_name());
  EXPECT_NE(log_.find("the PTY link " + path_ + " was deleted; created it again"),
            std::string::npos)
      << log_;
  // The recreated link still reaches the device.
  Host host(path_);
  ASSERT_TRUE(host.is_open());
  host.Write("ping");
  ASSERT_TRUE(RunUntil(io_, [&] {
    host.Poll();
    return host.got == "ping";
  }));
  host.Close();
  port_->Stop();
  EXPECT_FALSE(fs::exists(fs::symlink_status(path_))) << "Stop removes the recreated link";
}

TEST_F(PtyPortTest, WhatAppearsAtTheLinkPathIsNeverReplaced) {
  link_check_period_ = std::chrono::milliseconds(10);
  Serve(false);
  fs::remove(path_);
  { std::ofstream(path_) << "keep me"; }
  ASSERT_TRUE(RunUntil(io_, [&] {
    return log_.find("replaced by something else") != std::string::npos;
  })) << log_;
  // Several more checks: still reported once and left alone.
  const size_t checks_before = log_.size();
  for (int i = 0; i < 5; ++i) {
    auto t = asio::steady_timer(io_, std::chrono::milliseconds(10));
    bool fired = false;
    t.async_wait([&](const ErrorCode&) { fired = true; });
    ASSERT_TRUE(RunUntil(io_, [&] { return fired; }));
  }
  EXPECT_EQ(log_.size(), checks_before) << log_;
  port_->Stop();
  ASSERT_TRUE(fs::is_regular_file(path_));
  std::ifstream in(path_);
  std::string text;
  std::getline(in, text);
  EXPECT_EQ(text, "keep me");
}

TEST_F(PtyPortTest, ReplacesAStaleSymlink) {
  fs::create_symlink("/dev/pts/moco-gone-999", path_);
  Serve(false);
  EXPECT_EQ(fs::read_symlink(path_).string(), port_->slave_name());
  EXPECT_NE(log_.find("replacing stale link"), std::string::npos);
}

TEST_F(PtyPortTest, RefusesAPathThatIsNotASymlink) {
  { std::ofstream(path_) << "keep me"; }
  LinkOptions o;
  Link link(driver_, o);
  try {
    PtyPort port(link, path_);
    FAIL() << "a regular file was replaced";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("not a symlink"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(path_), std::string::npos) << e.what();
  }
  EXPECT_TRUE(fs::is_regular_file(path_));
}

TEST_F(PtyPortTest, RefusesASymlinkToSomethingThatExists) {
  fs::create_symlink("/dev/null", path_);
  LinkOptions o;
  Link link(driver_, o);
  EXPECT_THROW(PtyPort(link, path_), std::runtime_error);
  EXPECT_EQ(fs::read_symlink(path_).string(), "/dev/null");
}

TEST_F(PtyPortTest, UnusablePathGivesAClearError) {
  LinkOptions o;
  Link link(driver_, o);
  const std::string missing = dir_ + "/no-such-dir/dmc16";
  try {
    PtyPort port(link, missing);
    FAIL() << "created a link in a missing directory";
  } catch (const std::runtime_error& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("cannot create the PTY link " + missing), std::string::npos) << m;
    EXPECT_NE(m.find("does not exist"), std::string::npos) << m;
  }
  // A directory nobody may write to, root included (sysfs is read-only).
  try {
    PtyPort port(link, "/sys/moco-dmc16");
    FAIL() << "created a link under /sys";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("not writable"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace moco::transport
