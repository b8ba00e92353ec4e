// A rapidcheck rc::state model of DMC v2 motor control (dmc-v2-protocol.txt
// "Motor Control"; ARCHITECTURE house style 11): the model alone decides which
// commands are valid and where each motor must rest, the DMC-16 runs behind
// the conformance host, and every stream rule must hold after every command.
#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>
#include <rapidcheck/state.h>

#include <optional>
#include <ostream>
#include <vector>

#include "conformance/protocols/dmc/dmc_host.h"
#include "conformance/protocols/dmc/dmc_suites.h"
#include "conformance/targets/target.h"

namespace moco::conformance {
namespace {

constexpr uint8_t kMotors = 3;  // of the DMC-16's 16, to keep sequences dense

struct Model {
  std::vector<std::optional<int32_t>> rest_steps = std::vector<std::optional<int32_t>>(kMotors, 0);
  std::vector<bool> settled = std::vector<bool>(kMotors, true);  // known to be at rest
};

struct Sut {
  Sut() : target(InProcessTarget::ForModel("dmc16", "")) {
    target->Open();
    host = std::make_unique<DmcHost>(*target, verdicts, HostOptions{});
    host->Call(dmc::HiRequest{});
  }
  std::unique_ptr<InProcessTarget> target;
  Verdicts verdicts;
  std::unique_ptr<DmcHost> host;
};

using Cmd = rc::state::Command<Model, Sut>;

void AssertStreamRulesHold(const Sut& s) {
  for (const auto& [id, o] : s.verdicts.outcomes()) {
    if (o.status != Status::kFail) continue;
    const Rule* r = FindRule(id);
    RC_ASSERT(!(r != nullptr && r->level == Level::kMust));
  }
}

struct Move : Cmd {
  uint8_t motor = *rc::gen::inRange<uint8_t>(1, kMotors + 1);
  int32_t target_steps = *rc::gen::inRange(-3000, 3001);
  void apply(Model& m) const override {
    m.rest_steps[motor - 1u] = target_steps;
    m.settled[motor - 1u] = false;
  }
  void run(const Model&, Sut& s) const override {
    RC_ASSERT(As<dmc::MotorMoveResponse>(s.host->Call(dmc::MotorMove{motor, target_steps})) !=
              nullptr);
    AssertStreamRulesHold(s);
  }
  void show(std::ostream& os) const override {
    os << "MOTOR_MOVE " << int{motor} << " " << target_steps;
  }
};

struct StopAll : Cmd {
  void apply(Model& m) const override {
    for (size_t i = 0; i < kMotors; ++i) {
      if (!m.settled[i]) m.rest_steps[i].reset();  // stops somewhere on the way
    }
  }
  void run(const Model&, Sut& s) const override {
    RC_ASSERT(AckCodeOf(s.host->Call(dmc::MotorStopAll{})) == dmc::ToWire(dmc::AckCode::kOk));
    AssertStreamRulesHold(s);
  }
  void show(std::ostream& os) const override { os << "MOTOR_STOP_ALL"; }
};

struct Reset : Cmd {
  uint8_t motor = *rc::gen::inRange<uint8_t>(1, kMotors + 1);
  int32_t value = *rc::gen::inRange(-5000, 5001);
  void checkPreconditions(const Model& m) const override { RC_PRE(m.settled[motor - 1u]); }
  void apply(Model& m) const override { m.rest_steps[motor - 1u] = value; }
  void run(const Model&, Sut& s) const override {
    const DmcRecord* r = s.host->Call(dmc::MotorResetPosition{motor, value});
    RC_ASSERT(AckCodeOf(r) == dmc::ToWire(dmc::AckCode::kOk));
    AssertStreamRulesHold(s);
  }
  void show(std::ostream& os) const override {
    os << "MOTOR_RESET_POSITION " << int{motor} << " " << value;
  }
};

struct Wait : Cmd {
  int ms = *rc::gen::inRange(0, 1500);
  void run(const Model&, Sut& s) const override {
    s.host->Idle(ms * sim::kNsPerMs);
    AssertStreamRulesHold(s);
  }
  void show(std::ostream& os) const override { os << "wait " << ms << " ms"; }
};

// Waits for rest and compares every known motor with the model.
struct Settle : Cmd {
  void apply(Model& m) const override { m.settled.assign(kMotors, true); }
  void run(const Model& m, Sut& s) const override {
    RC_ASSERT(WaitRest(*s.host, 600 * sim::kNsPerSecond));
    const auto p = GetPositions(*s.host);
    RC_ASSERT(p.has_value());
    for (size_t i = 0; i < kMotors; ++i) {
      if (m.rest_steps[i]) RC_ASSERT((*p)[i] == *m.rest_steps[i]);
    }
    AssertStreamRulesHold(s);
  }
  void show(std::ostream& os) const override { os << "settle and compare positions"; }
};

RC_GTEST_PROP(StateModel, Dmc16FollowsTheMotorModel, ()) {
  Model model;
  Sut sut;
  rc::state::check(model, sut,
                   rc::state::gen::execOneOfWithArgs<Move, StopAll, Reset, Wait, Settle>());
}

}  // namespace
}  // namespace moco::conformance
