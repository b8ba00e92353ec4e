// Deliberately broken StackShot 3X controllers (the emulated device with one
// test fault switched on, devices::Stackshot3xFaults) are caught by the rule
// that names the fault, and pass that rule with the fault off; the random
// suite shrinks a failing sequence and saves it as a session file.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>

#include "conformance/core/patience_testing.h"
#include "conformance/core/report.h"
#include "conformance/core/rule_proof_testing.h"
#include "conformance/protocols/stackshot/stackshot_broken_device_testing.h"
#include "conformance/protocols/stackshot/stackshot_protocol.h"
#include "devices/stackshot3x/stackshot3x.h"
#include "session/session.h"

namespace moco::conformance {
namespace {

using stackshot::Command;

RunReport RunFaulty(const devices::Stackshot3xFaults& faults, RunOptions options = {}) {
  auto nvm = std::make_shared<devices::MemoryStateStore>();
  InProcessTarget target("stackshot3x-broken",
                         [faults, nvm](sim::Scheduler& s, devices::ByteSink& out) {
                           auto d = std::make_unique<devices::Stackshot3x>(
                               s, out, devices::Stackshot3xProfile{}, nvm.get());
                           d->SetFaults(faults);
                           return d;
                         });
  EXPECT_FALSE(target.Open().has_value());
  return RunStackshot(target, options);
}

using proof::ExpectCaught;

// Each fault against its rule, on the cases that exercise it; the same run
// with the fault off passes that rule.
struct FaultCase {
  const char* name;
  devices::Stackshot3xFaults faults;
  const char* cases;
  const char* rule;
  Status caught;
  int exit_code;  // SHOULD rules do not fail the run
};

void PrintTo(const FaultCase& f, std::ostream* os) { *os << f.name << " -> " << f.rule; }

class Fault : public ::testing::TestWithParam<FaultCase> {};

TEST_P(Fault, IsCaughtByItsRuleAndPassesWithoutIt) {
  const FaultCase& f = GetParam();
  RunOptions o;
  o.cases = f.cases;
  const RunReport broken = RunFaulty(f.faults, o);
  ExpectCaught(broken, f.rule, f.caught);
  EXPECT_EQ(ExitCode(broken), f.exit_code) << ConsoleReport(broken, false);
  const RunReport sound = RunFaulty({}, o);
  EXPECT_EQ(sound.rules.at(f.rule).status, Status::kPass) << ConsoleReport(sound, false);
  EXPECT_EQ(ExitCode(sound), 0);
}

devices::Stackshot3xFaults BadChecksum() {
  devices::Stackshot3xFaults f;
  f.bad_reply_checksum = true;
  return f;
}
devices::Stackshot3xFaults DropStop() {
  devices::Stackshot3xFaults f;
  f.drop_reply_to = stackshot::Id(Command::kRailStop);
  return f;
}
devices::Stackshot3xFaults MisechoStatus() {
  devices::Stackshot3xFaults f;
  f.misecho_reply_to = stackshot::Id(Command::kRailStatus);
  return f;
}
devices::Stackshot3xFaults RewritableSerial() {
  devices::Stackshot3xFaults f;
  f.serial_rewritable = true;
  return f;
}
devices::Stackshot3xFaults BusyForever() {
  devices::Stackshot3xFaults f;
  f.busy_never_clears = true;
  return f;
}

INSTANTIATE_TEST_SUITE_P(
    StackshotBroken, Fault,
    ::testing::Values(
        // A checksum byte no documented algorithm gives: SHOULD (ERRATA 2:
        // the algorithm is not given, so the run does not fail on it).
        FaultCase{"bad_checksum", BadChecksum(), "connect/*", "SS-CSUM-002", Status::kFail, 0},
        FaultCase{"bad_checksum_note", BadChecksum(), "connect/*", "SS-CSUM-001", Status::kNoted,
                  0},
        FaultCase{"missing_reply", DropStop(), "rail/stop", "SS-ANS-001", Status::kFail, 1},
        FaultCase{"wrong_command_echo", MisechoStatus(), "rail/at-rest", "SS-ANS-003",
                  Status::kFail, 1},
        FaultCase{"serial_not_write_once", RewritableSerial(), "nvm/serial", "SS-SERIAL-001",
                  Status::kFail, 1},
        FaultCase{"busy_never_clears", BusyForever(), "rail/move", "SS-STATUS-002", Status::kFail,
                  1},
        FaultCase{"busy_never_clears_refuses_moves", BusyForever(), "random/*", "SS-CODE-003",
                  Status::kFail, 1}),
    [](const ::testing::TestParamInfo<FaultCase>& i) { return std::string(i.param.name); });

TEST(StackshotBroken, EveryFaultOffPassesTheWholeRun) {
  const RunReport r = RunFaulty({});
  EXPECT_EQ(ExitCode(r), 0) << ConsoleReport(r, false);
}

TEST(StackshotBroken, RandomSuiteShrinksAFailingSequenceAndSavesIt) {
  const std::filesystem::path session =
      std::filesystem::temp_directory_path() /
      ("mococheck_ss_shrunk_" + std::to_string(getpid()) + ".jsonl");
  RunOptions o;
  o.cases = "random/*";
  o.random.seed = 3;
  o.random.steps = 40;
  o.random.session_path = session.string();
  const RunReport r = RunFaulty(DropStop(), o);
  ASSERT_EQ(r.cases.size(), 1u);
  EXPECT_TRUE(r.cases[0].MustFailed());
  const auto& log = r.cases[0].log;
  const auto has = [&](const std::string& s) {
    return std::find(log.begin(), log.end(), s) != log.end();
  };
  EXPECT_TRUE(has("shrunk to 1 step(s):")) << ConsoleReport(r, true);
  bool stop_step = false;
  for (const std::string& line : log) stop_step = stop_step || line.rfind("  CC_RAIL_STOP", 0) == 0;
  EXPECT_TRUE(stop_step) << ConsoleReport(r, true);
  auto loaded = session::LoadSession(session);
  ASSERT_TRUE(std::holds_alternative<session::Session>(loaded));
  const auto& s = std::get<session::Session>(loaded);
  EXPECT_EQ(s.header.protocol, wire::Protocol::kStackshot);
  EXPECT_EQ(s.header.clock, "virtual");
  bool stop_sent = false;
  for (const auto& e : s.entries) {
    if (e.from != session::Origin::kHost) continue;
    auto p = stackshot::DecodePacket(e.bytes);
    stop_sent = stop_sent || (p.ok() && p->command == stackshot::Id(Command::kRailStop));
  }
  EXPECT_TRUE(stop_sent);
  std::filesystem::remove(session);
}

// A broken controller is judged in at most twice the good one's time, with
// the same rules failing as when every answer is waited out.
TEST(BrokenStackshot, NoReplyToOneCommandIsJudgedFast) {
  patience_testing::ExpectJudgedFast(
      [](const RunOptions& o) { return ss_testing::RunBroken(ss_testing::PassThrough, o); },
      [](const RunOptions& o) {
        return ss_testing::RunBroken(
            [](const stackshot::Packet* request, stackshot::Packet reply, sim::Scheduler& s,
               devices::ByteSink& out) {
              if (!ss_testing::Is(request, Command::kRailStatus))
                ss_testing::PassThrough(request, std::move(reply), s, out);
            },
            o);
      });
}

TEST(BrokenStackshot, AControllerThatStopsMidRunIsJudgedFast) {
  patience_testing::ExpectJudgedFast(
      [](const RunOptions& o) { return ss_testing::RunBroken(ss_testing::PassThrough, o); },
      [](const RunOptions& o) {
        auto written = std::make_shared<size_t>(0);
        return ss_testing::RunBroken(
            [written](const stackshot::Packet* request, stackshot::Packet reply, sim::Scheduler& s,
                      devices::ByteSink& out) {
              if ((*written)++ < 300) ss_testing::PassThrough(request, std::move(reply), s, out);
            },
            o);
      });
}

}  // namespace
}  // namespace moco::conformance
