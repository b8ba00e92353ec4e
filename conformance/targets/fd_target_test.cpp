// The real-clock targets against a DMC-16 served by transport::Emulator over a
// real PTY and a real TCP socket (no pacing): the handshake, error and motor
// suites pass on the steady clock; unusable addresses are clear errors.
#include <gtest/gtest.h>

#include <filesystem>
#include <thread>

#include "conformance/runner/report.h"
#include "conformance/runner/runner.h"
#include "conformance/targets/target.h"
#include "transport/serve.h"

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
                     const std::function<void(transport::Emulator&)>& body) {
  transport::EmulatorConfig config;
  config.log_level = transport::LogLevel::kError;
  transport::DeviceConfig d;
  d.endpoint = endpoint;
  d.no_pacing = true;
  config.devices = {d};
  transport::Emulator e(config, [](std::string_view) {});
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
  WithServedDmc16("pty:" + (dir / "dmc16").string(), [&](transport::Emulator& e) {
    FdTarget target(FdTarget::Kind::kSerial, e.server(0).pty_path(), 115200);
    ASSERT_FALSE(target.Open().has_value());
    EXPECT_FALSE(target.VirtualClock());
    RunOptions o;
    o.cases = "connect/*,errors/*,motor/reset-position";
    const RunReport r = RunDmc(target, o);
    ASSERT_TRUE(r.hi.has_value());
    EXPECT_EQ(r.hi->motor_count, 16);
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
  WithServedDmc16("tcp:127.0.0.1:0", [&](transport::Emulator& e) {
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

}  // namespace
}  // namespace moco::conformance
