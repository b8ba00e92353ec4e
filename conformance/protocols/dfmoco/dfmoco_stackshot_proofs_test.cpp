// Proving tests of the StackShot 3X DfMoco dialect rules (DFM-SS-*,
// stackshot-protocol.txt section 3; ERRATA 3.9): the emulated StackShot 3X in
// DfMoco mode with one fault planted at its wire (each line it writes handed
// to a LineBreakage, each line of the host to an input breakage), run through
// the whole runner; the rule that names the fault fails, and the device
// without a fault passes every DFM-SS rule.
#include <gtest/gtest.h>

#include <memory>
#include <string>

#include "conformance/protocols/dfmoco/dfmoco_broken_device_testing.h"
#include "devices/stackshot3x/stackshot3x.h"
#include "wire/stackshot_constants.h"

namespace moco::conformance::dfmoco_testing {
namespace {

// What the host's line becomes before the StackShot reads it; it may write
// lines of its own to `out` (an answer the device should not give).
using SsInput = std::function<std::string(const std::string& line, devices::ByteSink& out)>;

// The emulated StackShot 3X in DfMoco mode with a broken output stage and,
// optionally, input stage.
class BrokenStackshot final : public devices::Device, private devices::ByteSink {
 public:
  BrokenStackshot(sim::Scheduler& s, devices::ByteSink& out, LineBreakage b, SsInput in)
      : s_(s), out_(out), b_(std::move(b)), in_(std::move(in)), inner_(s, *this) {
    RelayLineSwitchesOf(inner_);
  }
  std::string_view Model() const override { return "stackshot3x-broken"; }
  devices::DeviceLine Line() const override { return inner_.Line(); }
  void PowerOn() override {
    inner_.PowerOn();
    // Settings->Mode->Motion->DfMoco on the panel (section 3).
    inner_.SetGlobalModeFromPanel(stackshot::GlobalMode::kMotionDfMoco);
  }
  void PowerOff() override {
    inner_.PowerOff();
    partial_.clear();
  }
  bool Powered() const override { return inner_.Powered(); }
  void OnHostBytes(wire::ByteView bytes) override {
    std::string pass;
    for (const uint8_t b : bytes) {
      const char c = static_cast<char>(b);
      if (c != '\r' && c != '\n') {
        reading_.push_back(c);
        continue;
      }
      if (!reading_.empty()) {
        std::string line = in_ ? in_(reading_, out_) : reading_;
        reading_.clear();
        last_command_ = line;
        pass += line;
      }
      pass.push_back(c);
    }
    if (!pass.empty()) {
      inner_.OnHostBytes(
          wire::ByteView(reinterpret_cast<const uint8_t*>(pass.data()), pass.size()));
    }
  }
  void OnHostLink(bool open) override { inner_.OnHostLink(open); }
  sim::Rig* rig() override { return inner_.rig(); }
  sim::GioPort* gio() override { return inner_.gio(); }

 private:
  void Write(wire::ByteView bytes) override {
    for (const uint8_t b : bytes) {
      partial_.push_back(static_cast<char>(b));
      if (partial_.size() >= 2 && partial_.ends_with("\r\n")) {
        partial_.resize(partial_.size() - 2);
        const std::string line = std::move(partial_);
        partial_.clear();
        b_(line, last_command_, s_, out_);
      }
    }
  }

  sim::Scheduler& s_;
  devices::ByteSink& out_;
  LineBreakage b_;
  SsInput in_;
  std::string partial_;
  std::string reading_;
  std::string last_command_;
  devices::Stackshot3x inner_;
};

RunReport RunStackshot(LineBreakage b, const char* cases, SsInput in = {},
                       const std::string& dialect = "auto") {
  InProcessTarget target("stackshot3x-broken", [b, in](sim::Scheduler& s, devices::ByteSink& out) {
    return std::make_unique<BrokenStackshot>(s, out, b, in);
  });
  EXPECT_FALSE(target.Open().has_value());
  RunOptions options = Only(cases);
  options.host.dialect = dialect;
  return RunDfmoco(target, options);
}

// Rewrites one answer: `from` becomes `to` when the last command was `after`.
LineBreakage Rewrite(std::string after, std::string from, std::string to) {
  return [after, from, to](const std::string& line, const std::string& last, sim::Scheduler&,
                           devices::ByteSink& out) {
    WriteLine(out, last == after && line == from ? to : line);
  };
}

TEST(DfmocoStackshotProofs, TheStackShotInDfmocoModePassesEveryRule) {
  const RunReport r = RunStackshot(PassThrough, "*");
  EXPECT_EQ(r.device_info.value("dialect", ""), "stackshot3x");
  EXPECT_TRUE(FailedMusts(r).empty()) << ConsoleReport(r, false);
  for (const Rule& rule : DfmocoRules()) {
    if (!rule.id.starts_with("DFM-SS-")) continue;
    ASSERT_TRUE(r.rules.count(std::string(rule.id))) << rule.id;
    EXPECT_EQ(r.rules.at(std::string(rule.id)).status, Status::kPass) << rule.id;
  }
  // The sketch's own behaviour is not judged: not applicable.
  for (const char* id : {"DFM-MM-001", "DFM-MP-002", "DFM-PR-002", "DFM-HI-001"}) {
    EXPECT_EQ(r.rules.at(id).status, Status::kNotApplicable) << id;
  }
}

TEST(DfmocoStackshotProofs, TheSketchIsNotJudgedByTheStackShotRules) {
  const RunReport r = RunBroken(PassThrough, Only("*"));
  EXPECT_EQ(r.device_info.value("dialect", ""), "sketch");
  EXPECT_EQ(r.rules.at("DFM-SS-004").status, Status::kNotApplicable);
  EXPECT_EQ(r.rules.at("DFM-MM-001").status, Status::kPass);
}

TEST(DfmocoStackshotProofs, FourAxesIsCaughtBySs001) {
  const RunReport r = RunStackshot(
      [](const std::string& line, const std::string&, sim::Scheduler&, devices::ByteSink& out) {
        WriteLine(out, line == "hi 1 3 1.2.6" ? "hi 1 4 1.2.6" : line);
      },
      "stackshot/mp-all", {}, "stackshot3x");
  ExpectCaught(r, "DFM-SS-001");
}

TEST(DfmocoStackshotProofs, AMoveAnsweredWithTheTargetIsCaughtBySs002) {
  const RunReport r = RunStackshot(
      [](const std::string& line, const std::string& last, sim::Scheduler&,
         devices::ByteSink& out) {
        WriteLine(out, StartsWith(last, "mm") && StartsWith(line, "mm") ? last : line);
      },
      "stackshot/move-reports");
  ExpectCaught(r, "DFM-SS-002");
  EXPECT_EQ(r.rules.at("DFM-SS-003").status, Status::kPass);
}

TEST(DfmocoStackshotProofs, NoPeriodicMoveReportsAreCaughtBySs003) {
  const RunReport r = RunStackshot(
      [](const std::string& line, const std::string& last, sim::Scheduler&,
         devices::ByteSink& out) {
        if (StartsWith(line, "mm") && !StartsWith(last, "mm")) return;  // reports dropped
        WriteLine(out, line);
      },
      "stackshot/move-reports");
  ExpectCaught(r, "DFM-SS-003");
  EXPECT_TRUE(FailedMusts(r).empty());
}

TEST(DfmocoStackshotProofs, MpStarAnsweringOneMotorIsCaughtBySs004) {
  auto count = std::make_shared<int>(0);
  const RunReport r = RunStackshot(
      [count](const std::string& line, const std::string& last, sim::Scheduler&,
              devices::ByteSink& out) {
        if (last == "mp *" && StartsWith(line, "mp") && ++*count > 1) return;
        WriteLine(out, line);
      },
      "stackshot/mp-all");
  ExpectCaught(r, "DFM-SS-004");
}

TEST(DfmocoStackshotProofs, ZmAnsweredZmIsCaughtBySs005) {
  const RunReport r = RunStackshot(Rewrite("zm 1", "mp 1 0", "zm 1"), "stackshot/np-zm");
  ExpectCaught(r, "DFM-SS-005");
}

TEST(DfmocoStackshotProofs, NpToAMovingMotorSentElsewhereIsCaughtBySs006) {
  const RunReport r =
      RunStackshot(PassThrough, "stackshot/np-zm", [](const std::string& line, devices::ByteSink&) {
        return line == "np 1 3500" ? std::string("np 1 3600") : line;
      });
  ExpectCaught(r, "DFM-SS-006");
  EXPECT_EQ(r.rules.at("DFM-SS-005").status, Status::kPass);
}

TEST(DfmocoStackshotProofs, SaWithAMotorStoppingOnlyThatMotorIsCaughtBySs007) {
  const RunReport r = RunStackshot(Rewrite("sm 1", "sm 1", "sa"), "stackshot/stop-all-motor",
                                   [](const std::string& line, devices::ByteSink&) {
                                     return line == "sa 1" ? std::string("sm 1") : line;
                                   });
  ExpectCaught(r, "DFM-SS-007");
}

TEST(DfmocoStackshotProofs, APulseRateAboveTheMaximumEchoedIsCaughtBySs008) {
  const RunReport r = RunStackshot(
      [](const std::string& line, const std::string& last, sim::Scheduler&,
         devices::ByteSink& out) {
        WriteLine(out, last == "pr 1 100000000" && StartsWith(line, "pr") ? last : line);
      },
      "stackshot/pulse-rate");
  ExpectCaught(r, "DFM-SS-008");
}

TEST(DfmocoStackshotProofs, BfAcknowledgedAsGoMotionIsCaughtBySs009) {
  const RunReport r = RunStackshot(PassThrough, "stackshot/no-go-motion",
                                   [](const std::string& line, devices::ByteSink& out) {
                                     if (StartsWith(line, "bf")) WriteLine(out, "bf 1000");
                                     return line;
                                   });
  ExpectCaught(r, "DFM-SS-009");
  EXPECT_TRUE(FailedMusts(r).empty());
}

}  // namespace
}  // namespace moco::conformance::dfmoco_testing
