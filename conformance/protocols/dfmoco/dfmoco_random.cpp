// The DFMoco randomized sequence suite (dfmoco-protocol.txt "Messages"): a
// seeded generator of commands that are valid for the model's state (np and
// zm only on a motor known to rest), a model of where every motor must come
// to rest, and shrinking of a failing sequence to a short transcript saved in
// the docs/sessions.md format.
#include <algorithm>
#include <random>

#include "conformance/core/sequence.h"
#include "conformance/core/transcript.h"
#include "conformance/protocols/dfmoco/dfmoco_suites.h"
#include "conformance/protocols/dfmoco/dfmoco_timing.h"
#include "session/session.h"

namespace moco::conformance {
namespace {

using dfmoco_cases::kMs;
using dfmoco_cases::kRandomRestTimeoutNs;

struct Step {
  enum class Op {
    kStatus,
    kPosition,
    kMove,
    kStop,
    kStopAll,
    kNewPosition,
    kZero,
    kPulseRate,
    kJog,
    kInch,
    kWait,
    kSettle
  };
  Op op = Op::kStatus;
  int32_t motor = 1;
  int32_t a = 0;
};

// What the model knows of one motor.
struct MotorModel {
  std::optional<int32_t> rest_steps = 0;  // where it will rest; nullopt: unknown (stopped, jogged)
  std::string_view rule = "DFM-MM-003";   // the rule that judges rest_steps
  bool settled = true;                    // known to rest now
};

std::vector<Step> Generate(uint64_t seed, int steps, int32_t motor_count) {
  std::mt19937_64 rng(seed);
  auto uniform = [&](int64_t lo, int64_t hi) {
    return std::uniform_int_distribution<int64_t>(lo, hi)(rng);
  };
  const int32_t motors = std::min<int32_t>(motor_count, 4);
  std::vector<bool> settled(static_cast<size_t>(motors), true);
  std::vector<Step> out;
  while (static_cast<int>(out.size()) < steps) {
    Step s;
    s.op = static_cast<Step::Op>(uniform(0, 11));
    s.motor = static_cast<int32_t>(uniform(1, motors));
    const size_t mi = static_cast<size_t>(s.motor - 1);
    switch (s.op) {
      case Step::Op::kMove:
      case Step::Op::kJog:
      case Step::Op::kInch:
        s.a = static_cast<int32_t>(uniform(-3000, 3000));
        settled[mi] = false;
        break;
      case Step::Op::kNewPosition:
      case Step::Op::kZero:
        if (!settled[mi]) continue;  // "no movement": only on a motor at rest
        s.a = static_cast<int32_t>(uniform(-5000, 5000));
        break;
      case Step::Op::kPulseRate:
        s.a = static_cast<int32_t>(uniform(2000, 20000));
        break;
      case Step::Op::kWait:
        s.a = static_cast<int32_t>(uniform(0, 1500));
        break;
      case Step::Op::kSettle:
        settled.assign(settled.size(), true);
        break;
      default:
        break;
    }
    out.push_back(s);
  }
  return out;
}

std::string Describe(const Step& s) {
  const std::string m = std::to_string(s.motor);
  const std::string a = std::to_string(s.a);
  switch (s.op) {
    case Step::Op::kStatus:
      return "ms";
    case Step::Op::kPosition:
      return "mp " + m;
    case Step::Op::kMove:
      return "mm " + m + " " + a;
    case Step::Op::kStop:
      return "sm " + m;
    case Step::Op::kStopAll:
      return "sa";
    case Step::Op::kNewPosition:
      return "np " + m + " " + a;
    case Step::Op::kZero:
      return "zm " + m;
    case Step::Op::kPulseRate:
      return "pr " + m + " " + a;
    case Step::Op::kJog:
      return "jm " + m + " " + a;
    case Step::Op::kInch:
      return "im " + m + " " + a;
    case Step::Op::kWait:
      return "(wait " + a + " ms)";
    case Step::Op::kSettle:
      return "(ms until every motor rests)";
  }
  return "?";
}

// Runs `steps` on `h` and judges them: every command answered per its grammar
// (the host's stream checks: DFM-REPLY-001, the answer rules), and at the end
// every motor the model knows rests where the model says (DFM-MM-003,
// DFM-NP-002, DFM-ZM-002).
void Execute(DfmHost& h, Verdicts& v, const std::vector<Step>& steps, int32_t motor_count) {
  const int32_t motors = std::min<int32_t>(motor_count, 4);
  std::vector<MotorModel> model(static_cast<size_t>(motors));
  for (int32_t m = 1; m <= motors; ++m) {
    const auto p = DfmPosition(h, m);
    if (!p) return;
    model[static_cast<size_t>(m - 1)].rest_steps = *p;
  }
  for (const Step& s : steps) {
    MotorModel& mm = model[static_cast<size_t>(s.motor - 1)];
    switch (s.op) {
      case Step::Op::kWait:
        h.Idle(s.a * kMs);
        continue;
      case Step::Op::kSettle:
        DfmWaitRest(h, kRandomRestTimeoutNs);
        for (MotorModel& x : model) x.settled = true;
        continue;
      case Step::Op::kMove:
        mm = MotorModel{s.a, "DFM-MM-003", false};
        break;
      case Step::Op::kStop:
        if (!mm.settled) mm.rest_steps.reset();
        break;
      case Step::Op::kStopAll:
        for (MotorModel& x : model) {
          if (!x.settled) x.rest_steps.reset();
        }
        break;
      case Step::Op::kNewPosition:
        mm = MotorModel{s.a, "DFM-NP-002", true};
        break;
      case Step::Op::kZero:
        mm = MotorModel{0, "DFM-ZM-002", true};
        break;
      case Step::Op::kJog:
      case Step::Op::kInch:
        // A jog or an inch goes a bounded way towards its destination.
        if (!(mm.settled && mm.rest_steps == s.a)) mm.rest_steps.reset();
        mm.settled = false;
        break;
      default:
        break;
    }
    h.Call(Describe(s));
  }
  DfmWaitRest(h, kRandomRestTimeoutNs);
  for (int32_t m = 1; m <= motors; ++m) {
    const MotorModel& mm = model[static_cast<size_t>(m - 1)];
    if (!mm.rest_steps) continue;
    const auto got = DfmPosition(h, m);
    if (!got) continue;
    v.Check(mm.rule, *got == *mm.rest_steps, [&] {
      return Evidence{
          "motor " + std::to_string(m) + " at rest on " + std::to_string(*mm.rest_steps),
          std::to_string(*got), "", h.Now()};
    });
  }
}

}  // namespace

void DfmRandomSequence(DfmCaseContext& c) {
  const int32_t motors = c.device.motor_count;
  // A shorter sequence stays valid when shrunk: np and zm need a motor at
  // rest, and a dropped move only leaves it at rest sooner.
  RandomPlay<DfmHost, Step> play;
  play.protocol = Protocol::kDfmoco;
  play.note = "mococheck dfmoco random sequence";
  play.shrink_budget = 200;
  play.greet = [](DfmHost& h) { return As<dfmoco::HelloReply>(h.Call("hi")) != nullptr; };
  play.execute = [motors](DfmHost& h, Verdicts& v, const std::vector<Step>& steps) {
    Execute(h, v, steps, motors);
  };
  play.describe = [](const Step& s) { return Describe(s); };
  PlayRandomSequence(c, Generate(c.random.seed, c.random.steps, motors), play);
}

}  // namespace moco::conformance
