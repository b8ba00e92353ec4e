// A rapidcheck rc::state model of DFMoco motor control (dfmoco-protocol.txt
// "Messages"; ARCHITECTURE house style 11): the model alone decides which
// commands are valid (np and zm only on a motor known to rest) and where each
// motor must rest; the DFMoco Arduino runs behind the conformance host. Laws:
// every command is answered per its grammar (no MUST stream rule fails after
// any command), and at rest every motor the model knows is where it says.
#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>
#include <rapidcheck/state.h>

#include <optional>
#include <ostream>
#include <vector>

#include "conformance/protocols/dfmoco/dfmoco_host.h"
#include "conformance/protocols/dfmoco/dfmoco_suites.h"
#include "conformance/targets/target.h"

namespace moco::conformance {
namespace {

constexpr int32_t kMotors = 3;  // of the Uno's 4, to keep sequences dense

struct Model {
  std::vector<std::optional<int32_t>> rest_steps = std::vector<std::optional<int32_t>>(kMotors, 0);
  std::vector<bool> settled = std::vector<bool>(kMotors, true);  // known to rest now
};

struct Sut {
  Sut() : target(InProcessTarget::ForModel("dfmoco", "")) {
    target->Open();
    host = std::make_unique<DfmHost>(*target, verdicts, HostOptions{});
    host->Call("hi");
  }
  std::unique_ptr<InProcessTarget> target;
  Verdicts verdicts;
  std::unique_ptr<DfmHost> host;
};

using Cmd = rc::state::Command<Model, Sut>;

void AssertStreamRulesHold(const Sut& s) {
  for (const auto& [id, o] : s.verdicts.outcomes()) {
    if (o.status != Status::kFail) continue;
    const Rule* r = FindRule(id);
    RC_ASSERT(!(r != nullptr && r->level == Level::kMust));
  }
}

// Sends `line` and requires an answer of type T.
template <typename T>
void CallExpecting(Sut& s, const std::string& line) {
  RC_ASSERT(As<T>(s.host->Call(line)) != nullptr);
  AssertStreamRulesHold(s);
}

struct Move : Cmd {
  int32_t motor = *rc::gen::inRange<int32_t>(1, kMotors + 1);
  int32_t to_steps = *rc::gen::inRange(-3000, 3001);
  void apply(Model& m) const override {
    const auto i = static_cast<size_t>(motor - 1);
    // A motor in motion may be at p when it reads this (it has not left its
    // start yet, or it passes through): the sketch answers `mp m p`, keeps
    // its destination (FACTS DFMoco) and comes to rest elsewhere.
    if (m.settled[i]) {
      m.rest_steps[i] = to_steps;
    } else {
      m.rest_steps[i].reset();
    }
    m.settled[i] = false;
  }
  void run(const Model& m, Sut& s) const override {
    const DfmLine* l = s.host->Call("mm " + std::to_string(motor) + " " + std::to_string(to_steps));
    // `mm m p` when it must move, `mp m p` when it rests there already.
    const bool at = m.settled[static_cast<size_t>(motor - 1)] &&
                    m.rest_steps[static_cast<size_t>(motor - 1)] == to_steps;
    if (at) {
      RC_ASSERT(As<dfmoco::PositionReply>(l) != nullptr);
    } else {
      const auto* r = As<dfmoco::MoveReply>(l);
      if (r == nullptr) {
        // A motor in motion may pass through p: the model does not know where it is.
        RC_ASSERT(!at && (!m.settled[static_cast<size_t>(motor - 1)] ||
                          !m.rest_steps[static_cast<size_t>(motor - 1)]));
        RC_ASSERT(As<dfmoco::PositionReply>(l) != nullptr);
      } else {
        RC_ASSERT(r->position_steps == to_steps);
      }
    }
    AssertStreamRulesHold(s);
  }
  void show(std::ostream& os) const override { os << "mm " << motor << " " << to_steps; }
};

struct StopOne : Cmd {
  int32_t motor = *rc::gen::inRange<int32_t>(1, kMotors + 1);
  void apply(Model& m) const override {
    if (!m.settled[static_cast<size_t>(motor - 1)])
      m.rest_steps[static_cast<size_t>(motor - 1)].reset();
  }
  void run(const Model&, Sut& s) const override {
    CallExpecting<dfmoco::StopMotorReply>(s, "sm " + std::to_string(motor));
  }
  void show(std::ostream& os) const override { os << "sm " << motor; }
};

struct StopAll : Cmd {
  void apply(Model& m) const override {
    for (size_t i = 0; i < kMotors; ++i) {
      if (!m.settled[i]) m.rest_steps[i].reset();  // stops somewhere on the way
    }
  }
  void run(const Model&, Sut& s) const override { CallExpecting<dfmoco::StopAllReply>(s, "sa"); }
  void show(std::ostream& os) const override { os << "sa"; }
};

struct NewPosition : Cmd {
  int32_t motor = *rc::gen::inRange<int32_t>(1, kMotors + 1);
  int32_t value = *rc::gen::inRange(-5000, 5001);
  void checkPreconditions(const Model& m) const override {
    RC_PRE(m.settled[static_cast<size_t>(motor - 1)]);  // "(no movement)"
  }
  void apply(Model& m) const override { m.rest_steps[static_cast<size_t>(motor - 1)] = value; }
  void run(const Model&, Sut& s) const override {
    const DfmLine* l = s.host->Call("np " + std::to_string(motor) + " " + std::to_string(value));
    const auto* p = As<dfmoco::PositionReply>(l);
    RC_ASSERT(p != nullptr);
    RC_ASSERT(p->position_steps == value);
    AssertStreamRulesHold(s);
  }
  void show(std::ostream& os) const override { os << "np " << motor << " " << value; }
};

struct Zero : Cmd {
  int32_t motor = *rc::gen::inRange<int32_t>(1, kMotors + 1);
  void checkPreconditions(const Model& m) const override {
    RC_PRE(m.settled[static_cast<size_t>(motor - 1)]);
  }
  void apply(Model& m) const override { m.rest_steps[static_cast<size_t>(motor - 1)] = 0; }
  void run(const Model&, Sut& s) const override {
    CallExpecting<dfmoco::PositionReply>(s, "zm " + std::to_string(motor));
  }
  void show(std::ostream& os) const override { os << "zm " << motor; }
};

struct PulseRate : Cmd {
  int32_t motor = *rc::gen::inRange<int32_t>(1, kMotors + 1);
  int32_t rate = *rc::gen::inRange(0, 30000);
  void run(const Model&, Sut& s) const override {
    const DfmLine* l = s.host->Call("pr " + std::to_string(motor) + " " + std::to_string(rate));
    const auto* p = As<dfmoco::PulseRateReply>(l);
    RC_ASSERT(p != nullptr);
    RC_ASSERT(p->rate_steps_per_s == std::clamp(rate, 100, 20000));
    AssertStreamRulesHold(s);
  }
  void show(std::ostream& os) const override { os << "pr " << motor << " " << rate; }
};

struct Status_ : Cmd {
  void run(const Model&, Sut& s) const override {
    const auto* st = As<dfmoco::MotorStatusReply>(s.host->Call("ms"));
    RC_ASSERT(st != nullptr);
    RC_ASSERT(st->moving.size() == 4u);
    AssertStreamRulesHold(s);
  }
  void show(std::ostream& os) const override { os << "ms"; }
};

struct Wait : Cmd {
  int ms = *rc::gen::inRange(0, 1500);
  void run(const Model&, Sut& s) const override {
    s.host->Idle(ms * sim::kNsPerMs);
    AssertStreamRulesHold(s);
  }
  void show(std::ostream& os) const override { os << "(wait " << ms << " ms)"; }
};

// Polls ms until every motor rests and compares every known motor with the model.
struct Settle : Cmd {
  void apply(Model& m) const override { m.settled.assign(kMotors, true); }
  void run(const Model& m, Sut& s) const override {
    RC_ASSERT(DfmWaitRest(*s.host, 600 * sim::kNsPerSecond).rested);
    for (int32_t i = 1; i <= kMotors; ++i) {
      const auto p = DfmPosition(*s.host, i);
      RC_ASSERT(p.has_value());
      const auto& want = m.rest_steps[static_cast<size_t>(i - 1)];
      if (want) RC_ASSERT(*p == *want);
    }
    AssertStreamRulesHold(s);
  }
  void show(std::ostream& os) const override { os << "(settle and compare positions)"; }
};

RC_GTEST_PROP(DfmocoStateModel, TheSketchFollowsTheMotorModel, ()) {
  Model model;
  Sut sut;
  rc::state::check(model, sut,
                   rc::state::gen::execOneOfWithArgs<Move, StopOne, StopAll, NewPosition, Zero,
                                                     PulseRate, Status_, Wait, Settle>());
}

}  // namespace
}  // namespace moco::conformance
