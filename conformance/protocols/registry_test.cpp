// Laws every registered protocol's runner obeys alike (core/run.h).
#include "conformance/protocols/registry.h"

#include "conformance/core/run.h"

#include <gtest/gtest.h>

#include <set>
#include <string>
#include <string_view>
#include <vector>

namespace moco::conformance {
namespace {

// A device that never says anything, on a virtual clock.
class SilentTarget final : public Target {
 public:
  std::string Name() const override { return "silent"; }
  bool VirtualClock() const override { return true; }
  bool CanRestart() const override { return true; }
  std::optional<std::string> Open() override { return std::nullopt; }
  void Restart() override { now_ = 0; }
  TimeNs Now() const override { return now_; }
  bool Send(wire::ByteView) override {
    ++sends_;
    return true;
  }
  bool Receive(TimeNs deadline_ns, wire::Bytes&) override {
    now_ = std::max(now_, deadline_ns);
    return true;
  }
  size_t sends() const { return sends_; }

 private:
  TimeNs now_ = 0;
  size_t sends_ = 0;
};

TEST(Registry, EveryProtocolWithRulesHasARunnerAndOnlyItsOwnRules) {
  std::set<Protocol> seen;
  for (const ProtocolRunner& r : Runners()) {
    seen.insert(r.protocol);
    EXPECT_EQ(FindRunner(r.protocol), &r);
    const std::string prefix(wire::Info(r.protocol).rule_prefix);
    ASSERT_FALSE(prefix.empty());
    ASSERT_FALSE(r.rules().empty());
    for (const Rule& rule : r.rules()) EXPECT_EQ(std::string(rule.id).rfind(prefix, 0), 0u);
    EXPECT_FALSE(r.cases().empty());
  }
  for (const Protocol p : kAllProtocols) EXPECT_TRUE(seen.contains(p)) << ProtocolName(p);
  EXPECT_EQ(FindRunner(Protocol::kStackshotDfmoco), nullptr);
}

// A case needs what its own protocol declares (rules/<p>_needs.h) or what
// every protocol shares; `mococheck cases` prints the need's text, which
// names one need (the catalogue test keeps the texts distinct).
TEST(Registry, EveryCaseNeedsOnlyItsOwnProtocolsOrSharedNeeds) {
  for (const RuleSet& set : kRuleSets) {
    const ProtocolRunner* runner = FindRunner(set.protocol);
    ASSERT_NE(runner, nullptr) << ProtocolName(set.protocol);
    std::set<std::string_view> texts;
    for (const Need& n : set.needs) texts.insert(n.text);
    for (const Need& n : SharedNeeds::kShared) texts.insert(n.text);
    for (const CaseInfo& k : runner->cases()) {
      if (k.needs.empty()) continue;  // needs nothing
      EXPECT_TRUE(texts.contains(k.needs))
          << k.suite << "/" << k.name << " needs \"" << k.needs << "\", which "
          << ProtocolName(set.protocol) << " does not declare";
    }
  }
}

// The dialects a protocol's devices are judged in (mococheck run --dialect):
// named apart from each other and from auto, each described, and auto's
// choice named among them; a protocol without dialects says nothing of auto.
TEST(Registry, EveryProtocolsDialectsAreNamedAndAutoPicksOneOfThem) {
  size_t with_dialects = 0;
  for (const ProtocolRunner& r : Runners()) {
    if (r.dialects.empty()) {
      EXPECT_TRUE(r.auto_picks.empty()) << ProtocolName(r.protocol);
      continue;
    }
    ++with_dialects;
    std::set<std::string_view> names;
    for (const DialectChoice& d : r.dialects) {
      EXPECT_FALSE(d.name.empty()) << ProtocolName(r.protocol);
      EXPECT_NE(d.name, kAutoDialect) << ProtocolName(r.protocol);
      EXPECT_FALSE(d.description.empty()) << d.name;
      EXPECT_TRUE(names.insert(d.name).second) << ProtocolName(r.protocol) << " has two " << d.name;
    }
    bool named = false;
    for (std::string_view n : names)
      named = named || r.auto_picks.find(n) != std::string_view::npos;
    EXPECT_TRUE(named) << ProtocolName(r.protocol) << ": auto picks \"" << r.auto_picks << "\"";
  }
  EXPECT_GE(with_dialects, 1u) << "DFMoco judges the sketch's and the StackShot 3X's dialects";
}

// Every protocol on the wire can be mutated and replayed, by exactly one
// runner's hooks, and every protocol with a runner can be fuzzed.
TEST(Registry, EveryWireProtocolHasExactlyOneSetOfFuzzHooks) {
  for (const wire::ProtocolInfo& info : wire::Protocols()) {
    SCOPED_TRACE(std::string(info.name));
    size_t owners = 0;
    for (const ProtocolRunner& r : Runners()) {
      for (const FuzzHooks& h : r.fuzz()) owners += h.protocol == info.id ? 1 : 0;
    }
    EXPECT_EQ(owners, 1u);
    const FuzzHooks* hooks = FindFuzzHooks(info.id);
    ASSERT_NE(hooks, nullptr);
    EXPECT_NE(hooks->mutate, nullptr);
    EXPECT_NE(hooks->matcher, nullptr);
    EXPECT_GT(hooks->gap_ns, 0);
    if (FindRunner(info.id) != nullptr) {
      EXPECT_NE(hooks->start, nullptr);
    }
  }
}

// A device that sends nothing at all to the introduction (asked twice) gives
// no verdict under any protocol: a target error (exit 2) in every subset and
// every shard, with no case run and no rule judged, never a PASS.
TEST(Registry, ASilentDeviceIsATargetErrorInEverySubsetAndShard) {
  for (const ProtocolRunner& r : Runners()) {
    SCOPED_TRACE(std::string(ProtocolName(r.protocol)));
    std::vector<RunOptions> runs(1);
    runs.emplace_back().cases = r.cases().front().suite + "/*";
    for (uint32_t i = 0; i < 8; ++i) {
      RunOptions& o = runs.emplace_back();
      o.shard_index = i;
      o.shard_count = 8;
    }
    for (RunOptions& options : runs) {
      SCOPED_TRACE("cases '" + options.cases + "', shard " +
                   std::to_string(options.shard_index + 1) + "/" +
                   std::to_string(options.shard_count));
      SilentTarget target;
      ASSERT_FALSE(target.Open());
      options.random.steps = 5;
      const RunReport report = r.run(target, options);
      EXPECT_TRUE(report.device.empty());
      EXPECT_EQ(report.target_error, kNoIntroduction);
      EXPECT_EQ(ExitCode(report), 2);
      EXPECT_TRUE(report.cases.empty());
      EXPECT_FALSE(report.JudgedAnyRule());
      // Asked twice, as a host retries after its answer timeout.
      EXPECT_EQ(target.sends(), 2u);
    }
  }
}

// A device that sends bytes but never an introduction fails certification
// under every protocol: the cases that need nothing run and find their
// greeting unanswered; the others are not applicable, and say why. Once two
// cases have drawn no byte from it, the rest are not run, and say why.
class MumblingTarget final : public Target {
 public:
  std::string Name() const override { return "mumbling"; }
  bool VirtualClock() const override { return true; }
  bool CanRestart() const override { return true; }
  std::optional<std::string> Open() override { return std::nullopt; }
  void Restart() override {}
  TimeNs Now() const override { return now_; }
  bool Send(wire::ByteView) override {
    pending_ = ++sends_ <= 2;  // a byte that is no answer, to the introductions only
    return true;
  }
  bool Receive(TimeNs deadline_ns, wire::Bytes& out) override {
    if (pending_) {
      pending_ = false;
      out.push_back(0x7f);
      now_ += 1000;
      return true;
    }
    now_ = std::max(now_, deadline_ns);
    return true;
  }

 private:
  size_t sends_ = 0;
  bool pending_ = false;
  TimeNs now_ = 0;
};

TEST(Registry, ADeviceThatNeverIntroducesItselfFailsUnderEveryProtocolAlike) {
  for (const ProtocolRunner& r : Runners()) {
    SCOPED_TRACE(std::string(ProtocolName(r.protocol)));
    MumblingTarget target;
    ASSERT_FALSE(target.Open());
    RunOptions options;
    options.random.steps = 5;
    const RunReport report = r.run(target, options);
    EXPECT_TRUE(report.device.empty());
    EXPECT_TRUE(report.target_error.empty());
    EXPECT_EQ(ExitCode(report), 1);
    size_t ran = 0, not_applicable = 0, given_up = 0;
    for (const CaseResult& c : report.cases) {
      if (c.applicable) {
        ++ran;
        EXPECT_TRUE(c.MustFailed()) << c.suite << "/" << c.name;
        EXPECT_EQ(given_up, 0u) << "a case ran after the run gave up: " << c.name;
      } else if (c.not_applicable_because == kGaveUpOnSilence) {
        ++given_up;
      } else {
        ++not_applicable;
        EXPECT_EQ(c.not_applicable_because, "the device did not introduce itself");
      }
    }
    EXPECT_EQ(ran, kSilentCasesBeforeGivingUp);
    EXPECT_GT(given_up, 0u);
    EXPECT_GT(not_applicable, 0u);
    EXPECT_EQ(report.cases.size(), r.cases().size()) << "every case is reported";
    for (const auto& [id, s] : report.rules) {
      const Rule* rule = FindRule(id);
      ASSERT_NE(rule, nullptr);
      if (rule->needs != SharedNeeds::kNothing) {
        EXPECT_EQ(s.status, Status::kNotApplicable) << id;
      }
    }
  }
}

// A device that says nothing at first but answers later (a board still
// booting) is not given up on while it sends bytes: the run goes on as long
// as the cases draw an answer.
class LateTarget final : public Target {
 public:
  explicit LateTarget(size_t silent_sends) : silent_sends_(silent_sends) {}
  std::string Name() const override { return "late"; }
  bool VirtualClock() const override { return true; }
  bool CanRestart() const override { return true; }
  std::optional<std::string> Open() override { return std::nullopt; }
  void Restart() override {}
  TimeNs Now() const override { return now_; }
  bool Send(wire::ByteView) override {
    if (sends_++ >= silent_sends_) pending_ = true;
    return true;
  }
  bool Receive(TimeNs deadline_ns, wire::Bytes& out) override {
    if (pending_) {
      pending_ = false;
      out.push_back('?');  // a byte that is no answer: the device is there
      now_ += 1000;
      return true;
    }
    now_ = std::max(now_, deadline_ns);
    return true;
  }

 private:
  size_t silent_sends_;
  size_t sends_ = 0;
  bool pending_ = false;
  TimeNs now_ = 0;
};

TEST(Registry, ADeviceThatSendsBytesIsNeverGivenUpOnForSilence) {
  const ProtocolRunner* r = FindRunner(Protocol::kDfmoco);
  ASSERT_NE(r, nullptr);
  LateTarget target(0);
  ASSERT_FALSE(target.Open());
  RunOptions options;
  options.random.steps = 5;
  const RunReport report = r->run(target, options);
  for (const CaseResult& c : report.cases) {
    EXPECT_NE(c.not_applicable_because, kGaveUpOnSilence) << c.suite << "/" << c.name;
  }
}

}  // namespace
}  // namespace moco::conformance
