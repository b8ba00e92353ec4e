// Laws every registered protocol's runner obeys alike (core/run.h).
#include "conformance/protocols/registry.h"

#include <gtest/gtest.h>

#include <set>
#include <string>

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
  bool Send(wire::ByteView) override { return true; }
  bool Receive(TimeNs deadline_ns, wire::Bytes&) override {
    now_ = std::max(now_, deadline_ns);
    return true;
  }

 private:
  TimeNs now_ = 0;
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

// A device that does not introduce itself fails certification under every
// protocol: the cases that need nothing run and find their greeting
// unanswered; the others are not applicable, and say why.
TEST(Registry, ASilentDeviceFailsUnderEveryProtocolAlike) {
  for (const ProtocolRunner& r : Runners()) {
    SCOPED_TRACE(std::string(ProtocolName(r.protocol)));
    SilentTarget target;
    ASSERT_FALSE(target.Open());
    RunOptions options;
    options.random.steps = 5;
    const RunReport report = r.run(target, options);
    EXPECT_TRUE(report.device.empty());
    EXPECT_EQ(ExitCode(report), 1);
    size_t ran = 0, not_applicable = 0;
    for (const CaseResult& c : report.cases) {
      if (c.applicable) {
        ++ran;
        EXPECT_TRUE(c.MustFailed()) << c.suite << "/" << c.name;
      } else {
        ++not_applicable;
        EXPECT_EQ(c.not_applicable_because, "the device did not introduce itself");
      }
    }
    EXPECT_GT(ran, 0u);
    EXPECT_GT(not_applicable, 0u);
    for (const auto& [id, s] : report.rules) {
      const Rule* rule = FindRule(id);
      ASSERT_NE(rule, nullptr);
      if (rule->needs != Needs::kNothing) {
        EXPECT_EQ(s.status, Status::kNotApplicable) << id;
      }
    }
  }
}

}  // namespace
}  // namespace moco::conformance
