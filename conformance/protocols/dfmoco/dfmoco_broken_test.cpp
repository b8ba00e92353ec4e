// mococheck against the emulated DFMoco Arduino (dfmoco-protocol.txt; FACTS
// "DFMoco"): every MUST rule passes on the Uno and Mega profiles and the 1.x
// sketches, each deliberately broken device (DfmocoFaults) is caught by the
// rule that names its fault, any chunking of the device's output keeps every
// verdict, and the random suite shrinks a failing sequence and saves it.
#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <set>

#include "conformance/core/patience_testing.h"
#include "conformance/core/report.h"
#include "conformance/core/rule_proof_testing.h"
#include "conformance/protocols/dfmoco/dfmoco_broken_device_testing.h"
#include "conformance/protocols/dfmoco/dfmoco_protocol.h"
#include "devices/dfmoco_arduino/dfmoco_arduino.h"
#include "devices/faulty_sink.h"
#include "session/session.h"

namespace moco::conformance {
namespace {

// A DFMoco Arduino with `faults`, its output cut by `cuts` (empty: whole).
class TestDfmoco final : public devices::Device {
 public:
  TestDfmoco(sim::Scheduler& s, devices::ByteSink& out, devices::DfmocoProfile profile,
             devices::DfmocoFaults faults, std::vector<size_t> cuts)
      : sink_(out, devices::FaultySink::CutInto(std::move(cuts))),
        inner_(s, sink_, std::move(profile), std::move(faults)) {
    RelayLineSwitchesOf(inner_);
  }
  std::string_view Model() const override { return "dfmoco-test"; }
  devices::DeviceLine Line() const override { return inner_.Line(); }
  void PowerOn() override { inner_.PowerOn(); }
  void PowerOff() override { inner_.PowerOff(); }
  bool Powered() const override { return inner_.Powered(); }
  void OnHostBytes(wire::ByteView bytes) override { inner_.OnHostBytes(bytes); }
  void OnHostLink(bool open) override { inner_.OnHostLink(open); }

 private:
  devices::FaultySink sink_;  // the output in pieces of `cuts`, round robin
  devices::DfmocoArduino inner_;
};

RunReport RunDevice(devices::DfmocoProfile profile, devices::DfmocoFaults faults = {},
                    RunOptions options = {}, std::vector<size_t> cuts = {}) {
  InProcessTarget target("dfmoco-test", [=](sim::Scheduler& s, devices::ByteSink& out) {
    return std::make_unique<TestDfmoco>(s, out, profile, faults, cuts);
  });
  EXPECT_FALSE(target.Open().has_value());
  return RunDfmoco(target, options);
}

RunReport RunFaulty(devices::DfmocoFaults faults, RunOptions options = {}) {
  return RunDevice(devices::DfmocoProfile{}, std::move(faults), std::move(options));
}

using proof::ExpectCaught;

// Every MUST rule that applies passes, none is left unexercised, and the
// rules of the brief are judged.
void ExpectCertified(const RunReport& r) {
  EXPECT_EQ(ExitCode(r), 0) << ConsoleReport(r, false);
  for (const auto& [id, s] : r.rules) {
    const Rule* rule = FindRule(id);
    ASSERT_NE(rule, nullptr) << id;
    EXPECT_NE(s.status, Status::kFail) << id << "\n" << ConsoleReport(r, false);
    if (rule->level != Level::kNote && s.status != Status::kNotApplicable) {
      EXPECT_EQ(s.status, Status::kPass) << id << " is " << StatusName(s.status);
    }
  }
}

std::filesystem::path Fixture(const char* name) {
  const char* root = std::getenv("MOCO_SOURCE_DIR");
  return std::filesystem::path(root != nullptr ? root : ".") / "fixtures" / "profiles" / name;
}

TEST(DfmocoCatalogue, IdsAreUniqueWellFormedAndEveryRuleQuotesItsClause) {
  std::set<std::string> ids;
  for (const Rule& r : DfmocoRules()) {
    const std::string_view id = r.id;
    const size_t dash = id.rfind('-');
    EXPECT_EQ(id.rfind("DFM-", 0), 0u) << id;
    EXPECT_EQ(id.size() - dash, 4u) << id;  // three digits
    EXPECT_TRUE(ids.insert(std::string(id)).second) << "duplicate " << id;
    EXPECT_GE(r.clause.size(), 10u) << id << " quotes no clause";
    EXPECT_FALSE(r.title.empty()) << id;
    EXPECT_FALSE(r.source.empty()) << id;
    EXPECT_EQ(FindRule(id), &r);
  }
  EXPECT_GE(DfmocoRules().size(), 30u);
  EXPECT_EQ(FindRule("DFM-MS-002")->level, Level::kMust);
  EXPECT_EQ(FindRule("DFM-NP-003")->level, Level::kNote);    // protocol text vs FACTS
  EXPECT_EQ(FindRule("DFM-MP-002")->level, Level::kShould);  // "should send occasional"
}

TEST(DfmocoCatalogue, ApplicabilityFollowsTheHiReply) {
  const Rule& velocity = *FindRule("DFM-JM-003");
  const Rule& refusal = *FindRule("DFM-GO-008");
  const Rule& two = *FindRule("DFM-SM-003");
  EXPECT_TRUE(DfmocoApplies(velocity, {2, 4, "2.0.0"}));
  EXPECT_FALSE(DfmocoApplies(velocity, {1, 4, "1.3.1"}));
  EXPECT_TRUE(DfmocoApplies(refusal, {1, 4, "1.3.1"}));
  EXPECT_FALSE(DfmocoApplies(refusal, {1, 4, "1.3.0"}));
  EXPECT_FALSE(DfmocoApplies(refusal, {1, 4, "1.2.7"}));
  EXPECT_TRUE(DfmocoApplies(*FindRule("DFM-GO-001"), {1, 4, "1.2.7"}));
  EXPECT_FALSE(DfmocoApplies(*FindRule("DFM-GO-001"), {1, 4, "beta"}));
  EXPECT_TRUE(DfmocoApplies(two, {2, 2, "2.0.0"}));
  EXPECT_FALSE(DfmocoApplies(two, {2, 1, "2.0.0"}));
  EXPECT_TRUE(DfmocoApplies(*FindRule("DFM-LINE-001"), {0, 0, ""}));
  EXPECT_FALSE(DfmocoApplies(*FindRule("DFM-MM-001"), {2, 0, "2.0.0"}));
  EXPECT_FALSE(DfmocoApplies(*FindRule("DMC-MOVE-003"), {2, 4, "2.0.0"}));
  EXPECT_EQ(ParseDfmocoVersion("1.3.1"), (std::array<int, 3>{1, 3, 1}));
  EXPECT_EQ(ParseDfmocoVersion("2"), (std::array<int, 3>{2, 0, 0}));
  EXPECT_FALSE(ParseDfmocoVersion("x1").has_value());
}

TEST(DfmocoRun, EveryRuleHoldsOnTheUnoProfile) {
  const RunReport r = RunDevice(devices::LoadDfmocoProfile(Fixture("dfmoco-uno.json")));
  ExpectCertified(r);
  EXPECT_EQ(r.device_info["motor_count"], 4);
  EXPECT_EQ(r.device_info["version"], "2.0.0");
  EXPECT_NE(r.device.find("hi 2 4 2.0.0"), std::string::npos) << r.device;
  // The sketch's readings show up as notes, never as failures.
  EXPECT_EQ(r.rules.at("DFM-LINE-007").status, Status::kNoted);  // bare \n (FACTS vs ERRATA 2.1)
  EXPECT_EQ(r.rules.at("DFM-GO-002").status, Status::kNoted);    // bf 1000 (FACTS vs ERRATA 2.5)
  EXPECT_EQ(r.rules.at("DFM-NP-003").status, Status::kPass);     // answers mp, as the sketch
  EXPECT_EQ(r.rules.at("DFM-HI-007").status, Status::kPass);
}

TEST(DfmocoRun, EveryRuleHoldsOnTheMegaProfile) {
  const RunReport r = RunDevice(devices::LoadDfmocoProfile(Fixture("dfmoco-mega.json")));
  ExpectCertified(r);
  EXPECT_EQ(r.device_info["motor_count"], 8);
}

TEST(DfmocoRun, OneXSketchesLeaveOutTheirMissingFeatures) {
  devices::DfmocoProfile p;
  p.firmware = devices::DfmocoFirmware::k1_2_7;
  const RunReport r = RunDevice(p);
  ExpectCertified(r);
  EXPECT_EQ(r.rules.at("DFM-JM-003").status, Status::kNotApplicable);  // major 1: no velocity
  EXPECT_EQ(r.rules.at("DFM-GO-008").status, Status::kNotApplicable);  // bf -1 from 1.3.1 on
  p.firmware = devices::DfmocoFirmware::k1_3_1;
  const RunReport r131 = RunDevice(p);
  ExpectCertified(r131);
  EXPECT_EQ(r131.rules.at("DFM-GO-008").status, Status::kPass);
}

TEST(DfmocoBroken, WrongMsWidthIsCaughtByMs002) {
  devices::DfmocoFaults f;
  f.ms_width_delta = 4;  // an Uno answering with a Mega's 8 digits
  const RunReport r = RunFaulty(f);
  ExpectCaught(r, "DFM-MS-002");
  EXPECT_EQ(ExitCode(r), 1);
  f.ms_width_delta = -1;
  ExpectCaught(RunFaulty(f), "DFM-MS-002");
}

TEST(DfmocoBroken, MissingReplyIsCaughtByReply001) {
  devices::DfmocoFaults f;
  f.silent_word = "pr";
  const RunReport r = RunFaulty(f);
  ExpectCaught(r, "DFM-REPLY-001");
  EXPECT_EQ(ExitCode(r), 1);
}

TEST(DfmocoBroken, LateMpReportsAreCaughtByMp003) {
  devices::DfmocoFaults f;
  f.report_period_ms = 2500;
  const RunReport r = RunFaulty(f);
  ExpectCaught(r, "DFM-MP-003");
  ExpectCaught(r, "DFM-MP-004");
  // Late, but not wrong: the positions the reports carry are right.
  EXPECT_NE(r.rules.at("DFM-MP-005").status, Status::kFail);
  EXPECT_EQ(r.rules.at("DFM-MP-006").status, Status::kPass);
}

TEST(DfmocoBroken, WrongPositionAfterAStopIsCaughtByMp005) {
  devices::DfmocoFaults f;
  f.stop_report_offset_steps = 3;
  const RunReport r = RunFaulty(f);
  ExpectCaught(r, "DFM-MP-005");
  EXPECT_EQ(ExitCode(r), 1);
  // The answers to `mp m` are right: only the report is wrong.
  EXPECT_EQ(r.rules.at("DFM-MP-001").status, Status::kPass);
}

TEST(DfmocoBroken, GarbageLineIsCaughtByLine004) {
  devices::DfmocoFaults f;
  f.extra_line_after_ms = "dbg: steps=12";
  const RunReport r = RunFaulty(f);
  ExpectCaught(r, "DFM-LINE-004");
  EXPECT_EQ(ExitCode(r), 1);
  // The evidence quotes the line's bytes.
  bool quoted = false;
  for (const CaseResult& c : r.cases) {
    auto it = c.outcomes.find("DFM-LINE-004");
    if (it == c.outcomes.end() || it->second.evidence.empty()) continue;
    quoted = quoted || it->second.evidence[0].hex ==
                           wire::ToHex(wire::FromHex("6462673a2073746570733d31320d0a").value());
  }
  EXPECT_TRUE(quoted);
}

TEST(DfmocoBroken, AStrayReplyIsCaughtByLine005) {
  devices::DfmocoFaults f;
  f.extra_line_after_ms = "sa";  // a reply of the grammar that answers nothing
  const RunReport r = RunFaulty(f);
  ExpectCaught(r, "DFM-LINE-005");
  EXPECT_EQ(r.rules.at("DFM-LINE-004").status, Status::kPass);
}

// How the device's bytes are cut into writes never changes a verdict.
RC_GTEST_PROP(DfmocoBroken, AnyChunkingOfTheOutputKeepsEveryVerdict, ()) {
  const auto cuts = *rc::gen::container<std::vector<size_t>>(rc::gen::inRange<size_t>(1, 20));
  RunOptions o;
  o.cases = "connect/*,errors/*,motor/np-zm";
  const RunReport whole = RunDevice({}, {}, o);
  const RunReport cut = RunDevice({}, {}, o, cuts);
  RC_ASSERT(ExitCode(cut) == 0);
  RC_ASSERT(whole.rules.size() == cut.rules.size());
  for (const auto& [id, s] : whole.rules) RC_ASSERT(cut.rules.at(id).status == s.status);
}

TEST(DfmocoBroken, RandomSuiteShrinksAFailingSequenceAndSavesIt) {
  const std::filesystem::path session =
      std::filesystem::temp_directory_path() /
      ("mococheck_dfm_shrunk_" + std::to_string(getpid()) + ".jsonl");
  RunOptions o;
  o.cases = "random/*";
  o.random.seed = 3;
  o.random.steps = 40;
  o.random.session_path = session.string();
  devices::DfmocoFaults f;
  f.silent_word = "sa";
  const RunReport r = RunFaulty(f, o);
  ASSERT_EQ(r.cases.size(), 1u);
  EXPECT_TRUE(r.cases[0].MustFailed());
  const auto& log = r.cases[0].log;
  const auto has = [&](const std::string& s) {
    return std::find(log.begin(), log.end(), s) != log.end();
  };
  EXPECT_TRUE(has("shrunk to 1 step(s):")) << ConsoleReport(r, true);
  EXPECT_TRUE(has("  sa")) << ConsoleReport(r, true);
  auto loaded = session::LoadSession(session);
  ASSERT_TRUE(std::holds_alternative<session::Session>(loaded));
  const auto& s = std::get<session::Session>(loaded);
  EXPECT_EQ(s.header.protocol, wire::Protocol::kDfmoco);
  EXPECT_EQ(s.header.clock, "virtual");
  bool sa_sent = false;
  for (const auto& e : s.entries) {
    if (e.from != session::Origin::kHost) continue;
    sa_sent = sa_sent || std::string(e.bytes.begin(), e.bytes.end()) == "sa\r\n";
  }
  EXPECT_TRUE(sa_sent);
  std::filesystem::remove(session);
}

TEST(DfmocoBroken, RandomSuitePassesOnTheSketchForManySeeds) {
  for (uint64_t seed = 1; seed <= 8; ++seed) {
    RunOptions o;
    o.cases = "random/*";
    o.random.seed = seed;
    o.random.steps = 60;
    const RunReport r = RunFaulty({}, o);
    EXPECT_EQ(ExitCode(r), 0) << "seed " << seed << "\n" << ConsoleReport(r, true);
  }
}

// A broken sketch is judged in at most twice the good one's time, with the
// same rules failing as when every answer is waited out.
TEST(BrokenSketch, NoAnswerToOneCommandIsJudgedFast) {
  patience_testing::ExpectJudgedFast(
      [](const RunOptions& o) { return dfmoco_testing::RunBroken(dfmoco_testing::PassThrough, o); },
      [](const RunOptions& o) {
        return dfmoco_testing::RunBroken(
            [](const std::string& line, const std::string& last, sim::Scheduler& s,
               devices::ByteSink& out) {
              if (line.rfind("ms", 0) != 0) dfmoco_testing::PassThrough(line, last, s, out);
            },
            o);
      });
}

TEST(BrokenSketch, ASketchThatStopsMidRunIsJudgedFast) {
  patience_testing::ExpectJudgedFast(
      [](const RunOptions& o) { return dfmoco_testing::RunBroken(dfmoco_testing::PassThrough, o); },
      [](const RunOptions& o) {
        auto written = std::make_shared<size_t>(0);
        return dfmoco_testing::RunBroken(
            [written](const std::string& line, const std::string& last, sim::Scheduler& s,
                      devices::ByteSink& out) {
              if ((*written)++ < 300) dfmoco_testing::PassThrough(line, last, s, out);
            },
            o);
      });
}

}  // namespace
}  // namespace moco::conformance
