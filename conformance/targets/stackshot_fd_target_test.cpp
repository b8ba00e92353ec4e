// mococheck against a StackShot 3X served by serve::Emulator over a real
// PTY (stackshot-protocol.txt section 2 at 38400 baud, no pacing) on the
// steady clock: every MUST rule the suites reach from outside the process
// passes, and what only an in-process target can do is left unexercised.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <thread>

#include "conformance/core/report.h"
#include "conformance/protocols/stackshot/stackshot_protocol.h"
#include "conformance/targets/target.h"
#include "serve/serve.h"

namespace moco::conformance {
namespace {

namespace fs = std::filesystem;

fs::path TempDir() {
  const fs::path d =
      fs::temp_directory_path() / ("mococheck_ssfd_" + std::to_string(getpid()) + "_" +
                                   ::testing::UnitTest::GetInstance()->current_test_info()->name());
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

// Serves one StackShot 3X at `endpoint` while `body` runs; its NVM lives in `dir`.
void WithServedStackshot(const fs::path& dir, const std::string& endpoint,
                         const std::string& profile,
                         const std::function<void(serve::Emulator&)>& body) {
  serve::EmulatorConfig config;
  config.log_level = serve::LogLevel::kError;
  serve::DeviceConfig d;
  d.model = "stackshot3x";
  d.endpoint = endpoint;
  d.profile_path = profile;
  d.state_path = (dir / "nvm.json").string();
  d.no_pacing = true;
  config.devices = {d};
  serve::Emulator e(config, [](std::string_view) {});
  e.Start();
  std::thread io([&] { e.Run(); });
  body(e);
  transport::asio::post(e.io(), [&] { e.Stop(); });
  io.join();
}

TEST(StackshotFdTarget, EveryMustRulePassesOverARealPty) {
  const fs::path dir = TempDir();
  // A unit whose serial number was programmed at the factory, so that the
  // write-once checks run without burning one.
  const fs::path profile = dir / "profile.json";
  {
    std::ofstream out(profile);
    out << R"({"serial_number": 1234567})";
  }
  WithServedStackshot(
      dir, "pty:" + (dir / "ss3x").string(), profile.string(), [&](serve::Emulator& e) {
        FdTarget target(FdTarget::Kind::kSerial, e.server(0).pty_path(), 38400);
        ASSERT_FALSE(target.Open().has_value());
        RunOptions o;
        o.random.steps = 12;
        const RunReport r = RunStackshot(target, o);
        EXPECT_EQ(r.device_info["serial_number"], 1234567u);
        EXPECT_EQ(ExitCode(r), 0) << ConsoleReport(r, true);
        for (const auto& [id, s] : r.rules) {
          if (FindRule(id)->level != Level::kMust) continue;
          EXPECT_NE(s.status, Status::kFail) << id;
        }
        for (const char* id :
             {"SS-ANS-001", "SS-ANS-002", "SS-ANS-003", "SS-PKT-001", "SS-SERIAL-001", "SS-NVM-003",
              "SS-MOVE-001", "SS-STACK-001", "SS-CURVE-005"}) {
          EXPECT_EQ(r.rules.at(id).status, Status::kPass) << id << "\n" << ConsoleReport(r, false);
        }
        // The runner cannot press an external unit's buttons.
        EXPECT_EQ(r.rules.at("SS-STATUS-005").status, Status::kPass);
        // Deadlines were judged on the steady clock.
        EXPECT_NE(r.rules.at("SS-DL-001").status, Status::kNotExercised);
      });
  fs::remove_all(dir);
}

}  // namespace
}  // namespace moco::conformance
