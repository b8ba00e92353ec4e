// The StackShot 3X randomized sequence suite (stackshot-protocol.txt 1.1.3-
// 1.1.9 and CC_RAIL_* in section 2): a seeded generator of valid rail
// requests, a model of the status each request may get and of where each
// axis must come to rest, and shrinking of a failing sequence to a short
// transcript saved in the docs/sessions.md format.
#include <algorithm>
#include <random>

#include "conformance/core/sequence.h"
#include "conformance/core/transcript.h"
#include "conformance/protocols/stackshot/stackshot_suites.h"
#include "conformance/protocols/stackshot/stackshot_timing.h"
#include "session/session.h"

namespace moco::conformance {
namespace {

using ss_cases::kMs;
using stackshot::Action;
using stackshot::Command;

struct Step {
  enum class Op { kStatus, kPosition, kMove, kMoveAtSpeed, kStop, kZero, kWait, kPing, kSettle };
  Op op = Op::kStatus;
  uint8_t axis = 0;
  int32_t a = 0;          // steps, milliseconds or the ping value
  float fraction = 1.0f;  // MOVE_AT_SPEED
  bool backlash = false;  // MOVE
};

std::vector<Step> Generate(uint64_t seed, int steps, uint8_t axes) {
  std::mt19937_64 rng(seed);
  auto uniform = [&](int64_t lo, int64_t hi) {
    return std::uniform_int_distribution<int64_t>(lo, hi)(rng);
  };
  std::vector<Step> out;
  for (int i = 0; i < steps; ++i) {
    Step s;
    s.op = static_cast<Step::Op>(uniform(0, 8));
    s.axis = static_cast<uint8_t>(uniform(0, axes - 1));
    switch (s.op) {
      case Step::Op::kMove:
        s.a = static_cast<int32_t>(uniform(-3000, 3000));
        s.backlash = uniform(0, 1) == 1;
        break;
      case Step::Op::kMoveAtSpeed:
        // At least 10 % of the axis's top speed: every move ends within seconds.
        s.a = static_cast<int32_t>(uniform(-3000, 3000));
        s.fraction = static_cast<float>(uniform(2, 20)) * 0.05f;
        break;
      case Step::Op::kWait:
        s.a = static_cast<int32_t>(uniform(0, kSsRandomWaitMaxNs / kMs));
        break;
      case Step::Op::kPing:
        s.a = static_cast<int32_t>(uniform(0, 255));
        break;
      default:
        break;
    }
    out.push_back(s);
  }
  return out;
}

stackshot::HostCommand MoveCmd(const Step& s) {
  stackshot::RailMove m;
  m.direction = s.a < 0 ? stackshot::Direction::kBack : stackshot::Direction::kForward;
  m.units = stackshot::Units::kSteps;
  m.backlash = s.backlash;
  m.distance = static_cast<float>(s.a < 0 ? -s.a : s.a);
  return SsWrite(Command::kRailMove, m, s.axis);
}

stackshot::HostCommand MoveAtSpeedCmd(const Step& s) {
  stackshot::RailMoveAtSpeed m;
  m.direction = s.a < 0 ? stackshot::Direction::kBack : stackshot::Direction::kForward;
  m.units = stackshot::Units::kSteps;
  m.distance = static_cast<float>(s.a < 0 ? -s.a : s.a);
  m.speed_fraction = s.fraction;
  return SsWrite(Command::kRailMoveAtSpeed, m, s.axis);
}

std::string Describe(const Step& s) {
  const std::string axis = " axis " + stackshot::AxisName(s.axis);
  switch (s.op) {
    case Step::Op::kStatus:
      return "CC_RAIL_STATUS" + axis;
    case Step::Op::kPosition:
      return "CC_RAIL_POSITION_CURRENT" + axis;
    case Step::Op::kMove:
      return "CC_RAIL_MOVE" + axis + " " + std::to_string(s.a) + " steps" +
             (s.backlash ? " backlash" : "");
    case Step::Op::kMoveAtSpeed:
      return "CC_RAIL_MOVE_AT_SPEED" + axis + " " + std::to_string(s.a) + " steps at " +
             stackshot::FormatF32(s.fraction);
    case Step::Op::kStop:
      return "CC_RAIL_STOP" + axis;
    case Step::Op::kZero:
      return "CC_RAIL_POSITION_ZERO" + axis;
    case Step::Op::kWait:
      return "wait " + std::to_string(s.a) + " ms";
    case Step::Op::kPing:
      return "CC_PING " + std::to_string(s.a);
    case Step::Op::kSettle:
      return "wait for rest and compare positions";
  }
  return "?";
}

// Where each axis must rest, and the rule a mismatch breaks.
struct AxisModel {
  std::optional<int64_t> rest_steps;
  bool settled = true;  // known to be at rest
  std::string_view rule = "SS-MOVE-001";
};

void Compare(SsHost& h, Verdicts& v, const std::vector<AxisModel>& model) {
  for (size_t a = 0; a < model.size(); ++a) {
    if (!model[a].rest_steps) continue;
    const auto got = SsPositionSteps(h, static_cast<uint8_t>(a));
    v.Check(model[a].rule, got == model[a].rest_steps, [&] {
      return Evidence{"axis " + stackshot::AxisName(static_cast<uint8_t>(a)) + " at rest on " +
                          std::to_string(*model[a].rest_steps),
                      got ? std::to_string(*got) : "no position", "", h.Now()};
    });
  }
}

// Runs `steps` and judges them: each reply's status must be one the model
// allows (SS-CODE-003: RSP_OK, or BUSY for MOVE and POSITION_ZERO while the
// axis may still move), a settled axis reports no MOVING (SS-STATUS-003),
// and at rest every axis with a known end sits there.
void Execute(SsHost& h, Verdicts& v, const std::vector<Step>& steps, uint8_t axes) {
  std::vector<uint8_t> all;
  for (uint8_t a = 0; a < axes; ++a) all.push_back(a);
  SsWaitRest(h, all, kSsRandomRestWaitNs);
  std::vector<AxisModel> model(axes);
  for (uint8_t a = 0; a < axes; ++a) {
    model[a].rest_steps = SsPositionSteps(h, a);
    if (!model[a].rest_steps) return;
  }
  for (const Step& s : steps) {
    AxisModel& m = model[s.axis];
    const SsRecord* r = nullptr;
    bool busy_ok = false;
    switch (s.op) {
      case Step::Op::kStatus: {
        r = h.Call(SsRead(Command::kRailStatus, stackshot::Empty{}, s.axis));
        if (const auto* st = PayloadOf<stackshot::RailStatus>(r)) {
          const bool moving = (st->bits & stackshot::kRailStatusMoving) != 0;
          if (m.settled) {
            v.Check("SS-STATUS-003", !moving, [&] {
              return Evidence{"no MOVING on a rail at rest", Show(r), wire::ToHex(r->raw), r->t_ns};
            });
          }
          if (!moving) m.settled = true;
        }
        break;
      }
      case Step::Op::kPosition: {
        r = h.Call(SsRead(Command::kRailPositionCurrent,
                          stackshot::UnitsQuery{stackshot::Units::kSteps}, s.axis));
        const auto* p = PayloadOf<stackshot::UnitsF32>(r);
        if (p != nullptr && m.settled && m.rest_steps) {
          const int64_t got = std::llround(static_cast<double>(p->value.value()));
          v.Check(m.rule, got == *m.rest_steps, [&] {
            return Evidence{"at rest on " + std::to_string(*m.rest_steps), std::to_string(got),
                            wire::ToHex(r->raw), r->t_ns};
          });
        }
        break;
      }
      case Step::Op::kMove:
        r = h.Call(MoveCmd(s));
        busy_ok = !m.settled;
        if (StatusOf(r) == Action::kRspOk) {
          if (m.rest_steps) *m.rest_steps += s.a;
          m.settled = s.a == 0 && m.settled;
          m.rule = "SS-MOVE-001";
        }
        break;
      case Step::Op::kMoveAtSpeed:
        r = h.Call(MoveAtSpeedCmd(s));
        if (StatusOf(r) == Action::kRspOk) {
          // From the immediate position: known only when the rail was at rest.
          if (m.settled && m.rest_steps) {
            *m.rest_steps += s.a;
          } else {
            m.rest_steps.reset();
          }
          m.settled = s.a == 0 && m.settled;
          m.rule = "SS-MOVE-003";
        }
        break;
      case Step::Op::kStop:
        r = h.Call(SsWrite(Command::kRailStop, stackshot::Empty{}, s.axis));
        if (!m.settled) m.rest_steps.reset();
        break;
      case Step::Op::kZero:
        r = h.Call(SsWrite(Command::kRailPositionZero, stackshot::Empty{}, s.axis));
        busy_ok = !m.settled;
        if (StatusOf(r) == Action::kRspOk) {
          m.rest_steps = 0;
          m.settled = true;  // zeroing is refused while the axis moves
          m.rule = "SS-POS-001";
        }
        break;
      case Step::Op::kWait:
        h.Idle(s.a * kMs);
        break;
      case Step::Op::kPing:
        r = h.Call(SsRead(Command::kPing, stackshot::PingRequest{static_cast<uint8_t>(s.a)}));
        break;
      case Step::Op::kSettle:
        SsWaitRest(h, all, kSsRandomRestWaitNs);
        for (AxisModel& am : model) am.settled = true;
        Compare(h, v, model);
        break;
    }
    if (r != nullptr) {
      const Action st = *StatusOf(r);
      v.Check("SS-CODE-003", st == Action::kRspOk || (busy_ok && st == Action::kBusy), [&] {
        return Evidence{busy_ok ? "ok or busy" : "ok", Show(r), wire::ToHex(r->raw), r->t_ns};
      });
    }
  }
  SsWaitRest(h, all, kSsRandomRestWaitNs);
  Compare(h, v, model);
}

uint8_t AxisCount(const SsDeviceInfo& d) { return d.three_axes ? 3 : 1; }

}  // namespace

void SsRandomSequence(SsCaseContext& c) {
  const uint8_t axes = AxisCount(c.device);
  RandomPlay<SsHost, Step> play;
  play.protocol = Protocol::kStackshot;
  play.note = "mococheck StackShot random sequence";
  play.shrink_budget = 300;
  play.greet = [](SsHost& h) {
    return StatusOf(h.Call(SsRead(Command::kPing, stackshot::PingRequest{0}))) == Action::kRspOk;
  };
  play.execute = [axes](SsHost& h, Verdicts& v, const std::vector<Step>& steps) {
    Execute(h, v, steps, axes);
  };
  play.describe = [](const Step& s) { return Describe(s); };
  PlayRandomSequence(c, Generate(c.random.seed, c.random.steps, axes), play);
}

}  // namespace moco::conformance
