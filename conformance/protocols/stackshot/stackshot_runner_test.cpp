// mococheck against the in-process StackShot 3X (virtual time): the SS-*
// catalogue is well formed, every rule holds for the emulated controller,
// runs are deterministic, the random suite holds for many seeds, and a
// controller sending a constant checksum is a NOTE, not a failure.
#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>

#include "conformance/core/report.h"
#include "conformance/protocols/stackshot/stackshot_protocol.h"
#include "conformance/protocols/stackshot/stackshot_suites.h"

namespace moco::conformance {
namespace {

RunReport RunInProcess(RunOptions options = {}, const std::string& profile = "") {
  auto target = InProcessTarget::ForModel("stackshot3x", profile);
  EXPECT_FALSE(target->Open().has_value());
  return RunStackshot(*target, options);
}

TEST(StackshotCatalogue, IdsAreUniqueWellFormedAndEveryRuleQuotesItsClause) {
  std::set<std::string> ids;
  const auto shape = [](std::string_view id) {
    if (id.rfind("SS-", 0) != 0) return false;
    const size_t dash = id.rfind('-');
    if (dash <= 3 || id.size() - dash != 4) return false;
    for (size_t i = 3; i < dash; ++i) {
      if (id[i] < 'A' || id[i] > 'Z') return false;
    }
    for (size_t i = dash + 1; i < id.size(); ++i) {
      if (id[i] < '0' || id[i] > '9') return false;
    }
    return true;
  };
  for (const Rule& r : StackshotRules()) {
    EXPECT_TRUE(shape(r.id)) << r.id;
    EXPECT_TRUE(ids.insert(std::string(r.id)).second) << "duplicate " << r.id;
    EXPECT_FALSE(r.title.empty()) << r.id;
    EXPECT_GE(r.clause.size(), 10u) << r.id << " quotes no clause";
    EXPECT_FALSE(r.source.empty()) << r.id;
    EXPECT_EQ(FindRule(r.id), &r);
  }
  EXPECT_GE(StackshotRules().size(), 30u);
  // The readings the ERRATA leaves open are NOTEs (ERRATA: "never a failure").
  EXPECT_EQ(FindRule("SS-CSUM-001")->level, Level::kNote);
  EXPECT_EQ(FindRule("SS-SERIAL-002")->level, Level::kNote);
  EXPECT_EQ(FindRule("SS-SERIAL-001")->level, Level::kMust);
  EXPECT_EQ(FindRule("SS-ANS-002")->level, Level::kMust);
  EXPECT_EQ(StackshotNeeds::kThreeAxes.text, "axes X, Y and Z (StackShot 3X)");
}

TEST(StackshotRunner, EveryRuleHoldsForTheEmulatedStackshot3x) {
  const RunReport report = RunInProcess();
  EXPECT_EQ(report.protocol, "stackshot");
  EXPECT_NE(report.device.find("StackShot 3X 1.2.6"), std::string::npos) << report.device;
  EXPECT_EQ(report.device_info["axes"], 3);
  EXPECT_EQ(report.device_info["software_id"], 0x00010206u);
  EXPECT_EQ(ExitCode(report), 0) << ConsoleReport(report, false);
  size_t passed = 0;
  for (const auto& [id, s] : report.rules) {
    // Every rule is exercised and holds (the emulator takes every reading
    // the runner names, so not even a NOTE is raised).
    EXPECT_EQ(s.status, Status::kPass) << id << "\n" << ConsoleReport(report, false);
    passed += s.status == Status::kPass;
  }
  EXPECT_EQ(report.rules.size(), StackshotRules().size());
  EXPECT_EQ(passed, StackshotRules().size());
  for (const CaseResult& c : report.cases) {
    EXPECT_TRUE(c.applicable) << c.suite << "/" << c.name;
    EXPECT_FALSE(c.outcomes.empty()) << c.suite << "/" << c.name;
  }
  EXPECT_EQ(report.cases.size(), StackshotCases().size());
}

TEST(StackshotRunner, RunsAreDeterministicInVirtualTime) {
  const RunReport a = RunInProcess();
  const RunReport b = RunInProcess();
  ASSERT_EQ(a.cases.size(), b.cases.size());
  for (size_t i = 0; i < a.cases.size(); ++i) {
    EXPECT_EQ(a.cases[i].target_ns, b.cases[i].target_ns) << a.cases[i].name;
    ASSERT_EQ(a.cases[i].outcomes.size(), b.cases[i].outcomes.size());
    for (const auto& [id, o] : a.cases[i].outcomes) {
      EXPECT_EQ(o.checks, b.cases[i].outcomes.at(id).checks) << a.cases[i].name << " " << id;
    }
  }
}

TEST(StackshotRunner, InProcessRunIsFast) {
  const auto t0 = std::chrono::steady_clock::now();
  const RunReport r = RunInProcess();
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  TimeNs device_ns = 0;
  for (const CaseResult& c : r.cases) device_ns += c.target_ns;
  std::printf("in-process stackshot3x: %zu cases, %.1f s of device time in %.3f s wall\n",
              r.cases.size(), static_cast<double>(device_ns) / 1e9, s);
  EXPECT_LT(s, 30.0);
}

TEST(StackshotRunner, ShardsPartitionTheCases) {
  std::multiset<std::string> all, sharded;
  for (const CaseResult& c : RunInProcess().cases) all.insert(c.suite + "/" + c.name);
  for (uint32_t i = 0; i < 3; ++i) {
    RunOptions o;
    o.shard_index = i;
    o.shard_count = 3;
    for (const CaseResult& c : RunInProcess(o).cases) sharded.insert(c.suite + "/" + c.name);
  }
  EXPECT_EQ(all, sharded);
}

TEST(StackshotRunner, RandomSequencesHoldForManySeeds) {
  for (uint64_t seed = 1; seed <= 20; ++seed) {
    RunOptions o;
    o.cases = "random/*";
    o.random.seed = seed;
    o.random.steps = 60;
    const RunReport r = RunInProcess(o);
    ASSERT_EQ(r.cases.size(), 1u);
    EXPECT_FALSE(r.cases[0].MustFailed()) << "seed " << seed << "\n" << ConsoleReport(r, true);
    EXPECT_GT(r.cases[0].outcomes.at("SS-CODE-003").checks, 0u);
  }
}

// The random suite's law: any seed and length of valid rail requests leaves
// the StackShot 3X answering each once with a status the model allows and
// resting where the model says.
RC_GTEST_PROP(StackshotRandomSuite, AnySeedAndLengthHolds, ()) {
  RunOptions o;
  o.cases = "random/*";
  o.random.seed = *rc::gen::arbitrary<uint64_t>();
  o.random.steps = *rc::gen::inRange(1, 60);
  const RunReport r = RunInProcess(o);
  RC_ASSERT(r.cases.size() == 1u);
  RC_ASSERT(!r.cases[0].MustFailed());
}

TEST(StackshotRunner, AConstantChecksumIsANoteNotAFailure) {
  const std::filesystem::path p = std::filesystem::temp_directory_path() /
                                  ("mococheck_ss69_" + std::to_string(getpid()) + ".json");
  {
    std::ofstream out(p);
    out << R"({"checksum": "constant-0x69"})";
  }
  RunOptions o;
  o.cases = "connect/*";
  const RunReport r = RunInProcess(o, p.string());
  std::filesystem::remove(p);
  EXPECT_EQ(r.rules.at("SS-CSUM-001").status, Status::kNoted) << ConsoleReport(r, false);
  EXPECT_EQ(r.rules.at("SS-CSUM-002").status, Status::kPass);
  EXPECT_EQ(ExitCode(r), 0) << ConsoleReport(r, false);
}

TEST(StackshotRunner, ReportsCarryTheDeviceAndEveryRule) {
  RunOptions o;
  o.cases = "connect/*";
  const RunReport r = RunInProcess(o);
  const nlohmann::json j = JsonReport(r);
  EXPECT_EQ(j["target"], "in-process:stackshot3x");
  EXPECT_EQ(j["exit_code"], 0);
  EXPECT_EQ(j["rules"].size(), StackshotRules().size());
  const std::string x = JunitReport(r);
  EXPECT_NE(x.find("name=\"SS-PING-001\""), std::string::npos);
}

TEST(StackshotRunner, RuleFilterNarrowsTheChecks) {
  RunOptions o;
  o.rules = "SS-PING-*";
  o.cases = "connect/*";
  const RunReport r = RunInProcess(o);
  for (const auto& [id, s] : r.rules) EXPECT_EQ(id.rfind("SS-PING-", 0), 0u) << id;
  EXPECT_EQ(r.rules.at("SS-PING-001").status, Status::kPass);
}

}  // namespace
}  // namespace moco::conformance
