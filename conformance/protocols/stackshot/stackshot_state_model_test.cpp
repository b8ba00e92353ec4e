// A rapidcheck rc::state model of StackShot 3X rail control
// (stackshot-protocol.txt 1.1.3-1.1.9; ARCHITECTURE house style 11): the
// model alone decides which requests are valid and which status each must
// get, the emulated controller runs behind the conformance host, and the laws
// are that every request is answered once with that status, the stream rules
// hold after every command, and positions match the model at rest.
#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>
#include <rapidcheck/state.h>

#include <array>
#include <memory>
#include <optional>
#include <ostream>

#include "conformance/protocols/stackshot/stackshot_host.h"
#include "conformance/protocols/stackshot/stackshot_suites.h"
#include "conformance/targets/target.h"

namespace moco::conformance {
namespace {

using stackshot::Action;
using SsCommand = stackshot::Command;
constexpr uint8_t kAxes = 3;

struct Model {
  std::array<std::optional<int64_t>, kAxes> rest_steps{0, 0, 0};
  std::array<bool, kAxes> settled{true, true, true};  // known to be at rest
};

struct Sut {
  Sut() : target(InProcessTarget::ForModel("stackshot3x", "")) {
    target->Open();
    host = std::make_unique<SsHost>(*target, verdicts, HostOptions{});
  }
  std::unique_ptr<InProcessTarget> target;
  Verdicts verdicts;
  std::unique_ptr<SsHost> host;
};

using Cmd = rc::state::Command<Model, Sut>;

// Every request answered exactly once, with its command id, legal layouts
// and checksums: no MUST rule of the stream has failed.
void AssertStreamRulesHold(const Sut& s) {
  for (const auto& [id, o] : s.verdicts.outcomes()) {
    if (o.status != Status::kFail) continue;
    const Rule* r = FindRule(id);
    RC_ASSERT(!(r != nullptr && r->level == Level::kMust));
  }
  for (const SsRequest& r : s.host->requests()) RC_ASSERT(r.answer >= 0);
}

stackshot::HostCommand MoveCmd(uint8_t axis, int32_t delta, bool at_speed, float fraction,
                               bool backlash) {
  const auto dir = delta < 0 ? stackshot::Direction::kBack : stackshot::Direction::kForward;
  const float distance = static_cast<float>(delta < 0 ? -delta : delta);
  if (at_speed) {
    return SsWrite(SsCommand::kRailMoveAtSpeed,
                   stackshot::RailMoveAtSpeed{dir, stackshot::Units::kSteps, distance, fraction},
                   axis);
  }
  return SsWrite(SsCommand::kRailMove,
                 stackshot::RailMove{dir, stackshot::Units::kSteps, backlash, distance}, axis);
}

// CC_RAIL_MOVE on a rail at rest: RSP_OK, and it rests `delta` further on.
struct Move : Cmd {
  uint8_t axis = *rc::gen::inRange<uint8_t>(0, kAxes);
  int32_t delta = *rc::gen::inRange(-4000, 4001);
  bool backlash = *rc::gen::arbitrary<bool>();
  void checkPreconditions(const Model& m) const override { RC_PRE(m.settled[axis]); }
  void apply(Model& m) const override {
    if (m.rest_steps[axis]) *m.rest_steps[axis] += delta;
    m.settled[axis] = delta == 0;
  }
  void run(const Model&, Sut& s) const override {
    RC_ASSERT(StatusOf(s.host->Call(MoveCmd(axis, delta, false, 1, backlash))) == Action::kRspOk);
    AssertStreamRulesHold(s);
  }
  void show(std::ostream& os) const override {
    os << "CC_RAIL_MOVE axis " << int{axis} << " " << delta << (backlash ? " backlash" : "");
  }
};

// CC_RAIL_MOVE while the rail may move: RSP_OK or BUSY; which one decides.
struct MoveMaybeBusy : Cmd {
  uint8_t axis = *rc::gen::inRange<uint8_t>(0, kAxes);
  int32_t delta = *rc::gen::inRange(-4000, 4001);
  void checkPreconditions(const Model& m) const override { RC_PRE(!m.settled[axis]); }
  void apply(Model& m) const override {
    // The device's answer decides; the model can only forget the end.
    m.rest_steps[axis].reset();
  }
  void run(const Model&, Sut& s) const override {
    const auto st = StatusOf(s.host->Call(MoveCmd(axis, delta, false, 1, false)));
    RC_ASSERT(st == Action::kRspOk || st == Action::kBusy);
    AssertStreamRulesHold(s);
  }
  void show(std::ostream& os) const override {
    os << "CC_RAIL_MOVE axis " << int{axis} << " " << delta << " (maybe moving)";
  }
};

// CC_RAIL_MOVE_AT_SPEED: always RSP_OK; the end is known only from rest.
struct MoveAtSpeed : Cmd {
  uint8_t axis = *rc::gen::inRange<uint8_t>(0, kAxes);
  int32_t delta = *rc::gen::inRange(-4000, 4001);
  float fraction = static_cast<float>(*rc::gen::inRange(2, 21)) * 0.05f;
  void apply(Model& m) const override {
    if (m.settled[axis] && m.rest_steps[axis]) {
      *m.rest_steps[axis] += delta;
    } else {
      m.rest_steps[axis].reset();
    }
    m.settled[axis] = m.settled[axis] && delta == 0;
  }
  void run(const Model&, Sut& s) const override {
    RC_ASSERT(StatusOf(s.host->Call(MoveCmd(axis, delta, true, fraction, false))) ==
              Action::kRspOk);
    AssertStreamRulesHold(s);
  }
  void show(std::ostream& os) const override {
    os << "CC_RAIL_MOVE_AT_SPEED axis " << int{axis} << " " << delta << " at " << fraction;
  }
};

struct Stop : Cmd {
  uint8_t axis = *rc::gen::inRange<uint8_t>(0, kAxes);
  void apply(Model& m) const override {
    if (!m.settled[axis]) m.rest_steps[axis].reset();
  }
  void run(const Model&, Sut& s) const override {
    RC_ASSERT(StatusOf(s.host->Call(SsWrite(SsCommand::kRailStop, stackshot::Empty{}, axis))) ==
              Action::kRspOk);
    AssertStreamRulesHold(s);
  }
  void show(std::ostream& os) const override { os << "CC_RAIL_STOP axis " << int{axis}; }
};

struct Zero : Cmd {
  uint8_t axis = *rc::gen::inRange<uint8_t>(0, kAxes);
  void checkPreconditions(const Model& m) const override { RC_PRE(m.settled[axis]); }
  void apply(Model& m) const override { m.rest_steps[axis] = 0; }
  void run(const Model&, Sut& s) const override {
    RC_ASSERT(StatusOf(s.host->Call(SsWrite(SsCommand::kRailPositionZero, stackshot::Empty{},
                                            axis))) == Action::kRspOk);
    AssertStreamRulesHold(s);
  }
  void show(std::ostream& os) const override { os << "CC_RAIL_POSITION_ZERO axis " << int{axis}; }
};

// CC_RAIL_STATUS: a rail the model knows at rest shows no MOVING.
struct ReadStatus : Cmd {
  uint8_t axis = *rc::gen::inRange<uint8_t>(0, kAxes);
  void run(const Model& m, Sut& s) const override {
    const auto st = SsRailStatus(*s.host, axis);
    RC_ASSERT(st.has_value());
    if (m.settled[axis]) RC_ASSERT((*st & stackshot::kRailStatusMoving) == 0u);
    AssertStreamRulesHold(s);
  }
  void show(std::ostream& os) const override { os << "CC_RAIL_STATUS axis " << int{axis}; }
};

struct Wait : Cmd {
  int ms = *rc::gen::inRange(0, 1500);
  void run(const Model&, Sut& s) const override {
    s.host->Idle(ms * sim::kNsPerMs);
    AssertStreamRulesHold(s);
  }
  void show(std::ostream& os) const override { os << "wait " << ms << " ms"; }
};

// Waits for rest and compares every known axis with the model.
struct Settle : Cmd {
  void apply(Model& m) const override { m.settled.fill(true); }
  void run(const Model& m, Sut& s) const override {
    RC_ASSERT(SsWaitRest(*s.host, {0, 1, 2}, 600 * sim::kNsPerSecond));
    for (uint8_t a = 0; a < kAxes; ++a) {
      if (!m.rest_steps[a]) continue;
      RC_ASSERT(SsPositionSteps(*s.host, a) == m.rest_steps[a]);
      RC_ASSERT(SsPositionSteps(*s.host, a, true) == m.rest_steps[a]);
    }
    AssertStreamRulesHold(s);
  }
  void show(std::ostream& os) const override { os << "settle and compare positions"; }
};

RC_GTEST_PROP(StackshotStateModel, Stackshot3xFollowsTheRailModel, ()) {
  Model model;
  Sut sut;
  rc::state::check(model, sut,
                   rc::state::gen::execOneOfWithArgs<Move, MoveMaybeBusy, MoveAtSpeed, Stop, Zero,
                                                     ReadStatus, Wait, Settle>());
}

}  // namespace
}  // namespace moco::conformance
