// The randomized sequence suite (dmc-v2-protocol.txt "Motor Control"): a seeded
// generator of valid motor requests within the device's advertised motors, a
// model of where every motor must come to rest, and shrinking of a failing
// sequence to a short transcript saved in the docs/sessions.md format.
#include <algorithm>
#include <random>

#include "conformance/core/sequence.h"
#include "conformance/core/transcript.h"
#include "conformance/protocols/dmc/dmc_cases_internal.h"
#include "conformance/protocols/dmc/dmc_suites.h"
#include "conformance/protocols/dmc/dmc_timing.h"
#include "session/session.h"

namespace moco::conformance {
namespace {

using dmc::AckCode;
using dmc_cases::kMs;

struct Step {
  enum class Op { kStatus, kGetPosition, kMove, kStop, kStopAll, kReset, kSetSpeed, kJog, kWait };
  Op op = Op::kStatus;
  uint8_t motor = 1;
  int32_t a = 0;
  int32_t b = 0;
};

std::vector<Step> Generate(uint64_t seed, int steps, uint8_t motor_count) {
  std::mt19937_64 rng(seed);
  auto uniform = [&](int64_t lo, int64_t hi) {
    return std::uniform_int_distribution<int64_t>(lo, hi)(rng);
  };
  const uint8_t motors = std::min<uint8_t>(motor_count, 4);
  std::vector<Step> out;
  for (int i = 0; i < steps; ++i) {
    Step s;
    s.op = static_cast<Step::Op>(uniform(0, 8));
    s.motor = static_cast<uint8_t>(uniform(1, motors));
    switch (s.op) {
      case Step::Op::kMove:
      case Step::Op::kReset:
        s.a = static_cast<int32_t>(uniform(-3000, 3000));
        break;
      // Speeds keep every move within seconds: a jog at 20% of a 2000 steps/s
      // motor crosses the 6000-step range in 15 s.
      case Step::Op::kSetSpeed:
        s.a = static_cast<int32_t>(uniform(2000, 8000));
        s.b = static_cast<int32_t>(uniform(2000, 20000));
        break;
      case Step::Op::kJog:
        s.a = static_cast<int32_t>(uniform(2000, 10000));
        s.b = static_cast<int32_t>(uniform(-3000, 3000));
        break;
      case Step::Op::kWait:
        s.a = static_cast<int32_t>(uniform(0, dmc_cases::kRandomWaitMaxMs));
        break;
      default:
        break;
    }
    out.push_back(s);
  }
  return out;
}

// Runs `steps` on `h` and judges them. Checks: every request answered OK, or
// ERR_MOVING for RESET_POSITION of a moving motor (DMC-ACK-011), and at the
// end every motor whose last command was a move, jog or reset rests there
// (DMC-MOVE-003).
void Execute(DmcHost& h, Verdicts& v, const std::vector<Step>& steps, uint8_t motor_count) {
  std::vector<std::optional<int32_t>> model(motor_count);
  const auto initial = GetPositions(h);
  if (!initial) return;
  for (size_t m = 0; m < model.size() && m < initial->size(); ++m) model[m] = (*initial)[m];
  for (const Step& s : steps) {
    const DmcRecord* r = nullptr;
    const size_t mi = s.motor - 1u;
    switch (s.op) {
      case Step::Op::kStatus:
        r = h.Call(dmc::MotorStatusRequest{});
        break;
      case Step::Op::kGetPosition:
        r = h.Call(dmc::MotorGetPositionRequest{});
        break;
      case Step::Op::kMove:
        r = h.Call(dmc::MotorMove{s.motor, s.a});
        if (dmc_cases::MoveAccepted(r)) model[mi] = s.a;
        break;
      case Step::Op::kStop:
        r = h.Call(dmc::MotorStop{s.motor});
        model[mi].reset();
        break;
      case Step::Op::kStopAll:
        r = h.Call(dmc::MotorStopAll{});
        for (auto& m : model) m.reset();
        break;
      case Step::Op::kReset:
        r = h.Call(dmc::MotorResetPosition{s.motor, s.a});
        if (AckCodeOf(r) == dmc::ToWire(AckCode::kOk)) model[mi] = s.a;
        break;
      case Step::Op::kSetSpeed:
        r = h.Call(
            dmc::MotorSetSpeed{s.motor, static_cast<uint32_t>(s.a), static_cast<uint32_t>(s.b)});
        break;
      case Step::Op::kJog:
        r = h.Call(dmc::MotorJog{s.motor, static_cast<uint16_t>(s.a), s.b});
        if (AckCodeOf(r) == dmc::ToWire(AckCode::kOk)) model[mi] = s.b;
        break;
      case Step::Op::kWait:
        h.Idle(s.a * kMs);
        break;
    }
    if (const auto code = AckCodeOf(r)) {
      const bool moving_ok = s.op == Step::Op::kReset && *code == dmc::ToWire(AckCode::kErrMoving);
      v.Check("DMC-ACK-011", *code == dmc::ToWire(AckCode::kOk) || moving_ok, [&] {
        return Evidence{"ACK OK", "ACK " + dmc::AckCodeName(*code), wire::ToHex(r->raw), r->t_ns};
      });
    }
  }
  WaitRest(h, dmc_cases::kRandomRestWaitNs);
  const auto final_pos = GetPositions(h);
  if (!final_pos) return;
  for (size_t m = 0; m < model.size(); ++m) {
    if (!model[m]) continue;
    const int32_t got = m < final_pos->size() ? (*final_pos)[m] : 0;
    v.Check("DMC-MOVE-003", got == *model[m], [&] {
      return Evidence{"motor " + std::to_string(m + 1) + " at rest on " + std::to_string(*model[m]),
                      std::to_string(got), "", h.Now()};
    });
  }
}

std::string Describe(const Step& s) {
  switch (s.op) {
    case Step::Op::kStatus:
      return "MOTOR_STATUS";
    case Step::Op::kGetPosition:
      return "MOTOR_GET_POSITION";
    case Step::Op::kMove:
      return "MOTOR_MOVE " + std::to_string(s.motor) + " " + std::to_string(s.a);
    case Step::Op::kStop:
      return "MOTOR_STOP " + std::to_string(s.motor);
    case Step::Op::kStopAll:
      return "MOTOR_STOP_ALL";
    case Step::Op::kReset:
      return "MOTOR_RESET_POSITION " + std::to_string(s.motor) + " " + std::to_string(s.a);
    case Step::Op::kSetSpeed:
      return "MOTOR_SET_SPEED " + std::to_string(s.motor) + " " + std::to_string(s.a) + " " +
             std::to_string(s.b);
    case Step::Op::kJog:
      return "MOTOR_JOG " + std::to_string(s.motor) + " speed " + std::to_string(s.a) + " to " +
             std::to_string(s.b);
    case Step::Op::kWait:
      return "wait " + std::to_string(s.a) + " ms";
  }
  return "?";
}

}  // namespace

void RandomSequence(DmcCaseContext& c) {
  const uint8_t motors = c.device.motor_count;
  RandomPlay<DmcHost, Step> play;
  play.protocol = Protocol::kDmc;
  play.note = "mococheck random sequence";
  play.shrink_budget = 300;
  play.greet = [](DmcHost& h) { return As<dmc::HiResponse>(h.Call(dmc::HiRequest{})) != nullptr; };
  play.execute = [motors](DmcHost& h, Verdicts& v, const std::vector<Step>& steps) {
    Execute(h, v, steps, motors);
  };
  play.describe = [](const Step& s) { return Describe(s); };
  PlayRandomSequence(c, Generate(c.random.seed, c.random.steps, motors), play);
}

}  // namespace moco::conformance
