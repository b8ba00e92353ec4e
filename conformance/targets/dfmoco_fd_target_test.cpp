// mococheck's DFMoco suites over a real PTY (dfmoco-protocol.txt "Protocol":
// 57600 8N1) against the DFMoco Arduino served by serve::Emulator, on the
// steady clock: every MUST rule of the cases run passes.
#include <gtest/gtest.h>

#include <filesystem>
#include <thread>

#include "conformance/core/report.h"
#include "conformance/protocols/dfmoco/dfmoco_protocol.h"
#include "conformance/targets/target.h"
#include "serve/serve.h"

namespace moco::conformance {
namespace {

namespace fs = std::filesystem;

TEST(DfmocoFdTarget, HandshakeMotorAndErrorSuitesPassOverARealPty) {
  const fs::path dir =
      fs::temp_directory_path() / ("mococheck_dfm_pty_" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  serve::EmulatorConfig config;
  config.log_level = serve::LogLevel::kError;
  serve::DeviceConfig d;
  d.model = "dfmoco";
  d.endpoint = "pty:" + (dir / "dfmoco").string();
  d.no_pacing = true;
  config.devices = {d};
  serve::Emulator e(config, [](std::string_view) {});
  e.Start();
  std::thread io([&] { e.Run(); });

  FdTarget target(FdTarget::Kind::kSerial, e.server(0).pty_path(), 57600);
  ASSERT_FALSE(target.Open().has_value());
  EXPECT_FALSE(target.VirtualClock());
  RunOptions o;
  o.cases = "connect/hi,connect/queries,connect/pipelined,errors/*,motor/move,motor/np-zm";
  const RunReport r = RunDfmoco(target, o);
  EXPECT_EQ(r.device_info["motor_count"], 4);
  EXPECT_EQ(ExitCode(r), 0) << ConsoleReport(r, true);
  for (const char* id : {"DFM-HI-002", "DFM-MS-002", "DFM-LINE-001", "DFM-REPLY-001", "DFM-ERR-004",
                         "DFM-MM-003", "DFM-MP-005", "DFM-NP-002"}) {
    ASSERT_TRUE(r.rules.count(id)) << id;
    EXPECT_EQ(r.rules.at(id).status, Status::kPass) << id << "\n" << ConsoleReport(r, false);
  }
  // The start-up of an external device is not watched.
  EXPECT_EQ(r.rules.at("DFM-HI-001").status, Status::kNotExercised);

  transport::asio::post(e.io(), [&] { e.Stop(); });
  io.join();
  fs::remove_all(dir);
}

}  // namespace
}  // namespace moco::conformance
