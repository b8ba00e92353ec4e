// The real-clock targets against a DMC-16 served by serve::Emulator over a
// real PTY and a real TCP socket (no pacing): the handshake, error and motor
// suites pass on the steady clock; unusable addresses are clear errors.
#include <gtest/gtest.h>

#include <netinet/in.h>
#include <pty.h>
#include <sys/socket.h>
#include <termios.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <thread>

#include "base/termios_speed.h"
#include "conformance/core/report.h"
#include "conformance/protocols/dmc/dmc_protocol.h"
#include "conformance/targets/target.h"
#include "serve/serve.h"

namespace moco::conformance {
namespace {

namespace fs = std::filesystem;

fs::path TempDir() {
  const fs::path d =
      fs::temp_directory_path() / ("mococheck_fd_" + std::to_string(getpid()) + "_" +
                                   ::testing::UnitTest::GetInstance()->current_test_info()->name());
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

// Serves one DMC-16 at `endpoint` while `body` runs.
void WithServedDmc16(const std::string& endpoint,
                     const std::function<void(serve::Emulator&)>& body) {
  serve::EmulatorConfig config;
  config.log_level = serve::LogLevel::kError;
  serve::DeviceConfig d;
  d.endpoint = endpoint;
  d.no_pacing = true;
  config.devices = {d};
  serve::Emulator e(config, [](std::string_view) {});
  e.Start();
  std::thread io([&] { e.Run(); });
  body(e);
  transport::asio::post(e.io(), [&] { e.Stop(); });
  io.join();
}

void ExpectPassed(const RunReport& r, std::initializer_list<const char*> rules) {
  for (const char* id : rules) {
    ASSERT_TRUE(r.rules.count(id)) << id;
    EXPECT_EQ(r.rules.at(id).status, Status::kPass) << id << "\n" << ConsoleReport(r, false);
  }
}

TEST(FdTarget, HandshakeErrorAndResetSuitesPassOverARealPty) {
  const fs::path dir = TempDir();
  WithServedDmc16("pty:" + (dir / "dmc16").string(), [&](serve::Emulator& e) {
    FdTarget target(FdTarget::Kind::kSerial, e.server(0).pty_path(), 115200);
    ASSERT_FALSE(target.Open().has_value());
    EXPECT_FALSE(target.VirtualClock());
    RunOptions o;
    o.cases = "connect/*,errors/*,motor/reset-position";
    const RunReport r = RunDmc(target, o);
    ASSERT_TRUE(r.device_info.contains("motor_count"));
    EXPECT_EQ(r.device_info["motor_count"], 16);
    EXPECT_EQ(ExitCode(r), 0) << ConsoleReport(r, true);
    ExpectPassed(r, {"DMC-HI-001", "DMC-HI-002", "DMC-CSUM-001", "DMC-CSUM-002", "DMC-ACK-001",
                     "DMC-ACK-003", "DMC-ERR-009", "DMC-RST-002"});
    // Deadlines are judged on the steady clock (their outcome depends on the
    // machine's load, so only that they were judged is asserted here).
    EXPECT_NE(r.rules.at("DMC-DL-001").status, Status::kNotExercised);
    // The start-up of an external device is not watched.
    EXPECT_EQ(r.rules.at("DMC-HI-011").status, Status::kNotExercised);
  });
  fs::remove_all(dir);
}

TEST(FdTarget, HandshakeAndAMoveWithUpdatesPassOverTcp) {
  WithServedDmc16("tcp:127.0.0.1:0", [&](serve::Emulator& e) {
    FdTarget target(FdTarget::Kind::kTcp, "127.0.0.1:" + std::to_string(e.server(0).tcp_port()));
    ASSERT_FALSE(target.Open().has_value());
    RunOptions o;
    o.cases = "connect/hi,motor/move";
    const RunReport r = RunDmc(target, o);
    EXPECT_EQ(ExitCode(r), 0) << ConsoleReport(r, true);
    ExpectPassed(r, {"DMC-HI-002", "DMC-MOVE-003", "DMC-POS-004", "DMC-STAT-004"});
  });
}

TEST(FdTarget, UnusableAddressesAreClearErrors) {
  FdTarget pty(FdTarget::Kind::kSerial, "/nonexistent/dmc16");
  auto err = pty.Open();
  ASSERT_TRUE(err.has_value());
  EXPECT_NE(err->find("/nonexistent/dmc16"), std::string::npos);
  FdTarget baud(FdTarget::Kind::kSerial, "/dev/null", 12345);
  err = baud.Open();
  ASSERT_TRUE(err.has_value());
  EXPECT_NE(err->find("115200"), std::string::npos) << "names the rates to use";
  FdTarget tcp(FdTarget::Kind::kTcp, "127.0.0.1:1");
  err = tcp.Open();
  ASSERT_TRUE(err.has_value());
  EXPECT_NE(err->find("127.0.0.1:1"), std::string::npos);
}

TEST(FdTarget, APathThatIsNotADeviceIsRefusedAndNeverWritten) {
  const fs::path dir = TempDir();
  const fs::path file = dir / "not-a-port";
  { std::ofstream(file) << "precious"; }
  for (const char* scheme : {"serial", "pty"}) {
    FdTarget t(FdTarget::Kind::kSerial, file.string(), 115200, scheme);
    const auto err = t.Open();
    ASSERT_TRUE(err.has_value()) << scheme;
    EXPECT_NE(err->find(std::string(scheme) + ":" + file.string() + " is a regular file"),
              std::string::npos)
        << *err;
    EXPECT_FALSE(t.Send(wire::Bytes{1, 2, 3}));
  }
  std::ifstream in(file);
  EXPECT_EQ(std::string(std::istreambuf_iterator<char>(in), {}), "precious");
  FdTarget d(FdTarget::Kind::kSerial, dir.string(), 115200, "serial");
  const auto err = d.Open();
  ASSERT_TRUE(err.has_value());
  EXPECT_NE(err->find("is a directory"), std::string::npos) << *err;
  fs::remove_all(dir);
}

// A TCP listener on 127.0.0.1 at a free port (written to `port`); -1 on failure.
int ListenOnLoopback(uint16_t* port) {
  const int listener = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t len = sizeof a;
  if (listener < 0 || bind(listener, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0 ||
      listen(listener, 1) != 0 ||
      getsockname(listener, reinterpret_cast<sockaddr*>(&a), &len) != 0) {
    if (listener >= 0) close(listener);
    return -1;
  }
  *port = ntohs(a.sin_port);
  return listener;
}

TEST(FdTarget, APeerThatHangsUpIsALostLinkNotASigpipe) {
  uint16_t port = 0;
  const int listener = ListenOnLoopback(&port);
  ASSERT_GE(listener, 0);
  FdTarget t(FdTarget::Kind::kTcp, "127.0.0.1:" + std::to_string(port));
  ASSERT_FALSE(t.Open().has_value());
  EXPECT_EQ(t.Name().rfind("tcp:127.0.0.1:", 0), 0u) << t.Name();
  close(accept(listener, nullptr, nullptr));  // the device hangs up at once
  close(listener);
  EXPECT_FALSE(t.LinkLost().has_value());
  // Writing to the closed connection soon fails (EPIPE after the peer's
  // reset); without MSG_NOSIGNAL the SIGPIPE would have ended this test.
  const wire::Bytes frame(4096, 0x55);
  bool failed = false;
  for (int i = 0; i < 100000 && !failed; ++i) failed = !t.Send(frame);
  EXPECT_TRUE(failed);
  ASSERT_TRUE(t.LinkLost().has_value());
  EXPECT_NE(t.LinkLost()->find("writing to the device failed"), std::string::npos) << *t.LinkLost();
  wire::Bytes got;
  EXPECT_FALSE(t.Receive(t.Now() + 2'000'000'000, got));
}

TEST(FdTarget, APeerThatClosesIsALostLink) {
  uint16_t port = 0;
  const int listener = ListenOnLoopback(&port);
  ASSERT_GE(listener, 0);
  FdTarget t(FdTarget::Kind::kTcp, "127.0.0.1:" + std::to_string(port));
  ASSERT_FALSE(t.Open().has_value());
  close(accept(listener, nullptr, nullptr));
  close(listener);
  wire::Bytes got;
  EXPECT_FALSE(t.Receive(t.Now() + 2'000'000'000, got));
  ASSERT_TRUE(t.LinkLost().has_value());
  EXPECT_NE(t.LinkLost()->find("closed the connection"), std::string::npos) << *t.LinkLost();
  EXPECT_FALSE(t.Send(wire::Bytes{1}));
}

// A target opened on a new PTY's slave, whose far end is then closed (as an
// emulator that died).
std::unique_ptr<FdTarget> TargetOnAClosedPty() {
  int master = -1;
  int slave = -1;
  char name[256] = {};
  if (openpty(&master, &slave, name, nullptr, nullptr) != 0) return nullptr;
  auto t = std::make_unique<FdTarget>(FdTarget::Kind::kSerial, name, 115200, "pty");
  const bool opened = !t->Open().has_value();
  close(slave);
  close(master);
  return opened ? std::move(t) : nullptr;
}

// A serial: target takes every rate the serial driver names (the one table in
// emulator/base/termios_speed.h), and sets it on the line: 4800 and 500000
// were refused while the target kept a shorter table of its own.
TEST(FdTarget, EveryRateTheDriverNamesIsSetOnTheLine) {
  for (const uint32_t baud : {4800u, 57600u, 500000u}) {
    int master = -1;
    int slave = -1;
    char name[256] = {};
    ASSERT_EQ(openpty(&master, &slave, name, nullptr, nullptr), 0);
    FdTarget t(FdTarget::Kind::kSerial, name, baud, "serial");
    const auto err = t.Open();
    EXPECT_FALSE(err.has_value()) << baud << ": " << err.value_or("");
    termios tio{};
    ASSERT_EQ(tcgetattr(slave, &tio), 0);
    EXPECT_EQ(base::BaudOfTermiosSpeed(cfgetospeed(&tio)), std::optional<uint32_t>(baud)) << baud;
    close(slave);
    close(master);
  }
}

// The emulator serving a PTY dies mid-run: reading the PTY then gives end of
// file, and the link is lost at once (the run ends as a target error).
TEST(FdTarget, APtyWhoseEmulatorDiedIsALostLink) {
  const std::unique_ptr<FdTarget> target = TargetOnAClosedPty();
  ASSERT_NE(target, nullptr);
  FdTarget& t = *target;
  wire::Bytes got;
  EXPECT_FALSE(t.Receive(t.Now() + 10 * sim::kNsPerSecond, got));
  ASSERT_TRUE(t.LinkLost().has_value());
  EXPECT_NE(t.LinkLost()->find("closed the connection"), std::string::npos) << *t.LinkLost();
}

// Writing to a PTY whose far end is closed fails with EIO. A short hang-up is
// waited out (the far end may reopen), one that lasts the grace period loses
// the link, so a host that only writes does not retry forever.
TEST(FdTarget, WritesToAPtyClosedForTheGracePeriodLoseTheLink) {
  const std::unique_ptr<FdTarget> target = TargetOnAClosedPty();
  ASSERT_NE(target, nullptr);
  FdTarget& t = *target;
  EXPECT_FALSE(t.Send(wire::Bytes{1}));
  EXPECT_FALSE(t.LinkLost().has_value()) << "a fresh hang-up is not yet a lost link";
  const TimeNs deadline = t.Now() + 3 * FdTarget::kHangUpGraceNs;
  while (!t.LinkLost() && t.Now() < deadline) {
    EXPECT_FALSE(t.Send(wire::Bytes{1}));
    usleep(20'000);
  }
  ASSERT_TRUE(t.LinkLost().has_value()) << "writes into a closed PTY were retried for good";
  EXPECT_NE(t.LinkLost()->find("has been closed"), std::string::npos) << *t.LinkLost();
}

}  // namespace
}  // namespace moco::conformance
